"""Scenes build their problem once, and read model errors as data."""

import pytest

import liegroup_int.scenes.beam as beam_kind
from liegroup_int.problems import ParameterError, RigidBody
from liegroup_int.problems.beam.model import Material, Profile
from liegroup_int.scenes import SceneError, load_scene


@pytest.mark.parametrize("make, field", [
    (lambda: Material(E=-1.0, rho=1.0), "E"),
    (lambda: Profile("ramp", ramp=0.0), "ramp"),
    (lambda: RigidBody(inertia=(1.0, 1.0, 5.0)), "inertia"),
    (lambda: RigidBody(mass=-1.0), "mass"),
])
def test_model_errors_name_their_field(make, field):
    with pytest.raises(ParameterError) as info:
        make()
    assert info.value.field == field and str(info.value) == f"{field}: {info.value.reason}"
    assert isinstance(info.value, ValueError)  # callers catching ValueError keep working


@pytest.mark.parametrize("scene, override, key", [
    ("cantilever", {"material.rho": -2.0}, "material.rho"),
    ("cantilever", {"loads.end.profile": "ramp", "loads.end.ramp": 0.0}, "loads.end.ramp"),
    ("heavy_top", {"body.inertia": [1.0, 1.0, 5.0]}, "body.inertia"),
])
def test_scene_errors_name_the_key(scene, override, key):
    with pytest.raises(SceneError, match=f"key '{key}'"):
        load_scene(scene, overrides=override)


@pytest.mark.parametrize("formulation", ["galerkin", "primal"])
def test_a_run_builds_the_beam_once(monkeypatch, formulation):
    calls = []
    original = beam_kind._undamped

    def counted(scene):
        calls.append(scene)
        return original(scene)

    monkeypatch.setattr(beam_kind, "_undamped", counted)
    scene = load_scene("cantilever", {"space.formulation": formulation})  # validation builds it
    sim = beam_kind.build(scene)  # the run reuses it (and sizes the damping of collocation)
    assert len(calls) == 1
    if formulation == "galerkin":  # kelvin_voigt = "auto": no spectrum, no damping, said so
        assert sim.problem.damping_report is None and sim.problem.tau == 0.0
        assert sim.info["kelvin_voigt_auto"] == f"0 ({beam_kind.GALERKIN_CLEAN})"
        assert sim.stability.clean == beam_kind.GALERKIN_CLEAN
    else:
        assert sim.problem.damping_report is not None and not sim.stability.clean


def test_a_large_mesh_starts_without_a_dense_spectrum(tmp_path):
    """n_ctrl = 1001 (12,012 unknowns): the Galerkin default builds its banded mass matrices
    by sparse products and computes no dense spectrum at the start (the probe says it is
    skipped, and why), so the run starts and takes its steps (n_ctrl = 2001 starts and ends
    in 6.7 s on the 2-core machine; a dense 24,012-unknown spectrum would need 4.6 GB)."""
    from liegroup_int.runner import run_scene

    sc = load_scene("cantilever", {"space.n_ctrl": 1001, "t_end": 4e-7, "output.every": 2e-7,
                                   "integrator.dt": "auto", "output.plots": False, "output.hdf5": False})
    res = run_scene(sc, tmp_path)
    assert res.summary["status"] == "ok" and res.summary["steps"] >= 2
    assert res.summary["guards"]["probe"] == f"skipped ({beam_kind.GALERKIN_CLEAN})"


def test_numpy_values_in_overrides_are_numbers():
    """Overrides from Python may hold NumPy scalars and one-dimensional arrays: they are
    read as the numbers they are (the same scene as with plain floats and ints), and a bool
    or an array of the wrong shape is refused in one line."""
    import numpy as np

    from liegroup_int.scenes import KINDS

    given = {"loads.end.force": np.array([0, 0, -1]), "space.n_ctrl": np.int64(9), "t_end": np.float32(0.5),
             "bodies": [{"at": "end", "mass": np.float64(0.1), "offset": np.zeros(3)}]}
    plain = {"loads.end.force": [0.0, 0.0, -1.0], "space.n_ctrl": 9, "t_end": 0.5,
             "bodies": [{"at": "end", "mass": 0.1, "offset": [0.0, 0.0, 0.0]}]}
    a, b = (KINDS["beam"].build(load_scene("cantilever", over)) for over in (given, plain))
    assert a.problem.n == b.problem.n == 9
    assert np.array_equal(a.problem.point_loads[0][2].force, b.problem.point_loads[0][2].force)
    for bad, key in (({"space.n_ctrl": np.bool_(True)}, "space.n_ctrl"),
                     ({"loads.end.force": np.zeros((3, 1))}, "loads.end.force"),
                     ({"integrator.dt": np.array([1e-3, 2e-3])}, "integrator.dt")):
        with pytest.raises(SceneError, match=f"key '{key}'") as exc:
            load_scene("cantilever", bad)
        assert "\n" not in str(exc.value)
