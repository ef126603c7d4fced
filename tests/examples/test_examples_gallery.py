"""Every example in examples/ runs as a smoke test (with --quick) and gives its figure."""

import importlib.util
from pathlib import Path

import numpy as np


EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def _load(name):
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_every_example_is_covered():
    assert {p.stem for p in EXAMPLES.glob("*.py")} == {"heavy_top", "pendulum_to_paraview", "screw_motion_se3",
                                                       "time_convergence", "render_pvd", "toda_lattice",
                                                       "n_pendulum", "spin_and_subspace"}


def _wrote(capsys) -> list[Path]:
    """The paths an example says it wrote (``wrote PATH ...`` lines)."""
    return [Path(ln.split()[1].rstrip(";")) for ln in capsys.readouterr().out.splitlines() if ln.startswith("wrote ")]


def test_heavy_top(tmp_path, capsys):
    runs = _load("heavy_top").main(["--quick", "--out", str(tmp_path)])
    assert _wrote(capsys) == [tmp_path / "heavy_top.png"]
    d, _ = runs["rkmk65, tol = 1e-9"]
    assert abs(d["E"][-1] - d["E"][0]) < 1e-6 * abs(d["E"][0])  # tolerance-limited drift
    assert (tmp_path / "heavy_top.png").exists()


def test_pendulum_to_paraview(tmp_path, capsys):
    res = _load("pendulum_to_paraview").main(["--quick", "--out", str(tmp_path)])
    assert _wrote(capsys) == [tmp_path / "pendulum"]
    assert res.summary["status"] == "ok"
    assert len(list((tmp_path / "pendulum" / "paraview").glob("*.vtu"))) == 6  # t = 0 and 5 outputs
    assert _load("render_pvd").main([str(tmp_path / "pendulum"), str(tmp_path / "pvd.png")]) == 6
    assert _wrote(capsys) == [tmp_path / "pvd.png"]
    assert (tmp_path / "pvd.png").stat().st_size > 10000


def test_screw_motion_se3():
    assert _load("screw_motion_se3").main(["--quick"]) < 1e-12  # constant body twist: exact up to round-off


def test_time_convergence(tmp_path, capsys):
    rate = _load("time_convergence").main(["--quick", "--out", str(tmp_path)])
    [where] = _wrote(capsys)
    assert where == tmp_path / "time_convergence" and (where / "study.csv").exists()
    assert abs(rate - 4.0) < 0.4


def test_toda_lattice(tmp_path, capsys):
    """RKMK4 and CF4 on Isospectral(5) keep the spectrum to round-off over T = 10 (measured
    2e-14 .. 1e-13); DOP853 at tolerance 1e-6 drifts by about 1e-8 over the same span."""
    runs = _load("toda_lattice").main(["--quick", "--out", str(tmp_path)])
    assert _wrote(capsys) == [tmp_path / "toda_lattice.png"]
    for method in ("rkmk4", "cf4"):
        assert runs[method][0][-1, 1] <= 1e-12
    assert runs["DOP853, tol 1e-06"][0][-1, 1] >= 1e-10


def test_n_pendulum(tmp_path, capsys):
    """The double pendulum over 0.5 s: RKMK4 (dt = 1e-3) and RKMK45 (1e-8, 26 steps) keep the
    energy to 1e-7 J (measured 2.0e-10 and 5.5e-8 J) and the constraints to 1e-13 (3.4e-15,
    1.2e-15); over 10 s the splitting methods keep the constraints to round-off (4.4e-16)
    and the energy within 0.02 J (strang at dt = 0.01: 0.010 J) and 0.01 J (yoshida4 at 0.02:
    0.0024 J): their bounded errors, measured 0.011 and 0.005 J over 500 s, of an energy of
    -19.4 J."""
    runs, long = _load("n_pendulum").main(["--quick", "--out", str(tmp_path)])
    assert _wrote(capsys) == [tmp_path / "n_pendulum.png"]
    for h, _ in runs.values():
        assert h[:, 1].max() <= 1e-7 and h[:, 2].max() <= 1e-13
    for label, bound in (("strang, dt = 0.01", 0.02), ("yoshida4, dt = 0.02", 0.01)):
        h, _ = long[label]
        assert h[-1, 0] == 10.0 and h[:, 1].max() <= bound and h[:, 2].max() <= 1e-13


def test_spin_and_subspace(tmp_path, capsys):
    """|m| = 1 to round-off (measured 1.1e-15 over 10 s); Oja's flow orthonormal to 1e-13
    (1.4e-14) and within 1e-4 of the dominant projector at t = 10 (2.0e-5; the gap 1
    gives exp(-t))."""
    spin, sub = _load("spin_and_subspace").main(["--quick", "--out", str(tmp_path)])
    assert _wrote(capsys) == [tmp_path / "spin_and_subspace.png"]
    assert np.max(np.abs(np.linalg.norm(spin[:, 1:], axis=1) - 1.0)) <= 1e-14
    assert sub[:, 2].max() <= 1e-13 and sub[-1, 1] <= 1e-4
