"""Per-stage cost of the generic (Python) path for a user's vector field.

    python benchmarks/generic_overhead.py

Two measurements on SO(3) x R^3 (the README's free rigid body), process CPU time:

* the driver and group overhead per stage, with an ``f`` that returns a constant (so what
  is left is the RKMK machinery: stage combinations, the action ``exp(u) y``, ``dexpinv``,
  checks); fixed-step RKMK4 and adaptive RKMK45;
* the README example itself (RKMK4, dt = 1e-3, 20 s) and its ``f`` alone;
* the same body with ``f`` compiled by ``numba.njit``: the whole step loop runs compiled
  (the compiled engine, ``GroupProblem.compiled_kernels``); compile time reported apart.

Single points of the built-in groups go through the compiled kernels of
``liegroup_int/groups/kernels_numba.py``; ``--numpy`` switches them off for comparison.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from liegroup_int import Product, Rn, SO3, integrate
from liegroup_int.integrators import GroupProblem, integrate_adaptive, resolve_method


def problem(f, numpy_only: bool):
    pb = GroupProblem(Product(SO3, Rn(3)), f)
    if numpy_only:
        pb._compiled = None
    return pb


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--numpy", action="store_true", help="switch the compiled group kernels off")
    args = ap.parse_args(argv)
    space = Product(SO3, Rn(3))
    y0 = space.join(np.eye(3), np.array([0.01, 5.0, 0.01]))
    xi = np.array([0.1, 0.2, 0.3, 0.0, 0.0, 0.0])
    const = problem(lambda t, y: xi, args.numpy)
    integrate(const, y0, (0.0, 0.01), method="rkmk4", dt=1e-3)  # warm-up (compiled kernels)
    t0 = time.process_time()
    sol = integrate(const, y0, (0.0, 2.0), method="rkmk4", dt=1e-3)
    cpu = time.process_time() - t0
    print(f"overhead per stage, constant f, rkmk4: {cpu / sol.stats.rhs_evals * 1e6:.1f} us "
          f"({sol.stats.rhs_evals} evaluations)")
    # adaptive: a constant field is integrated exactly, so the steps are capped (h_max) to
    # time many of them; the error norm and the controller are part of the overhead
    tab = resolve_method("rkmk45")
    t0 = time.process_time()
    _, _, st = integrate_adaptive(const, tab, (0.0, 2.0), y0, rtol=1e-9, atol=1e-12, h_max=1e-3)
    cpu = time.process_time() - t0
    print(f"overhead per stage, constant f, rkmk45 (h_max = 1e-3): {cpu / st.rhs_evals * 1e6:.1f} us "
          f"({st.rhs_evals} evaluations, {st.steps} steps: {st.rhs_evals / st.steps:.2f} per step with FSAL)")
    inertia = np.array([1.0, 2.0, 3.0])

    def f(t, y):
        R, W = space.split(y)
        return np.concatenate([R @ W, np.cross(inertia * W, W) / inertia])

    readme = problem(f, args.numpy)
    t0 = time.process_time()
    sol = integrate(readme, y0, (0.0, 20.0), method="rkmk4", dt=1e-3)
    cpu = time.process_time() - t0
    t1 = time.process_time()
    for _ in range(20000):
        f(0.0, y0)
    per_f = (time.process_time() - t1) / 20000
    print(f"README example (rkmk4, dt = 1e-3, 20 s): {cpu:.2f} s CPU, {sol.stats.steps} steps; its f alone "
          f"{per_f * 1e6:.1f} us per call")
    if args.numpy:
        return
    from numba import njit

    @njit
    def f_compiled(t, y):
        out = np.empty(6)
        for i in range(3):
            out[i] = y[3 * i] * y[9] + y[3 * i + 1] * y[10] + y[3 * i + 2] * y[11]
        a0, a1, a2 = inertia[0] * y[9], inertia[1] * y[10], inertia[2] * y[11]
        out[3] = (a1 * y[11] - a2 * y[10]) / inertia[0]
        out[4] = (a2 * y[9] - a0 * y[11]) / inertia[1]
        out[5] = (a0 * y[10] - a1 * y[9]) / inertia[2]
        return out

    t0 = time.process_time()
    integrate(f_compiled, y0, (0.0, 1e-3), space=space, method="rkmk4", dt=1e-3)
    compile_s = time.process_time() - t0
    t0 = time.process_time()
    solc = integrate(f_compiled, y0, (0.0, 20.0), space=space, method="rkmk4", dt=1e-3)
    cpu_c = time.process_time() - t0
    print(f"same body, numba.njit f: {cpu_c:.3f} s CPU ({cpu_c / solc.stats.rhs_evals * 1e6:.2f} us per stage, "
          f"{cpu / cpu_c:.0f}x less than the Python f; compilation {compile_s:.1f} s once); final states differ "
          f"by {np.abs(solc.y_final - sol.y_final).max():.1e}")


if __name__ == "__main__":
    main()
