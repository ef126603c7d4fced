"""Scenes and the command line: loading, overrides, errors, outputs."""

import csv
import json
import subprocess
import sys

import numpy as np
import pytest

from liegroup_int.cli import main
from liegroup_int.integrators import eigenvalues
from liegroup_int.scenes.beam import problem
from liegroup_int.io import read_history
from liegroup_int.scenes import SceneError, builtin_names, load_scene, parse_override

RIGID = ["free_rigid_body", "heavy_top"]


def test_builtins_listed(capsys):
    assert set(RIGID + ["pendulum", "cantilever", "arch", "spinning_helix", "flying_spaghetti"]) <= set(builtin_names())
    assert main(["scenes"]) == 0
    out = capsys.readouterr().out
    assert all(name in out for name in builtin_names())


@pytest.mark.parametrize("name", builtin_names())
def test_every_builtin_validates(name):
    assert main(["validate", name]) == 0


@pytest.mark.parametrize("text, key, value", [
    ("integrator.dt=1e-4", "integrator.dt", 1e-4),
    ("integrator.method=rkmk6", "integrator.method", "rkmk6"),
    ("body.inertia=[1, 2, 2.5]", "body.inertia", [1, 2, 2.5]),
    ("bc.start = hinged", "bc.start", "hinged"),
])
def test_parse_override(text, key, value):
    assert parse_override(text) == (key, value)


def test_run_writes_history_and_summary(tmp_path):
    out = tmp_path / "run"
    rc = main(["run", "heavy_top", "--out", str(out), "--quiet", "--set", "t_end=0.5", "--set", "output.every=0.1"])
    assert rc == 0
    hist = read_history(out / "history.csv")
    np.testing.assert_allclose(hist["t"], [0.0, 0.1, 0.2, 0.3, 0.4, 0.5], atol=1e-12)
    assert {"energy", "casimir", "orth_error"} <= set(hist)
    s = json.loads((out / "summary.json").read_text())
    assert s["scene"] == "heavy_top" and s["method"] == "rkmk4" and s["steps"] == 500
    assert np.array(s["final"]["R"]).shape == (3, 3) and len(s["final"]["omega_body"]) == 3
    # RKMK4 at h=1e-3 over 0.5 s: energy drift ~1e-12 relative
    assert abs(hist["energy"][-1] - hist["energy"][0]) < 1e-9 * abs(hist["energy"][0])
    assert (out / "history.png").exists()


def test_beam_run_writes_tip_and_shapes(tmp_path):
    out = tmp_path / "pend"
    rc = main(["run", "pendulum", "--out", str(out), "--quiet", "--set", "t_end=0.01", "--set", "output.every=0.005"])
    assert rc == 0
    hist = read_history(out / "history.csv")
    assert {"tip_x", "tip_y", "tip_z", "energy"} <= set(hist)
    s = json.loads((out / "summary.json").read_text())
    assert len(s["final"]["tip"]) == 3 and s["final"]["tip"][2] < 0  # falling under gravity
    assert (out / "shapes.png").exists() and (out / "history.png").exists()


@pytest.mark.parametrize("args, fragment", [
    (["run", "no_such_scene"], "not a scene file and not a built-in"),
    (["run", "heavy_top", "--set", "integrator.mthod=rkmk4"], "unknown key 'integrator.mthod'"),
    (["run", "heavy_top", "--set", "integrator.dt=-1"], "'integrator.dt' = -1: expected a positive number"),
    (["run", "heavy_top", "--set", "t_end=0"], "'t_end' = 0: expected a positive number"),
    (["run", "heavy_top", "--set", "integrator.dt=20"], "expected a step <= t_end"),
    (["run", "heavy_top", "--set", "integrator.method=rkmk9"], "integrator.method"),
    (["run", "heavy_top", "--set", "body.inertia=[1, 1, 5]"], "triangle inequality"),
    (["run", "pendulum", "--set", "space.n_ctrl=4"], "space.n_ctrl"),
    (["run", "heavy_top", "--set", "integrator.rtol=1e-6"], "both given"),
    (["run", "heavy_top", "--set", "oops"], "expected KEY=VALUE"),
])
def test_bad_input_is_one_line_exit_2(args, fragment, capsys, tmp_path):
    rc = main(args + ["--out", str(tmp_path / "x")] if args[0] == "run" else args)
    err = capsys.readouterr().err
    assert rc == 2
    assert fragment in err and err.count("\n") == 1 and "Traceback" not in err


def test_bad_toml_file(tmp_path, capsys):
    f = tmp_path / "bad.toml"
    f.write_text("t_end = [1,\n")
    assert main(["validate", str(f)]) == 2
    assert "invalid TOML" in capsys.readouterr().err


def test_blow_up_exits_3_and_keeps_history(tmp_path, capsys):
    # the cantilever (default Galerkin, |lambda|max = 1.809e6 1/s) at 1.1x its stable RK4
    # step (|lambda| h = 3.1 > 2.83) diverges; the divergence is caught (measured: the
    # energy balance at the first output, 1.72e-5 s) and the rows written before it stay on disk
    out = tmp_path / "boom"
    rc = main(["run", "cantilever", "--out", str(out), "--quiet", "--set", "integrator.dt=1.72e-6",
               "--set", "t_end=0.01", "--set", "output.every=1.72e-5", "--set", "guard.dt=false"])
    err = capsys.readouterr().err
    # caught by the energy balance (or, if it grows between two outputs, the rotation guard or
    # the non-finite check); the diagnosis names the step as the cause, measured at the last
    # recorded state
    assert rc == 3 and err.count("\n") == 1
    assert "energy balance broken" in err or "non-finite" in err or "rotation increment" in err
    assert "cause: the step is beyond the stability limit" in err
    hist = read_history(out / "history.csv")
    assert len(hist["t"]) >= 2 and np.all(np.isfinite(hist["tip_z"]))
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "failed" and 0 < s["t_reached"] < 0.01


def test_console_script_entry_point(tmp_path):
    r = subprocess.run([sys.executable, "-m", "liegroup_int", "run", "heavy_top", "--quiet", "--out", str(tmp_path / "h"),
                        "--set", "t_end=0.01"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert "heavy_top" in r.stdout


def test_scene_file_with_override(tmp_path):
    f = tmp_path / "mytop.toml"
    f.write_text('problem = "rigid_body"\nt_end = 1.0\n[integrator]\ndt = 0.01\n[body]\ninertia = [1.0, 1.0, 1.5]\n')
    sc = load_scene(f, {"integrator.method": "rkmk6"})
    assert sc.name == "mytop" and sc.integrator.method == "rkmk6" and sc["body.inertia"] == (1.0, 1.0, 1.5)
    with pytest.raises(SceneError, match="mytop.toml: key 'body.mass'"):
        load_scene(f, {"body.mass": -1.0})


def test_scene_reference_is_current(capsys):
    from pathlib import Path

    from liegroup_int.scenes.reference import schema_markdown

    doc = Path(__file__).resolve().parents[2] / "docs" / "scenes.md"
    assert doc.read_text().strip() == schema_markdown().strip(), "regenerate: liegroup-int scenes --reference > docs/scenes.md"


def test_plot_command_writes_png_and_pdf(tmp_path, capsys):
    out = tmp_path / "p"
    assert main(["run", "pendulum", "--quiet", "--out", str(out), "--set", "t_end=0.01", "--set", "output.every=0.002"]) == 0
    assert main(["plot", str(out), "--times", "0", "0.01"]) == 0
    for name in ("plot_history.png", "plot_history.pdf", "plot_shapes.png", "plot_shapes.pdf"):
        assert (out / name).stat().st_size > 1000
    assert main(["plot", str(tmp_path / "nothing")]) == 2
    assert "no history.csv" in capsys.readouterr().err


def test_converge_and_sweep_commands(tmp_path, capsys):
    out = tmp_path / "conv"
    rc = main(["converge", "heavy_top", "--param", "integrator.dt", "--values", "0.02", "0.01", "0.005", "0.0025",
               "--set", "t_end=0.2", "--out", str(out), "--serial"])
    text = capsys.readouterr().out
    assert rc == 0 and (out / "study.csv").exists() and (out / "convergence.png").exists()
    # the command prints the rate of its own table; that RKMK4's rate is 4 on this study is
    # checked once, in tests/test_studies.py
    rows = list(csv.DictReader((out / "study.csv").open()))
    assert len(rows) == 4 and all(r["status"] == "ok" for r in rows)
    assert np.isfinite(float(text.split("fitted rate:")[1].split()[0]))
    out2 = tmp_path / "sweep"
    rc = main(["sweep", "heavy_top", "--grid", "integrator.method=rkmk3,rkmk4", "integrator.dt=0.02,0.01",
               "--set", "t_end=0.2", "--out", str(out2), "--serial"])
    assert rc == 0 and len((out2 / "study.csv").read_text().strip().splitlines()) == 5  # header + 4 runs
    assert main(["sweep", "heavy_top", "--grid", "integrator.dt=-1", "--out", str(tmp_path / "bad"), "--serial"]) == 2


def test_validate_spectrum_flags_a_spurious_growing_mode(capsys):
    # primal collocation of the cantilever at rest: p = 4, n_ctrl = 31 has a purely imaginary
    # spectrum (measured max Re lambda 2.5e-7 1/s, FD noise, at |lambda|max 2.4e6); p = 10,
    # n_ctrl = 32 (384 unknowns) has a spurious growing mode of +1.52e4 1/s at |Im lambda| =
    # 1.41e6 1/s, high in the spectrum (|lambda|max 4.5e6) like the +1.3e4 1/s mode of p = 8,
    # n_ctrl = 61 in docs/verification.md: 760 e-folds over 0.05 s. "auto" removes it with
    # tau = 2.05e-7 s, a damping ratio of 5.4e-6 on the first mode (auto accepts 1e-3)
    primal = ["--set", "space.formulation=primal"]
    assert main(["validate", "cantilever", "--spectrum", *primal]) == 0
    out, err = capsys.readouterr()
    # |lambda|max as printed, against the NumPy eigenvalues of the same problem (an
    # independent path: dense Jacobian of the NumPy backend), to the printed 4 digits
    lam_cli = float(out.split("|lambda|max = ")[1].split()[0])
    pb = problem(load_scene("cantilever", {"integrator.backend": "numpy", "space.formulation": "primal"}))
    lam_np = float(np.abs(eigenvalues(pb, 0.0, pb.initial_state())).max())
    assert lam_cli == pytest.approx(lam_np, rel=1e-3) and "stable dt rkmk4" in out and "warning" not in err
    undamped = [*primal, "--set", "space.degree=10", "--set", "space.n_ctrl=32", "--set", "material.kelvin_voigt=0"]
    assert main(["validate", "cantilever", "--spectrum", *undamped]) == 0
    out, err = capsys.readouterr()
    assert err.startswith("warning:") and "spurious" in err and err.count("\n") == 1
    growth = float(out.split("max Re lambda = ")[1].split()[0])
    assert growth > 1e3
    # the scene's own kelvin_voigt = "auto" sizes the damping that removes it
    assert main(["validate", "cantilever", "--spectrum", *undamped[:6]]) == 0
    out, err = capsys.readouterr()
    assert "kelvin_voigt = auto: tau = " in out and "warning" not in err
    assert float(out.split("spectrum at t=0")[1].split("max Re lambda = ")[1].split()[0]) <= 1e-2


def test_a_directory_named_like_a_builtin_does_not_hide_it(tmp_path, monkeypatch):
    """A run's output directory ``pendulum/`` in the working directory: the name still
    means the built-in scene; an explicit path to the directory is refused in one line."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "pendulum").mkdir()
    assert load_scene("pendulum").source == "builtin:pendulum"
    with pytest.raises(SceneError, match="a directory, not a scene file"):
        load_scene("./pendulum")
