"""``liegroup-int buckle SCENE``: critical load factors and buckling modes of a beam scene.

The analysis is :func:`~liegroup_int.problems.beam.buckling.buckling_loads` (linear
buckling from the tangents at the reference and at the first load step, the lowest factor
refined along the load path). Files in the output directory:

* ``buckle.csv``: ``mode, load_factor, load_factor_linear, dominant``;
* ``summary.json``: scene, discretization, load time, factors (refined and linear), the
  critical loads of each mode (every non-zero load key of the scene times its factor), the
  refinement's history, Newton iterations, CPU time;
* ``mode_XX.vtu`` + ``modes.pvd``: the buckling modes on the centreline of the equilibrium
  they were computed about (point data ``displacement``, ``rotation``, largest
  displacement 1), as ``modes`` writes them;
* ``buckle.png``: the first modes.
"""

from __future__ import annotations

import csv
import sys
import time
from pathlib import Path

import numpy as np

from . import __version__
from .io import write_json
from .scenes import Scene, SceneError

#: Scene keys of loads scaled by the load factor (vectors; ``[[point_loads]]`` entries too).
LOAD_KEYS = ("loads.start.force", "loads.start.couple", "loads.end.force", "loads.end.couple",
             "loads.distributed_force", "loads.distributed_couple", "loads.gravity")


def applied_loads(scene: Scene) -> dict[str, np.ndarray]:
    """The scene's non-zero loads by key, ``(3,)`` each (``point_loads[k].force`` for the
    entries of ``[[point_loads]]``)."""
    out = {k: np.asarray(scene[k], float) for k in LOAD_KEYS if np.any(scene[k])}
    for k, entry in enumerate(scene["point_loads"]):
        for q in ("force", "couple"):
            if np.any(entry.get(q, 0.0)):
                out[f"point_loads[{k}].{q}"] = np.asarray(entry[q], float)
    return out


def _shapes(pb, res):
    """Real mode shapes ``(points, displacement, rotation)`` on the equilibrium centreline."""
    from .io.modes import real_shapes
    from .scenes.beam import mode_shape

    shape_of = mode_shape(pb, res.state)
    return real_shapes([shape_of(v) for v in res.vectors], res.load_factors)


def run_buckle(scene: Scene, out_dir: Path, n: int = 3, steps: int = 10, refine: bool = True,
               t: float | None = None) -> dict:
    """Buckling analysis of ``scene`` under its loads at ``t`` (default ``t_end``); writes the
    files of the module docstring to ``out_dir`` and returns the summary. Raises
    :class:`SceneError` (one line) on what the analysis refuses."""
    from .io.modes import dominant, plot_modes, write_mode_shapes
    from .problems.beam.buckling import buckling_loads
    from .static_run import static_problem

    pb = static_problem(scene, "buckle")
    t = scene.t_end if t is None else float(t)
    clock = time.process_time()
    try:
        res = buckling_loads(pb, n, t=t, load_steps=steps, refine=refine)
    except ValueError as exc:
        raise SceneError(f"{scene.source}: {exc}") from None
    cpu = time.process_time() - clock
    shapes = _shapes(pb, res)
    doms = [dominant(d, r, float(np.max(np.ptp(p, axis=0))) or 1.0) for p, d, r in shapes]
    loads = applied_loads(scene)
    rows = [{"mode": k + 1, "load_factor": float(f), "load_factor_linear": float(fl), "dominant": doms[k],
             "critical_loads": {key: (f * v).tolist() for key, v in loads.items()}}
            for k, (f, fl) in enumerate(zip(res.load_factors, res.linear))]
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    with open(out_dir / "buckle.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=["mode", "load_factor", "load_factor_linear", "dominant"])
        w.writeheader()
        for r in rows:
            w.writerow({k: (repr(v) if isinstance(v, float) else v) for k, v in r.items() if k != "critical_loads"})
    write_mode_shapes(out_dir, shapes)
    labels = [f"mode {r['mode']}: lambda = {r['load_factor']:.6g} ({r['dominant']})" for r in rows]
    plot_modes(out_dir / "buckle.png", shapes, labels, title=f"{scene.name}: buckling modes")
    summary = {
        "scene": scene.name, "source": scene.source, "version": __version__, "command": "buckle",
        "discretization": {"formulation": pb.formulation, "degree": scene["space.degree"],
                           "n_ctrl": scene["space.n_ctrl"], "length": pb.space.length},
        "load_time": t, "load_steps": steps, "refine": refine, "refined": res.refined, "accuracy": res.accuracy, "note": res.note,
        "at_load_factor": res.at_factor, "refinement_history": res.history, "equilibria": res.iterations + 1,
        "newton_iterations": res.newton, "singularity": res.singularity,
        "applied_loads": {k: v.tolist() for k, v in loads.items()},
        "modes": rows, "cpu_time_s": cpu,
    }
    write_json(out_dir / "summary.json", summary)
    return summary


def _print(scene: Scene, s: dict, out: Path) -> None:
    floor = f" to {s['accuracy']:.1g}, the tangents' round-off" if s.get("accuracy") else ""
    how = (f"lowest refined along the load path{floor}" if s["refined"] else
           "linear buckling" if not s["refine"] else f"refinement incomplete: {s['note']}")
    print(f"{scene.name}: {len(s['modes'])} lowest critical load factors ({how}; {s['equilibria']} equilibria, "
          f"{s['newton_iterations']} Newton iterations, {s['cpu_time_s']:.3g} s CPU; loads at t = "
          f"{s['load_time']:g})")
    print(f"{'mode':>4}  {'lambda':>14}  {'linear':>14}  dominant  critical loads")
    for r in s["modes"]:
        crit = "; ".join(f"{k} = ({', '.join(f'{x:.6g}' for x in v)})" for k, v in r["critical_loads"].items())
        print(f"{r['mode']:>4}  {r['load_factor']:14.8g}  {r['load_factor_linear']:14.8g}  {r['dominant']:>8}  {crit}")
    if s["refine"] and s["modes"]:
        print(f"modes 2.. from the tangent's secant between the reference and the equilibrium at load factor "
              f"{s['at_load_factor']:.8g}")
    print(f"-> {out} (buckle.csv, summary.json, buckle.png, mode_XX.vtu, modes.pvd)")


def main_buckle(args) -> int:
    """The ``buckle`` command (:mod:`liegroup_int.cli`): exit 0, 2 (bad input, one line) or
    3 (the lowest factor not confirmed along the load path; the files are written)."""
    from .scenes import parse_override
    from .static_run import load_static_scene

    if args.n < 1:
        raise SceneError(f"buckle: --n {args.n}: expected at least one mode")
    if args.steps < 1:
        raise SceneError(f"buckle: --steps {args.steps}: expected a positive number of load steps")
    scene = load_static_scene(args.scene, dict(parse_override(s) for s in args.overrides), "buckle")
    out = args.out if args.out is not None else Path("runs") / f"{scene.name}-buckle"
    try:
        s = run_buckle(scene, out, n=args.n, steps=args.steps, refine=not args.no_refine, t=args.time)
    except OSError as exc:
        print(f"error: cannot write {exc.filename or out}: {exc.strerror or exc}", file=sys.stderr)
        return 2
    _print(scene, s, out)
    if s["refine"] and not s["refined"]:
        print(f"error: {scene.source}: no critical load confirmed along the load path ({s['note']}); the linear "
              "factors are estimates only (docs/cli.md, buckle)", file=sys.stderr)
        return 3
    return 0
