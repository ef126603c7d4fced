"""CPU of a static solve: the 45-degree bend cantilever by Newton-Raphson with load steps.

    python benchmarks/static_bend45.py [--n-ctrl 11 21 41] [--steps 5]

For each ``n_ctrl`` (p = 4, Galerkin, NumPy backend): the tip, its distance to the
finest mesh's tip, the Newton iterations and residual evaluations in all, and the CPU
time of :func:`~liegroup_int.solve_static` (best of three). A dynamic run that settles on
the same equilibrium (the load ramped over about 12 periods of the first mode, RKMK4 at
n_ctrl = 11) takes 733,792 steps and about 25 s of CPU, and its tip still oscillates by
0.1 about the equilibrium.
"""

from __future__ import annotations

import numpy as np

from liegroup_int.bench.table import markdown, parser
from liegroup_int.bench.timing import best_of
from liegroup_int.problems.beam.statics import solve_static
from liegroup_int.scenes import load_scene
from liegroup_int.scenes.beam import problem

#: Simo & Vu-Quoc (1986), 8 linear elements: the tip under the full load (600)
SIMO_VU_QUOC = np.array([47.23, 15.79, 53.37])


def measure(n_ctrl: int, steps: int, repeats: int) -> dict:
    pb = problem(load_scene("bend45", {"integrator.backend": "numpy", "space.n_ctrl": n_ctrl}))
    timing = best_of(lambda: solve_static(pb, load_steps=steps), repeats)
    res = timing.result
    return {"tip": pb.tip(res.state), "iterations": sum(res.iterations), "evaluations": res.evaluations,
            "cpu": timing.seconds}


def main(argv=None) -> None:
    ap = parser(__doc__)
    ap.add_argument("--n-ctrl", type=int, nargs="+", default=[11, 21, 41])
    ap.add_argument("--steps", type=int, default=5)
    args = ap.parse_args(argv)
    repeats = 3
    if args.quick:
        args.n_ctrl, args.steps, repeats = [5, 7], 2, 1
    res = {n: measure(n, args.steps, repeats) for n in args.n_ctrl}
    finest = res[max(res)]["tip"]
    rows = [[n, ", ".join(f"{x:.4f}" for x in r["tip"]), f"{np.max(np.abs(r['tip'] - finest)):.2g}",
             f"{np.max(np.abs(r['tip'] - SIMO_VU_QUOC)):.3f}", r["iterations"], r["evaluations"], f"{r['cpu']:.3f}"]
            for n, r in res.items()]
    print(markdown(["n_ctrl", "tip (x, y, z)", "vs finest", "vs Simo & Vu-Quoc", "Newton iterations",
                    "residual evaluations", "CPU [s]"], rows))


if __name__ == "__main__":
    main()
