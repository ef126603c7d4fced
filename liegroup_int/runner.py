"""Run a scene: build its problem, integrate, stream outputs, write the summary."""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import __version__
from .integrators import IntegrationError, integrate_adaptive, integrate_fixed, resolve_method
from .io import HistoryWriter, write_json
from .scenes import KINDS, Scene, SceneError


class RunError(RuntimeError):
    """A run stopped early; files written so far stay valid. One-line message."""


@dataclass
class RunResult:
    out_dir: Path
    summary: dict
    history: Path


def output_times(scene: Scene, dt: float | None) -> np.ndarray:
    """Record times: every ``output.every`` seconds (a whole number of fixed steps), and t_end."""
    every = scene.output.every if scene.output.every is not None else scene.t_end / 200.0
    if dt is not None:
        every = max(1, round(every / dt)) * dt
    n = int(np.floor(scene.t_end / every + 1e-9))
    t = every * np.arange(1, n + 1)
    t = t[t < scene.t_end - 1e-12 * scene.t_end]
    return np.append(t, scene.t_end)


class Progress:
    """Progress bar on stderr (tqdm), updated at most 4 times per second."""

    def __init__(self, t_end: float, enabled: bool):
        self.t_end, self.bar, self._last = t_end, None, 0.0
        if enabled:
            from tqdm import tqdm

            self.bar = tqdm(total=t_end, unit="s(sim)", file=sys.stderr, dynamic_ncols=True,
                            bar_format="{l_bar}{bar}| {n:.4g}/{total:.4g} s [{elapsed}<{remaining}, {postfix}]")

    def __call__(self, t, y, stats):
        if self.bar is None:
            return
        now = time.perf_counter()
        if now - self._last >= 0.25:
            self._last = now
            self.bar.n = t
            self.bar.set_postfix_str(f"{stats.steps} steps", refresh=True)

    def close(self, t):
        if self.bar is not None:
            self.bar.n = t
            self.bar.refresh()
            self.bar.close()


def stable_dt_hint(scene: Scene, sim) -> str:
    """``stable dt estimate ...`` for problems with a spectral radius (beams), else ''."""
    from .integrators import spectral_radius, stable_step
    from .problems.beam import BeamProblem

    if not isinstance(sim.problem, BeamProblem):
        return ""
    try:
        lam = spectral_radius(sim.problem, 0.0, sim.y0)
        step = stable_step(resolve_method(scene.integrator.method), lam, scene.t_end)
    except Exception:  # the hint must never mask the original error
        return ""
    return f"stable dt estimate {step.dt:.3g} s (|lambda|max = {lam:.3g} 1/s, {step.rule})"


def write_plots(out_dir: Path, scene: Scene, sim, history: Path) -> list[str]:
    """History PNG, and for problems that record shapes, a deformed-shape PNG (+ npz)."""
    from .io import plot_history, plot_shapes, read_history

    made = []
    data = read_history(history)
    if len(data.get("t", [])) >= 2:
        made.append(plot_history(data, out_dir / "history.png", title=scene.name).name)
    snap = sim.snapshot
    if snap is not None and len(snap.t) >= 2:
        pb = sim.problem
        u = np.linspace(0.0, 1.0, 101)
        B = pb.space.point_matrix(u)
        shapes = np.einsum("uj,mjk->muk", B, np.asarray(snap.c))
        np.savez_compressed(out_dir / "shapes.npz", t=np.asarray(snap.t), control_points=np.asarray(snap.c), u=u,
                            centreline=shapes)
        made.append(plot_shapes(np.asarray(snap.t), shapes, out_dir / "shapes.png", title=scene.name).name)
    return made


def run_scene(scene: Scene, out_dir: Path, quiet: bool = True) -> RunResult:
    """Integrate ``scene`` and write ``history.csv`` and ``summary.json`` into ``out_dir``.

    Raises
    ------
    RunError
        The integration stopped (blow-up, step-size failure); ``history.csv`` keeps
        the rows written so far and ``summary.json`` records the failure.
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    kind = KINDS[scene.kind]
    sim = kind.build(scene)
    spec = scene.integrator
    dt = spec.dt
    if dt == "auto":
        dt = sim.info["dt_auto"]
    tab = resolve_method(spec.method)
    t_out = output_times(scene, dt)
    history = out_dir / "history.csv"
    writer = HistoryWriter(history, sim.diagnostics, getattr(sim, "columns", None) or sim.info.get("columns"))
    observers = [writer]
    if sim.snapshot is not None:
        observers.append(sim.snapshot)

    def observer(t, y):
        for obs in observers:
            obs(t, y)

    progress = Progress(scene.t_end, enabled=not quiet and sys.stderr.isatty())
    summary = {
        "scene": scene.name,
        "source": scene.source,
        "problem": scene.kind,
        "method": spec.method,
        "tableau": tab.name,
        "dt": dt,
        "rtol": spec.rtol,
        "atol": spec.atol,
        "t_end": scene.t_end,
        "version": __version__,
        "scene_keys": dict(scene.raw),
        **sim.info,
    }
    t_reached, y_final, status, error = 0.0, sim.y0, "ok", None
    start = time.perf_counter()
    try:
        if dt is not None:
            t_reached, y_final, stats = integrate_fixed(sim.problem, tab, (0.0, scene.t_end), sim.y0, dt, observer, t_out, progress)
        else:
            t_reached, y_final, stats = integrate_adaptive(
                sim.problem, tab, (0.0, scene.t_end), sim.y0, spec.rtol or 1e-6, spec.atol or 1e-9, observer, t_out, progress,
                h_max=sim.info.get("dt_auto", np.inf),
            )
    except IntegrationError as exc:
        status, error = "failed", f"{scene.name}: {exc}"
        hint = stable_dt_hint(scene, sim)
        if hint:
            error += f"; {hint}"
        stats = None
        t_reached = exc.t
    finally:
        writer.close()
        progress.close(t_reached)
    summary.update({"status": status, "t_reached": t_reached, "wall_time_s": time.perf_counter() - start})
    if stats is not None:
        summary.update(stats.as_dict())
        summary["wall_time_s"] = stats.wall_time_s
        summary["final"] = sim.final_state(y_final)
        summary["final"]["t"] = t_reached
    else:
        summary["error"] = error
    summary["history_rows"] = writer.rows
    summary["plots"] = write_plots(out_dir, scene, sim, history)
    write_json(out_dir / "summary.json", summary)
    if error is not None:
        raise RunError(error + f" (history up to the last output is in {history})")
    return RunResult(out_dir, summary, history)
