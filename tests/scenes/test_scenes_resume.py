"""Checkpoints, resume, interruption and killed runs."""

import json
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from liegroup_int.cli import main
from liegroup_int.io import read_history
from liegroup_int.io.checkpoint import read_checkpoint
from liegroup_int.io.hdf5 import read_results


def _final_state(d):
    return read_checkpoint(d / "checkpoint.npz")


@pytest.mark.parametrize("scene, sets, T", [
    ("heavy_top", ["output.every=0.05"], 1.0),
    ("cantilever", ["output.every=1e-5", "space.n_ctrl=11", "integrator.dt=2e-6"], 2e-4),
    # an adaptive pair (the controller's memory crosses the checkpoint), the NumPy backend,
    # and a time-varying load (a ramp across the resume time)
    ("heavy_top", ["output.every=0.05", "integrator.dt=none", "integrator.method=rkmk45", "integrator.rtol=1e-6",
                   "integrator.atol=1e-9"], 1.0),
    # the NumPy backend without the plots and the start guard's power iteration (370 NumPy
    # rates): 0.2-0.5 s and 0.3 s of each of its three runs against 0.05-0.1 s of steps,
    # and neither is part of what resumes (the other cases run both)
    ("cantilever", ["output.every=1e-5", "space.n_ctrl=11", "integrator.dt=2e-6", "integrator.backend=numpy",
                    "output.plots=false", "guard.dt=false"], 1e-4),
    ("cantilever", ["output.every=1e-5", "space.n_ctrl=11", "integrator.dt=2e-6", "loads.end.profile=ramp",
                    "loads.end.ramp=1.5e-4"], 2e-4),
    # splitting methods: the leapfrog (its work of the loads crosses the checkpoint) and
    # the rigid body's exact flows
    ("cantilever", ["output.every=1e-5", "space.n_ctrl=11", "integrator.dt=1e-6", "integrator.method=strang"],
     2e-4),
    ("heavy_top", ["output.every=0.05", "integrator.method=yoshida4"], 1.0),
], ids=["heavy_top", "cantilever", "heavy_top-rkmk45", "cantilever-numpy", "cantilever-ramp", "cantilever-strang",
        "heavy_top-yoshida4"])
def test_resumed_run_is_bitwise_identical(tmp_path, scene, sets, T):
    s = sum((["--set", x] for x in sets), [])
    full, half = tmp_path / "full", tmp_path / "half"
    assert main(["run", scene, "--quiet", "--out", str(full), "--set", f"t_end={T}"] + s) == 0
    assert main(["run", scene, "--quiet", "--out", str(half), "--set", f"t_end={T / 2}"] + s) == 0
    assert main(["run", "--quiet", "--resume", str(half), "--set", f"t_end={T}", scene]) == 0
    a, b = _final_state(full), _final_state(half)
    assert a["t"] == b["t"]
    for k in a["state"]:
        assert np.array_equal(a["state"][k], b["state"][k]), k  # bit for bit
    ha, hb = read_history(full / "history.csv"), read_history(half / "history.csv")
    assert np.array_equal(ha["t"], hb["t"])
    for k in ha:
        assert np.array_equal(ha[k], hb[k]), k
    ra, rb = read_results(full / "results.h5"), read_results(half / "results.h5")
    assert np.array_equal(ra["history"]["t"], rb["history"]["t"])
    sa, sb = json.loads((full / "summary.json").read_text()), json.loads((half / "summary.json").read_text())
    assert sa["steps"] == sb["steps"] and sa["final"] == sb["final"]


def _spawn(args, cwd):
    return subprocess.Popen([sys.executable, "-m", "liegroup_int"] + args, cwd=cwd, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)


def _wait_rows(path, n, proc, timeout=60.0):
    t0 = time.time()
    while time.time() - t0 < timeout:
        if path.exists() and len(path.read_text().splitlines()) > n:
            return
        if proc.poll() is not None:
            raise AssertionError(f"run ended early: {proc.communicate()}")
        time.sleep(0.05)
    raise AssertionError("no output rows")


def test_sigint_checkpoints_and_resume_completes(tmp_path):
    out = tmp_path / "run"
    args = ["run", "heavy_top", "--quiet", "--out", str(out), "--set", "t_end=200", "--set", "output.every=0.01"]
    p = _spawn(args, tmp_path)
    _wait_rows(out / "history.csv", 5, p)
    p.send_signal(signal.SIGINT)
    _, err = p.communicate(timeout=60)
    assert p.returncode == 130 and "interrupted" in err and "--resume" in err and err.count("\n") == 1
    s = json.loads((out / "summary.json").read_text())
    ck = read_checkpoint(out / "checkpoint.npz")
    assert s["status"] == "interrupted" and 0 < ck["t"] < 200
    # the history ends at the checkpoint time (the stop happens at an output time)
    assert read_history(out / "history.csv")["t"][-1] == pytest.approx(ck["t"])
    # finish a shortened run from the checkpoint
    t_end = ck["t"] + 0.05
    assert main(["run", "--quiet", "--resume", str(out), "--set", f"t_end={t_end}", "heavy_top"]) == 0
    h = read_history(out / "history.csv")
    assert h["t"][-1] == pytest.approx(t_end) and np.all(np.diff(h["t"]) > 0)


def test_killed_run_keeps_valid_outputs(tmp_path):
    out = tmp_path / "run"
    p = _spawn(["run", "heavy_top", "--quiet", "--out", str(out), "--set", "t_end=200", "--set", "output.every=0.01"],
               tmp_path)
    _wait_rows(out / "history.csv", 10, p)
    p.send_signal(signal.SIGKILL)
    p.communicate(timeout=30)
    h = read_history(out / "history.csv")
    r = read_results(out / "results.h5")  # readable after SIGKILL: written in whole blocks
    assert len(h["t"]) >= 10 and np.all(np.isfinite(h["energy"]))
    n = len(r["history"].get("t", []))
    # the CSV gets its row at every output; the HDF5 file is written in blocks (io/hdf5.py:
    # at most 256 outputs or 2 s buffered), so after a kill it holds a prefix of the CSV's
    # rows, never more, and loses at most one block
    assert len(h["t"]) - 256 <= n <= len(h["t"])
    if n:
        np.testing.assert_array_equal(r["history"]["t"], h["t"][:n])
        # snapshots every output.snapshot_every (default t_end/100 = 2 s: every 200th output)
        # among the rows written, none lost with them
        t_snap = h["t"][:n][np.round(h["t"][:n] / 0.01) % 200 == 0]
        np.testing.assert_array_equal(r["snapshots"]["t"], t_snap)
        assert r["snapshots"]["y"].shape == (len(t_snap), 12)


def _wait_checkpoint(out, proc, timeout=60.0):
    """Until summary.json names a checkpoint (it is rewritten just after each one)."""
    t0 = time.time()
    while time.time() - t0 < timeout:
        try:
            if json.loads((out / "summary.json").read_text()).get("checkpoint_t") is not None:
                return
        except (OSError, ValueError):
            pass
        if proc.poll() is not None:
            raise AssertionError(f"run ended early: {proc.communicate()}")
        time.sleep(0.02)
    raise AssertionError("no checkpoint")


def _same_run(a, b):
    """Final checkpoints, history.csv and results.h5 of two run directories are equal, bit
    for bit."""
    ca, cb = _final_state(a), _final_state(b)
    assert ca["t"] == cb["t"] and ca["stats"]["steps"] == cb["stats"]["steps"]
    for k in ca["state"]:
        assert np.array_equal(ca["state"][k], cb["state"][k]), k
    ha, hb = read_history(a / "history.csv"), read_history(b / "history.csv")
    assert ha.keys() == hb.keys() and all(np.array_equal(ha[k], hb[k]) for k in ha)
    ra, rb = read_results(a / "results.h5"), read_results(b / "results.h5")
    for group in ("history", "snapshots"):
        assert all(np.array_equal(ra[group][k], rb[group][k]) for k in ra[group]), group


def test_sigkill_after_the_first_checkpoint_resumes_bitwise(tmp_path, capsys):
    """A run killed (SIGKILL) just after its first checkpoint (the first output time, long
    before output.checkpoint_every = 60 s) has a summary saying "running" at that
    checkpoint; a new run into its directory is refused with the advice to --resume, and
    the resumed run equals an uninterrupted one bit for bit (state, history, HDF5). Both
    span 200 s, so both use the compiled kernels (short heavy-top runs use NumPy's, which
    round differently)."""
    sets = ["--set", "t_end=200", "--set", "output.every=0.01", "--set", "output.plots=false"]
    out = tmp_path / "killed"
    p = _spawn(["run", "heavy_top", "--quiet", "--out", str(out)] + sets, tmp_path)
    _wait_checkpoint(out, p)
    p.send_signal(signal.SIGKILL)
    p.communicate(timeout=30)
    t_ck = read_checkpoint(out / "checkpoint.npz")["t"]
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "running" and s["checkpoint_t"] == t_ck and s["steps"] == round(t_ck / 1e-3)
    assert 0 < t_ck < 200
    assert main(["run", "heavy_top", "--quiet", "--out", str(out)] + sets) == 2
    advice = capsys.readouterr().err
    assert f"(running; checkpoint at t={t_ck:.6g} s); continue it with `liegroup-int run --resume {out}`" in advice
    capsys.readouterr()
    assert main(["run", "--quiet", "--resume", str(out)]) == 0
    line = capsys.readouterr().out.splitlines()[0]  # the steps are the whole run's, the time this process's
    assert f"{round(200 / 1e-3)} steps" in line and f"since the resume at t = {t_ck:.6g} s" in line
    full = tmp_path / "full"
    assert main(["run", "heavy_top", "--quiet", "--out", str(full)] + sets) == 0
    _same_run(full, out)
    assert json.loads((out / "summary.json").read_text())["status"] == "ok"


def test_a_run_without_checkpoint_is_restarted_with_overwrite(tmp_path, capsys):
    """output.checkpoint_every = 0: no checkpoint before the end. Killed, the directory
    holds history rows and a "running" summary without checkpoint: --resume and a new run
    into it give the same line, saying to start again with --overwrite, which works."""
    out = tmp_path / "run"
    args = ["run", "heavy_top", "--quiet", "--out", str(out), "--set", "output.checkpoint_every=0",
            "--set", "output.every=0.01"]
    p = _spawn(args + ["--set", "t_end=200"], tmp_path)
    _wait_rows(out / "history.csv", 5, p)
    p.send_signal(signal.SIGKILL)
    p.communicate(timeout=30)
    assert not (out / "checkpoint.npz").exists()
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "running" and s["checkpoint_t"] is None
    expected = (f"error: {out}: holds a run of heavy_top (running) without a checkpoint, so it cannot be resumed; "
                f"start it again with `liegroup-int run heavy_top --out {out} --overwrite`, or give --out another "
                f"directory\n")
    assert main(["run", "--quiet", "--resume", str(out)]) == 2 and capsys.readouterr().err == expected
    assert main(args + ["--set", "t_end=0.1"]) == 2 and capsys.readouterr().err == expected
    assert main(args + ["--set", "t_end=0.1", "--overwrite"]) == 0
    assert json.loads((out / "summary.json").read_text())["status"] == "ok"


def test_a_checkpoint_whose_points_differ_is_refused_in_one_line(tmp_path, capsys):
    """A Galerkin checkpoint holds the rotations at the quadrature points. One written with
    ``gauss-spline`` (71 points at n_ctrl = 31) but recorded as ``space.quadrature =
    "auto"``, which now builds ``gauss-spline-reduced`` (58 points): --resume says which
    state array differs and where, exits 2 and leaves the run directory as it was (without
    the check the compiled kernels read past the arrays and the process aborted)."""
    out = tmp_path / "run"
    assert main(["run", "pendulum", "--quiet", "--no-plots", "--out", str(out), "--set", "t_end=0.01",
                 "--set", "space.quadrature=gauss-spline"]) == 0
    ck = out / "checkpoint.npz"
    with np.load(ck, allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    meta = json.loads(str(arrays["meta"]))
    meta["scene_keys"]["space.quadrature"] = "auto"
    arrays["meta"] = np.array(json.dumps(meta))
    np.savez(ck, **arrays)
    before = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}
    capsys.readouterr()
    assert main(["run", "--quiet", "--resume", str(out), "--set", "t_end=0.02"]) == 2
    err = capsys.readouterr().err
    assert err == (f"error: {ck}: the checkpoint's state 'K' has shape (71, 3), the scene as it builds now has "
                   f"(58, 3) (its discretization's points differ, e.g. another quadrature rule); the run cannot be "
                   f"resumed: start a new run\n")
    assert {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()} == before


def test_energy_guard_stops_an_exploding_energy(tmp_path):
    from liegroup_int.integrators import BlowUpError, Stats
    from liegroup_int.io import HistoryWriter
    from liegroup_int.runner import EnergyGuard

    energies = iter([0.0, 1e-9, 1e-3, 0.5, 1.0, 0.9, 2.0e3])
    w = HistoryWriter(tmp_path / "h.csv", {"energy": lambda t, y: next(energies)})
    guard = EnergyGuard(w, 1e3, lambda: Stats(steps=7))
    for k in range(6):  # growth from rest (0 -> 1) is not a blow-up; 2000 > 1000 * 1.0 is
        w(float(k), None)
        guard(float(k), None)
    w(6.0, None)
    with pytest.raises(BlowUpError, match="energy grew to 2e\\+03"):
        guard(6.0, None)
    w.close()
