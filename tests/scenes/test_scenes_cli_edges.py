"""First-hour edges of the CLI: resume rules, the SCENE of a resume, unwritable outputs."""

import csv
import json

from liegroup_int.cli import main


def _pendulum(tmp_path):
    out = tmp_path / "pend"
    assert main(["run", "pendulum", "--quiet", "--no-plots", "--out", str(out), "--set", "t_end=0.02"]) == 0
    return out


def test_resume_refuses_a_changed_discretization_and_leaves_the_run_alone(tmp_path, capsys):
    out = _pendulum(tmp_path)
    before = (out / "summary.json").read_text()
    rc = main(["run", "--resume", str(out), "--set", "t_end=0.04", "--set", "space.n_ctrl=61"])
    err = capsys.readouterr().err
    assert rc == 2 and "key 'space.n_ctrl' cannot change on resume" in err and err.count("\n") == 1
    assert (out / "summary.json").read_text() == before  # untouched
    # an unchanged value and the safe keys are accepted
    assert main(["run", "--resume", str(out), "--quiet", "--set", "t_end=0.04", "--set", "space.n_ctrl=31",
                 "--no-plots"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["t_reached"] == 0.04
    # history_rows counts the whole file, like the cumulative steps
    rows = len((out / "history.csv").read_text().strip().splitlines()) - 1
    assert summary["history_rows"] == rows == 9  # t = 0 and every 0.005 s to 0.04


def test_resume_scene_is_optional_and_must_match(tmp_path, capsys):
    out = _pendulum(tmp_path)
    rc = main(["run", "cantilever", "--resume", str(out), "--set", "t_end=0.04"])
    err = capsys.readouterr().err
    assert rc == 2 and "holds a run of builtin:pendulum, not cantilever" in err
    assert main(["run", "pendulum", "--resume", str(out), "--quiet", "--set", "t_end=0.03"]) == 0
    assert main(["run"]) == 2 and "give a SCENE" in capsys.readouterr().err


def test_an_unwritable_out_is_one_line(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    rc = main(["run", "heavy_top", "--quiet", "--out", str(blocker / "run")])
    err = capsys.readouterr().err
    assert rc == 2 and err.startswith("error: cannot write") and err.count("\n") == 1 and "Traceback" not in err


def test_an_existing_run_is_not_mixed_with_a_new_one(tmp_path, capsys):
    out = tmp_path / "run"
    args = ["run", "heavy_top", "--quiet", "--no-plots", "--out", str(out), "--set", "t_end=0.1"]
    assert main(args) == 0
    (out / "stale.vtu").write_text("old")
    assert main(args) == 2
    assert capsys.readouterr().err == (f"error: {out}: holds a run of heavy_top (ok; checkpoint at t=0.1 s); continue "
                                       f"it with `liegroup-int run --resume {out}` (--set t_end=T to extend it), "
                                       f"replace it with --overwrite, or give --out another directory\n")
    assert (out / "stale.vtu").exists()  # refused: untouched
    assert main(args + ["--overwrite"]) == 0
    assert not (out / "stale.vtu").exists() and (out / "summary.json").exists()


def test_outputs_finer_than_the_step_are_announced(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["run", "heavy_top", "--quiet", "--no-plots", "--out", str(out), "--set", "t_end=0.05",
                 "--set", "integrator.dt=0.01", "--set", "output.every=0.001"]) == 0
    err = capsys.readouterr().err
    assert "output.every = 0.001 s is below the step dt = 0.01 s: one output per step, 5 outputs" in err
    assert json.loads((out / "summary.json").read_text())["history_rows"] == 6  # t = 0 and 5 steps


def test_converge_refuses_a_rate_through_round_off(tmp_path, capsys):
    """The old user-guide example: time errors of 1e-14 on the pendulum are rounding; the
    command flags them and fits no rate."""
    out = tmp_path / "conv"
    rc = main(["converge", "pendulum", "--param", "integrator.dt", "--values", "1e-5", "5e-6", "2.5e-6", "1.25e-6",
               "--set", "t_end=0.01", "--serial", "--out", str(out)])
    text = capsys.readouterr().out
    assert rc == 0 and text.count("within 100x of round-off: not fitted") == 3
    assert "no rate fitted: 3 of 3 errors are within 100x of the round-off floor" in text
    assert "fitted rate:" not in text


def test_converge_with_every_run_refused_is_one_line(tmp_path, capsys):
    out = tmp_path / "conv"
    # RK2 at both steps amplifies the pendulum's fastest mode (|lambda|max = 2.368e4 1/s) by
    # 2.7e25x and 9.1e9x over the run (measured): the dt guard refuses both before a step
    rc = main(["converge", "pendulum", "--param", "integrator.dt", "--values", "6e-5", "4e-5", "--set", "t_end=0.01",
               "--set", "integrator.method=rkmk2", "--serial", "--out", str(out)])
    err = capsys.readouterr().err
    assert rc == 3 and "error: no convergence table: no successful run" in err and "Traceback" not in err
    assert (out / "study.csv").exists()


def test_did_you_mean(capsys):
    assert main(["run", "cantilevr"]) == 2
    assert "did you mean 'cantilever'?" in capsys.readouterr().err
    assert main(["run", "heavy_top", "--set", "integrator.mthod=rkmk4"]) == 2
    assert "unknown key 'integrator.mthod' (did you mean 'integrator.method'?)" in capsys.readouterr().err


def test_ctrl_c_during_a_study_keeps_the_finished_runs_and_a_rerun_continues(tmp_path):
    import signal
    import subprocess
    import sys
    import time

    out = tmp_path / "study"
    # undamped pendulum runs (no dense spectrum at set-up) of 0.1 s, 1667 to 13,334 steps:
    # measured 0.05 s to 0.35 s of integration each, 0.6 s for the last three, so the signal,
    # sent within a 20 ms poll of the second run's start, lands before the study ends
    cmd = [sys.executable, "-m", "liegroup_int", "converge", "pendulum", "--param", "integrator.dt", "--values",
           "6e-5", "3e-5", "1.5e-5", "7.5e-6", "--set", "t_end=0.1", "--set", "material.kelvin_voigt=0",
           "--set", "guard.spectrum=false", "--set", "output.hdf5=false",
           "--set", "output.plots=false", "--set", "output.paraview=false", "--serial", "--out", str(out)]
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    first = out / "run_000" / "summary.json"  # "running" from the start, "ok" once finished
    second = out / "run_001" / "summary.json"

    def status(path):
        try:
            return json.loads(path.read_text())
        except (OSError, ValueError):
            return {}

    # the signal goes once the second run has written its first checkpoint (its time loop
    # is under way, with its signal handler); the first run is finished by then
    t0 = time.time()
    while status(second).get("checkpoint_t") is None and p.poll() is None and time.time() - t0 < 120:
        time.sleep(0.02)
    assert status(second).get("checkpoint_t") is not None and status(first).get("status") == "ok", p.communicate()
    p.send_signal(signal.SIGINT)
    _, err = p.communicate(timeout=120)
    assert p.returncode == 130, err
    assert err.count("\n") == 1 and "interrupted after" in err and "Traceback" not in err
    rows = list(csv.DictReader((out / "study.csv").open()))
    assert len(rows) >= 1 and all(r["status"] == "ok" for r in rows)
    stamp = first.stat().st_mtime_ns
    # the same command again: the finished runs are kept, the rest run
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert first.stat().st_mtime_ns == stamp
    assert len(list(csv.DictReader((out / "study.csv").open()))) == 4
