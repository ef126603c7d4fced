"""Cost per step and stable step of the beam formulations, side by side.

    python benchmarks/formulation_cost.py [--scenes pendulum cantilever] [--n-ctrl 21 31 61]

For each scene, p = 4 and each ``n_ctrl``: the spectral radius ``|lambda|max`` at the initial
state (power iteration), the RKMK4 stable step ``2.83 / |lambda|max``, the CPU time of one
RKMK4 step in the compiled engine (numba backend, undamped, after a warm-up; best of
three runs of ``steps`` steps at ``|lambda| h = 1``), and from these the CPU per simulated
second at ``|lambda| h = 2.26`` (what ``dt = "auto"`` takes). Ratios are against primal
collocation, measured in the same run.
"""

from __future__ import annotations

from liegroup_int.bench.table import markdown, parser
from liegroup_int.bench.timing import best_of
from liegroup_int.integrators import integrate_fixed, resolve_method, spectral_radius
from liegroup_int.scenes import load_scene
from liegroup_int.scenes.beam import problem

FORMULATIONS = ("primal", "galerkin")


def measure(scene: str, n_ctrl: int, formulation: str, steps: int) -> dict:
    pb = problem(load_scene(scene, {"space.formulation": formulation, "space.n_ctrl": n_ctrl,
                                    "material.kelvin_voigt": 0.0, "integrator.backend": "numba"}))
    y0 = pb.initial_state()
    lam = spectral_radius(pb, 0.0, y0)
    tab = resolve_method("rkmk4")
    dt = 1.0 / lam
    integrate_fixed(pb, tab, (0.0, 3 * dt), y0, dt)  # compile, warm caches
    step = best_of(lambda: integrate_fixed(pb, tab, (0.0, steps * dt), y0, dt), 3).seconds / steps
    return {"lam": lam, "dt_stable": 2.83 / lam, "step_us": 1e6 * step, "cpu_per_s": step * lam / 2.26}


def main(argv=None) -> None:
    ap = parser(__doc__)
    ap.add_argument("--scenes", nargs="+", default=["pendulum", "cantilever"])
    ap.add_argument("--n-ctrl", type=int, nargs="+", default=[21, 31, 61])
    ap.add_argument("--steps", type=int, default=2000)
    args = ap.parse_args(argv)
    if args.quick:
        args.n_ctrl, args.steps = [11], 20
    rows = []
    for scene in args.scenes:
        for n in args.n_ctrl:
            res = {f: measure(scene, n, f, args.steps) for f in FORMULATIONS}
            base = res["primal"]["cpu_per_s"]
            rows += [[scene, n, f, f"{r['lam']:.4g}", f"{r['dt_stable']:.3g}", f"{r['step_us']:.1f}",
                      f"{r['cpu_per_s']:.3g}", f"{r['cpu_per_s'] / base:.2f}"] for f, r in res.items()]
    print(markdown(["scene", "n_ctrl", "formulation", "lambda_max [1/s]", "stable RKMK4 dt [s]", "CPU per step [us]",
                    "CPU per simulated s [s]", "ratio to primal"], rows))


if __name__ == "__main__":
    main()
