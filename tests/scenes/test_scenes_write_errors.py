"""A failing write (a full disk, simulated: ENOSPC) stops a run like any other fault: one
line naming the file and the error, exit code 3, the last complete checkpoint kept, and the
run resumable from it once there is space again."""

from __future__ import annotations

import errno
import json

import numpy as np
import pytest

import liegroup_int.io.hdf5 as hdf5
import liegroup_int.io.paraview as paraview
import liegroup_int.runner as runner
from liegroup_int.cli import main
from liegroup_int.io import HistoryWriter
from liegroup_int.io.checkpoint import read_checkpoint

#: The pendulum, short: 20 outputs over 0.02 s at its stable step, checkpoints at the first
#: output and then at every output (checkpoint_every below the time of one output).
SETS = ["t_end=0.02", "output.every=1e-3", "output.plots=false", "output.checkpoint_every=1e-9"]
ENOSPC = "No space left on device"


def _run(out, *extra):
    argv = ["run", "pendulum", "--quiet", "--out", str(out)]
    for s in SETS + list(extra):
        argv += ["--set", s]
    return main(argv)


def _fail_after(n_ok, filename):
    """A write that succeeds ``n_ok`` times, then raises ENOSPC naming ``filename``."""
    calls = [0]

    def check():
        calls[0] += 1
        if calls[0] > n_ok:
            raise OSError(errno.ENOSPC, ENOSPC, str(filename))

    return check


def _history_fails(monkeypatch, out):
    check = _fail_after(5, out / "history.csv")
    real = HistoryWriter.__call__
    monkeypatch.setattr(HistoryWriter, "__call__", lambda self, t, y: (check(), real(self, t, y))[1])
    return out / "history.csv"


def _checkpoint_fails(monkeypatch, out):
    check = _fail_after(3, out / "checkpoint.npz.tmp.npz")
    real = runner.write_checkpoint
    monkeypatch.setattr(runner, "write_checkpoint", lambda *a: (check(), real(*a))[1])
    return out / "checkpoint.npz.tmp.npz"


def _paraview_fails(monkeypatch, out):
    real = paraview._atomic_write
    check = _fail_after(8, out / "beam.pvd")

    def write(path, text):
        if path.suffix == ".pvd":
            check()
        real(path, text)

    monkeypatch.setattr(paraview, "_atomic_write", write)
    return out / "beam.pvd"


def _hdf5_fails(monkeypatch, out):
    """The disk of results.h5 reports no free space from the third block on (results.h5 is
    written in blocks at each checkpoint, here each output)."""
    import shutil

    real = shutil.disk_usage
    calls = [0]

    def usage(path):
        calls[0] += 1
        u = real(path)
        return u._replace(free=0) if calls[0] > 2 else u

    monkeypatch.setattr(hdf5.shutil, "disk_usage", usage)
    return out / "results.h5"


@pytest.mark.parametrize("fail", [_history_fails, _checkpoint_fails, _paraview_fails, _hdf5_fails],
                         ids=["history", "checkpoint", "paraview", "hdf5"])
def test_a_failing_write_stops_the_run_in_one_line_and_it_resumes(tmp_path, capsys, monkeypatch, fail):
    """Each writer's file fails after a few outputs: the run stops with one line naming that
    file and ENOSPC, exit code 3; the summary records the failure; the checkpoint on disk is
    an earlier complete one, and with the write working again, --resume finishes the run to
    the same final state as a run that never failed, bit for bit."""
    out = tmp_path / "run"
    path = fail(monkeypatch, out)
    assert _run(out) == 3
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert err.startswith(f"error: pendulum: cannot write {path}: {ENOSPC}")
    ck = read_checkpoint(out / "checkpoint.npz")
    assert f"the checkpoint at t={ck['t']:.6g} is kept" in err and f"--resume {out}`" in err
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "failed" and s["checkpoint_t"] == ck["t"] and ENOSPC in s["error"]
    assert 0 < ck["t"] < 0.02 and not list(out.rglob("*.tmp"))
    monkeypatch.undo()
    assert main(["run", "--quiet", "--resume", str(out)]) == 0
    full = tmp_path / "full"
    assert _run(full) == 0
    a, b = read_checkpoint(full / "checkpoint.npz"), read_checkpoint(out / "checkpoint.npz")
    assert a["t"] == b["t"] and all(np.array_equal(a["state"][k], b["state"][k]) for k in a["state"])


def test_a_write_failing_before_any_checkpoint_says_to_start_again(tmp_path, capsys, monkeypatch):
    out = tmp_path / "run"
    check = _fail_after(0, out / "history.csv")
    real = HistoryWriter.__call__
    monkeypatch.setattr(HistoryWriter, "__call__", lambda self, t, y: (check(), real(self, t, y))[1])
    assert _run(out) == 3
    err = capsys.readouterr().err
    assert err == (f"error: pendulum: cannot write {out / 'history.csv'}: {ENOSPC} at t=0; no checkpoint yet: free "
                   f"space, then `liegroup-int run pendulum --out {out} --overwrite`\n")
    assert not (out / "checkpoint.npz").exists()


def test_the_hdf5_block_is_refused_before_hdf5_sees_it(tmp_path, monkeypatch):
    """With too little room for the next block, flush raises ENOSPC naming results.h5 and
    writes nothing; the file keeps its earlier blocks and closes cleanly."""
    import shutil

    w = hdf5.Hdf5Writer(tmp_path / "r.h5", {"e": lambda t, y: t}, {}, lambda y: {"y": np.zeros(3)}, {})
    w(0.0, None)
    w.flush()
    w(1.0, None)
    real = shutil.disk_usage
    monkeypatch.setattr(hdf5.shutil, "disk_usage", lambda p: real(p)._replace(free=hdf5.HEADROOM))
    with pytest.raises(OSError, match="No space left on device") as exc:
        w.close()
    assert exc.value.errno == errno.ENOSPC and exc.value.filename == str(tmp_path / "r.h5")
    monkeypatch.undo()
    r = hdf5.read_results(tmp_path / "r.h5")
    assert r["history"]["t"].tolist() == [0.0] and r["snapshots"]["y"].shape == (1, 3)
