"""Two flows on homogeneous spaces: Landau-Lifshitz-Gilbert spin relaxation on the sphere,
and Oja's subspace flow on a Stiefel manifold converging to a dominant eigenspace.

    python examples/spin_and_subspace.py [--quick] [--out DIR]

1. ``m' = w(m) x m`` on ``Sphere()`` with ``w = (H + a m x H) / (1 + a^2)`` (LLG in
   Landau-Lifshitz form, ``H`` = external field plus uniaxial anisotropy, damping
   ``a = 0.1``): |m| stays 1 to round-off while the spin spirals into the field.
2. ``Y' = (I - Y Y^T) A Y`` on ``Stiefel(6, 2)``, as the generator ``A Y Y^T - Y Y^T A`` of
   SO(6): ``Y`` stays orthonormal, and ``Y Y^T`` converges to the projector on the two
   dominant eigenvectors of the symmetric ``A`` (checked against ``numpy.linalg.eigh``).
"""

import argparse
from pathlib import Path

import numpy as np

from liegroup_int import Sphere, Stiefel, integrate


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--out", type=Path, default=Path("examples_out"))
    a = ap.parse_args(argv)
    T1, T2 = (10.0, 10.0) if a.quick else (60.0, 40.0)

    S = Sphere()
    H_ext, K, e = np.array([0.2, 0.0, 1.0]), 0.5, np.array([1.0, 0.0, 0.0])

    def spin(t, m):
        H = H_ext + K * (m @ e) * e
        return (H + 0.1 * np.cross(m, H)) / (1 + 0.1**2)

    spin_hist = []
    integrate(spin, S.project(np.array([0.0, 1.0, 0.3])), (0.0, T1), space=S, method="rkmk4", dt=0.02,
              t_eval=np.linspace(0.0, T1, 301)[1:], observer=lambda t, m: spin_hist.append((t, *m)))
    spin_hist = np.array(spin_hist)
    unit = np.max(np.abs(np.linalg.norm(spin_hist[:, 1:], axis=1) - 1.0))
    print(f"LLG spin: max ||m| - 1| = {unit:.1e} over {T1:g} s; m(T) = {np.round(spin_hist[-1, 1:], 4)}")

    rng = np.random.default_rng(3)
    Q = np.linalg.qr(rng.standard_normal((6, 6)))[0]
    A = Q @ np.diag([5.0, 4.0, 3.0, 1.0, 0.5, 0.0]) @ Q.T
    V = Stiefel(6, 2)
    w, U = np.linalg.eigh(A)
    P = U[:, -2:] @ U[:, -2:].T
    sub_hist = []
    integrate(lambda t, Y: V.group.vee(A @ Y @ Y.T - Y @ Y.T @ A), V.sample(rng), (0.0, T2), space=V,
              method="rkmk4", dt=0.02, t_eval=np.linspace(0.0, T2, 201)[1:],
              observer=lambda t, Y: sub_hist.append((t, np.max(np.abs(Y @ Y.T - P)), V.constraint(Y))))
    sub_hist = np.array(sub_hist)
    print(f"Oja flow: |Y Y^T - P| = {sub_hist[-1, 1]:.1e} at t = {T2:g}; max |Y^T Y - I| = {sub_hist[:, 2].max():.1e}")

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 3.6))
    for i, c in enumerate("xyz"):
        ax1.plot(spin_hist[:, 0], spin_hist[:, 1 + i], label=f"m_{c}")
    ax1.set_xlabel("t")
    ax1.set_title("LLG spin on S^2 (RKMK4)")
    ax1.legend(fontsize=8)
    ax1.grid(alpha=0.3)
    ax2.semilogy(sub_hist[:, 0], sub_hist[:, 1], label="|Y Y^T - P|")
    ax2.semilogy(sub_hist[:, 0], np.maximum(sub_hist[:, 2], 1e-17), label="|Y^T Y - I|")
    ax2.set_xlabel("t")
    ax2.set_title("Oja's flow on V_2(R^6) (RKMK4)")
    ax2.legend(fontsize=8)
    ax2.grid(alpha=0.3)
    a.out.mkdir(parents=True, exist_ok=True)
    path = a.out / "spin_and_subspace.png"
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")
    return spin_hist, sub_hist


if __name__ == "__main__":
    main()
