"""``liegroup-int static SCENE``: static equilibrium of a beam scene, written to a directory.

Files in the output directory:

* ``summary.json``: scene, discretization, load time, load factors, Newton iterations and
  relative residual norms per step, ``converged``, the tip position and, when a step did
  not converge, the one-line ``error`` (the rest describes the last converged step);
* ``history.csv``: the load path, a row per converged load step (``step, load_factor,
  iterations, residual, tip_x, tip_y, tip_z``; with ``--arc-length``: the path's points,
  ``step, load_factor, iterations, tip_x, tip_y, tip_z``);
* ``shape.csv``: the centreline of the last converged state at 101 parameters
  (``u, x, y, z``);
* ``static.vtu``: that state at the frame points with its section frames (ParaView);
* ``state.npz``: its state arrays (``c, v, w, R, K``).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from . import __version__
from .io import write_json
from .io.paraview import write_beam_vtu
from .problems.beam.statics import StaticDivergence, solve_static
from .scenes import Scene, SceneError


class StaticFailed(RuntimeError):
    """A load step did not converge; the files describe the last converged one."""


def check_scene(scene: Scene, command: str = "static") -> None:
    """One-line refusal of a scene the static solver cannot take (not a beam, not the
    Galerkin formulation), naming ``command``."""
    if scene.kind != "beam":
        raise SceneError(f"{scene.source}: {command} needs a beam scene (problem = \"beam\"), not {scene.kind!r}")
    if scene["space.formulation"] != "galerkin":
        raise SceneError(f'{scene.source}: {command} needs space.formulation = "galerkin" '
                         f'(got "{scene["space.formulation"]}")')


def load_static_scene(source, overrides: dict, command: str = "static") -> Scene:
    """The scene ``source`` with ``overrides`` and the NumPy backend (the static solver's
    Jacobians run on it), after :func:`check_scene` on the scene as given (a scene that is
    not a beam has no backend key to set)."""
    from .scenes import load_scene

    check_scene(load_scene(source, overrides), command)
    return load_scene(source, {**overrides, "integrator.backend": "numpy"})


def static_problem(scene: Scene, command: str = "static"):
    """The scene's beam problem, after :func:`check_scene` (the ``static`` and ``buckle``
    commands load the scene with the NumPy backend: the solver evaluates the forces in
    NumPy and a compiled action would only add a compilation)."""
    from .scenes.beam import problem

    check_scene(scene, command)
    return problem(scene)


class _Printer:
    """Progress: one line per load step with the relative residual of each iterate."""

    def __init__(self, steps: int, enabled: bool):
        self.steps, self.enabled, self.open = steps, enabled, False

    def __call__(self, step, lam, it, r):
        if not self.enabled:
            return
        if it == 0:
            self.close()
            print(f"step {step}/{self.steps}  lambda = {lam:.4g}  residuals:", end="", flush=True)
            self.open = True
        print(f" {r:.2e}", end="", flush=True)

    def close(self):
        if self.open:
            print(flush=True)
            self.open = False


def run_static(scene: Scene, out_dir: Path, steps: int = 10, tol: float = 1e-8, max_iter: int = 30,
               t: float | None = None, quiet: bool = False) -> dict:
    """Solve the static equilibrium of ``scene`` at load time ``t`` (default ``t_end``) and
    write the files of the module docstring to ``out_dir``; returns the summary.

    Raises :class:`SceneError` on bad input (one line) and :class:`StaticFailed` when a
    load step does not converge (after writing the last converged state)."""
    pb = static_problem(scene)
    t = scene.t_end if t is None else float(t)
    printer = _Printer(steps, not quiet)
    clock = time.process_time()
    error = None
    try:
        res = solve_static(pb, load_steps=steps, tol=tol, max_iter=max_iter, t=t, progress=printer)
    except ValueError as exc:
        printer.close()
        raise SceneError(f"{scene.source}: {exc}") from None
    except StaticDivergence as exc:
        res, error = exc.result, str(exc)
    printer.close()
    summary = _summary(scene, pb, res, t, steps, tol, max_iter, time.process_time() - clock, error)
    _write(out_dir, pb, res.state, summary)
    _write_path(out_dir, res)
    if error is not None:
        raise StaticFailed(f"{scene.source}: {error}; the last converged state is in {out_dir}")
    return summary


def _summary(scene: Scene, pb, res, t, steps, tol, max_iter, cpu_s, error) -> dict:
    return {
        "scene": scene.name, "source": scene.source, "version": __version__, "command": "static",
        "discretization": {"formulation": pb.formulation, "degree": scene["space.degree"],
                           "n_ctrl": scene["space.n_ctrl"], "length": pb.space.length},
        "load_time": t, "load_steps": steps, "tol": tol, "max_iter": max_iter,
        "converged": res.converged, "load_factors": res.load_factors, "iterations": res.iterations,
        "residuals": res.residuals, "load_norm": res.load_norm, "tangents": res.tangents,
        "residual_evaluations": res.evaluations, "cpu_time_s": cpu_s,
        "tip": pb.tip(res.state).tolist(), **_reactions(pb, res.state, t),
        **({"error": error} if error is not None else {}),
    }


def _reactions(pb, y, t: float) -> dict:
    """The supports' and joints' reactions at the state (spatial force and couple)."""
    out = {"reactions": {name: {"force": f.tolist(), "couple": c.tolist()} for name, (f, c) in pb.reactions(y, t).items()}}
    if getattr(pb, "joints", ()):
        out["joint_reactions"] = [{"force": f.tolist(), "couple": c.tolist()} for f, c in pb.joint_reactions(y, t)]
    return out


def _write_path(out_dir: Path, res) -> None:
    """``history.csv``: the converged load steps."""
    rows = [[k + 1, lam, it, r[-1], *tip] for k, (lam, it, r, tip) in
            enumerate(zip(res.load_factors, res.iterations, res.residuals, res.tips))]
    np.savetxt(Path(out_dir) / "history.csv", np.array(rows, dtype=float).reshape(-1, 7), delimiter=",",
               header="step,load_factor,iterations,residual,tip_x,tip_y,tip_z", comments="", fmt="%.17g")


def _write(out_dir: Path, pb, y, summary: dict) -> None:
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    u = np.linspace(0.0, 1.0, 101)
    line = pb.centreline(y, u)
    np.savetxt(out_dir / "shape.csv", np.column_stack([u, line]), delimiter=",", header="u,x,y,z", comments="")
    _, N0, s = pb.frame_points
    write_beam_vtu(out_dir / "static.vtu", np.asarray(N0) @ y.c, y.R[:len(N0)], {"s": np.asarray(s, float)})
    np.savez(out_dir / "state.npz", **y.arrays())
    write_json(out_dir / "summary.json", summary)


def run_arc_length(scene: Scene, out_dir: Path, ds: float, steps: int, tol: float, max_iter: int,
                   t: float | None = None) -> dict:
    """``static --arc-length DS``: the equilibrium path by arc-length continuation
    (:func:`~liegroup_int.problems.beam.arclength.arc_length_path`) until the load factor
    passes 1 or ``steps`` steps; ``history.csv`` the path, the last point's state in the
    other files; returns the summary (``limit_load_factor`` when the path passed a limit)."""
    from .problems.beam.arclength import arc_length_path

    pb = static_problem(scene)
    t = scene.t_end if t is None else float(t)
    clock = time.process_time()
    try:
        path = arc_length_path(pb, steps=steps, ds=ds, t=t, tol=tol, max_iter=max_iter, lam_max=1.0)
    except ValueError as exc:
        raise SceneError(f"{scene.source}: {exc}") from None
    y = path.states[-1]
    summary = {
        "scene": scene.name, "source": scene.source, "version": __version__, "command": "static --arc-length",
        "discretization": {"formulation": pb.formulation, "degree": scene["space.degree"],
                           "n_ctrl": scene["space.n_ctrl"], "length": pb.space.length},
        "load_time": t, "arc_length_step": ds, "steps": len(path.iterations), "tol": tol,
        "converged": path.converged, "load_factors": path.load_factors, "iterations": path.iterations,
        "limit_load_factor": path.limit, "cpu_time_s": time.process_time() - clock,
        "tip": pb.tip(y).tolist(), **_reactions(pb, y, t)}
    _write(out_dir, pb, y, summary)
    rows = [[k, lam, it, *tip] for k, (lam, it, tip) in
            enumerate(zip(path.load_factors, [0] + path.iterations, path.tips))]
    np.savetxt(Path(out_dir) / "history.csv", np.array(rows, dtype=float), delimiter=",",
               header="step,load_factor,iterations,tip_x,tip_y,tip_z", comments="", fmt="%.17g")
    if not path.converged:
        raise StaticFailed(f"{scene.source}: arc length: the corrector did not converge after load factor "
                           f"{path.load_factors[-1]:.6g} (step {len(path.iterations) + 1}); try a smaller --arc-length; "
                           f"the path so far is in {out_dir}")
    return summary


def main_static(args) -> int:
    """The ``static`` command (:mod:`liegroup_int.cli`): exit 0, 2 (bad input) or 3 (a load
    step did not converge)."""
    from .scenes import parse_override

    if args.steps < 1:
        raise SceneError(f"static: --steps {args.steps}: expected a positive number of load steps")
    if args.max_iter < 1:
        raise SceneError(f"static: --max-iter {args.max_iter}: expected a positive number of iterations")
    if not args.tol > 0:
        raise SceneError(f"static: --tol {args.tol}: expected a positive tolerance")
    scene = load_static_scene(args.scene, dict(parse_override(s) for s in args.overrides))
    out = args.out if args.out is not None else Path("runs") / f"{scene.name}-static"
    if args.arc_length is not None and not args.arc_length > 0:
        raise SceneError(f"static: --arc-length {args.arc_length}: expected a positive step")
    try:
        if args.arc_length is not None:
            s = run_arc_length(scene, out, args.arc_length, args.steps, args.tol, args.max_iter, args.time)
            limit = s["limit_load_factor"]
            print(f"{scene.name}: arc-length path of {s['steps']} steps to load factor {s['load_factors'][-1]:.6g}; "
                  + (f"limit load factor {limit:.6g}" if limit is not None else "no limit point on the way")
                  + f"; {s['cpu_time_s']:.3g} s CPU -> {out}")
            return 0
        s = run_static(scene, out, steps=args.steps, tol=args.tol, max_iter=args.max_iter, t=args.time,
                       quiet=args.quiet)
    except StaticFailed as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 3
    except OSError as exc:
        print(f"error: cannot write {exc.filename or out}: {exc.strerror or exc}", file=sys.stderr)
        return 2
    tip = ", ".join(f"{x:.6g}" for x in s["tip"])
    print(f"{scene.name}: equilibrium in {len(s['load_factors'])} load steps, {sum(s['iterations'])} Newton "
          f"iterations, {s['cpu_time_s']:.3g} s CPU; tip ({tip}) -> {out}")
    return 0
