"""Outputs a structural engineer reads: centreline histories at any s (output.points),
support reactions (quantity reactions), section fields (output.fields) in results.h5 and
the ParaView series; each computed only when the scene asks for it."""

from __future__ import annotations

import glob

import h5py
import meshio
import numpy as np
import pytest

from liegroup_int.io import read_history
from liegroup_int.runner import run_scene
from liegroup_int.scenes import SceneError, load_scene

WEIGHT = 0.8475  # the pendulum's self-weight [N/m] times its length 1 m


def _run(tmp_path, name="pendulum", **over):
    keys = {"t_end": 0.02, "output.every": 0.005, "output.plots": False, "output.paraview": False, **over}
    res = run_scene(load_scene(name, keys), tmp_path)
    return res, read_history(tmp_path / "history.csv")


def test_points_are_the_centreline_at_fractions_of_length(tmp_path):
    _, h = _run(tmp_path, **{"output.points": [0.0, 0.5, 1.0]})
    for a in "xyz":
        assert np.allclose(h[f"s1_{a}"], h[f"tip_{a}"], atol=1e-14)  # s = L is the last control point
    assert np.allclose(h["s0_x"], 0.0, atol=1e-14) and np.allclose(h["s0_z"], 0.0, atol=1e-14)  # the hinge
    assert h["s0p5_x"][0] == pytest.approx(0.5, abs=1e-12)  # straight reference: s = L/2 at x = 0.5


def test_points_on_a_curved_beam_follow_arc_length(tmp_path):
    """On the arch (a circular arc as a k-refined NURBS), s = L/2 is equidistant from both
    ends, and s = L/4 from s = 0 and s = L/2: the chords of equal arcs (to the 64 n_ctrl
    chord-length grid, 1e-6 relative)."""
    _, h = _run(tmp_path, "arch", **{"t_end": 1e-4, "output.every": 5e-5, "output.points": [0.0, 0.25, 0.5, 1.0]})
    x = {f: np.array([h[f"s{f}_{a}"][0] for a in "xyz"]) for f in ("0", "0p25", "0p5", "1")}
    d = np.linalg.norm
    assert d(x["0p5"] - x["0"]) == pytest.approx(d(x["1"] - x["0p5"]), rel=1e-6)
    assert d(x["0p25"] - x["0"]) == pytest.approx(d(x["0p5"] - x["0p25"]), rel=1e-6)


def test_reactions_balance_the_momentum_of_the_pendulum(tmp_path):
    """d/dt of the total momentum = weight + reaction at the hinge: the impulse of weight
    plus reaction against the change of momentum, over 0.3 s (n_ctrl = 31, default
    Galerkin formulation). The reaction is the weak form's end residual, so the balance is
    exact up to the trapezoid rule that integrates the sampled reaction into an impulse:
    measured 2.0e-6 of the momentum change (z; 1.6e-6 in x) with samples every 5e-4 s,
    9.5e-8 (7.0e-8) every 1e-4 s, the trapezoid rule's h^2 (25x for 5x finer samples,
    measured 21x). Asserted: below 1e-5 and at least 10x smaller with the finer samples.
    The step, 5e-5 s (|lambda| h = 1.15, half of dt = auto), adds little of its own: at
    2.5e-5 s the figures are 2.1e-6 (1.7e-6) and 9.6e-8 (7.6e-8)."""
    mism = []
    for every in (5e-4, 1e-4):
        d = tmp_path / f"every{every}"
        _, h = _run(d, **{"t_end": 0.3, "space.n_ctrl": 31, "integrator.dt": 5e-5, "output.every": every,
                          "output.quantities": ["reactions", "momentum"], "output.hdf5": False})
        t, dt = h["t"], h["t"][1] - h["t"][0]
        worst = 0.0
        for ax, load in (("x", 0.0), ("z", -WEIGHT)):
            r = h[f"reaction_start_f{ax}"]
            impulse = np.concatenate([[0.0], np.cumsum(0.5 * (r[1:] + r[:-1]) * dt)]) + load * t
            dp = h[f"p_{ax}"] - h[f"p_{ax}"][0]
            worst = max(worst, float(np.max(np.abs(dp - impulse)) / np.max(np.abs(dp))))
        # a hinge takes no couple (measured exactly 0 N m) against the weight's moment about
        # the hinge, 0.42 N m
        assert np.allclose(h["reaction_start_cy"], 0.0, atol=1e-3 * WEIGHT)
        mism.append(worst)
    assert mism[0] < 1e-5 and mism[1] < mism[0] / 10


def test_reactions_need_a_support():
    with pytest.raises(SceneError, match="'reactions' needs a clamped or hinged end"):
        load_scene("flying_spaghetti", {"output.quantities": ["tip", "reactions"]})


def test_fields_in_hdf5_and_paraview_only_when_asked(tmp_path):
    res, _ = _run(tmp_path / "a", **{"output.fields": ["n", "Gamma", "velocity"], "output.paraview": True})
    with h5py.File(tmp_path / "a" / "results.h5") as f:
        snaps = f["snapshots"]
        assert {"section_n", "section_Gamma", "section_velocity"} <= set(snaps)
        # at the points that carry the rotations: Galerkin, p = 4, n_ctrl = 31, the
        # gauss-spline-reduced rule: half the 112 B-splines of its product space (56 nodes)
        # and both ends, 58
        assert "section_m" not in snaps and snaps["section_n"].shape[1:] == (58, 3)
        # velocity at those points is B0 v; the first is s = 0: the hinge point does not move
        assert np.max(np.abs(snaps["section_velocity"][:, 0])) < 1e-12
    m = meshio.read(sorted(glob.glob(str(tmp_path / "a" / "paraview" / "*.vtu")))[-1])
    assert {"n", "Gamma", "velocity"} <= set(m.point_data) and m.point_data["n"].shape == (58, 3)
    _run(tmp_path / "b")
    with h5py.File(tmp_path / "b" / "results.h5") as f:
        assert not [k for k in f["snapshots"] if k.startswith("section_")]


def test_section_fields_at_rest_and_unknown_names():
    from liegroup_int.scenes import KINDS

    sim = KINDS["beam"].build(load_scene("cantilever"))
    pb = sim.problem
    f = pb.section_fields(sim.y0)
    # unstressed reference state at rest: strains at round-off, resultants at round-off
    # times the stiffness (EA = 2.1e7 N). The strain x' sums p + 1 = 5 terms of size
    # |N'| |x| ~ p (n_ctrl - p) / L ~ 100 that cancel to 1, so its round-off is up to about
    # 5 * 100 * 2.2e-16 = 1.1e-13 (measured 1.4e-14)
    scale = {"N": np.max(pb.CN), "n": np.max(pb.CN), "M": np.max(pb.CM), "m": np.max(pb.CM)}
    assert all(np.max(np.abs(v)) <= 1.1e-13 * scale.get(k, 1.0) for k, v in f.items()), {
        k: float(np.max(np.abs(v))) for k, v in f.items()}
    with pytest.raises(ValueError, match="unknown section field"):
        sim.problem.section_fields(sim.y0, ("shear",))
