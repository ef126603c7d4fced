"""Work-precision on homogeneous spaces: RKMK4, the commutator-free CF4 and the
Crouch-Grossman CG4a against scipy's DOP853 on the embedding.

    python benchmarks/manifold_work_precision.py [--plot docs/img/manifold_work_precision.png]

Two problems, each against a tight reference at the final time T:

1. **Toda lattice** on ``Isospectral(5)`` (``examples/toda_lattice.py``), T = 20: error
   ``max |L(T) - L_ref(T)|`` and the eigenvalue drift. DOP853 integrates the flattened
   matrix ``L' = [B(L), L]`` (no projection: none keeps the spectrum).
2. **Landau-Lifshitz-Gilbert spin** on ``Sphere()`` (``tests/manifolds/test_manifolds_flows.py``),
   T = 5: error ``max |m(T) - m_ref(T)|`` and ``| |m| - 1 |``. DOP853 integrates
   ``m' = w(m) x m`` in R^3 and its result is projected onto the sphere (``m / |m|``).

Ours: fixed steps (the generic NumPy loop; no compiled SO(n) engine). Peer: DOP853 over
``rtol = atol`` from 1e-4 to 1e-12. Reported: CPU time per run (best of 3), and the CPU
ratio at equal error, interpolated log-log along each method's curve.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

from liegroup_int import Isospectral, Sphere, integrate


def _cpu(fn, repeat=3):
    best, out = np.inf, None
    for _ in range(repeat):
        t0 = time.process_time()
        out = fn()
        best = min(best, time.process_time() - t0)
    return out, best


def toda_case():
    rng = np.random.default_rng(0)
    a, b = rng.standard_normal(5), rng.uniform(0.5, 1.5, 4)
    L0 = np.diag(a) + np.diag(b, 1) + np.diag(b, -1)
    M = Isospectral(5)

    def field(t, L):
        return M.group.vee(np.triu(L, 1) - np.tril(L, -1))

    def flat(t, y):
        L = y.reshape(5, 5)
        B = np.triu(L, 1) - np.tril(L, -1)
        return (B @ L - L @ B).ravel()

    ev0 = np.linalg.eigvalsh(L0)
    return dict(name="Toda lattice, Isospectral(5), T = 20", space=M, y0=L0, field=field, T=20.0,
                peer=lambda tol: solve_ivp(flat, (0, 20.0), L0.ravel(), method="DOP853", rtol=tol,
                                           atol=tol).y[:, -1].reshape(5, 5),
                invariant=lambda L: float(np.max(np.abs(np.linalg.eigvalsh(L) - ev0))), steps=(0.2, 0.1, 0.05, 0.025))


def llg_case():
    H_ext, K, e = np.array([0.2, 0.0, 1.0]), 0.5, np.array([1.0, 0.0, 0.0])

    def field(t, m):
        H = H_ext + K * (m @ e) * e
        return (H + 0.1 * np.cross(m, H)) / (1 + 0.1**2)

    def rhs(t, m):
        return np.cross(field(t, m), m)

    S = Sphere()
    m0 = S.project(np.array([0.0, 1.0, 0.3]))

    def peer(tol):
        m = solve_ivp(rhs, (0, 5.0), m0, method="DOP853", rtol=tol, atol=tol).y[:, -1]
        return m / np.linalg.norm(m)

    return dict(name="LLG spin, Sphere(), T = 5", space=S, y0=m0, field=field, T=5.0, peer=peer,
                invariant=lambda m: abs(float(np.linalg.norm(m)) - 1.0), steps=(0.2, 0.1, 0.05, 0.025, 0.0125))


def run_case(case):
    ref = integrate(case["field"], case["y0"], (0.0, case["T"]), space=case["space"], method="rkmk6",
                    dt=case["steps"][-1] / 8).y_final
    rows = {}
    for method in ("rkmk4", "cf4", "cg4a"):
        pts = []
        for dt in case["steps"]:
            y, cpu = _cpu(lambda: integrate(case["field"], case["y0"], (0.0, case["T"]), space=case["space"],
                                            method=method, dt=dt).y_final)
            pts.append((cpu, float(np.max(np.abs(y - ref))), case["invariant"](y), f"dt={dt:g}"))
        rows[method] = pts
    pts = []
    for tol in (1e-4, 1e-6, 1e-8, 1e-10, 1e-12):
        y, cpu = _cpu(lambda: case["peer"](tol))
        pts.append((cpu, float(np.max(np.abs(y - ref))), case["invariant"](y), f"tol={tol:g}"))
    rows["DOP853"] = pts
    return rows


def cpu_at(pts, err):
    """CPU at a given error, log-log interpolation along a curve (NaN outside it)."""
    e = np.log([p[1] for p in pts])
    c = np.log([p[0] for p in pts])
    order = np.argsort(e)
    e, c = e[order], c[order]
    le = np.log(err)
    return float(np.exp(np.interp(le, e, c))) if e[0] <= le <= e[-1] else float("nan")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--plot", type=Path, default=Path("docs/img/manifold_work_precision.png"))
    args = ap.parse_args(argv)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cases = [toda_case(), llg_case()]
    fig, axes = plt.subplots(1, len(cases), figsize=(11, 4))
    for ax, case in zip(axes, cases):
        rows = run_case(case)
        print(f"\n### {case['name']}\n")
        print("| method | setting | CPU [s] | error | invariant |")
        print("|---|---|---|---|---|")
        for method, pts in rows.items():
            for cpu, err, inv, setting in pts:
                print(f"| {method} | {setting} | {cpu:.4f} | {err:.2e} | {inv:.1e} |")
            ax.loglog([p[1] for p in pts], [p[0] for p in pts], "o-", label=method)
        print("\nCPU ratio at equal error (ours / DOP853):")
        for err in (1e-6, 1e-8, 1e-10):
            peer = cpu_at(rows["DOP853"], err)
            cells = ", ".join(f"{m} {cpu_at(rows[m], err) / peer:.2g}" for m in ("rkmk4", "cf4", "cg4a"))
            print(f"- error {err:g}: {cells}")
        ax.set_xlabel("error at T")
        ax.set_ylabel("CPU [s]")
        ax.set_title(case["name"], fontsize=9)
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8)
    fig.tight_layout()
    args.plot.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.plot, dpi=110)
    print(f"\nwrote {args.plot}")


if __name__ == "__main__":
    main()
