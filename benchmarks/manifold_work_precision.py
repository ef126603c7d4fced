"""Work-precision on homogeneous spaces: RKMK4, the commutator-free CF4 and the
Crouch-Grossman CG4a against scipy's DOP853 on the embedding.

    python benchmarks/manifold_work_precision.py [--plot docs/img/manifold_work_precision.png] [--quick]

Four problems, each against a tight reference at the final time T:

1. **Toda lattice** on ``Isospectral(5)`` (``examples/toda_lattice.py``), T = 20: error
   ``max |L(T) - L_ref(T)|`` and the eigenvalue drift. DOP853 integrates the flattened
   matrix ``L' = [B(L), L]`` (no projection: none keeps the spectrum).
2. **Landau-Lifshitz-Gilbert spin** on ``Sphere()`` (``tests/manifolds/test_manifolds_flows.py``),
   T = 5: error ``max |m(T) - m_ref(T)|`` and ``| |m| - 1 |``. DOP853 integrates
   ``m' = w(m) x m`` in R^3 and its result is projected onto the sphere (``m / |m|``).

3. **Heavy top** (the non-symmetric top of ``benchmarks/rigid_body_work_precision.py``, the
   built-in ``RigidBody`` plugin), T = 5: error on the flat state ``(R, W)``, invariant the
   energy drift. RKMK4 runs in the compiled engine (the plugin's kernels); CF4 and CG4a in
   the generic loop. DOP853 integrates ``R' = R hat(W)`` and ``W'`` on the flattened
   ``(R, W)``; ``R`` is projected onto SO(3) (polar factor) at the end.
4. **Double 3D pendulum** on (TS^2)^2 (:class:`liegroup_int.problems.NPendulum`), T = 2: error on the
   flat state, invariant the energy drift. DOP853 integrates ``q' = w x q``, ``w' = ...``
   in R^12 with the same accelerations, projected onto (TS^2)^2 at the end.

Ours: fixed steps (the generic NumPy loop unless noted). ``rkmk4 compiled`` (Toda, LLG):
the same RKMK4 with the field written as a ``numba.njit`` function, which runs in the
compiled engine (SO(n) and SO(3) kernels; compiled once before timing). Peer:
DOP853 over ``rtol = atol`` from 1e-4 to 1e-12. Reported: CPU time per run (best of 3), and
the CPU ratio at equal error, interpolated log-log along each method's curve.
``--quick``: the LLG spin only, two steps, three tolerances, one timed run each, the
reference (RKMK6) at half the smaller step instead of an eighth, no compiled field
(compiling the engine for a user's ``f`` takes seconds in every process).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from numba import njit
from scipy.integrate import solve_ivp

from liegroup_int import Isospectral, Sphere, integrate
from liegroup_int.bench.table import figure_dir, markdown, parser
from liegroup_int.bench.timing import best_of
from liegroup_int.problems import NPendulum

#: ``ref_refine``: the reference is RKMK6 at the smallest step divided by this
QUICK = dict(cases=["llg"], steps=2, tols=(1e-4, 1e-7, 1e-10), repeats=1, compiled=False, ref_refine=2)
FULL = dict(steps=None, tols=(1e-4, 1e-6, 1e-8, 1e-10, 1e-12), repeats=3, compiled=True, ref_refine=8)


def _cpu(fn, repeat=3):
    t = best_of(fn, repeat)
    return t.result, t.seconds


@njit
def _toda_njit(t, L):
    """The Toda generator vee(triu(L) - tril(L)) in SOn's coordinates: -L[i, j], i < j."""
    n = L.shape[0]
    out = np.empty(n * (n - 1) // 2)
    k = 0
    for i in range(n):
        for j in range(i + 1, n):
            out[k] = -L[i, j]
            k += 1
    return out


@njit
def _llg_njit(t, m):
    H = np.array([0.2 + 0.5 * m[0], 0.0, 1.0])
    c = np.array([m[1] * H[2] - m[2] * H[1], m[2] * H[0] - m[0] * H[2], m[0] * H[1] - m[1] * H[0]])
    return (H + 0.1 * c) / 1.01


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
    return dict(name="Toda lattice, Isospectral(5), T = 20", space=M, y0=L0, field=field, T=20.0, field_njit=_toda_njit,
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

    return dict(name="LLG spin, Sphere(), T = 5", space=S, y0=m0, field=field, T=5.0, peer=peer, field_njit=_llg_njit,
                invariant=lambda m: abs(float(np.linalg.norm(m)) - 1.0), steps=(0.2, 0.1, 0.05, 0.025, 0.0125))


def heavy_top_case():
    from liegroup_int import SO3
    from liegroup_int.groups.so3 import hat
    from liegroup_int.problems import RigidBody

    top = RigidBody(inertia=(1.0, 0.8, 0.5), mass=1.0, com=(0.0, 0.0, 0.5))
    y0 = top.state(SO3.exp(np.array([0.5, 0.0, 0.0])), np.array([0.4, -0.2, 6.0]))

    def rhs(t, z):
        R, W = z[:9].reshape(3, 3), z[9:]
        dW = top.vector_field(t, top.state(R, W))[3:]  # (R W, dW/dt): the body's own equations
        return np.concatenate([(R @ hat(W)).ravel(), dW])

    def peer(tol):
        z = solve_ivp(rhs, (0, 5.0), np.concatenate([top.split(y0)[0].ravel(), top.split(y0)[1]]),
                      method="DOP853", rtol=tol, atol=tol).y[:, -1]
        u, _, vt = np.linalg.svd(z[:9].reshape(3, 3))
        return top.state(u @ vt, z[9:])

    E0 = float(top.energy(y0))
    return dict(name="heavy top, SO(3) x R^3, T = 5", problem=top.problem(), space=None, y0=y0, field=None, T=5.0,
                peer=peer, invariant=lambda y: abs(float(top.energy(y)) - E0), steps=(0.02, 0.01, 0.005, 0.0025))


def pendulum_case():
    pend = NPendulum(2)
    space, gen, y0, energy = pend.space, pend.generator, pend.initial_state(), pend.energy

    def rhs(t, y):
        xi = gen(t, y).reshape(2, 6)  # (rho_j, theta_j) = (q_j x w'_j, w_j): w'_j = rho_j x q_j
        Y = y.reshape(2, 6)
        return np.concatenate([np.concatenate([np.cross(Y[j, 3:], Y[j, :3]), np.cross(xi[j, :3], Y[j, :3])])
                               for j in range(2)])

    def peer(tol):
        return space.project(solve_ivp(rhs, (0, 2.0), y0, method="DOP853", rtol=tol, atol=tol).y[:, -1])

    E0 = energy(y0)
    return dict(name="double 3D pendulum, (TS^2)^2, T = 2", space=space, y0=y0, field=gen, T=2.0, peer=peer,
                invariant=lambda y: abs(energy(y) - E0), steps=(0.02, 0.01, 0.005, 0.0025))


def _ours(case, method, dt):
    if method == "rkmk4 compiled":
        return integrate(case["field_njit"], case["y0"], (0.0, case["T"]), space=case["space"], method="rkmk4",
                         dt=dt).y_final
    if case.get("problem") is not None:
        return integrate(case["problem"], case["y0"], (0.0, case["T"]), method=method, dt=dt).y_final
    return integrate(case["field"], case["y0"], (0.0, case["T"]), space=case["space"], method=method, dt=dt).y_final


def run_case(case, cfg):
    steps = case["steps"][:cfg["steps"]]
    ref = _ours(case, "rkmk6", steps[-1] / cfg["ref_refine"])
    rows = {}
    compiled = cfg["compiled"] and "field_njit" in case
    methods = ("rkmk4", "cf4", "cg4a") + (("rkmk4 compiled",) if compiled else ())
    for method in methods:
        pts = []
        for dt in steps:
            y, cpu = _cpu(lambda: _ours(case, method, dt), cfg["repeats"])
            pts.append((cpu, float(np.max(np.abs(y - ref))), case["invariant"](y), f"dt={dt:g}"))
        rows[method] = pts
    pts = []
    for tol in cfg["tols"]:
        y, cpu = _cpu(lambda: case["peer"](tol), cfg["repeats"])
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


def report(case, rows) -> None:
    print(f"\n### {case['name']}\n")
    print(markdown(["method", "setting", "CPU [s]", "error", "invariant"],
                   [[m, setting, f"{cpu:.4f}", f"{err:.2e}", f"{inv:.1e}"]
                    for m, pts in rows.items() for cpu, err, inv, setting in pts]))
    print("\nCPU ratio at equal error (ours / DOP853; - outside a curve):")
    for err in (1e-6, 1e-8, 1e-10):
        peer = cpu_at(rows["DOP853"], err)
        ratios = [cpu_at(rows[m], err) / peer for m in rows if m != "DOP853"]
        cells = ", ".join(f"{m} {r:.2g}" if np.isfinite(r) else f"{m} -" for m, r in zip(rows, ratios))
        print(f"- error {err:g}: {cells}")


def main(argv=None):
    ap = parser(__doc__)
    ap.add_argument("--plot", type=Path, default=None, help="figure (default: OUT/manifold_work_precision.png)")
    ap.add_argument("--cases", nargs="+", default=["toda", "llg", "heavy_top", "pendulum"],
                    choices=("toda", "llg", "heavy_top", "pendulum"))
    args = ap.parse_args(argv)
    cfg = {**FULL, "cases": args.cases} if not args.quick else QUICK
    plot_path = args.plot or figure_dir(args, Path("docs/img")) / "manifold_work_precision.png"
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    make = {"toda": toda_case, "llg": llg_case, "heavy_top": heavy_top_case, "pendulum": pendulum_case}
    fig, axes = plt.subplots(2, 2, figsize=(11, 8))
    for ax, case in zip(axes.ravel(), [make[c]() for c in cfg["cases"]]):
        rows = run_case(case, cfg)
        report(case, rows)
        for method, pts in rows.items():
            ax.loglog([p[1] for p in pts], [p[0] for p in pts], "o-", label=method)
        ax.set_xlabel("error at T")
        ax.set_ylabel("CPU [s]")
        ax.set_title(case["name"], fontsize=9)
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8)
    fig.tight_layout()
    plot_path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(plot_path, dpi=110)
    print(f"\nwrote {plot_path}")


if __name__ == "__main__":
    main()
