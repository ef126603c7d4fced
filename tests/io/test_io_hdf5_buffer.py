"""The HDF5 writer's blocks: what is on disk when, and ParaView only when asked."""

import numpy as np

from liegroup_int.cli import main
from liegroup_int.io.hdf5 import Hdf5Writer, read_results


def _writer(path, **kw):
    return Hdf5Writer(path, {"x": lambda t, y: float(y[0])}, {}, lambda y: {"y": y}, {"scene": "test"}, **kw)


def test_outputs_are_written_in_blocks_and_at_close(tmp_path):
    path = tmp_path / "r.h5"
    w = _writer(path, flush_outputs=4, flush_s=1e9)
    for k in range(6):
        w(0.1 * k, np.array([k, 2.0 * k]))
        if k == 2:  # three outputs pending: nothing written yet, the file is readable
            assert "t" not in read_results(path)["history"]
    r = read_results(path)  # the fourth output wrote the block of four
    np.testing.assert_array_equal(r["history"]["x"], [0.0, 1.0, 2.0, 3.0])
    w.close()  # the rest at the end
    r = read_results(path)
    np.testing.assert_array_equal(r["history"]["t"], 0.1 * np.arange(6))
    np.testing.assert_array_equal(r["snapshots"]["y"], np.stack([np.arange(6.0), 2.0 * np.arange(6.0)], axis=1))


def test_an_explicit_flush_writes_everything_pending(tmp_path):
    path = tmp_path / "r.h5"
    w = _writer(path, flush_outputs=100, flush_s=1e9)
    w(0.0, np.array([1.0]))
    w(1.0, np.array([2.0]))
    w.flush()  # what a checkpoint does before it is written
    np.testing.assert_array_equal(read_results(path)["history"]["x"], [1.0, 2.0])
    w.close()


def test_paraview_only_when_asked(tmp_path):
    common = ["--quiet", "--set", "t_end=2e-4", "--set", "output.every=5e-5", "--set", "space.n_ctrl=11",
              "--set", "integrator.dt=1e-6"]
    assert main(["run", "cantilever", "--out", str(tmp_path / "off"), *common]) == 0  # default: off
    assert not (tmp_path / "off" / "paraview").exists() and not (tmp_path / "off" / "beam.pvd").exists()
    assert main(["run", "cantilever", "--out", str(tmp_path / "on"), *common, "--set", "output.paraview=true"]) == 0
    assert len(list((tmp_path / "on" / "paraview").glob("*.vtu"))) == 5  # t = 0 and 4 outputs


def test_timing_breakdown_and_no_plots(tmp_path):
    """summary.json splits the run's time; --no-plots draws nothing and costs nothing."""
    import json

    out = tmp_path / "run"
    assert main(["run", "heavy_top", "--quiet", "--no-plots", "--out", str(out), "--set", "t_end=0.2"]) == 0
    s = json.loads((out / "summary.json").read_text())
    timing = s["timing"]
    assert set(timing) == {"compile_s", "setup_s", "integrate_s", "output_s", "plots_s"}
    assert all(v >= 0 for v in timing.values()) and s["plots"] == []
    assert not (out / "history.png").exists()
    # the loop's wall time is the integration plus the outputs written inside it
    assert timing["integrate_s"] + timing["output_s"] >= 0.99 * s["wall_time_s"]


def test_progress_line_shows_steps_and_rate(capsys):
    """One comma between the times and the postfix (tqdm adds it), and the steps per second
    of this run."""
    from liegroup_int.integrators import Stats
    from liegroup_int.runner import Progress

    p = Progress(0.0, 1.0, enabled=True)
    p(0.1, None, Stats(steps=0))
    p._last = 0.0  # let the next update through
    p(0.5, None, Stats(steps=1000))
    p.close(1.0)
    err = capsys.readouterr().err
    assert ", ," not in err and "1000 steps, " in err and "steps/s]" in err
