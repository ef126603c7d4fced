"""The N-fold 3D pendulum on (TS^2)^N with SE(3)^N acting (Celledoni, Cokaj, Leone, Murari &
Owren, "Lie group integrators for mechanical systems", Int. J. Comput. Math. 2022), with
fixed and variable steps.

    python examples/n_pendulum.py [--quick] [--n 2] [--out DIR]

Point masses ``m_i`` on massless links of lengths ``L_i``, ``x_i = sum_{k<=i} L_k q_k``, a
fixed pivot, gravity ``-g e3``. With ``M_jk = sum_{i >= max(j,k)} m_i`` the constrained
Euler-Lagrange equations, crossed with ``q_j`` to remove the multipliers, are linear in the
angular accelerations:

    sum_k M_jk L_j L_k [(q_j . q_k) I - q_k q_j^T] w'_k
        = sum_k M_jk L_j L_k |w_k|^2 q_j x q_k - g M_jj L_j q_j x e3,

(``q_j . w'_j = 0`` closes the system). The generator on link ``j`` is
``(rho_j, theta_j) = (q_j x w'_j, w_j)`` (``TangentSphere``). Prints the energy drift and
the constraint error of RKMK4 and of the adaptive RKMK45 pair, and plots the drift.
"""

import argparse
from pathlib import Path

import numpy as np

from liegroup_int import ProductSpace, TangentSphere, integrate

G = 9.81


def n_pendulum(n, masses=None, lengths=None):
    """``(space, generator, y0, energy)`` of an N-fold pendulum: unit masses and lengths by
    default, links started along a helix-like zig-zag with some angular velocity."""
    m = np.ones(n) if masses is None else np.asarray(masses, float)
    L = np.ones(n) if lengths is None else np.asarray(lengths, float)
    if m.shape != (n,) or L.shape != (n,) or np.any(m <= 0) or np.any(L <= 0):
        raise ValueError(f"masses and lengths: expected {n} positive values each, got {m.tolist()} and {L.tolist()}")
    Msum = np.array([[m[max(j, k):].sum() for k in range(n)] for j in range(n)])
    C = Msum * np.outer(L, L)
    space = ProductSpace.power(TangentSphere(), n)
    e3 = np.array([0.0, 0.0, 1.0])

    def split(y):
        Y = np.asarray(y, dtype=float).reshape(n, 6)
        return Y[:, :3], Y[:, 3:]

    def accelerations(q, w):
        A = np.zeros((3 * n, 3 * n))
        b = np.zeros(3 * n)
        for j in range(n):
            for k in range(n):
                A[3 * j:3 * j + 3, 3 * k:3 * k + 3] = C[j, k] * ((q[j] @ q[k]) * np.eye(3) - np.outer(q[k], q[j]))
                b[3 * j:3 * j + 3] += C[j, k] * (w[k] @ w[k]) * np.cross(q[j], q[k])
            A[3 * j:3 * j + 3, 3 * j:3 * j + 3] += np.outer(q[j], q[j])  # q_j . w'_j = 0
            b[3 * j:3 * j + 3] -= G * Msum[j, j] * L[j] * np.cross(q[j], e3)
        return np.linalg.solve(A, b).reshape(n, 3)

    def generator(t, y):
        q, w = split(y)
        dw = accelerations(q, w)
        return np.concatenate([np.concatenate([np.cross(q[j], dw[j]), w[j]]) for j in range(n)])

    def energy(y):
        q, w = split(y)
        v = np.cross(w, q)  # q'_k
        kinetic = 0.5 * np.einsum("jk,jd,kd->", C, v, v)
        heights = np.cumsum(L * q[:, 2])
        return float(kinetic + G * (m * heights).sum())

    ang = np.linspace(0.4, 1.4, n)
    q0 = np.stack([np.sin(ang) * np.cos(2 * ang), np.sin(ang) * np.sin(2 * ang), -np.cos(ang)], axis=1)
    w0 = np.stack([np.cross(q0[j], [0.3, -0.2, 0.5]) + 0.1 * j * q0[j] for j in range(n)])
    y0 = space.project(np.concatenate([np.concatenate([q0[j], w0[j]]) for j in range(n)]))
    return space, generator, y0, energy


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--n", type=int, default=2)
    ap.add_argument("--out", type=Path, default=Path("examples_out"))
    a = ap.parse_args(argv)
    T = 0.5 if a.quick else 10.0
    space, gen, y0, energy = n_pendulum(a.n)
    E0 = energy(y0)
    t_eval = np.linspace(0.0, T, 101)[1:]
    runs = {}
    for label, kw in (("rkmk4, dt = 1e-3", dict(method="rkmk4", dt=1e-3)),
                      ("rkmk45, tol = 1e-8", dict(method="rkmk45", rtol=1e-8, atol=1e-8))):
        hist = []
        sol = integrate(gen, y0, (0.0, T), space=space, t_eval=t_eval,
                        observer=lambda t, y: hist.append((t, abs(energy(y) - E0), float(space.constraint(y)))), **kw)
        h = np.array(hist[1:])
        runs[label] = (h, sol.stats)
        print(f"{label}: {sol.stats.steps} steps; energy drift {h[:, 1].max():.2e} J (E0 = {E0:.3f} J), "
              f"constraints {h[:, 2].max():.1e}")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 3.6))
    for label, (h, _) in runs.items():
        ax.semilogy(h[:, 0], np.maximum(h[:, 1], 1e-17), label=label)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("|E(t) - E(0)| [J]")
    ax.set_title(f"{a.n}-fold 3D pendulum on (TS^2)^{a.n}")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    a.out.mkdir(parents=True, exist_ok=True)
    path = a.out / "n_pendulum.png"
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")
    return runs


if __name__ == "__main__":
    main()
