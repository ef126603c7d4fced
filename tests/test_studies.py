"""Parameter studies: grids, serial vs Dask runs, convergence tables and study files."""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest

from liegroup_int.scenes import SceneError
from liegroup_int.studies import (
    convergence_table,
    default_quantity,
    expand_grid,
    fit_rate,
    parse_grid,
    parse_values,
    quantity_vector,
    run_study,
    table_rate,
    time_split,
    write_study,
)

DTS = [0.02, 0.01, 0.005, 0.0025]
BASE = {"t_end": 1.0, "integrator.method": "rkmk4"}
TIMING = ("wall_time_s", "run_dir", "timing", "task_s")


@pytest.fixture(scope="module")
def serial_rows(tmp_path_factory):
    out = tmp_path_factory.mktemp("study_serial")
    return out, run_study("heavy_top", BASE, expand_grid({"integrator.dt": DTS}), out, serial=True)


@pytest.fixture(scope="module")
def dask_rows(tmp_path_factory):
    out = tmp_path_factory.mktemp("study_dask")
    return out, run_study("heavy_top", BASE, expand_grid({"integrator.dt": DTS}), out, n_workers=2)


def _strip(row):
    return {k: v for k, v in row.items() if k not in TIMING}


def test_serial_rows(serial_rows):
    out, rows = serial_rows
    assert [r["run"] for r in rows] == [0, 1, 2, 3]
    assert [r["overrides"] for r in rows] == [{"integrator.dt": dt} for dt in DTS]
    for r, dt in zip(rows, DTS):
        assert r["status"] == "ok" and r["error"] is None
        assert r["steps"] == round(1.0 / dt) and r["rhs_evals"] == 4 * r["steps"]
        assert r["run_dir"] == str(out / f"run_{r['run']:03d}")
        assert (out / f"run_{r['run']:03d}" / "summary.json").exists()
        assert np.asarray(r["final"]["R"]).shape == (3, 3) and len(r["final"]["omega_body"]) == 3
    json.dumps(rows)  # plain Python values only


def test_study_runs_skip_their_plots_and_report_their_time(serial_rows):
    """Study runs draw no per-run plots (STUDY_DEFAULTS), and the time split adds up: the
    runs' parts plus the rest of each task are the tasks' time, and the wall time is the
    tasks' time plus what lies outside them."""
    out, rows = serial_rows
    assert not list(out.glob("run_*/history.png")) and not list(out.glob("run_*/shapes.png"))
    tasks = sum(r["task_s"] for r in rows)
    split = time_split(rows, wall_s=tasks + 0.5, workers=1)
    parts = sum(split[k] for k in ("integrate_s", "output_s", "plots_s", "setup_s", "task_rest_s"))
    assert parts == pytest.approx(tasks, rel=1e-12)
    assert split["plots_s"] < 1e-3 and split["outside_runs_s"] == pytest.approx(0.5)  # plots_s: the timer alone
    assert time_split(rows, wall_s=tasks / 2 + 0.25, workers=2)["outside_runs_s"] == pytest.approx(0.25)


def test_dask_matches_serial(serial_rows, dask_rows):
    """Same code on worker processes: final states are bitwise equal (floats compared with
    ==, through Python's float equality on the JSON-ready lists); only timing and run dirs differ."""
    (_, s), (out, d) = serial_rows, dask_rows
    assert [_strip(r) for r in d] == [_strip(r) for r in s]
    assert [r["run_dir"] for r in d] == [str(out / f"run_{i:03d}") for i in range(len(DTS))]


def test_rkmk4_rate_is_four(serial_rows):
    """Errors of dt = 0.02, 0.01, 0.005 against the dt = 0.0025 run fall like dt^4 (rkmk4
    is a 4th-order method and the heavy top is smooth). Tolerance 0.4: the reference has
    its own error, about 1/16 of the dt = 0.005 error, which flattens the fit slightly,
    and the coarsest step is still slightly pre-asymptotic."""
    _, rows = serial_rows
    table = convergence_table(rows, "integrator.dt", quantity="R+omega_body")
    assert [t["value"] for t in table] == DTS[:-1]
    assert all(t["reference_run"] == 3 and t["quantity"] == "R+omega_body" for t in table)
    errs = [t["error"] for t in table]
    assert errs == sorted(errs, reverse=True) and errs[-1] > 0
    rate = fit_rate([t["value"] for t in table], errs)
    assert abs(rate - 4.0) < 0.4, rate
    assert table_rate(table) == rate
    assert convergence_table(rows, "integrator.dt", quantity="auto") == table


def test_explicit_reference_and_quantities(serial_rows):
    _, rows = serial_rows
    ref = rows[-1]
    table = convergence_table(rows[:-1], "integrator.dt", reference=ref, quantity="omega_body")
    assert len(table) == 3 and all(t["reference_run"] == 3 for t in table)
    with pytest.raises(ValueError, match="'finest' or a row"):
        convergence_table(rows, "integrator.dt", reference="largest", quantity="R")  # never the coarsest
    assert default_quantity(rows[0]) == "R+omega_body"
    assert quantity_vector(rows[0], "R+omega_body").shape == (12,)
    with pytest.raises(ValueError, match="tip"):
        convergence_table(rows, "integrator.dt", quantity="tip")  # not a rigid-body field
    with pytest.raises(ValueError, match="t_end"):
        convergence_table(rows, "t_end", quantity="R")  # not a grid key


def test_write_study(serial_rows, tmp_path):
    _, rows = serial_rows
    table = convergence_table(rows, "integrator.dt", quantity="R+omega_body")
    written = write_study(tmp_path, rows, table)
    assert {p.name for p in written} == {"study.csv", "study.json", "convergence.csv", "convergence.png",
                                         "work_precision.png"}
    with open(tmp_path / "study.csv") as fh:
        recs = list(csv.DictReader(fh))
    assert len(recs) == len(rows)
    assert [float(r["integrator.dt"]) for r in recs] == DTS
    assert float(recs[0]["final.omega_body.2"]) == rows[0]["final"]["omega_body"][2]
    doc = json.loads((tmp_path / "study.json").read_text())
    assert doc["rows"] == rows and len(doc["convergence"]) == 3
    assert math.isclose(doc["rate"], table_rate(table)) and doc["no_rate"] is None
    assert doc["rate_fit"]["values"] == DTS[:-1] and doc["rate_fit"]["stderr"] > 0
    assert (tmp_path / "convergence.png").stat().st_size > 1000
    assert {p.name for p in write_study(tmp_path / "plain", rows)} == {"study.csv", "study.json"}


def test_invalid_grid_value_fails_before_running(tmp_path):
    grid = expand_grid({"integrator.dt": [0.01, -1.0]})
    with pytest.raises(SceneError, match="integrator.dt"):
        run_study("heavy_top", BASE, grid, tmp_path / "s", serial=True)
    with pytest.raises(SceneError, match="integrator.dtt"):
        run_study("heavy_top", BASE, [{"integrator.dtt": 0.01}], tmp_path / "s")  # before any cluster starts
    assert not (tmp_path / "s").exists()


def test_blow_up_gives_failed_row(tmp_path):
    base = {"t_end": 2e-4, "output.every": 2e-5, "space.n_ctrl": 31}
    # 1.1x the RK4 limit of the default (Galerkin) cantilever: 2.83 / 1.809e6 1/s = 1.56e-6 s
    rows = run_study("cantilever", base | {"guard.dt": False}, [{"integrator.dt": 1.72e-6}], tmp_path, serial=True)
    (row,) = rows
    assert row["status"] == "failed" and row["final"] is None and row["steps"] is None
    assert "beyond the stability limit" in row["error"] and "\n" not in row["error"]
    assert 0 < row["t_reached"] < 2e-4
    assert json.loads((tmp_path / "run_000" / "summary.json").read_text())["status"] == "failed"
    table = convergence_table(rows + [_fake_ok(0.5e-6)], "integrator.dt", quantity="tip")
    assert table[0]["error"] is None and table[0]["status"] == "failed"
    written = write_study(tmp_path, rows)  # failed rows are written too
    csv = next(p for p in written if p.name == "study.csv").read_text().splitlines()
    assert len(csv) == 2 and "failed" in csv[1] and "beyond the stability limit" in csv[1]


def _fake_ok(dt):
    return {"run": 9, "overrides": {"integrator.dt": dt}, "status": "ok", "final": {"tip": [1.0, 0.0, 0.0]}}


def test_expand_grid():
    assert expand_grid({}) == [{}]
    assert expand_grid({"a": [1, 2], "b": ["x", "y"]}) == [
        {"a": 1, "b": "x"}, {"a": 1, "b": "y"}, {"a": 2, "b": "x"}, {"a": 2, "b": "y"}]
    for bad in ({"a": []}, {"a": 1}, {"a": "xy"}):
        with pytest.raises(ValueError):
            expand_grid(bad)


def test_parse_grid_and_values():
    grid = parse_grid(["integrator.dt=1e-3, 5e-4", "integrator.method=rkmk4,rkmk45",
                       "geometry.direction=[1,0,0],[0, 1, 0]"])
    assert grid == {"integrator.dt": [1e-3, 5e-4], "integrator.method": ["rkmk4", "rkmk45"],
                    "geometry.direction": [[1, 0, 0], [0, 1, 0]]}
    assert parse_values("space.n_ctrl", ["11", "21"]) == [11, 21]
    for bad in (["integrator.dt"], ["=1,2"], ["a=1,"], ["a=1", "a=2"]):
        with pytest.raises(SceneError):
            parse_grid(bad)


def test_fit_rate():
    x = np.array([0.1, 0.05, 0.025, 0.0125])
    assert math.isclose(fit_rate(x, 3.0 * x**2), 2.0)
    for xs, es in (([1, 2], [1, 2]), ([1, 2, 3], [1, 0, 2]), ([1, 2, 3], [1, -1, 2]), ([1, 1, 1], [1, 2, 3]),
                   ([1, 2, np.nan], [1, 2, 3]), ([1, 2, 2], [1, 2, 3])):
        with pytest.raises(ValueError):
            fit_rate(xs, es)
