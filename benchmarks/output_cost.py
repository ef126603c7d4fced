"""What an output time costs in the compiled engine, beside the steps.

    python benchmarks/output_cost.py [--quick]

The compiled loops run from one output time to the next in one call; each call unboxes the
kernels' data (the beam's stage rate and action, a user's field and events, as first-class
function values), copies the state in and out and resumes. Per case: the process CPU time of
``steps`` fixed RKMK4 steps with only the end as output, and with an output at every step
(``t_eval`` on the step grid), best of three; the difference per output is the cost of a
call. Cases: the Galerkin pendulum (p = 4, n_ctrl 21, ``integrate(problem, ...)``) and a
user's ``numba.njit`` field on SO(3).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from liegroup_int import SO3, integrate
from liegroup_int.bench.table import markdown, parser
from liegroup_int.bench.timing import best_of
from liegroup_int.scenes import load_scene
from liegroup_int.scenes.beam import problem


@njit(cache=True)
def spin(t, y):
    return np.array([0.1, 0.0, 1.0 + t])


def cases(steps: int) -> list[tuple]:
    """``(name, f, y0, space, dt)`` per case."""
    pb = problem(load_scene("pendulum", {"space.n_ctrl": 21, "integrator.backend": "numba"}))
    return [("Galerkin pendulum, p4 n21", pb, pb.initial_state(), None, 1e-5),
            ("user njit field on SO(3)", spin, np.eye(3), SO3, 1e-3)]


def per_call(f, y0, space, dt: float, steps: int) -> tuple[float, float]:
    """Seconds per step with the end as the only output, and per extra output time."""
    T = steps * dt
    grid = np.linspace(0.0, T, steps + 1)

    def run(t_eval):
        return integrate(f, y0, (0.0, T), space=space, method="rkmk4", dt=dt, t_eval=t_eval)

    end = best_of(lambda: run(np.array([T]))).seconds
    every = best_of(lambda: run(grid)).seconds
    return end / steps, (every - end) / steps


def main(argv=None) -> None:
    args = parser(__doc__, quick_help="200 steps instead of 2000").parse_args(argv)
    steps = 200 if args.quick else 2000
    rows = []
    for name, f, y0, space, dt in cases(steps):
        step, output = per_call(f, y0, space, dt, steps)
        rows.append([name, steps, f"{1e6 * step:.2f}", f"{1e6 * output:.2f}", f"{output / step:.2f}"])
    print(markdown(["case", "steps", "us per step", "us per output time", "output / step"], rows))


if __name__ == "__main__":
    main()
