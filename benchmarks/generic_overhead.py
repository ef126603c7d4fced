"""Per-stage cost of the generic (Python) path for a user's vector field.

    python benchmarks/generic_overhead.py

Two measurements on SO(3) x R^3 (the README's free rigid body), process CPU time:

* the driver and group overhead per stage, with an ``f`` that returns a constant (so what
  is left is the RKMK machinery: stage combinations, the action ``exp(u) y``, ``dexpinv``,
  checks); fixed-step RKMK4 and adaptive RKMK45;
* the README example itself (RKMK4, dt = 1e-3, 20 s) and its ``f`` alone;
* the same body with ``f`` compiled by ``numba.njit``: the whole step loop runs compiled
  (the compiled engine, ``GroupProblem.compiled_kernels``); compile time reported apart.

Single points of the built-in groups go through the groups' compiled kernels
(``GroupProblem(..., compiled=True)``, the default); ``--numpy`` switches them off for
comparison. ``--quick``: short spans, and no ``numba.njit`` ``f``.
"""

from __future__ import annotations

import numpy as np

from liegroup_int import Product, Rn, SO3, integrate
from liegroup_int.bench.table import markdown, parser
from liegroup_int.bench.timing import cpu
from liegroup_int.integrators import GroupProblem, integrate_adaptive, resolve_method

SPACE = Product(SO3, Rn(3))
Y0 = SPACE.join(np.eye(3), np.array([0.01, 5.0, 0.01]))
INERTIA = np.array([1.0, 2.0, 3.0])


def readme_f(t, y):
    R, W = SPACE.split(y)
    return np.concatenate([R @ W, np.cross(INERTIA * W, W) / INERTIA])


def overhead(numpy_only: bool, span: float) -> list[list]:
    """Rows: cost per stage of the driver with a constant f, fixed-step and adaptive."""
    xi = np.array([0.1, 0.2, 0.3, 0.0, 0.0, 0.0])
    const = GroupProblem(SPACE, lambda t, y: xi, compiled=not numpy_only)
    integrate(const, Y0, (0.0, 0.01), method="rkmk4", dt=1e-3)  # warm-up (compiled kernels)
    sol, c = cpu(lambda: integrate(const, Y0, (0.0, span), method="rkmk4", dt=1e-3))
    rows = [["overhead per stage, constant f, rkmk4", f"{c / sol.stats.rhs_evals * 1e6:.1f} us",
             f"{sol.stats.rhs_evals} evaluations"]]
    # adaptive: a constant field is integrated exactly, so the steps are capped (h_max) to
    # time many of them; the error norm and the controller are part of the overhead
    (_, _, st), c = cpu(lambda: integrate_adaptive(const, resolve_method("rkmk45"), (0.0, span), Y0, rtol=1e-9,
                                                   atol=1e-12, h_max=1e-3))
    rows.append(["overhead per stage, constant f, rkmk45 (h_max = 1e-3)", f"{c / st.rhs_evals * 1e6:.1f} us",
                 f"{st.rhs_evals} evaluations, {st.steps} steps: {st.rhs_evals / st.steps:.2f} per step with FSAL"])
    return rows


def compiled_f(sol, cpu_py: float, span: float) -> list:
    """Row: the same body with f compiled by numba.njit (the whole loop compiled)."""
    from numba import njit

    @njit
    def f_compiled(t, y):
        out = np.empty(6)
        for i in range(3):
            out[i] = y[3 * i] * y[9] + y[3 * i + 1] * y[10] + y[3 * i + 2] * y[11]
        a0, a1, a2 = INERTIA[0] * y[9], INERTIA[1] * y[10], INERTIA[2] * y[11]
        out[3] = (a1 * y[11] - a2 * y[10]) / INERTIA[0]
        out[4] = (a2 * y[9] - a0 * y[11]) / INERTIA[1]
        out[5] = (a0 * y[10] - a1 * y[9]) / INERTIA[2]
        return out

    _, compile_s = cpu(lambda: integrate(f_compiled, Y0, (0.0, 1e-3), space=SPACE, method="rkmk4", dt=1e-3))
    solc, c = cpu(lambda: integrate(f_compiled, Y0, (0.0, span), space=SPACE, method="rkmk4", dt=1e-3))
    return ["same body, numba.njit f", f"{c:.3f} s CPU ({c / solc.stats.rhs_evals * 1e6:.2f} us per stage)",
            f"{cpu_py / c:.0f}x less than the Python f; compilation {compile_s:.1f} s once; final states differ "
            f"by {np.abs(solc.y_final - sol.y_final).max():.1e}"]


def main(argv=None):
    ap = parser(__doc__)
    ap.add_argument("--numpy", action="store_true", help="switch the compiled group kernels off")
    args = ap.parse_args(argv)
    span_c, span_r = (0.05, 0.2) if args.quick else (2.0, 20.0)
    rows = overhead(args.numpy, span_c)
    readme = GroupProblem(SPACE, readme_f, compiled=not args.numpy)
    sol, c = cpu(lambda: integrate(readme, Y0, (0.0, span_r), method="rkmk4", dt=1e-3))
    _, per_f = cpu(lambda: [readme_f(0.0, Y0) for _ in range(20000)])
    rows.append([f"README example (rkmk4, dt = 1e-3, {span_r:g} s)", f"{c:.2f} s CPU",
                 f"{sol.stats.steps} steps; its f alone {per_f / 20000 * 1e6:.1f} us per call"])
    if not (args.numpy or args.quick):
        rows.append(compiled_f(sol, c, span_r))
    print(markdown(["measurement", "CPU", "note"], rows))


if __name__ == "__main__":
    main()
