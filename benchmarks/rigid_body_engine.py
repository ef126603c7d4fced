"""Rigid bodies through the compiled engine: cost per stage and the controller's rejections.

    python benchmarks/rigid_body_engine.py [--quick]
    PYTHONPATH=/path/to/older/checkout python benchmarks/rigid_body_engine.py   # the same, older code

Two tables:

* process CPU time per RKMK stage of the heavy top with fixed-step RKMK4 (one body over
  20 s at dt = 1e-4; 1000 bodies in one state over 0.2 s at dt = 1e-3), best of 5 / 3;
* accepted and rejected steps of the adaptive pairs where the rotation guard matters: a body
  spinning at 200 rad/s with ``max_increment_angle = 0.5`` (the setup of
  ``test_adaptive_counts_rejections_and_guards_rotation``) and the heavy top at loose and
  tight tolerances, through the compiled engine and the generic loop.
"""

from __future__ import annotations

import numpy as np

from liegroup_int import integrate
from liegroup_int.bench.table import markdown, parser
from liegroup_int.bench.timing import best_of
from liegroup_int.integrators import integrate_fixed, resolve_method
from liegroup_int.problems import RigidBody

TOP = RigidBody(inertia=(1.0, 1.0, 0.5), mass=1.0, com=(0.0, 0.0, 0.5))
Y_TOP = TOP.state(np.eye(3), np.array([0.3, 0.0, 10.0]))


def stage_cost(y0, T: float, dt: float, repeats: int) -> float:
    """Best CPU microseconds per stage (and body) of fixed-step RKMK4 over ``[0, T]``."""
    pb, tab = TOP.problem(), resolve_method("rkmk4")
    integrate_fixed(pb, tab, (0.0, 10 * dt), y0, dt)  # compile / load
    t = best_of(lambda: integrate_fixed(pb, tab, (0.0, T), y0, dt), repeats)
    n_bodies = 1 if np.ndim(y0) == 1 else np.shape(y0)[0]
    return t.seconds / t.result[2].rhs_evals / n_bodies * 1e6


def rejections(span: float) -> list[list]:
    """Accepted and rejected steps of the adaptive cases, compiled and generic loops."""
    spin = RigidBody(inertia=(1.0, 1.0, 1.0))
    y_spin = spin.state(np.eye(3), np.array([0.0, 0.0, 200.0]))
    cases = [("body at 200 rad/s, max angle 0.5, rkmk45, rtol 1e-3", spin, y_spin, 0.2, "rkmk45", 1e-3, 0.5)]
    for m, tol in (("rkmk45", 1e-4), ("rkmk65", 1e-4), ("rkmk45", 1e-8), ("rkmk65", 1e-10)):
        cases.append((f"heavy top, {m}, tol {tol:g}", TOP, Y_TOP, span, m, tol, 1.0))
    rows = []
    for label, body, y0, T, method, tol, max_angle in cases:
        for loop, monitor in (("compiled", None), ("generic", lambda *a: None)):
            sol = integrate(body.problem(), y0, (0.0, T), method=method, rtol=tol, atol=tol, monitor=monitor,
                            max_increment_angle=max_angle)
            rows.append([label, loop, sol.stats.steps, sol.stats.rejected])
    return rows


def main(argv=None) -> None:
    ap = parser(__doc__, quick_help="spans 100x shorter, one repeat")
    args = ap.parse_args(argv)
    k, repeats = (0.01, 1) if args.quick else (1.0, None)
    one = stage_cost(Y_TOP, 20.0 * k, 1e-4, repeats or 5)
    many = stage_cost(np.stack([Y_TOP] * 1000), 0.2 * k, 1e-3, repeats or 3)
    print(markdown(["fixed-step RKMK4, heavy top", "us per stage (and body)"],
                   [["one body", f"{one:.3f}"], ["1000 bodies in one state", f"{many:.3f}"]]))
    print()
    print(markdown(["adaptive case", "loop", "accepted", "rejected"], rejections(20.0 * k)))


if __name__ == "__main__":
    main()
