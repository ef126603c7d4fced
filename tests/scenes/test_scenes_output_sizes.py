"""Outputs sized for the run: state snapshots and ParaView files at their own interval
(``output.snapshot_every``, ``output.paraview_every``), history rows at ``output.every``,
and the sizes of the outputs reported in summary.json and after the run's line."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET

import h5py
import numpy as np
import pytest

from liegroup_int.budget import TEXT_FLOAT_BYTES
from liegroup_int.cli import main
from liegroup_int.io import read_history
from liegroup_int.io.hdf5 import CHUNK_BYTES, read_results
from liegroup_int.scenes import KINDS, SceneError, build_scene, builtin_path, load_scene, output_stride
from liegroup_int.scenes.schema import flatten, read_toml

#: The pendulum, short: 20 outputs of 20 steps (dt = 5e-5 s) each over 0.02 s.
SETS = {"t_end": "0.02", "output.every": "1e-3"}


def _argv(out, **sets):
    argv = ["run", "pendulum", "--quiet", "--out", str(out)]
    for k, v in {**SETS, **sets}.items():
        argv += ["--set", f"{k}={v}"]
    return argv


def _pvd_times(out):
    return [float(d.get("timestep")) for d in ET.parse(out / "beam.pvd").getroot().iter("DataSet")]


@pytest.mark.parametrize("key", ["output.paraview_every", "output.snapshot_every"])
@pytest.mark.parametrize("value, expected", [
    ("0", "expected a positive number"),
    ("-1e-3", "expected a positive number"),
    ("'often'", "expected a finite number [s]"),
    ("nan", "expected a finite number [s]"),
    ("0.05", "expected <= t_end = 0.02"),
    ("5e-4", "expected >= output.every = 0.001 s"),
])
def test_bad_intervals_are_refused_in_one_line(tmp_path, capsys, key, value, expected):
    out = tmp_path / "run"
    assert main(_argv(out, **{key: value})) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"error: builtin:pendulum: key '{key}'"), err
    assert expected in err and "Traceback" not in err
    assert not out.exists()


def test_below_the_default_output_interval_is_refused():
    """Without output.every, the floor is its default t_end/200 (0.05 s for heavy_top's 10 s)."""
    given = flatten(read_toml(builtin_path("heavy_top")))
    del given["output.every"]
    assert build_scene({**given, "output.snapshot_every": 0.05}, "top.toml", "top").output.snapshot_every == 0.05
    with pytest.raises(SceneError, match=r"^top.toml: key 'output.snapshot_every' = 0.04: expected >= output.every "
                                         r"\(default t_end/200\) = 0.05 s"):
        build_scene({**given, "output.snapshot_every": 0.04}, "top.toml", "top")


def test_rounding_rule():
    """Nearest whole multiple of the record interval, halves up, at least one; default
    t_end/100."""
    assert output_stride(4e-3, 0.02, 1e-3) == 4
    assert output_stride(2.6e-3, 0.02, 1e-3) == 3 and output_stride(2.4e-3, 0.02, 1e-3) == 2
    assert output_stride(3.5, 100.0, 1.0) == 4 and output_stride(2.5, 100.0, 1.0) == 3
    assert output_stride(1e-3, 0.02, 1e-3) == 1 and output_stride(None, 0.02, 1e-3) == 1
    assert output_stride(None, 10.0, 0.005) == 20


def test_files_at_their_own_interval(tmp_path, capsys):
    """paraview_every = 4 every: VTU files at outputs 0, 4, ..., 20 (6); snapshot_every =
    2.6e-3 rounds to 3 outputs: snapshots at 0, 3, ..., 18 and the last output, 20 (8);
    history rows at every output (21)."""
    out = tmp_path / "run"
    assert main(_argv(out, **{"output.paraview_every": "4e-3", "output.snapshot_every": "2.6e-3",
                              "output.plots": "false"})) == 0
    h = read_history(out / "history.csv")
    np.testing.assert_allclose(h["t"], 1e-3 * np.arange(21), rtol=0, atol=1e-12)
    vtu = sorted((out / "paraview").glob("beam_*.vtu"))
    assert [p.name for p in vtu] == [f"beam_{k:05d}.vtu" for k in range(6)]
    np.testing.assert_allclose(_pvd_times(out), 4e-3 * np.arange(6), rtol=0, atol=1e-12)
    r = read_results(out / "results.h5")
    np.testing.assert_array_equal(r["history"]["t"], h["t"])
    t_snap = np.array([h["t"][k] for k in (0, 3, 6, 9, 12, 15, 18, 20)])
    np.testing.assert_array_equal(r["snapshots"]["t"], t_snap)
    assert r["snapshots"]["c"].shape[0] == 8
    s = json.loads((out / "summary.json").read_text())
    assert (s["history_rows"], s["snapshots"], s["paraview_files"]) == (21, 8, 6)
    assert s["output_strides"] == {"snapshot": 3, "paraview": 4}


def test_reported_sizes_are_the_files_on_disk(tmp_path, capsys):
    """summary.json's output_bytes per kind equal the sizes of the files (with the plots,
    whose sizes are added once they are drawn), and the line after the run's line gives
    them."""
    out = tmp_path / "run"
    assert main(_argv(out)) == 0
    lines = capsys.readouterr().out.splitlines()
    s = json.loads((out / "summary.json").read_text())
    b = s["output_bytes"]
    size = {p.name: p.stat().st_size for p in out.iterdir() if p.is_file()}
    vtu = sum(p.stat().st_size for p in (out / "paraview").glob("*.vtu"))
    assert b == {"history.csv": size["history.csv"], "results.h5": size["results.h5"],
                 "checkpoint.npz": size["checkpoint.npz"], "paraview": vtu + size["beam.pvd"],
                 "plots": size["history.png"] + size["shapes.png"] + size["shapes.npz"]}
    assert len(lines) == 2 and lines[0].startswith("pendulum: ")
    assert lines[1].startswith("outputs ") and "history.csv" in lines[1] and "(21 rows)" in lines[1]
    assert f"ParaView {b['paraview'] / 1e3:.3g} kB ({s['paraview_files']} files)" in lines[1]
    assert "ms of output per history row" in lines[1]


def test_resume_keeps_the_intervals_and_may_change_them(tmp_path):
    """A run of 0.01 s resumed to 0.02 s: without the keys it keeps the run's own strides
    (their default t_end/100 would change with t_end); given on resume, they apply from
    the checkpoint on. The VTU files past the checkpoint of the first run are replaced."""
    out = tmp_path / "run"
    sets = {"t_end": "0.01", "output.every": "5e-4", "output.plots": "false"}
    argv = ["run", "pendulum", "--quiet", "--out", str(out)] + sum((["--set", f"{k}={v}"] for k, v in sets.items()), [])
    assert main(argv + ["--set", "output.paraview_every=2e-3"]) == 0
    assert main(["run", "--quiet", "--resume", str(out), "--set", "t_end=0.02",
                 "--set", "output.paraview_every=5e-3"]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["output_strides"] == {"snapshot": 1, "paraview": 10}  # 0.01/100 < every: 1, kept
    # up to 0.01: every 4th output (and 0.01 itself, the first run's last); then every 10th
    np.testing.assert_allclose(_pvd_times(out), [0.0, 0.002, 0.004, 0.006, 0.008, 0.01, 0.015, 0.02], atol=1e-12)
    assert len(list((out / "paraview").glob("*.vtu"))) == 8 == s["paraview_files"]
    r = read_results(out / "results.h5")
    np.testing.assert_array_equal(r["snapshots"]["t"], r["history"]["t"])  # stride 1 throughout


def test_bytes_per_row_and_per_snapshot_are_bounded(tmp_path):
    """200 outputs of the pendulum, a snapshot and a VTU file at every 5th (41 of each):
    bytes per history row, per snapshot and per VTU file stay under bounds from the values
    they hold.

    * history.csv: at most TEXT_FLOAT_BYTES (24) per value: a float's repr is at most 24
      characters (sign, 17 digits, point, exponent e-308) and one separator, less the
      leading zero such a long repr never has; plus the header;
    * results.h5: the values (8 bytes each: history rows and state snapshots), plus less
      than one chunk per dataset (HDF5 allocates whole chunks of CHUNK_BYTES, 64 KiB), plus
      64 KiB of metadata (object headers, chunk indexes, the scene attribute: 42 kB
      measured for 12 datasets). Chunks of 256 snapshots, far more than a run of t_end/100
      snapshots fills, would exceed it by 1 MB here;
    * a VTU file: TEXT_FLOAT_BYTES per value plus 1 kB of XML (the budget's estimate).
    """
    out = tmp_path / "run"
    assert main(_argv(out, t_end="0.2", **{"output.snapshot_every": "5e-3", "output.paraview_every": "5e-3",
                                          "output.plots": "false"})) == 0
    s = json.loads((out / "summary.json").read_text())
    rows = s["history_rows"]
    assert rows == 201 and s["snapshots"] == 41 and s["paraview_files"] == 41
    scene = load_scene("pendulum", {"t_end": 0.2})
    sim = KINDS[scene.kind].build(scene)
    snap = sum(np.asarray(a).nbytes for a in sim.to_arrays(sim.y0).values())
    n_cols = len(read_history(out / "history.csv"))
    header = len((out / "history.csv").read_text().splitlines()[0]) + 1
    assert (s["output_bytes"]["history.csv"] - header) / rows <= TEXT_FLOAT_BYTES * n_cols
    with h5py.File(out / "results.h5", "r") as f:
        n_sets = len(f["history"]) + len(f["snapshots"])
    values = rows * 8 * n_cols + s["snapshots"] * (snap + 8)
    assert s["output_bytes"]["results.h5"] <= values + n_sets * CHUNK_BYTES + 2**16
    points, frames, data = sim.frames(sim.y0)
    n_float = np.size(points) + np.size(frames) + sum(np.size(a) for a in data.values())
    for p in sorted((out / "paraview").glob("*.vtu"))[::10]:
        assert p.stat().st_size <= TEXT_FLOAT_BYTES * n_float + 1024, p.name
