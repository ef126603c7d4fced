"""Fuzzing the scene loader: any input gives a valid scene or a one-line SceneError.

Files of any bytes (other encodings, binary, a byte-order mark) and extreme settings (steps
below the floor, more outputs than the maximum, outputs beyond the memory or the disk) are
refused in one line with exit code 2 before anything is written."""

import json
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from liegroup_int.scenes import (
    SceneError,
    build_scene,
    builtin_names,
    builtin_path,
    load_scene,
)
from liegroup_int.cli import main
from liegroup_int.scenes.schema import flatten, read_toml

BASES = {name: flatten(read_toml(builtin_path(name))) for name in builtin_names()}
# keep the fuzzed beams small so building a scene stays cheap
for v in BASES.values():
    if "space.n_ctrl" in v:
        v["space.n_ctrl"] = 8
        v["space.degree"] = min(v.get("space.degree", 4), 4)

scalars = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(min_value=-10**6, max_value=10**6),
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([1e-300, 5e-324, 1e300, 1e9, 2**63]),  # extreme steps, spans and counts
    st.text(max_size=8),
)
values = st.one_of(scalars, st.lists(scalars, max_size=4), st.lists(st.lists(scalars, max_size=3), max_size=3))
key_names = st.sampled_from(sorted({k for v in BASES.values() for k in v} | {"integrator.mthod", "space", "x.y.z"}))


@st.composite
def mutated_scene(draw):
    base = dict(BASES[draw(st.sampled_from(sorted(BASES)))])
    for _ in range(draw(st.integers(min_value=1, max_value=4))):
        op = draw(st.sampled_from(["set", "delete", "add"]))
        key = draw(key_names)
        if op == "delete":
            base.pop(key, None)
        else:
            val = draw(values)
            if val is None:
                continue  # TOML has no null
            base[key] = val
    return base


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(mutated_scene())
def test_loader_gives_scene_or_one_line_error(given_keys):
    try:
        scene = build_scene(given_keys, "fuzz.toml", "fuzz")
    except SceneError as exc:
        msg = str(exc)
        assert msg.startswith("fuzz.toml") and "\n" not in msg
        return
    assert scene.t_end > 0 and math.isfinite(scene.t_end)


@pytest.mark.parametrize("over, key", [({"section.d": 1.157920892373162e+77}, "section.d"),
                                       ({"section.shape": "square", "section.t": 1e200}, "section.t")])
def test_overflowing_section_is_one_line_error(over, key):
    """A size whose section constants overflow a float (a case the fuzz test above finds:
    unguarded, it raises OverflowError) is refused naming the key, once."""
    with pytest.raises(SceneError) as err:
        load_scene("pendulum", over)
    msg = str(err.value)
    assert f"key '{key}': too large" in msg and msg.count("builtin:pendulum") == 1


# ---------------------------------------------------------------------- files of any bytes
@settings(max_examples=300, deadline=None)
@given(st.binary(max_size=64), st.booleans())
def test_any_bytes_give_a_table_or_one_line_error(tmp_path_factory, data, bom):
    path = tmp_path_factory.mktemp("bytes") / "s.toml"
    path.write_bytes((b"\xef\xbb\xbf" if bom else b"") + data)
    try:
        assert isinstance(read_toml(path), dict)
    except SceneError as exc:
        assert str(exc).startswith(str(path)) and "\n" not in str(exc)


def _heavy_top_text() -> bytes:
    return builtin_path("heavy_top").read_bytes()


@pytest.mark.parametrize("data, expected", [
    (b'name = "caf\xe9"\n', "not UTF-8 text (byte 0xe9 at line 1, column 12); save the scene as UTF-8"),
    (b"\x7fELF\x02\x01\x01\x00\x00", "a binary file (NUL byte at offset 7), not a TOML scene"),
    ("t_end = 1.0\n".encode("utf-16"), "a UTF-16 file; save the scene as UTF-8 text"),
])
def test_bad_files_refused_in_one_line(tmp_path, capsys, data, expected):
    path = tmp_path / "bad.toml"
    path.write_bytes(data)
    assert main(["run", str(path), "--out", str(tmp_path / "out")]) == 2
    assert capsys.readouterr().err == f"error: {path}: {expected}\n"
    assert not (tmp_path / "out").exists()


def test_byte_order_mark_accepted(tmp_path):
    path = tmp_path / "bom.toml"
    path.write_bytes(b"\xef\xbb\xbf" + _heavy_top_text())
    assert dict(load_scene(path).raw) == dict(load_scene("heavy_top").raw)


# ---------------------------------------------------------------------- extreme settings
@pytest.mark.parametrize("sets, expected", [
    (["integrator.dt=1e-300"], "key 'integrator.dt' = 1e-300: expected >= t_end / 1e+09 = 1e-08 s (at most 1e+09 "
                               "steps; 1e+301 asked); raise dt or shorten t_end"),
    (["t_end=1e9"], "key 'integrator.dt' = 0.001: expected >= t_end / 1e+09 = 1 s (at most 1e+09 steps; 1e+12 "
                    "asked); raise dt or shorten t_end"),
    (["t_end=20000", "output.every=0.001"], "key 'output.every' = 0.001: 2e+07 outputs over 20000 s, more than "
                                            "1e+06; give output.every >= 0.02 s or shorten t_end"),
    (["t_end=1e9", "integrator.dt=1", "output.every=1e-3"],
     "key 'output.every' = 0.001 (whole steps of 1 s: every 1 s): 1e+09 outputs over 1e+09 s, more than 1e+06; "
     "give output.every >= 1e+03 s or shorten t_end"),
    (["integrator.dt=none", "integrator.method=rkmk45", "integrator.rtol=1e-6", "t_end=1e7", "output.every=1"],
     "key 'output.every' = 1.0: 1e+07 outputs over 1e+07 s, more than 1e+06; give output.every >= 10 s or "
     "shorten t_end"),
])
def test_extreme_settings_refused_before_writing(tmp_path, capsys, sets, expected):
    out = tmp_path / "out"
    argv = ["run", "heavy_top", "--quiet", "--out", str(out)]
    for s in sets:
        argv += ["--set", s]
    assert main(argv) == 2
    assert capsys.readouterr().err == f"error: builtin:heavy_top: {expected}\n"
    assert not out.exists()


def test_auto_step_counts_checked_after_the_step_is_known(tmp_path, capsys):
    """dt = "auto" is resolved when the beam is built (9.85e-5 s for the Galerkin pendulum,
    so outputs every 1e-4 s land on every step): the output count is checked then, still
    before anything is written."""
    out = tmp_path / "out"
    assert main(["run", "pendulum", "--quiet", "--out", str(out), "--set", "t_end=100", "--set", "output.every=1e-4",
                 "--set", "integrator.dt=auto"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "1.02e+06 outputs over 100 s, more than 1e+06" in err
    assert "give output.every >= 0.000197 s" in err and not out.exists()


def test_disk_estimate_bounds_a_real_run(tmp_path):
    """The disk estimated from the initial state bounds what a pendulum run of 500 outputs
    writes (results.h5, history.csv, VTU files: 501 rows, and at the default t_end/100 101
    snapshots and 101 VTU files): at least all of it, at most 1.5x (text floats are counted
    at 24 bytes, their longest repr)."""
    from liegroup_int.budget import output_sizes
    from liegroup_int.scenes import KINDS

    out = tmp_path / "pm"
    assert main(["run", "pendulum", "--quiet", "--no-plots", "--out", str(out), "--set", "t_end=0.5",
                 "--set", "output.every=1e-3"]) == 0
    written = sum(p.stat().st_size for p in out.rglob("*") if p.is_file() and p.name not in ("checkpoint.npz",
                                                                                             "summary.json"))
    scene = load_scene("pendulum", {"t_end": 0.5, "output.every": 1e-3, "output.plots": False})
    sim = KINDS[scene.kind].build(scene)
    s = json.loads((out / "summary.json").read_text())
    assert (s["history_rows"], s["snapshots"], s["paraview_files"]) == (501, 101, 101)
    assert written <= output_sizes(scene, sim, sim.y0).disk(501, 101, 101) <= 1.5 * written


def test_outputs_beyond_memory_or_disk_refused(tmp_path):
    """1000 outputs of the pendulum: refused when they need more than half the memory
    given or more than the disk given, accepted at exactly the limits."""
    from liegroup_int.budget import check_budget, output_sizes
    from liegroup_int.scenes import KINDS

    scene = load_scene("pendulum", {"t_end": 1.0, "output.every": 1e-3})
    sim = KINDS[scene.kind].build(scene)
    sizes = output_sizes(scene, sim, sim.y0)
    snap = sum(np.asarray(a).nbytes for a in sim.to_arrays(sim.y0).values())
    assert sizes.snapshot_memory == snap  # the shapes
    assert 0 < sizes.row_memory < 8 * 64  # the time, the history row read back for the plot
    held, written = sizes.memory(1000, 1000), sizes.disk(1000, 1000, 1000)
    args = (scene, sim, sim.y0, 0.0, 1e-3, 1e-3, tmp_path / "out")
    assert check_budget(*args, memory=2 * held, disk=written) == 1000
    with pytest.raises(SceneError, match=r"1000 outputs \(every 0.001 s over 1 s\) would hold .* in memory, more "
                                         r"than half the .* available; raise output.every or output.snapshot_every, "
                                         r"or set output.plots=false"):
        check_budget(*args, memory=2 * held - 2, disk=10**12)
    with pytest.raises(SceneError, match=r"would write .*, more than the .* free in .*out; raise output.every \(or "
                                         r"output.snapshot_every / output.paraview_every\), or set "
                                         r"output.hdf5=false / output.paraview=false"):
        check_budget(*args, memory=10**12, disk=written - 1)
    # one snapshot and one VTU file in ten outputs: the budget counts 100 of each
    assert check_budget(*args, memory=2 * sizes.memory(1000, 100), disk=sizes.disk(1000, 100, 100),
                        snapshot_stride=10, paraview_stride=10) == 1000
    with pytest.raises(SceneError, match="would write"):
        check_budget(*args, memory=10**12, disk=sizes.disk(1000, 100, 100) - 1, snapshot_stride=10,
                     paraview_stride=10)
