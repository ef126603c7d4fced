"""Where a run's time goes: start-up, set-up, integration, outputs and plots.

    python benchmarks/run_overhead.py [--no-cold] [--quick]

Runs the CLI as a user does (``python -m liegroup_int ...`` in a subprocess, numba cache
warm: one untimed run first) and reports, per case, the process CPU time of the child
(``resource.getrusage(RUSAGE_CHILDREN)``), its wall-clock time (less than the CPU time
where threads overlap: a run loads its plotting library while the compiled loop
integrates) and the split that ``summary.json`` records
(``timing``: setup, integrate, output, plots), with the cost per output (history) row and
the bytes the run wrote (``output_bytes``); for the ``converge`` study, the split of
``study.json`` (``timing``). The pendulum cases give the cost per row with and without
ParaView: as shipped (snapshots and VTU files every ``t_end/100``) and with a snapshot and
a VTU file at every row.

Then (unless ``--no-cold``) the first run on an empty numba cache (``NUMBA_CACHE_DIR`` a
new directory), without and after ``liegroup-int compile``, in wall-clock seconds.
``--quick``: four short cases (``scenes``, ten heavy-top steps, the pendulum over 0.2 s with
ParaView as shipped and without ParaView at every row: at 0.2 s the shipped spacing
``t_end/100`` is below the row spacing, so both write at every row), no warm-up runs (on an
empty numba cache the first run of each scene includes compilation), no study, no cold runs.
"""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from liegroup_int.bench.table import markdown, parser

CASES = [
    ("liegroup-int scenes", ["scenes"], None),
    ("README main job: run cantilever", ["run", "cantilever", "--quiet"], "run"),
    ("  the same, --no-plots", ["run", "cantilever", "--quiet", "--no-plots"], "run"),
    ("  the same, --no-plots, output.hdf5=false", ["run", "cantilever", "--quiet", "--no-plots", "--set",
                                                    "output.hdf5=false"], "run"),
    ("  the same, --no-plots, output.paraview=true", ["run", "cantilever", "--quiet", "--no-plots", "--set",
                                                       "output.paraview=true"], "run"),
    ("heavy_top, 10 steps", ["run", "heavy_top", "--quiet", "--set", "t_end=0.1", "--set", "integrator.dt=0.01"],
     "run"),
    ("heavy_top, 10 steps, --no-plots", ["run", "heavy_top", "--quiet", "--no-plots", "--set", "t_end=0.1",
                                         "--set", "integrator.dt=0.01"], "run"),
    ("heavy_top as shipped (10,000 steps), --no-plots", ["run", "heavy_top", "--quiet", "--no-plots"], "run"),
]


def pendulum_cases(t_end: float) -> list[tuple]:
    """The pendulum over ``t_end`` (2001 rows for 10 s), --no-plots: ParaView on (as shipped)
    and off, with snapshots and VTU files every t_end/100 (the defaults) and at every row."""
    base = ["run", "pendulum", "--quiet", "--no-plots", "--set", f"t_end={t_end:g}"]
    dense = ["--set", "output.snapshot_every=0.005", "--set", "output.paraview_every=0.005"]
    return [
        (f"run pendulum, t_end={t_end:g}, --no-plots (ParaView on)", base, "run"),
        ("  the same, output.paraview=false", base + ["--set", "output.paraview=false"], "run"),
        ("  the same, ParaView on, snapshot and VTU at every row", base + dense, "run"),
        ("  the same, output.paraview=false, snapshot at every row",
         base + dense + ["--set", "output.paraview=false"], "run"),
    ]


CASES += pendulum_cases(10.0)
QUICK_CASES = [CASES[0], CASES[6]] + [pendulum_cases(0.2)[k] for k in (0, 3)]

STUDY = ["converge", "heavy_top", "--param", "integrator.dt", "--values", "0.02", "0.01", "0.005", "0.0025", "--set",
         "t_end=1"]


def child_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run(args: list[str], out: Path | None) -> tuple[float, float, dict | None]:
    """``(process CPU s, wall s, summary or None)`` of one CLI call."""
    full = [sys.executable, "-m", "liegroup_int", *args] + (["--out", str(out)] if out is not None else [])
    c0, w0 = child_cpu(), time.perf_counter()
    subprocess.run(full, check=True, capture_output=True, text=True)
    wall, cpu = time.perf_counter() - w0, child_cpu() - c0
    summary = json.loads((out / "summary.json").read_text()) if out is not None else None
    return cpu, wall, summary


def study(extra: list[str], out: Path) -> tuple[float, dict]:
    w0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "liegroup_int", *STUDY, *extra, "--out", str(out)], check=True,
                   capture_output=True, text=True)
    return time.perf_counter() - w0, json.loads((out / "study.json").read_text())["timing"]


def cold(tmp: Path) -> None:
    """First runs on an empty numba cache, wall-clock seconds."""
    def timed(args, cache):
        env = dict(os.environ, NUMBA_CACHE_DIR=str(cache))
        w0 = time.perf_counter()
        subprocess.run([sys.executable, "-m", "liegroup_int", *args], check=True, capture_output=True, text=True,
                       env=env)
        return time.perf_counter() - w0

    print("\n| first run, empty numba cache | wall s |")
    print("|---|---|")
    print(f"| `run cantilever` | {timed(['run', 'cantilever', '--quiet', '--out', str(tmp / 'c1')], tmp / 'nc1'):.1f} |")
    print(f"| `compile` (beam, rigid_body) | {timed(['compile'], tmp / 'nc2'):.1f} |")
    print(f"| then `run cantilever` | {timed(['run', 'cantilever', '--quiet', '--out', str(tmp / 'c2')], tmp / 'nc2'):.1f} |")
    print(f"| then `run heavy_top` | {timed(['run', 'heavy_top', '--quiet', '--out', str(tmp / 'c3')], tmp / 'nc2'):.1f} |")


def case_rows(cases, tmp: Path) -> list[list]:
    rows = []
    for k, (label, args, kind) in enumerate(cases):
        cpu, wall, s = run(args, tmp / f"r{k}" if kind else None)
        if s is None:
            rows.append([label, f"{cpu:.2f}", f"{wall:.2f}", "", "", "", "", "", "", "", ""])
            continue
        t = s["timing"]
        per = 1e3 * t["output_s"] / max(1, s["history_rows"])
        mb = sum(s.get("output_bytes", {}).values()) / 1e6
        rows.append([label, f"{cpu:.2f}", f"{wall:.2f}", f"{t['setup_s']:.2f}", f"{t['integrate_s']:.2f}",
                     f"{t['output_s']:.3f}", f"{per:.2f}", f"{mb:.3g}", f"{t['plots_s']:.2f}",
                     f"{cpu / t['integrate_s']:.1f}x", f"{wall / t['integrate_s']:.1f}x"])
    return rows


def study_rows(tmp: Path) -> list[list]:
    rows = []
    for label, extra in (("--serial", ["--serial"]), ("local Dask cluster, 2 workers", [])):
        wall, t = study(extra, tmp / f"study{len(extra)}")
        rows.append([label, f"{wall:.2f}", f"{t['integrate_s']:.2f}", f"{t['output_s']:.2f}", f"{t['plots_s']:.2f}",
                     f"{t['setup_s']:.2f}", f"{t['outside_runs_s']:.2f}"])
    return rows


def main(argv=None) -> None:
    ap = parser(__doc__)
    ap.add_argument("--no-cold", action="store_true", help="skip the runs on an empty numba cache")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        if not args.quick:  # numba cache
            run(["run", "heavy_top", "--quiet", "--no-plots", "--set", "t_end=0.01"], tmp / "warm2")
            run(["run", "pendulum", "--quiet", "--no-plots", "--set", "t_end=0.01"], tmp / "warm3")
            run(["run", "cantilever", "--quiet", "--no-plots", "--set", "t_end=1e-4", "--set", "output.every=5e-5"],
                tmp / "warm")
        print(markdown(["case", "process CPU s", "wall s", "setup s", "integrate s", "output s", "output ms/row",
                        "output MB", "plots s", "CPU / integrate", "wall / integrate"],
                       case_rows(QUICK_CASES if args.quick else CASES, tmp)))
        if args.quick:
            return
        print()
        print(markdown(["`converge heavy_top`, 4 runs of 1 s", "wall s", "integrate s", "outputs s", "plots s",
                        "set-up s", "outside the runs s"], study_rows(tmp)))
        if not args.no_cold:
            cold(tmp)


if __name__ == "__main__":
    main()
