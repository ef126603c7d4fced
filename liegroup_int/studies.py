"""Parameter studies: grids of scene overrides run serially or on Dask, convergence tables.

A study is a list of *grid points* (dicts of dotted scene keys, ``{"integrator.dt": 1e-3}``)
applied on top of a scene and common base overrides. Every point's scene is validated
before anything runs (a bad key raises :class:`SceneError` at once); then each point runs
with :func:`liegroup_int.runner.run_scene` into ``out_dir/run_XXX`` and yields a small
*row* dict. A run that fails (blow-up, step-size failure) gives a row with
``status = "failed"`` and the one-line error instead of stopping the study.

Typical use::

    grid = expand_grid({"integrator.dt": [0.02, 0.01, 0.005, 0.0025]})
    rows = run_study("heavy_top", {"t_end": 1.0}, grid, "runs/study")
    table = convergence_table(rows, "integrator.dt", quantity="auto")  # coarse to fine
    fit = fit_table(table)  # rate with its spread, or ValueError naming what breaks it
    write_study("runs/study", rows, table)

Parallel runs use ``dask.distributed`` (``pip install "dask[distributed]"``): a local
cluster of worker processes, or an existing scheduler by address. Workers only need
``liegroup_int`` importable (they rebuild the scene from its validated keys, not from the
file) and must see ``out_dir`` (shared file system for remote workers).
"""

from __future__ import annotations

import csv
import itertools
import json
import logging
import math
import shutil
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping, NamedTuple, Sequence

import numpy as np

from .runner import RunError, run_scene
from .scenes import SceneError, load_scene, parse_override
from .scenes.scene import build_scene

#: Row fields, in CSV column order (the overrides come after ``run``, the flattened
#: final state before ``error``).
ROW_FIELDS = ("run", "status", "steps", "rhs_evals", "wall_time_s", "t_reached", "error", "run_dir")


# ---------------------------------------------------------------------- grids
def expand_grid(grid: Mapping[str, Sequence]) -> list[dict]:
    """Cartesian product of value lists, as override dicts.

    Parameters
    ----------
    grid : mapping of str to sequence
        Dotted scene key -> non-empty list of values.

    Returns
    -------
    list of dict
        One dict per combination, the last key varying fastest (``itertools.product``
        order); ``[{}]`` for an empty grid.

    Raises
    ------
    ValueError
        A value list is empty or not a list/tuple.
    """
    keys = list(grid)
    for key in keys:
        values = grid[key]
        if not isinstance(values, (list, tuple)) or len(values) == 0:
            raise ValueError(f"grid key {key!r}: expected a non-empty list of values, got {values!r}")
    return [dict(zip(keys, combo)) for combo in itertools.product(*(grid[k] for k in keys))]


def _split_top_level(text: str) -> list[str]:
    """Split on commas outside brackets and quotes (``"[1,2,3],[4,5,6]"`` -> 2 items)."""
    parts, depth, quote, start = [], 0, None, 0
    for i, ch in enumerate(text):
        if quote:
            quote = None if ch == quote else quote
        elif ch in "\"'":
            quote = ch
        elif ch in "[{":
            depth += 1
        elif ch in "]}":
            depth -= 1
        elif ch == "," and depth == 0:
            parts.append(text[start:i])
            start = i + 1
    parts.append(text[start:])
    return [p.strip() for p in parts]


def parse_values(key: str, values: Sequence[str]) -> list:
    """Command-line values of one key (``--values 1e-3 5e-4``), each read as a TOML value
    when it parses as one (numbers, booleans, arrays, quoted strings), else as a string.

    Parameters
    ----------
    key : str
        Dotted scene key.
    values : sequence of str

    Returns
    -------
    list
    """
    return [parse_override(f"{key}={v}")[1] for v in values]


def parse_grid(specs: Sequence[str]) -> dict[str, list]:
    """``["KEY=V1,V2", ...]`` (``--grid`` arguments) -> ``{KEY: [v1, v2], ...}``.

    Commas inside brackets or quotes do not split (``geometry.direction=[1,0,0],[0,1,0]``).

    Raises
    ------
    SceneError
        A spec without ``=``, an empty key or value, or a key given twice.
    """
    grid: dict[str, list] = {}
    for spec in specs:
        if "=" not in spec:
            raise SceneError(f"--grid {spec!r}: expected KEY=V1,V2,...")
        key, raw = (s.strip() for s in spec.split("=", 1))
        items = _split_top_level(raw)
        if not key or any(not item for item in items):
            raise SceneError(f"--grid {spec!r}: expected KEY=V1,V2,... with non-empty values")
        if key in grid:
            raise SceneError(f"--grid {spec!r}: key {key!r} given twice")
        grid[key] = parse_values(key, items)
    return grid


# ---------------------------------------------------------------------- running
@dataclass(frozen=True)
class StudyTask:
    """One grid point, ready to run anywhere (picklable: no file access needed).

    Attributes
    ----------
    index : int
    given : dict
        The scene's validated flat keys (``Scene.raw``, overrides applied).
    source, name : str
        The scene's source (for messages) and name.
    overrides : dict
        The grid point (only the varied keys).
    run_dir : str
        Absolute output directory of this run.
    """

    index: int
    given: dict
    source: str
    name: str
    overrides: dict
    run_dir: str


#: Keys every study run gets unless the study sets them: no per-run history and shape
#: plots (about 1 s per run, most of a short run; the study draws its own figures).
STUDY_DEFAULTS: dict[str, Any] = {"output.plots": False}


def prepare_tasks(scene: str | Path, base_overrides: Mapping[str, Any] | None, grid: Sequence[Mapping[str, Any]],
                  out_dir: str | Path) -> list[StudyTask]:
    """Load and validate every grid point's scene; raise on the first invalid one.

    Parameters
    ----------
    scene : str or Path
        Scene file or built-in name.
    base_overrides : mapping, optional
        Overrides common to all runs (a grid point's keys take precedence); they take
        precedence over :data:`STUDY_DEFAULTS`.
    grid : sequence of mapping
        Grid points (see :func:`expand_grid`).
    out_dir : str or Path
        Study directory; run ``i`` goes to ``out_dir/run_{i:03d}``.

    Returns
    -------
    list of StudyTask

    Raises
    ------
    SceneError
        An invalid grid point (message names the scene, key and value).
    ValueError
        An empty grid.
    """
    if len(grid) == 0:
        raise ValueError("grid: expected at least one grid point")
    path = Path(scene)
    scene_ref = str(path.resolve()) if (path.suffix == ".toml" or path.exists()) else str(scene)
    out_dir = Path(out_dir).resolve()
    tasks = []
    for i, point in enumerate(grid):
        s = load_scene(scene_ref, {**STUDY_DEFAULTS, **dict(base_overrides or {}), **dict(point)})
        tasks.append(StudyTask(i, dict(s.raw), s.source, s.name, dict(point), str(out_dir / f"run_{i:03d}")))
    return tasks


def _plain(obj):
    """numpy scalars/arrays inside dicts and lists -> Python floats, ints and lists."""
    if isinstance(obj, dict):
        return {k: _plain(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_plain(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _plain(obj.tolist())
    if isinstance(obj, np.generic):
        return obj.item()
    return obj


def _one_line(exc: BaseException) -> str:
    lines = str(exc).strip().splitlines()
    return lines[0] if lines else type(exc).__name__


def _failed_row(task: StudyTask, exc: BaseException) -> dict:
    summary_path = Path(task.run_dir) / "summary.json"
    summary = json.loads(summary_path.read_text()) if summary_path.exists() else {}
    return {"run": task.index, "overrides": task.overrides, "status": "failed", "steps": None, "rhs_evals": None,
            "wall_time_s": summary.get("wall_time_s"), "t_reached": summary.get("t_reached"), "final": None,
            "error": _one_line(exc), "run_dir": task.run_dir}


def run_task(task: StudyTask) -> dict:
    """Run one grid point (in this process) and return its row.

    Parameters
    ----------
    task : StudyTask

    Returns
    -------
    dict
        ``run, overrides, status ("ok" | "failed"), steps, rhs_evals, wall_time_s,
        t_reached, final (the summary's final fields, e.g. tip (3,) or R (3, 3) and
        omega_body (3,); None if failed), error (one line or None), run_dir``.
    """
    done = _finished_row(task)
    if done is not None:  # a rerun of an interrupted study keeps the runs it finished
        return done
    if Path(task.run_dir).exists():  # an unfinished run: start it again from nothing
        shutil.rmtree(task.run_dir)
    c = time.perf_counter()
    try:
        scene = build_scene(task.given, task.source, task.name)
        res = run_scene(scene, Path(task.run_dir), quiet=True)
    except RunError as exc:
        if exc.interrupted:
            raise KeyboardInterrupt from None
        return _failed_row(task, exc)
    except SceneError as exc:
        return _failed_row(task, exc)
    return _row(task, res.summary, time.perf_counter() - c)


def _row(task: StudyTask, s: Mapping, task_s: float | None = None) -> dict:
    """A finished run's row; ``timing`` is its summary's split (compile, setup, integrate,
    output, plots) and ``task_s`` the time of the whole task in its process."""
    return _plain({"run": task.index, "overrides": task.overrides, "status": s["status"], "steps": s.get("steps"),
                   "rhs_evals": s.get("rhs_evals"), "wall_time_s": s.get("wall_time_s"),
                   "t_reached": s.get("t_reached"), "final": s.get("final"), "error": None, "method": s.get("method"),
                   "run_dir": task.run_dir, "timing": s.get("timing"), "task_s": task_s})


def time_split(rows: Sequence[Mapping], wall_s: float, workers: int = 1) -> dict:
    """Where a study's time went: the runs' own split summed over the runs (``integrate``,
    ``output``, ``plots``, ``setup`` with compilation), the rest of the tasks (scene
    parsing, directories), and what lies outside the runs: ``wall_s`` less the tasks' time
    shared over ``workers`` processes (process and cluster start, imports, scheduling).
    Runs kept from an earlier study count for nothing."""
    keys = ("integrate_s", "output_s", "plots_s")
    split = dict.fromkeys(keys + ("setup_s", "task_rest_s"), 0.0)
    task_total = 0.0
    for r in rows:
        tm, ts = r.get("timing"), r.get("task_s")
        if not tm or ts is None:
            continue
        for k in keys:
            split[k] += float(tm.get(k, 0.0))
        inside = sum(float(tm.get(k, 0.0)) for k in keys)
        setup = float(tm.get("setup_s", 0.0)) + float(tm.get("compile_s", 0.0))
        split["setup_s"] += setup
        split["task_rest_s"] += max(0.0, float(ts) - inside - setup)
        task_total += float(ts)
    split["outside_runs_s"] = max(0.0, wall_s - task_total / max(1, workers))
    split["wall_s"] = wall_s
    split["workers"] = workers
    return split


def format_time_split(split: Mapping) -> str:
    """One line: the study's wall time and where the runs' time went."""
    return (f"time: {split['wall_s']:.2f} s wall ({split['workers']} process(es)); summed over the runs: "
            f"integrate {split['integrate_s']:.2f} s, outputs {split['output_s']:.2f} s, plots {split['plots_s']:.2f} s, "
            f"set-up and compilation {split['setup_s']:.2f} s, rest of the tasks {split['task_rest_s']:.2f} s; "
            f"outside the runs (processes, cluster, imports) {split['outside_runs_s']:.2f} s")


def _finished_row(task: StudyTask) -> dict | None:
    """The row of a run already finished in ``task.run_dir`` with the same scene keys, or
    ``None``."""
    path = Path(task.run_dir) / "summary.json"
    if not path.exists():
        return None
    try:
        s = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    same = json.dumps(_plain(s.get("scene_keys")), sort_keys=True) == json.dumps(_plain(task.given), sort_keys=True)
    return _row(task, s) if s.get("status") == "ok" and same else None


class StudyInterrupted(Exception):
    """A signal stopped a study; ``rows`` holds the runs finished before it (grid order)."""

    def __init__(self, rows: list[dict], total: int):
        super().__init__(f"interrupted after {len(rows)} of {total} runs")
        self.rows, self.total = rows, total


def _gather(client, tasks: list[StudyTask]) -> list[dict]:
    from dask.distributed import as_completed

    futures = client.map(run_task, tasks, pure=False)
    done: dict[int, dict] = {}
    try:
        for fut in as_completed(futures):
            row = fut.result()
            done[row["run"]] = row
    except KeyboardInterrupt:
        client.cancel(futures)
        raise StudyInterrupted([done[i] for i in sorted(done)], len(tasks)) from None
    return [done[t.index] for t in tasks]


def _run_dask(tasks: list[StudyTask], scheduler: str | None, n_workers: int) -> list[dict]:
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError as exc:
        raise ImportError(f'parallel studies need dask[distributed] (pip install "dask[distributed]"), '
                          f"or run serially: {exc}") from exc
    if scheduler:
        with Client(scheduler) as client:
            return _gather(client, tasks)
    with LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True, dashboard_address=None,
                      silence_logs=logging.ERROR) as cluster, Client(cluster) as client:
        return _gather(client, tasks)


def run_study(scene: str | Path, base_overrides: Mapping[str, Any] | None, grid: Sequence[Mapping[str, Any]],
              out_dir: str | Path, scheduler: str | None = None, n_workers: int = 2,
              serial: bool = False) -> list[dict]:
    """Run a scene at every grid point; one row per run, in grid order.

    Parameters
    ----------
    scene : str or Path
        Scene file or built-in name.
    base_overrides : mapping, optional
        Overrides common to all runs.
    grid : sequence of mapping
        Grid points, e.g. from :func:`expand_grid`.
    out_dir : str or Path
        Study directory; run ``i`` writes ``out_dir/run_{i:03d}/`` (history.csv,
        summary.json, plots).
    scheduler : str, optional
        Address of a running Dask scheduler (``"tcp://host:8786"``). Default: a
        ``LocalCluster`` of ``n_workers`` single-threaded processes, created and closed
        here.
    n_workers : int
        Worker processes of the local cluster (ignored with ``scheduler`` or ``serial``).
    serial : bool
        Run in this process, one after the other, without Dask (same rows up to timing).

    Returns
    -------
    list of dict
        Rows of :func:`run_task`.

    Raises
    ------
    SceneError
        An invalid grid point, before any run starts.
    ValueError
        An empty grid or ``n_workers < 1``.
    ImportError
        Dask is needed (``serial=False``) but not installed.
    StudyInterrupted
        SIGINT/SIGTERM during the study; it holds the rows finished so far. Running the same
        study again keeps the runs whose directory holds a finished run with the same keys.
    """
    if not serial and scheduler is None and (int(n_workers) != n_workers or n_workers < 1):
        raise ValueError(f"n_workers: expected an integer >= 1, got {n_workers!r}")
    tasks = prepare_tasks(scene, base_overrides, grid, out_dir)
    Path(out_dir).mkdir(parents=True, exist_ok=True)
    if serial:
        rows = []
        try:
            for t in tasks:
                rows.append(run_task(t))
        except KeyboardInterrupt:
            raise StudyInterrupted(rows, len(tasks)) from None
        return rows
    return _run_dask(tasks, scheduler, int(n_workers))


# ---------------------------------------------------------------------- convergence
def default_quantity(row: Mapping) -> str:
    """``"tip"`` for beams, ``"R+omega_body"`` for rigid bodies (from a row's ``final``).

    Raises
    ------
    ValueError
        The row has no final state or neither field set.
    """
    final = row.get("final") or {}
    if "tip" in final:
        return "tip"
    if "R" in final and "omega_body" in final:
        return "R+omega_body"
    raise ValueError(f"run {row.get('run')}: no final 'tip' or 'R'/'omega_body' to compare; give a quantity")


def quantity_vector(row: Mapping, quantity: str) -> np.ndarray:
    """A row's final ``quantity`` as a flat vector.

    Parameters
    ----------
    row : mapping
        A successful study row.
    quantity : str
        A field of ``row["final"]`` (``"tip"``, ``"energy"``, ``"R"``, ...) or several
        joined by ``+`` (``"R+omega_body"``), concatenated after flattening.

    Returns
    -------
    numpy.ndarray, shape (k,)
    """
    final = row.get("final") or {}
    parts = []
    for name in quantity.split("+"):
        if name not in final:
            raise ValueError(f"run {row.get('run')}: final state has no {name!r}; available: {', '.join(final)}")
        parts.append(np.ravel(np.asarray(final[name], dtype=float)))
    return np.concatenate(parts)


#: The last part of a varied key -> +1 when larger values are finer (more control points,
#: higher degree), -1 when smaller values are (time step, tolerances).
FINER = {"n_ctrl": 1, "degree": 1, "dt": -1, "rtol": -1, "atol": -1}


def finer_direction(param: str, finer: str | None = None) -> int:
    """+1 when larger values of ``param`` are finer, -1 when smaller values are.

    Parameters
    ----------
    param : str
        The varied key, e.g. ``"integrator.dt"`` (-1) or ``"space.n_ctrl"`` (+1).
    finer : {"larger", "smaller"}, optional
        States the direction for a key not in :data:`FINER` (and overrides it).

    Raises
    ------
    ValueError
        An unknown key without ``finer``, or a bad ``finer``.
    """
    if finer is not None:
        if finer not in ("larger", "smaller"):
            raise ValueError(f"finer: expected 'larger' or 'smaller', got {finer!r}")
        return 1 if finer == "larger" else -1
    last = param.rsplit(".", 1)[-1]
    if last not in FINER:
        raise ValueError(f"{param}: cannot tell whether larger or smaller values are finer; state it with "
                         f"--finer larger|smaller (known keys end in {', '.join(FINER)})")
    return FINER[last]


def coarse_to_fine(rows: Sequence[Mapping], param: str, direction: int) -> list[Mapping]:
    """Rows sorted from the coarsest to the finest ``param`` value (stable for ties)."""
    return sorted(rows, key=lambda r: direction * _param_value(r, param))


def _param_value(row: Mapping, param: str) -> float:
    value = (row.get("overrides") or {}).get(param)
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f"run {row.get('run')}: override {param!r} = {value!r}: expected a finite number "
                         f"(is {param!r} a grid key?)")
    return float(value)


def _pick_finest(rows: Sequence[Mapping], param: str, direction: int) -> Mapping:
    ok = [r for r in rows if r.get("status") == "ok"]
    if not ok:
        raise ValueError("no successful run to use as the reference")
    ordered = coarse_to_fine(ok, param, direction)
    best = _param_value(ordered[-1], param)
    if sum(_param_value(r, param) == best for r in ok) > 1:
        raise ValueError(f"several runs have {param} = {best!r}; select one study line (or pass a reference row)")
    return ordered[-1]


def convergence_table(rows: Sequence[Mapping], param: str, reference: str | Mapping = "finest",
                      quantity: str = "auto", finer: str | None = None) -> list[dict]:
    """Error of each run's final ``quantity`` against a reference run, coarse to fine.

    Parameters
    ----------
    rows : sequence of dict
        Study rows (:func:`run_study`); ``param`` must be one of their overrides.
    param : str
        The varied key, e.g. ``"integrator.dt"``.
    reference : "finest" or dict
        ``"finest"``: the successful run with the finest ``param`` value (the smallest
        ``integrator.dt``, the largest ``space.n_ctrl``: :func:`finer_direction`); or an
        explicit reference row (e.g. from a separate, finer run).
    quantity : str
        Final-state field(s) compared (see :func:`quantity_vector`); ``"auto"`` picks
        :func:`default_quantity` of the reference.
    finer : {"larger", "smaller"}, optional
        Which values of ``param`` are finer, for keys :func:`finer_direction` does not know.

    Returns
    -------
    list of dict
        One entry per run except the reference, from the coarsest to the finest value:
        ``run, param, value, finer, quantity, status, error (Euclidean norm of the
        difference; None if the run failed), rel_error (error / |reference|), round_off
        (rel_error within :func:`round_off_floor`), wall_time_s, steps, rhs_evals,
        reference_run``.

    Raises
    ------
    ValueError
        No usable reference, non-numeric ``param`` values, an unknown quantity or direction.
    """
    direction = finer_direction(param, finer)
    if isinstance(reference, str):
        if reference != "finest":
            raise ValueError(f"reference: expected 'finest' or a row, got {reference!r}")
        ref = _pick_finest(rows, param, direction)
    else:
        ref = reference
        if ref.get("status") != "ok":
            raise ValueError(f"reference row (run {ref.get('run')}) did not succeed")
    if quantity == "auto":
        quantity = default_quantity(ref)
    finer = "larger" if direction > 0 else "smaller"
    return [_entry(row, ref, param, finer, quantity) for row in coarse_to_fine(rows, param, direction) if row is not ref]


def _entry(row: Mapping, ref: Mapping, param: str, finer: str, quantity: str) -> dict:
    """One convergence-table entry: ``row``'s error in ``quantity`` against ``ref``."""
    q_ref = quantity_vector(ref, quantity)
    scale = float(np.linalg.norm(q_ref))
    err = None
    if row.get("status") == "ok":
        err = float(np.linalg.norm(quantity_vector(row, quantity) - q_ref))
    rel = None if err is None or scale == 0.0 else err / scale
    return {"run": row.get("run"), "param": param, "value": row["overrides"][param], "finer": finer,
            "quantity": quantity, "status": row.get("status"), "error": err, "rel_error": rel,
            "round_off": rel is not None and rel <= round_off_floor(row.get("steps"), ref.get("steps")),
            "wall_time_s": row.get("wall_time_s"), "steps": row.get("steps"), "rhs_evals": row.get("rhs_evals"),
            "reference_run": ref.get("run")}


#: A relative error within this factor of the accumulated rounding of a run is not a
#: discretization error: a rate fitted through such points means nothing.
ROUND_OFF_FACTOR = 100.0


def round_off_floor(steps, ref_steps) -> float:
    """Relative error below which a run's difference from the reference may be rounding:
    ``ROUND_OFF_FACTOR * eps * sqrt(steps + ref_steps)`` (random-walk accumulation of one
    rounding per step in both runs)."""
    n = float((steps or 0) + (ref_steps or 0))
    return ROUND_OFF_FACTOR * float(np.finfo(float).eps) * math.sqrt(max(n, 1.0))


def _checked_points(xs: Sequence[float], errs: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
    x, e = np.asarray(xs, dtype=float), np.asarray(errs, dtype=float)
    if x.ndim != 1 or x.shape != e.shape:
        raise ValueError(f"xs and errs: expected two 1-d arrays of the same length, got {x.shape} and {e.shape}")
    if x.size < 3:
        raise ValueError(f"fit_rate: expected at least 3 points, got {x.size}")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(e)) and np.all(x > 0) and np.all(e > 0)):
        raise ValueError("fit_rate: expected finite, positive parameter values and errors")
    if np.unique(x).size != x.size:
        raise ValueError("fit_rate: parameter values repeat")
    return x, e


def fit_rate(xs: Sequence[float], errs: Sequence[float]) -> float:
    """Least-squares slope of ``log(err)`` against ``log(x)`` (the observed order).

    Parameters
    ----------
    xs : sequence of float, shape (k,)
        Positive, distinct parameter values.
    errs : sequence of float, shape (k,)
        Positive errors.

    Returns
    -------
    float

    Raises
    ------
    ValueError
        Fewer than 3 points, non-positive or non-finite values, or repeated ``xs``.
    """
    x, e = _checked_points(xs, errs)
    return float(np.polyfit(np.log(x), np.log(e), 1)[0])


class RateFit(NamedTuple):
    """An observed order with its spread.

    Attributes
    ----------
    rate : float
        Least-squares slope ``p`` of ``log(err)`` against ``log(h)``, ``h`` = the value
        (smaller is finer) or its inverse (larger is finer): ``err ~ h^p``.
    stderr : float
        Standard error of that slope (0 for a perfect line; ``k - 2`` degrees of freedom).
    local_min, local_max : float
        The smallest and largest slope between neighbouring points.
    values : tuple
        The parameter values fitted, coarse to fine.
    """

    rate: float
    stderr: float
    local_min: float
    local_max: float
    values: tuple


def fit_rate_spread(hs: Sequence[float], errs: Sequence[float]) -> tuple[float, float, float, float]:
    """``(slope, standard error of the slope, min and max local slope)`` of ``log(err)``
    against ``log(h)``, for the points of :func:`fit_rate`."""
    h, e = _checked_points(hs, errs)
    lx, le = np.log(h), np.log(e)
    slope, icpt = np.polyfit(lx, le, 1)
    resid = le - (slope * lx + icpt)
    stderr = math.sqrt(float(resid @ resid) / (lx.size - 2) / float(((lx - lx.mean()) ** 2).sum()))
    local = np.diff(le) / np.diff(lx)
    return float(slope), stderr, float(local.min()), float(local.max())


def _fit_break(table: Sequence[Mapping]) -> tuple[list[Mapping], str | None]:
    """The entries a rate may be fitted over (coarse to fine, above the round-off floor, each
    error below the previous one), or a one-line reason naming the values that break it."""
    param = table[0]["param"] if table else "?"
    used = [t for t in table if t.get("error") is not None]
    floor = [t for t in used if t.get("round_off") or t["error"] == 0]
    above = [t for t in used if t not in floor]
    if floor and above and above[-1]["run"] != used[len(above) - 1]["run"]:
        t = floor[0]
        return [], (f"{param} = {t['value']!r} is within {ROUND_OFF_FACTOR:g}x of the round-off floor but finer "
                    f"values are not; the errors are not discretization errors")
    for a, b in zip(above, above[1:]):
        if not b["error"] < a["error"]:
            return [], (f"errors do not shrink from coarse to fine: {param} = {b['value']!r} gives {b['error']:.2e}, "
                        f"not below {a['error']:.2e} at {a['value']!r} (not in the asymptotic range: another error "
                        f"source dominates, or the values are too coarse)")
    if len(above) < 3 and floor:
        return [], (f"{len(floor)} of {len(table)} errors are within {ROUND_OFF_FACTOR:g}x of the round-off floor "
                    f"(relative {min(t['rel_error'] or 0.0 for t in floor):.1e}) at {param} = "
                    f"{', '.join(repr(t['value']) for t in floor)}; use coarser values or a longer span")
    if len(above) < 3:
        return [], f"{len(above)} usable errors; a rate needs at least 3 (give more values)"
    return above, None


def fit_table(table: Sequence[Mapping]) -> RateFit:
    """The observed order of a convergence table (:func:`convergence_table`), with spread.

    Only entries whose errors sit above the round-off floor and shrink strictly from the
    coarsest to the finest value are fitted, and only when there are at least 3.

    Raises
    ------
    ValueError
        One line naming the values that prevent a fit.
    """
    used, reason = _fit_break(table)
    if reason is not None:
        raise ValueError(reason)
    sign = 1.0 if used[0].get("finer", "smaller") == "smaller" else -1.0
    hs = [float(t["value"]) ** sign for t in used]
    rate, stderr, lo, hi = fit_rate_spread(hs, [t["error"] for t in used])
    return RateFit(rate, stderr, lo, hi, tuple(t["value"] for t in used))


def table_rate(table: Sequence[Mapping]) -> float:
    """:attr:`RateFit.rate` of :func:`fit_table`."""
    return fit_table(table).rate


def format_fit(fit: RateFit, param: str, finer: str) -> str:
    """One line: the rate, its standard error, the local slopes and what was fitted."""
    h = param if finer == "smaller" else f"1/{param}"
    return (f"fitted rate: {fit.rate:.3f} +- {fit.stderr:.2g} (standard error of the log-log slope over "
            f"{len(fit.values)} runs; local slopes {fit.local_min:.2f} to {fit.local_max:.2f}; error ~ ({h})^rate)")


def order_note(fit: RateFit, method: str | None) -> str | None:
    """For a step-size study: one line when the fitted rate is not the method's order (off by
    more than 0.5 and three standard errors), saying what that usually means; else None."""
    if method is None:
        return None
    from .integrators import resolve_method

    try:
        order = resolve_method(method).order
    except (KeyError, ValueError):
        return None
    if abs(fit.rate - order) <= max(0.5, 3.0 * fit.stderr):
        return None
    why = ("the errors are not yet in the asymptotic range: at steps near the stability limit the fastest modes, "
           "not the method's truncation, set the error; try smaller integrator.dt values or a smoother load")
    if fit.rate > order:
        why = "the errors fall faster than the method's order: a smooth or special solution, or a round-off floor"
    return f"note: the fitted rate {fit.rate:.2f} is not {method}'s order {order}: {why}"


# ---------------------------------------------------------------------- output
def _flat_final(final: Mapping | None) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for name, value in (final or {}).items():
        a = np.asarray(value)
        if a.ndim == 0:
            out[f"final.{name}"] = value
        else:
            out.update({f"final.{name}.{i}": float(x) for i, x in enumerate(a.ravel())})
    return out


def _csv_rows(rows: Sequence[Mapping]) -> tuple[list[str], list[dict]]:
    """Flat CSV records: ``run``, the override keys, the row fields, ``final.*``."""
    flat = []
    for row in rows:
        rec = {"run": row.get("run"), **dict(row.get("overrides") or {})}
        rec.update({k: row.get(k) for k in ROW_FIELDS if k != "run"})
        rec.update(_flat_final(row.get("final")))
        flat.append(rec)
    override_keys = list(dict.fromkeys(k for row in rows for k in (row.get("overrides") or {})))
    final_keys = list(dict.fromkeys(k for rec in flat for k in rec if k.startswith("final.")))
    header = ["run", *override_keys, *[k for k in ROW_FIELDS if k not in ("run", "error", "run_dir")],
              *final_keys, "error", "run_dir"]
    return header, flat


def _csv_value(v) -> str:
    if v is None:
        return ""
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, (list, tuple, dict)):
        return json.dumps(v)
    return str(v)


def _write_csv(path: Path, header: list[str], records: Sequence[Mapping]) -> Path:
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        for rec in records:
            w.writerow([_csv_value(rec.get(k)) for k in header])
    return path


def _positive_errors(table: Sequence[Mapping]) -> list[Mapping]:
    return [t for t in table if t.get("error") is not None and t["error"] > 0]


def plot_convergence(table: Sequence[Mapping], path: Path) -> Path:
    """Error against the varied parameter (log-log), with the fitted slope if >= 3 points."""
    from .io.plots import _figures

    plt = _figures()
    used = _positive_errors(table)
    x = np.array([t["value"] for t in used])
    e = np.array([t["error"] for t in used])
    fig, ax = plt.subplots(figsize=(6, 4.5))
    ax.loglog(x, e, "o-", label=f"error in {used[0]['quantity']}")
    try:
        fit = fit_table(table)
    except ValueError:
        fit = None
    if fit is not None:
        xv = np.array(fit.values, dtype=float)
        ev = np.array([t["error"] for t in used if t["value"] in fit.values])
        slope = fit.rate if used[0].get("finer", "smaller") == "smaller" else -fit.rate
        c = np.polyfit(np.log(xv), np.log(ev), 1)[1]
        xf = np.array([xv.min(), xv.max()])
        ax.loglog(xf, np.exp(c) * xf**slope, "k--", label=f"fitted rate {fit.rate:.2f} +- {fit.stderr:.2g}")
    ax.set_xlabel(used[0]["param"])
    ax.set_ylabel(f"|error| (reference: run {used[0]['reference_run']})")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="best")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def plot_work_precision(table: Sequence[Mapping], path: Path) -> Path:
    """Error against wall time (log-log), one point per run, labelled by the parameter."""
    from .io.plots import _figures

    plt = _figures()
    used = [t for t in _positive_errors(table) if t.get("wall_time_s")]
    fig, ax = plt.subplots(figsize=(6, 4.5))
    wall, err = [t["wall_time_s"] for t in used], [t["error"] for t in used]
    ax.loglog(wall, err, "o-", label=f"error in {used[0]['quantity']}")
    for t in used:
        ax.annotate(f"{t['value']:.3g}", (t["wall_time_s"], t["error"]), textcoords="offset points", xytext=(4, 4),
                    fontsize=8)
    ax.set_xlabel("wall time [s]")
    ax.set_ylabel("|error|")
    ax.set_title(f"work-precision ({used[0]['param']})")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="best")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def write_study(out_dir: str | Path, rows: Sequence[Mapping], table: Sequence[Mapping] | None = None,
                timing: Mapping | None = None) -> list[Path]:
    """Write a study's results.

    Files: ``study.csv`` (one line per run: run, override keys, status, steps,
    rhs_evals, wall_time_s, t_reached, flattened ``final.*`` fields, error, run_dir) and
    ``study.json`` (``{"rows", "convergence", "rate", "rate_fit", "no_rate", "timing"}``:
    ``rate_fit`` is :class:`RateFit` as a dict, ``no_rate`` the reason when no rate was
    fitted, ``timing`` from :func:`time_split`). With a ``table`` also
    ``convergence.csv``, ``convergence.png`` (error vs parameter, log-log, fitted slope
    in the legend when >= 3 positive errors) and ``work_precision.png`` (error vs wall
    time), the PNGs only when some error is positive.

    Parameters
    ----------
    out_dir : str or Path
    rows : sequence of dict
        From :func:`run_study`.
    table : sequence of dict, optional
        From :func:`convergence_table`.
    timing : mapping, optional
        From :func:`time_split`.

    Returns
    -------
    list of Path
        The files written.
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    header, records = _csv_rows(rows)
    written = [_write_csv(out_dir / "study.csv", header, records)]
    fit, no_rate = None, None
    if table:
        try:
            fit = fit_table(table)
        except ValueError as exc:
            no_rate = str(exc)
    convergence = _plain(list(table)) if table is not None else None
    doc = {"rows": _plain(list(rows)), "convergence": convergence, "rate": None if fit is None else fit.rate,
           "rate_fit": None if fit is None else _plain(fit._asdict()), "no_rate": no_rate,
           "timing": _plain(dict(timing)) if timing is not None else None}
    (out_dir / "study.json").write_text(json.dumps(doc, indent=2) + "\n")
    written.append(out_dir / "study.json")
    if table:
        keys = list(dict.fromkeys(k for t in table for k in t))
        written.append(_write_csv(out_dir / "convergence.csv", keys, table))
        if _positive_errors(table):
            written.append(plot_convergence(table, out_dir / "convergence.png"))
            if any(t.get("wall_time_s") for t in _positive_errors(table)):
                written.append(plot_work_precision(table, out_dir / "work_precision.png"))
    return written
