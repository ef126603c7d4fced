"""Run a scene: build its problem, integrate, stream outputs, checkpoint, summarize.

Files in the output directory:

* ``history.csv`` (streamed rows), ``results.h5`` (history and state snapshots, streamed),
  and, when asked, the ParaView series ``{problem}.pvd`` + ``paraview/*.vtu``; history rows
  are written every ``output.every``, state snapshots and ParaView files every
  ``output.snapshot_every`` / ``output.paraview_every`` (whole multiples of it,
  :func:`liegroup_int.scenes.output_stride`) and at the last output,
* ``checkpoint.npz`` (state at the last checkpointed output time),
* ``summary.json`` (``status = "running"`` from the start, rewritten at every checkpoint with
  its time ``checkpoint_t``; final at the end, also for failed or interrupted runs),
* ``history.png`` and, for problems that record shapes, ``shapes.png`` / ``shapes.npz``.

Checkpoints are taken at output times: the first output after the start, the first after
5 wall seconds, then every ``output.checkpoint_every`` wall seconds; at the end; and when
SIGINT/SIGTERM arrives (the run then stops at its next output time). A run killed after its
first output can be resumed; :func:`run_dir_advice` says what a directory holds and how to
continue or restart it.
Resuming from a checkpoint continues on the same time grid, so a fixed-step run resumed
from an output time reproduces the uninterrupted run bit for bit.
"""

from __future__ import annotations

import json
import math
import signal
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import __version__
from .budget import check_budget
from .guards import EnergyBalance, diagnose, start_checks
from .integrators import (BlowUpError, IntegrationError, Stats, integrate_adaptive, integrate_fixed, is_splitting, resolve_scheme,
                          stepper_for)
from .integrators.splitting import integrate_composition
from .io import HistoryWriter, write_json
from .io.checkpoint import read_checkpoint, write_checkpoint
from .run_events import EventWatcher, TerminalEvent
from .scenes import KINDS, Scene, SceneError, load_scene, output_stride


class RunError(RuntimeError):
    """A run stopped early; files written so far stay valid. One-line message.

    ``interrupted`` is true when a signal (SIGINT/SIGTERM) stopped it."""

    interrupted: bool = False


class Interrupted(IntegrationError):
    """SIGINT/SIGTERM: the run stopped at an output time after writing a checkpoint."""


class WriteFailed(IntegrationError):
    """An output file could not be written (full disk, I/O error); the message names the
    file and the error."""


#: What output writers raise when a write fails (full disk, I/O errors; h5py's too).
WRITE_ERRORS = (OSError,)
#: What closing a file may raise after a failed write (h5py: RuntimeError on a file left
#: unusable).
CLOSE_ERRORS = (OSError, RuntimeError)


def _write_error(exc: BaseException, path) -> str:
    """``cannot write FILE: ERROR`` in one line (the file the error names, else ``path``)."""
    where = getattr(exc, "filename", None) or path
    text = str(exc).strip()
    what = getattr(exc, "strerror", None) or (text.splitlines()[0] if text else type(exc).__name__)
    return f"cannot write {where}: {what}"


@dataclass
class RunResult:
    out_dir: Path
    summary: dict
    history: Path


def record_interval(scene: Scene, dt: float | None) -> float:
    """``output.every`` (default ``t_end/200``), a whole number of steps for fixed steps."""
    every = scene.output.every if scene.output.every is not None else scene.t_end / 200.0
    if dt is not None:
        every = max(1, round(every / dt)) * dt
    return every


def output_times(t_end: float, every: float) -> np.ndarray:
    """``every * k`` for k = 1, 2, ... up to ``t_end``; ``t_end`` itself if it is not within
    1e-9 of such a multiple. Computed the same way for every run length, so a run to
    ``T/2`` ends on a time of the grid of a run to ``T``."""
    n = int(np.floor(t_end / every + 1e-9))
    t = every * np.arange(1, n + 1)
    if n == 0 or abs(t[-1] - t_end) > 1e-9 * every:
        t = np.append(t, t_end)
    return t


_MISSING = object()


class CompileNotice:
    """Says once on stderr that numba is compiling (a first run), as the first compilation
    starts: the set-up and the warm-up may compile kernels, which takes seconds the user
    would otherwise wait through in silence. A context manager; inert without numba."""

    MESSAGE = "compiling kernels (first run only; `liegroup-int compile` does it ahead of time) ..."

    def __init__(self, enabled: bool):
        self.enabled, self.said, self._cm = enabled, False, None

    def __enter__(self):
        if not self.enabled:
            return self
        try:
            from numba.core import event
        except ImportError:  # pragma: no cover - numba is a dependency
            return self
        notice = self

        class _Listener(event.Listener):
            def on_start(self, ev):
                if not notice.said:
                    notice.said = True
                    print(CompileNotice.MESSAGE, file=sys.stderr, flush=True)

            def on_end(self, ev):
                pass

        self._cm = event.install_listener("numba:compile", _Listener())
        self._cm.__enter__()
        return self

    def __exit__(self, *exc):
        if self._cm is not None:
            self._cm.__exit__(*exc)
            self._cm = None
        return False


#: Seconds of set-up (build, start-up checks) after which a run says on stderr that it is
#: still setting up.
SETUP_NOTICE_S = 2.0


class SetupNotice:
    """Says once on stderr that the set-up is still running when it takes longer than
    :data:`SETUP_NOTICE_S` (a large mesh, a static start, a spectrum): no silent start-up.
    A context manager; the notice comes from a timer thread, cancelled on exit."""

    def __init__(self, what: str, enabled: bool):
        self.what, self.enabled, self._timer = what, enabled, None

    def _say(self):
        print(f"setting up {self.what} (more than {SETUP_NOTICE_S:g} s: building the discretization, start-up "
              "checks) ...", file=sys.stderr, flush=True)

    def __enter__(self):
        if self.enabled:
            import threading

            self._timer = threading.Timer(SETUP_NOTICE_S, self._say)
            self._timer.daemon = True
            self._timer.start()
        return self

    def __exit__(self, *exc):
        if self._timer is not None:
            self._timer.cancel()
        return False


def warm_up(problem, tab, t0: float, y0, dt: float | None) -> float:
    """Compile (or load from numba's cache) the engine's loop the run will use, with one
    throw-away step from ``(t0, y0)``; returns the seconds it took (0 without a compiled
    loop). Failures are left to the run itself, which reports them."""
    from .integrators.controller import DEFAULT_CONTROLLER

    c = time.perf_counter()
    if is_splitting(tab):
        return _warm_split(problem, tab, t0, y0, dt)
    try:
        st = stepper_for(problem, tab)
        if st is None:  # no compiled loop (and no import of the engine, hence of numba)
            return 0.0
        if dt is not None:
            st.advance(t0, y0, t0 + dt, dt, 1, math.inf)
        else:
            h = 1e-9 * max(1.0, abs(t0))
            st.advance_to(t0, y0, t0 + h, h, 1e-4, 0.0, 1e-6, 1e-9, math.inf, 10, math.inf,
                          DEFAULT_CONTROLLER.gains(tab))
    except Exception:  # noqa: BLE001 - the run reports its own failures
        pass
    return time.perf_counter() - c


def _warm_split(problem, comp, t0: float, y0, dt: float) -> float:
    """:func:`warm_up` of a splitting method: one throw-away step of its compiled loop."""
    c = time.perf_counter()
    try:
        problem.split_steps(y0, dt, comp.gammas_f, 1, t=t0)
    except Exception:  # noqa: BLE001 - the run reports its own failures
        pass
    return time.perf_counter() - c


class Progress:
    """Progress bar on stderr (tqdm), updated at most 4 times per second."""

    def __init__(self, t0: float, t_end: float, enabled: bool):
        self.bar, self._last = None, 0.0
        self._start, self._steps0 = time.perf_counter(), None
        if enabled:
            from tqdm import tqdm

            # tqdm writes ", " before the postfix itself
            self.bar = tqdm(total=t_end, initial=t0, unit="s(sim)", file=sys.stderr, dynamic_ncols=True,
                            bar_format="{l_bar}{bar}| {n:.4g}/{total:.4g} s [{elapsed}<{remaining}{postfix}]")

    def __call__(self, t, y, stats):
        if self.bar is None:
            return
        now = time.perf_counter()
        if self._steps0 is None:  # steps of earlier segments (resumed runs) are not this run's rate
            self._steps0 = stats.steps
        if now - self._last >= 0.25:
            self._last = now
            self.bar.n = t
            rate = (stats.steps - self._steps0) / max(now - self._start, 1e-9)
            self.bar.set_postfix_str(f"{stats.steps} steps, {rate:.3g} steps/s", refresh=True)

    def close(self, t):
        if self.bar is not None:
            self.bar.n = t
            self.bar.refresh()
            self.bar.close()


#: Wall seconds after which the second checkpoint is due (the first is at the first output
#: time), unless ``output.checkpoint_every`` is shorter.
EARLY_CHECKPOINT_S = 5.0


class Checkpointer:
    """Observer: writes checkpoints (with the run's counters ``stats``) at output times.

    A checkpoint is written at the first output time after the start, at the first output time after
    :data:`EARLY_CHECKPOINT_S` wall seconds, then whenever ``every_s`` wall seconds have
    passed since the last one (``every_s = 0``: none of these), and when a stop was
    requested (signal); after a requested stop it raises :class:`Interrupted`. A run killed
    after its first output can thus be resumed.
    """

    def __init__(self, path: Path, every_s: float, to_arrays, meta: dict, stats: Stats):
        self.path, self.every_s, self.to_arrays, self.meta = Path(path), every_s, to_arrays, meta
        self.stats = stats
        self.last_wall = time.perf_counter()
        self.stop_requested = False
        self.t_saved: float | None = None
        self.saves = 0
        #: the run's start time: the first checkpoint comes at the first output after it
        self.t_start = -math.inf
        #: called before each checkpoint (buffered writers flush, so that their files hold
        #: every output up to the checkpoint a resume continues from)
        self.flushers: list = []
        #: called with the checkpoint time after each checkpoint (the running summary)
        self.after_save: list = []

    def save(self, t, y):
        """Flush the writers, write the checkpoint (atomically), then the running summary;
        a failing write raises :class:`WriteFailed` and leaves the previous checkpoint."""
        try:
            for flush in self.flushers:
                flush()
            write_checkpoint(self.path, t, self.to_arrays(y), self.stats.as_dict() | {"h_min": self.stats.h_min,
                                                                                       "h_max": self.stats.h_max},
                             self.meta)
        except WRITE_ERRORS as exc:
            raise WriteFailed(_write_error(exc, self.path), t, self.stats.steps) from None
        self.t_saved = t
        self.saves += 1
        self.last_wall = time.perf_counter()
        try:
            for after in self.after_save:
                after(t)
        except WRITE_ERRORS as exc:
            raise WriteFailed(_write_error(exc, self.path.with_name("summary.json")), t, self.stats.steps) from None

    def _wait_s(self) -> float:
        """Wall seconds from the last checkpoint to the next one."""
        return min(self.every_s, EARLY_CHECKPOINT_S) if self.saves < 2 else self.every_s

    def __call__(self, t, y):
        # the starting point is no progress: a run killed before its first output starts again
        due = self.every_s > 0 and t > self.t_start and (
            self.saves == 0 or time.perf_counter() - self.last_wall >= self._wait_s())
        if due or self.stop_requested:
            self.save(t, y)
        if self.stop_requested:
            raise Interrupted(f"interrupted at t={t:.6g}; checkpoint written", t, self.stats.steps)


def _once_per_output(fn):
    """``fn(t, y)`` evaluated once per output: repeated calls with the same ``t`` and state
    object return the first value (the history and HDF5 writers both record it)."""
    last = [None, None, None]

    def call(t, y):
        if last[0] != t or last[1] is not y:
            last[0], last[1], last[2] = t, y, fn(t, y)
        return last[2]

    return call


class EnergyGuard:
    """Stops a run whose recorded energy explodes between output times.

    After three outputs, an energy magnitude above ``factor`` times the largest earlier
    one is taken as a blow-up (a stable run does not grow its energy a thousandfold
    between two outputs). Uses the value the history writer already computed, so it adds
    no diagnostic evaluation.
    """

    def __init__(self, writer: HistoryWriter, factor: float, stats_of):
        self.writer, self.factor, self.stats_of = writer, factor, stats_of
        self.scale, self.count = 0.0, 0

    def __call__(self, t, y):
        e = abs(self.writer.last.get("energy", 0.0))
        self.count += 1
        if self.count > 3 and self.scale > 0 and e > self.factor * self.scale:
            step = self.stats_of().steps
            raise BlowUpError(f"energy grew to {e:.3g} from at most {self.scale:.3g} at t={t:.6g} (step {step}); "
                              f"the run is unstable", t, step)
        self.scale = max(self.scale, e)


def _shapes(snapshot, results: Path | None) -> dict | None:
    """The plugin's shapes (``Simulation.snapshot``): from the snapshots stored in
    ``results`` (HDF5, closed and complete), else from what the observer kept."""
    if results is None:
        return snapshot.shapes() if hasattr(snapshot, "shapes") else None
    if not hasattr(snapshot, "from_snapshots"):
        return None
    import h5py

    with h5py.File(results, "r") as f:
        snaps = f["snapshots"]
        if "t" not in snaps:  # no output written
            return None
        # datasets, read by the plugin as it needs them (the beam reads the control points)
        return snapshot.from_snapshots(snaps["t"][:], {k: snaps[k] for k in snaps if k != "t"})


def write_plots(out_dir: Path, scene: Scene, history: Path, shapes: dict | None = None,
                energy_scale: float = 0.0) -> list[str]:
    """History PNG (the energy balance relative to ``energy_scale`` when given), and for
    problems that record shapes (``Simulation.snapshot``), a deformed-shape PNG and
    shapes.npz."""
    from .io import plot_history, plot_shapes, read_history

    made = []
    data = read_history(history)
    if len(data.get("t", [])) >= 2:
        step = f"dt = {scene.integrator.dt:g} s" if isinstance(scene.integrator.dt, float) else (
            f"rtol = {scene.integrator.rtol:g}" if scene.integrator.rtol else "")
        title = f"{scene.name}: {scene.integrator.method}" + (f", {step}" if step else "")
        made.append(plot_history(data, out_dir / "history.png", title=title, energy_scale=energy_scale,
                                 balance_tolerance=scene.guard.energy_balance).name)
    if shapes is not None and len(shapes["t"]) >= 2:
        np.savez_compressed(out_dir / "shapes.npz", **shapes)
        made.append(plot_shapes(shapes["t"], shapes["centreline"], out_dir / "shapes.png", title=scene.name,
                                bodies=(shapes.get("body_joint"), shapes.get("body_centre"))).name)
    return made


def _truncate_csv(path: Path, t_max: float) -> None:
    lines = path.read_text().splitlines(keepends=True)
    keep = [lines[0]] + [ln for ln in lines[1:] if ln.strip() and float(ln.split(",", 1)[0]) <= t_max]
    path.write_text("".join(keep))


def _install_signal_handlers(ckpt: Checkpointer):
    if threading.current_thread() is not threading.main_thread():
        return {}
    old = {}

    def handler(signum, frame):
        if ckpt.stop_requested:  # second signal: stop now (the last checkpoint stays valid)
            raise KeyboardInterrupt
        ckpt.stop_requested = True

    for sig in (signal.SIGINT, signal.SIGTERM):
        old[sig] = signal.signal(sig, handler)
    return old


def run_scene(scene: Scene, out_dir: Path, quiet: bool = True, resume: dict | None = None,
              claim: Callable[[Path], None] | None = None, load_s: float = 0.0) -> RunResult:
    """Integrate ``scene`` and write its results into ``out_dir`` (:func:`_run_scene`);
    without ``quiet``, a line on stderr says when numba compiles (a first run). ``load_s``:
    the seconds spent loading and checking the scene before (added to the set-up time)."""
    compiles = KINDS[scene.kind].compiles
    with CompileNotice(enabled=not quiet and compiles is not None and compiles(scene)):
        return _run_scene(scene, out_dir, quiet, resume, claim, load_s)


def _run_scene(scene: Scene, out_dir: Path, quiet: bool = True, resume: dict | None = None,
               claim: Callable[[Path], None] | None = None, load_s: float = 0.0) -> RunResult:
    """Integrate ``scene`` and write its results into ``out_dir``: start (build, checks),
    outputs, warm-up, time loop, summary, then plots.

    Parameters
    ----------
    quiet : bool
        No progress bar.
    resume : dict, optional
        A checkpoint (:func:`read_checkpoint`) to continue from; outputs are appended.
    claim : callable, optional
        ``claim(out_dir)`` before the first file is written, after the scene's start-up
        checks (so that a scene error is reported before a question about the directory);
        it may raise to refuse the directory.

    Raises
    ------
    RunError
        The integration stopped (blow-up, step-size failure, interruption); the history
        keeps the rows written so far, ``summary.json`` records the failure.
    """
    out_dir = Path(out_dir)
    clock0 = time.perf_counter()
    with SetupNotice(scene.name, enabled=not quiet):
        start = _start(scene, resume)
        guard_facts, warnings = _checks(scene, start, out_dir)
        watcher = EventWatcher(scene, start.sim, start.tab, start.dt, observer=None)
    if claim is not None:
        claim(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    outs = _outputs(scene, start, out_dir, resume)
    summary = _summary_head(scene, start, resume, guard_facts, warnings)
    outs.ckpt.after_save.append(_running_summary(out_dir / "summary.json", summary, start.stats, outs.ckpt.t_saved))
    compile_s = warm_up(start.sim.problem, start.tab, start.t0, start.y0, start.dt)
    if compile_s > 2.0 and not quiet:
        print(f"compiled the step loop in {compile_s:.1f} s (first run only: cached for later runs)", file=sys.stderr)
    # the compiled loops release the GIL; without one (0 s), a thread would only compete for it
    plots_ready = _preload_plots() if scene.output.plots and compile_s > 0.0 else None
    t_loop = time.perf_counter()
    end = _integrate(scene, start, outs, out_dir, quiet, resume is not None, watcher)
    loop_s = time.perf_counter() - t_loop
    summary.update(_summary_tail(scene, start, outs, end))
    if scene.events:
        summary["events"] = watcher.found
        summary["stopped_by_event"] = end.event
    if end.status != "ok" or end.event is not None:
        summary["wall_time_s"] = loop_s
    summary["timing"] = _timing(compile_s, load_s + t_loop - clock0 - compile_s, loop_s, outs.output_s[0])
    summary["plots"] = []
    _finish(scene, start, outs, end, out_dir, summary, plots_ready)
    return RunResult(out_dir, summary, outs.history)


class _ShortSwitch:
    """Python's thread switch interval at 0.1 ms while at least one preloading thread runs
    (runs in several threads of one process share the setting), then back to what it was."""

    lock, active, saved = threading.Lock(), 0, 0.005

    @classmethod
    def enter(cls) -> None:
        with cls.lock:
            if cls.active == 0:
                cls.saved = sys.getswitchinterval()
                sys.setswitchinterval(min(cls.saved, 1e-4))
            cls.active += 1

    @classmethod
    def leave(cls) -> None:
        with cls.lock:
            cls.active -= 1
            if cls.active == 0:
                sys.setswitchinterval(cls.saved)


def _preload_plots() -> threading.Thread:
    """A started daemon thread that prepares the plotting library (:func:`.io.plots.preload`)
    while the compiled loop integrates with the GIL released; :func:`_plots` joins it. While
    it runs, the thread switch interval is short (:class:`_ShortSwitch`): the loop returns to
    Python at every output time and would otherwise wait up to 5 ms for the GIL each time.
    An error there is left to the plots themselves, which import the same modules."""
    from .io.plots import preload

    _ShortSwitch.enter()

    def run():
        try:
            preload()
        except Exception:  # noqa: BLE001 (the plots report it, in the main thread)
            pass
        finally:
            _ShortSwitch.leave()

    th = threading.Thread(target=run, name="preload-plots", daemon=True)
    th.start()
    return th


def _finish(scene: Scene, start: "_Start", outs: "_Outputs", end: "_End", out_dir: Path, summary: dict,
            plots_ready: threading.Thread | None = None) -> None:
    """Write the summary (complete before the plots: a slow or killed plot loses nothing
    computed), then the plots unless a write failed; raise :class:`RunError` for a run that
    stopped early or whose summary cannot be written."""
    error = end.error
    try:
        write_json(out_dir / "summary.json", summary)
        if scene.output.plots and not end.write_failed:
            _plots(scene, start, outs, out_dir, summary, plots_ready)
    except WRITE_ERRORS as exc:
        error = error or f"{scene.name}: {_write_error(exc, out_dir / 'summary.json')}"
    if error is not None:
        upto = outs.ckpt.t_saved if end.status == "interrupted" else end.t
        exc = RunError(error + ("" if end.write_failed else f" (outputs up to t={upto:.6g} are in {out_dir})"))
        exc.interrupted = end.status == "interrupted"
        raise exc


def _checks(scene: Scene, start: "_Start", out_dir: Path) -> tuple[dict, list]:
    """Refusals before anything is written (SceneError): the outputs' count, memory and disk
    first (cheap), then the guards (a dt beyond the stable step, a spurious growing mode at
    rest). Returns the guards' facts and the warnings, printed on stderr."""
    check_budget(scene, start.sim, start.y0, start.t0, start.dt, start.every, out_dir,
                 snapshot_stride=start.snapshot_stride, paraview_stride=start.paraview_stride)
    guard_facts, warnings = start_checks(scene, start.sim, start.tab, start.dt, start.t0, start.y0)
    warnings = list(warnings) + _output_warnings(scene, start)
    for w in warnings:
        print(f"warning: {w}", file=sys.stderr)
    return guard_facts, warnings


def _timing(compile_s: float, setup_s: float, loop_s: float, output_s: float) -> dict:
    return {
        "compile_s": compile_s,  # the compiled step loop: numba compilation, or loading it from the cache
        "setup_s": setup_s,  # scene, space, damping sizing, dt = "auto", guards, writers
        "integrate_s": loop_s - output_s,  # steps (first call: numba compilation or cache load)
        "output_s": output_s,  # history, HDF5, ParaView, checkpoints at output times
        "plots_s": 0.0,  # drawn after the summary is first written (then rewritten with their time)
    }


@dataclass
class _Start:
    """What a run starts from: the built problem, its step and method, and the initial (or
    resumed) time, state, counters, output interval and energy."""

    sim: object
    dt: float | None
    tab: object
    t0: float
    y0: object
    stats: Stats
    every: float
    e0: float | None
    #: outputs from one state snapshot (one ParaView file) to the next
    snapshot_stride: int = 1
    paraview_stride: int = 1


def _strides(scene: Scene, every: float, meta: dict | None) -> dict:
    """``{"snapshot_stride", "paraview_stride"}`` of a run: from the scene's keys, or for
    a key not given in a resumed run, the run's own (its default depends on ``t_end``,
    which a resume may change; checkpoints without it wrote every output)."""
    out = {}
    for name, given in (("snapshot", scene.output.snapshot_every), ("paraview", scene.output.paraview_every)):
        key = f"{name}_stride"
        out[key] = output_stride(given, scene.t_end, every) if given is not None or meta is None else meta.get(key, 1)
    return out


def _start(scene: Scene, resume: dict | None) -> _Start:
    sim = KINDS[scene.kind].build(scene)
    spec = scene.integrator
    dt = sim.info["dt_auto"] if spec.dt == "auto" else spec.dt
    tab = resolve_scheme(spec.method)
    if is_splitting(tab) and getattr(sim.problem, "split_steps", None) is None:
        raise SceneError(f"{scene.source}: key 'integrator.method' = {spec.method!r} is a splitting method, which this "
                         f"problem ({scene.kind}) does not offer: use an RKMK method (rkmk4)")
    if resume is None:
        every = record_interval(scene, dt)
        return _Start(sim, dt, tab, 0.0, sim.y0, Stats(), every, None, **_strides(scene, every, None))
    t0, meta, st = resume["t"], resume["meta"], resume["stats"]
    if scene.t_end <= t0:
        raise SceneError(f"{scene.source}: key 't_end' = {scene.t_end!r}: expected > {t0:.6g}, the checkpoint time")
    stats = Stats(steps=st["steps"], rejected=st["rejected"], rhs_evals=st["rhs_evals"],
                  wall_time_s=st["wall_time_s"], h_min=st["h_min"], h_max=st["h_max"],
                  quadrature=st.get("quadrature", 0.0), controller=meta.get("controller"))
    y0 = sim.from_arrays(_checked_state(sim, resume["state"], resume.get("path", scene.source)))
    return _Start(sim, dt, tab, t0, y0, stats, meta["every"], meta.get("energy0"), **_strides(scene, meta["every"], meta))


def _checked_state(sim, state: dict, where: str) -> dict:
    """The checkpoint's state arrays, or a one-line error when their names or shapes are not
    those of the scene's discretization as it builds now (its points changed: another
    quadrature rule or mesh, as ``space.quadrature = "auto"`` may resolve differently)."""
    want = {k: np.shape(v) for k, v in sim.to_arrays(sim.y0).items()}
    got = {k: np.shape(v) for k, v in state.items()}
    for name in sorted(want.keys() | got.keys()):
        if want.get(name) != got.get(name):
            raise SceneError(f"{where}: the checkpoint's state '{name}' has shape {got.get(name)}, the scene as it "
                             f"builds now has {want.get(name)} (its discretization's points differ, e.g. another "
                             f"quadrature rule); the run cannot be resumed: start a new run")
    return state


def _output_warnings(scene: Scene, start: _Start) -> list[str]:
    """An output interval below the step: one output per step (and as many VTU files)."""
    dt = start.dt
    if dt is None or scene.output.every is None or scene.output.every >= dt * (1 - 1e-9):
        return []
    n_out = int(round((scene.t_end - start.t0) / start.every))
    n_vtu = math.ceil(n_out / start.paraview_stride)
    return [f"{scene.source}: output.every = {scene.output.every:g} s is below the step dt = {dt:g} s: one "
            f"output per step, {n_out} outputs"
            + (f" (ParaView: {n_vtu} VTU files)" if scene.output.paraview and start.sim.frames is not None else "")]


def _quantities(scene: Scene, sim, balance) -> dict:
    """The recorded quantities: the scene's, then those the plugin records for its own keys
    (beams: output.points); each evaluated once per output, whichever writer asks first."""
    quantities = {}
    wanted = list(scene.output.quantities) + [q for q in sim.diagnostics if q not in scene.output.quantities]
    for q in wanted:  # the run's own quantities need its work of the loads
        if q == "energy_balance" and balance is not None:
            quantities[q] = balance.evaluate
        elif q == "work" and balance is not None:
            quantities[q] = balance.work
        elif q in sim.diagnostics:
            quantities[q] = sim.diagnostics[q]
    return {q: _once_per_output(fn) for q, fn in quantities.items()}


@dataclass
class _Outputs:
    """The run's writers and observers, in the order they see each output."""

    history: Path
    writer: HistoryWriter
    h5: object
    balance: EnergyBalance | None
    ckpt: Checkpointer
    observers: list
    last: dict
    output_s: list
    paraview: object = None


def _due(stride: int, every: float, t_last: float) -> Callable[[float], bool]:
    """``due(t)``: whether the output at ``t`` is one of every ``stride`` outputs of the
    run's grid (``k every`` with ``k`` a multiple of ``stride``, the same grid for a
    resumed run) or its last output (``t_last``)."""

    def due(t: float) -> bool:
        return stride == 1 or round(t / every) % stride == 0 or t >= t_last - 1e-9 * every

    return due


class _AtDue:
    """Observer calling ``inner(t, y)`` at the output times ``due(t)`` selects."""

    def __init__(self, inner, due: Callable[[float], bool]):
        self.inner, self.due = inner, due
        self.pvd = getattr(inner, "pvd", None)  # the file named when a write fails

    def __call__(self, t, y):
        if self.due(t):
            self.inner(t, y)


#: Longest wall time [s] the ParaView index of a run lags behind its files (the HDF5
#: writer's block time): the index is also written at every checkpoint and at the end.
PVD_INDEX_S = 2.0


def _outputs(scene: Scene, start: _Start, out_dir: Path, resume: dict | None) -> _Outputs:
    sim, t0, every = start.sim, start.t0, start.every
    history = out_dir / "history.csv"
    if resume is not None and history.exists():
        _truncate_csv(history, t0 + 1e-9 * every)
    balance, e0 = None, start.e0
    if sim.conserved is not None:
        e0 = float(sim.conserved(start.y0)) if e0 is None else e0
        balance = EnergyBalance(sim.conserved, start.stats, e0, scene.guard.energy_balance,
                                scale=resume["meta"].get("energy_scale", 0.0) if resume is not None else 0.0)
    quantities = _quantities(scene, sim, balance)
    columns = sim.info.get("columns")
    writer = HistoryWriter(history, quantities, columns, append=resume is not None)
    observers = [writer]
    snapshot_due = _due(start.snapshot_stride, every, scene.t_end)
    h5 = _hdf5_writer(scene, sim, out_dir, resume, quantities, columns, t0 + 1e-9 * every, snapshot_due)
    if h5 is not None:
        observers.append(h5)
    elif sim.snapshot is not None:  # shapes come from results.h5; without it the plugin keeps them
        observers.append(_AtDue(sim.snapshot, snapshot_due))
    pv = None
    if scene.output.paraview and sim.frames is not None:
        from .io.paraview import FrameSeriesWriter

        pv = FrameSeriesWriter(out_dir, sim.frames, stem=scene.kind, index_every_s=PVD_INDEX_S)
        if resume is not None:
            pv.resume_after(t0 + 1e-9 * every)
        observers.append(_AtDue(pv, _due(start.paraview_stride, every, scene.t_end)))
    meta = {"source": scene.source, "scene_keys": dict(scene.raw), "every": every, "method": scene.integrator.method,
            "dt": start.dt, "energy0": e0, "snapshot_stride": start.snapshot_stride,
            "paraview_stride": start.paraview_stride}
    ckpt = Checkpointer(out_dir / "checkpoint.npz", scene.output.checkpoint_every, sim.to_arrays, meta, start.stats)
    ckpt.t_saved = t0 if resume is not None else None  # a resumed run starts from its checkpoint
    ckpt.t_start = t0
    for w in (h5, pv):
        if w is not None:
            ckpt.flushers.append(w.flush)
    if scene.output.blowup_factor > 0 and "energy" in sim.diagnostics:
        observers.insert(1, EnergyGuard(writer, scene.output.blowup_factor, lambda: ckpt.stats))
    last = {"t": t0, "y": start.y0}  # the last recorded state, for the failure diagnosis
    observers.append(_remember(last, meta, balance, start.stats))
    if balance is not None:  # after the writers, so the failing row is on disk
        observers.append(balance)
    observers.append(ckpt)
    return _Outputs(history, writer, h5, balance, ckpt, observers, last, [0.0], pv)


def _hdf5_writer(scene: Scene, sim, out_dir: Path, resume: dict | None, quantities: dict, columns, t_keep: float,
                 snapshot_due: Callable[[float], bool]):
    if not scene.output.hdf5:
        return None
    from .io.hdf5 import Hdf5Writer

    attrs = {"scene": dict(scene.raw), "source": scene.source, "version": __version__, "problem": scene.kind}
    snap = sim.to_arrays if sim.fields is None else (lambda y: {**sim.to_arrays(y), **sim.fields(y)})
    h5 = Hdf5Writer(out_dir / "results.h5", quantities, columns, snap, attrs, append=resume is not None,
                    snapshot_due=snapshot_due)
    if resume is not None:
        h5.truncate_after(t_keep)
    return h5


def _remember(last: dict, meta: dict, balance, stats: Stats):
    """Observer: keeps the last recorded state (failure diagnosis) and what a resume needs
    in the checkpoint's metadata (energy scale, adaptive controller memory)."""

    def remember(t, y):
        last["t"], last["y"] = t, y
        if balance is not None:
            meta["energy_scale"] = balance.scale
        if stats.controller is not None:  # adaptive runs: resumed runs continue from it
            meta["controller"] = dict(stats.controller)

    return remember


def _summary_head(scene: Scene, start: _Start, resume, guard_facts: dict, warnings: list) -> dict:
    spec = scene.integrator
    return {
        "scene": scene.name, "source": scene.source, "problem": scene.kind, "method": spec.method,
        "tableau": start.tab.name, "dt": start.dt, "rtol": spec.rtol, "atol": spec.atol, "t_end": scene.t_end,
        "version": __version__, "scene_keys": dict(scene.raw), "resumed_from": start.t0 if resume is not None else None,
        **start.sim.info,
        **({"guards": guard_facts} if guard_facts else {}),
        **({"warnings": warnings} if warnings else {}),
    }


def _running_summary(path: Path, head: dict, stats: Stats, t_checkpoint: float | None):
    """Writes summary.json of a run under way (``status = "running"``, the counters and the
    time of the last checkpoint, ``None`` before the first), now and as
    ``write(t_checkpoint)`` after each checkpoint."""

    def write(t_checkpoint: float | None) -> None:
        write_json(path, head | {"status": "running", "checkpoint_t": t_checkpoint, "t_reached": t_checkpoint}
                   | stats.as_dict())

    write(t_checkpoint)
    return write


@dataclass
class _End:
    """How the integration ended: ``status`` "ok", "interrupted" or "failed", the time
    reached, the final state (``ok``), the counters and the one-line error."""

    status: str
    t: float
    y: object
    stats: Stats
    error: str | None
    write_failed: bool = False
    #: the terminal event that stopped the run
    event: str | None = None


def _integrate(scene: Scene, start: _Start, outs: _Outputs, out_dir: Path, quiet: bool, resumed: bool,
               watcher: EventWatcher) -> _End:
    """The time loop with the observers at output times; progress at output times only (no
    per-step monitor, so a compiled problem runs the steps between two outputs in one call
    of the engine). Failures, a failing write among them, are caught, diagnosed and
    returned, with the files closed."""
    t0, y0, stats = start.t0, start.y0, start.stats
    progress = Progress(t0, scene.t_end, enabled=not quiet and sys.stderr.isatty())
    observer = _observer(outs, progress, stats, skip_first=resumed)
    watcher.observer = observer
    old_handlers = _install_signal_handlers(outs.ckpt)
    end = _End("ok", t0, y0, stats, None)
    try:
        try:
            t, y, stats = _loop(scene, start, watcher)
            outs.ckpt.save(t, y)
            end = _End("ok", t, y, stats, None)
        except TerminalEvent as ev:  # the row and checkpoint at the event, then stop there
            observer(ev.t, ev.y)
            outs.ckpt.save(ev.t, ev.y)
            end = _End("ok", ev.t, ev.y, stats, None, event=ev.name)
    except Interrupted as exc:
        end = _End("interrupted", exc.t, y0, stats,
                   f"{scene.name}: {exc}; resume with: liegroup-int run {scene.source.removeprefix('builtin:')} "
                   f"--resume {out_dir}")
    except WriteFailed as exc:
        end = _End("failed", exc.t, y0, stats, _write_failed(scene, exc, outs.ckpt.t_saved, out_dir), True)
    except IntegrationError as exc:
        error = f"{scene.name}: {exc}"
        cause = diagnose(scene, start.sim, start.tab, start.dt, outs.last["t"], outs.last["y"])
        end = _End("failed", exc.t, y0, stats, error + (f"; {cause}" if cause else ""))
    finally:
        for sig, h in old_handlers.items():
            signal.signal(sig, h)
        closing = _close_writers(outs)
        progress.close(end.t)
    if closing is not None and end.error is None:  # the last block of a file could not be written
        end = _End("failed", end.t, end.y, end.stats,
                   _write_failed(scene, WriteFailed(closing, end.t, end.stats.steps), outs.ckpt.t_saved, out_dir), True)
    return end


def _loop(scene: Scene, start: _Start, observer):
    """``(t, y, stats)`` at t_end: the fixed-step or adaptive integration from the start."""
    spec, t0 = scene.integrator, start.t0
    t_out = output_times(scene.t_end, start.every)
    t_out = t_out[t_out > t0 + 1e-9 * start.every]
    if is_splitting(start.tab):  # t_end off the step grid: its last interval takes shorter equal steps
        return integrate_composition(start.sim.problem, start.tab, (t0, t_out[-1]), start.y0, start.dt, observer,
                                     t_out, stats=start.stats, fit=True)
    if start.dt is not None:
        return integrate_fixed(start.sim.problem, start.tab, (t0, t_out[-1]), start.y0, start.dt, observer, t_out,
                               stats=start.stats)
    return integrate_adaptive(start.sim.problem, start.tab, (t0, t_out[-1]), start.y0, spec.rtol or 1e-6,
                              spec.atol or 1e-9, observer, t_out, h_max=start.sim.info.get("dt_auto", np.inf),
                              stats=start.stats)


def _write_failed(scene: Scene, exc: WriteFailed, t_checkpoint: float | None, out_dir: Path) -> str:
    """One line: the file and the error, and what the directory keeps to go on from."""
    keep = (f"the checkpoint at t={t_checkpoint:.6g} is kept: free space, then `liegroup-int run --resume {out_dir}`"
            if t_checkpoint is not None else
            f"no checkpoint yet: free space, then `liegroup-int run {scene.source.removeprefix('builtin:')} "
            f"--out {out_dir} --overwrite`")
    return f"{scene.name}: {exc} at t={exc.t:.6g}; {keep}"


def _close_writers(outs: _Outputs) -> str | None:
    """Close the history, HDF5 and ParaView writers (writing what they buffer); ``None``,
    or the first failing write as ``cannot write FILE: ERROR``."""
    failed = None
    for w in (outs.writer, outs.h5, outs.paraview):
        if w is None:
            continue
        try:
            w.close()
        except CLOSE_ERRORS as exc:
            failed = failed or _write_error(exc, _file_of(w))
    return failed


def _observer(outs: _Outputs, progress: Progress, stats: Stats, skip_first: bool):
    """Calls every observer at an output time and times it; a resumed run does not record
    its starting point again."""
    first = [skip_first]

    def observer(t, y):
        if first[0]:
            first[0] = False
            return
        c = time.perf_counter()
        for obs in outs.observers:
            try:
                obs(t, y)
            except WRITE_ERRORS as exc:
                raise WriteFailed(_write_error(exc, _file_of(obs)), t, stats.steps) from None
        progress(t, y, stats)
        outs.output_s[0] += time.perf_counter() - c

    return observer


def _file_of(observer) -> str:
    """The file an output observer writes (for a failing write's message)."""
    for attr in ("path", "pvd"):
        if getattr(observer, attr, None) is not None:
            return str(getattr(observer, attr))
    return "the outputs"


def output_bytes(out_dir: Path, stem: str, plots=()) -> dict[str, int]:
    """Bytes on disk of a run's outputs by kind: ``history.csv``, ``results.h5``,
    ``paraview`` (``paraview/*.vtu`` and the index ``{stem}.pvd``), ``checkpoint.npz`` and
    ``plots`` (the files named in ``plots`` and shapes.npz); kinds not on disk are left out."""
    out_dir = Path(out_dir)
    sizes = {name: (out_dir / name).stat().st_size for name in ("history.csv", "results.h5", "checkpoint.npz")
             if (out_dir / name).is_file()}
    pvd = out_dir / f"{stem}.pvd"
    if pvd.is_file():
        sizes["paraview"] = pvd.stat().st_size + sum(f.stat().st_size for f in (out_dir / "paraview").glob("*.vtu"))
    if plots:
        drawn = [out_dir / name for name in plots] + [out_dir / "shapes.npz"]
        sizes["plots"] = sum(f.stat().st_size for f in drawn if f.is_file())
    return sizes


def _size(n: float) -> str:
    """Bytes in the largest decimal unit below them (``197 kB``, ``1.3 MB``)."""
    for unit, size in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= size:
            return f"{n / size:.3g} {unit}"
    return f"{n:.0f} B"


def format_outputs(summary: dict) -> str:
    """One line: the outputs' sizes by kind with their counts, and the output time per
    history row (``summary.json``'s ``output_bytes``, counts and ``timing``)."""
    b, parts = summary.get("output_bytes", {}), []
    for kind, label, count in (("history.csv", "history.csv", f"{summary.get('history_rows', 0)} rows"),
                               ("results.h5", "results.h5", f"{summary.get('snapshots', 0)} snapshots"),
                               ("paraview", "ParaView", f"{summary.get('paraview_files', 0)} files"),
                               ("checkpoint.npz", "checkpoint.npz", ""), ("plots", "plots", "")):
        if kind in b:
            parts.append(f"{label} {_size(b[kind])}" + (f" ({count})" if count else ""))
    rows = max(1, summary.get("history_rows", 0))
    per_row = 1e3 * summary.get("timing", {}).get("output_s", 0.0) / rows
    return f"outputs {_size(sum(b.values()))}: {', '.join(parts)}; {per_row:.2f} ms of output per history row"


def _summary_tail(scene: Scene, start: _Start, outs: _Outputs, end: _End) -> dict:
    tail = {"status": end.status, "t_reached": end.t, "checkpoint_t": outs.ckpt.t_saved,
            "history_rows": outs.writer.rows, "snapshots": outs.h5.snapshots if outs.h5 is not None else 0,
            "paraview_files": len(outs.paraview.entries) if outs.paraview is not None else 0,
            "output_strides": {"snapshot": start.snapshot_stride, "paraview": start.paraview_stride},
            "output_bytes": output_bytes(outs.history.parent, scene.kind)}
    if outs.balance is not None:
        b = outs.balance
        tail["energy_balance"] = {"defect": b.defect, "worst_fraction": b.worst, "energy_scale": b.scale,
                                  "work": end.stats.quadrature, "tolerance": scene.guard.energy_balance}
    tail.update(end.stats.as_dict())
    tail["wall_time_s"] = end.stats.wall_time_s
    if end.status == "ok":
        tail["final"] = start.sim.final_state(end.y) | {"t": end.t}
    else:
        tail["error"] = end.error
    return tail


def _plots(scene: Scene, start: _Start, outs: _Outputs, out_dir: Path, summary: dict,
           plots_ready: threading.Thread | None = None) -> None:
    """The run's plots, drawn after the summary is written (once ``plots_ready``, the
    preloading thread, has finished); their names and time are added to it."""
    c = time.perf_counter()
    if plots_ready is not None:
        plots_ready.join()
    shapes = None
    if start.sim.snapshot is not None:
        shapes = _shapes(start.sim.snapshot, out_dir / "results.h5" if outs.h5 is not None else None)
    scale = outs.balance.scale if outs.balance is not None else 0.0
    summary["plots"] = write_plots(out_dir, scene, outs.history, shapes, scale)
    summary["timing"]["plots_s"] = time.perf_counter() - c
    summary["output_bytes"] = output_bytes(out_dir, scene.kind, summary["plots"])
    write_json(out_dir / "summary.json", summary)


#: Scene keys a resumed run may change: the span and what is written, not the model, the
#: discretization or the method (the checkpoint holds a state of those). The intervals of
#: snapshots and ParaView files may change: both series store their times (``snapshots/t``,
#: the index's time steps), so a change at the checkpoint leaves them readable; history
#: rows keep ``output.every``, the grid the resumed run continues on.
RESUME_KEYS = ("t_end", "output.plots", "output.paraview", "output.paraview_every", "output.snapshot_every",
               "output.checkpoint_every", "output.blowup_factor", "guard.energy_balance")


#: Files whose presence means a directory holds a run.
RUN_FILES = ("summary.json", "history.csv", "results.h5", "checkpoint.npz")


def _checkpoint_time(path: Path) -> float | None:
    try:
        with np.load(path, allow_pickle=False) as z:
            return float(z["t"])
    except (OSError, ValueError, KeyError):
        return None


def run_dir_advice(out_dir: Path, scene: str | None = None) -> str | None:
    """What ``out_dir`` holds and what to do with it, in one line (the refusal of a new run
    into it and of a resume without checkpoint give the same); ``None`` when it holds no run.

    Parameters
    ----------
    out_dir : Path
    scene : str, optional
        The scene to name in the command when summary.json does not (killed early).
    """
    out_dir = Path(out_dir)
    if not any((out_dir / f).exists() for f in RUN_FILES):
        return None
    try:
        summary = json.loads((out_dir / "summary.json").read_text())
    except (OSError, ValueError):
        summary = {}
    source = str(summary.get("source") or scene or "SCENE").removeprefix("builtin:")
    status = summary.get("status", "no summary")
    t = _checkpoint_time(out_dir / "checkpoint.npz") if (out_dir / "checkpoint.npz").exists() else None
    if t is not None:
        return (f"{out_dir}: holds a run of {source} ({status}; checkpoint at t={t:.6g} s); continue it with "
                f"`liegroup-int run --resume {out_dir}` (--set t_end=T to extend it), replace it with --overwrite, "
                f"or give --out another directory")
    return (f"{out_dir}: holds a run of {source} ({status}) without a checkpoint, so it cannot be resumed; start it "
            f"again with `liegroup-int run {source} --out {out_dir} --overwrite`, or give --out another directory")


def resume_run(out_dir: Path, overrides: dict, quiet: bool = True, scene: str | None = None) -> RunResult:
    """Continue the run stored in ``out_dir`` from its checkpoint (``--resume DIR``).

    ``overrides`` may change only :data:`RESUME_KEYS`; any other key that differs from the
    checkpoint's scene, and a ``scene`` other than the checkpoint's, raise
    :class:`SceneError` before anything is written."""
    path = Path(out_dir) / "checkpoint.npz"
    if not path.exists():
        raise SceneError(run_dir_advice(out_dir, scene) or f"{out_dir}: holds no run to resume (no checkpoint.npz)")
    ckpt = read_checkpoint(path)
    meta = ckpt["meta"]
    keys = dict(meta["scene_keys"])
    source = meta["source"]
    src = source.removeprefix("builtin:")
    if scene is not None and str(scene) not in (src, source):
        raise SceneError(f"{out_dir}: holds a run of {source}, not {scene}; give no SCENE with --resume")
    for k, v in overrides.items():
        if k not in RESUME_KEYS and keys.get(k, _MISSING) != v:
            raise SceneError(f"{out_dir}: key '{k}' cannot change on resume (the checkpoint holds a state of "
                             f"{source} as it was run); only {', '.join(RESUME_KEYS)} can; start a new run")
    keys.update(overrides)
    scene = load_scene(src, keys)
    return run_scene(scene, out_dir, quiet=quiet, resume=ckpt)
