"""Rigid bodies on a ball or hinge joint at a beam end (``[[bodies]] joint``, Galerkin): the
body turns on its own (a node of the state: :mod:`liegroup_int.problems.beam.nodes`).
Checked against a stiff arm's rigid frequencies (a hinge's spring; a pendulum under gravity
about the static equilibrium), a torque-free spin on a ball joint at the body's centre, the
energy balance of a ball pendulum, the two backends, the outputs of a run, and the one-line
refusals."""

from __future__ import annotations

import numpy as np
import pytest

from liegroup_int import integrate
from liegroup_int.integrators import modal_analysis
from liegroup_int.problems.beam import solve_static
from liegroup_int.runner import run_scene
from liegroup_int.io import read_history
from liegroup_int.scenes import KINDS, SceneError, load_scene

#: a body of 0.5 kg, principal inertias about its centre along the end section's d1, d2, d3
M, J = 0.5, np.array([2e-3, 3e-3, 1e-3])
#: a member 1 m along x clamped at x = 0 (the t_frame's section: rhoA 1 kg/m, rhoI 0.01 kg m)
ARM = {"beams": [{"name": "a", "kind": "straight", "length": 1.0, "direction": [1, 0, 0]}], "joints": [],
       "loads.end.force": [0.0, 0.0, 0.0], "space.n_ctrl": 6}
#: made nearly rigid: its first bending mode at 3 kHz
STIFF = {f"section.{k}": 1e8 for k in ("EI1", "EI2", "GJ")} | {"section.EA": 1e10, "section.GA": 1e10}
#: the end section's d1, d2, d3 are the spatial y, z, x here: an offset (0, -l, 0) hangs the
#: body's centre l below the tip
L_ARM = 0.2


def _scene(body: dict, backend: str = "numba", **over):
    return load_scene("t_frame", {**ARM, "integrator.backend": backend,
                                  "bodies": [{"at": "end", "mass": M, "inertia": list(J), **body}], **over})


def _problem(body: dict, backend: str = "numba", **over):
    return KINDS["beam"].build(_scene(body, backend, **over)).problem


def test_the_body_s_node_is_joined_to_the_end():
    """One node: a control row and a point after the member's, joined to the end by the
    body's joint; the centreline's points exclude it."""
    pb = _problem({"joint": "hinge", "axis": [0.0, 1.0, 0.0]})
    assert (pb.n, pb.m) == (pb.n_beam + 1, pb.m_beam + 1)
    (j,) = pb.joints
    assert (j.a, j.b, j.kind) == (pb.n_beam - 1, pb.n_beam, "hinge")
    (b,) = pb.bodies
    assert (b.row, b.point) == (pb.n_beam, pb.m_beam)
    u, basis, s = pb.frame_points
    assert len(u) == basis.shape[0] == len(s) == pb.m_beam and basis.shape[1] == pb.n


@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_a_stiff_arm_s_hinged_body_swings_at_the_rigid_frequencies(backend):
    """A body on a hinge about y at the tip of the stiff arm, its centre 0.2 m below. With a
    spring of 3 N m/rad and no gravity the swing is ``sqrt(k / I)``; with gravity and no
    spring, about the static equilibrium (the arm sagged), ``sqrt(m g l / I)``, ``I = J_1 + m
    l^2`` about the axis. Measured 1.8e-8 and 1e-9 from them (the arm's flexibility and the
    finite differences), both backends; asserted 1e-6."""
    I = J[0] + M * L_ARM**2
    hinge = {"joint": "hinge", "axis": [0.0, 1.0, 0.0], "offset": [0.0, -L_ARM, 0.0]}
    pb = _problem({**hinge, "stiffness": 3.0}, backend, **STIFF)
    f = modal_analysis(pb, 0.0, pb.initial_state(), 1).modes[0].freq_hz
    assert f == pytest.approx(np.sqrt(3.0 / I) / (2 * np.pi), rel=1e-6)
    pg = _problem(hinge, backend, **STIFF, **{"loads.gravity": [0.0, 0.0, -9.81]})
    res = solve_static(pg, load_steps=1, tol=1e-12)
    assert res.converged
    f = modal_analysis(pg, 0.0, res.state, 1).modes[0].freq_hz
    assert f == pytest.approx(np.sqrt(M * 9.81 * L_ARM / I) / (2 * np.pi), rel=1e-6)


def test_a_body_on_a_ball_joint_at_its_centre_spins_free_of_torque():
    """A ball joint at the body's centre passes no couple: spun about a skew axis (W = (3, 1,
    2) rad/s), the body precesses (W changes by up to 0.5 rad/s over 0.2 s) with its angular
    momentum ``R J W`` and kinetic energy constant, and the stiff arm stays at rest.
    Measured: 5e-16 kg m^2/s and 5e-17 J; asserted 1e-12 of them. The arm's velocities, 1.4e-9
    m/s, are the stiff reference's round-off (strains of 1e-16 on EA = 1e10); asserted 1e-8."""
    pb = _problem({"joint": "ball"}, **STIFF)
    y0 = pb.initial_state()
    W0 = np.array([3.0, 1.0, 2.0])
    y0.w[-1] = W0
    y = integrate(pb, y0, (0.0, 0.2), dt=2e-6).y_final
    L0, L1 = y0.R[-1] @ (J * W0), y.R[-1] @ (J * y.w[-1])
    assert np.max(np.abs(L1 - L0)) <= 1e-12 * np.linalg.norm(L0)
    assert abs(y.w[-1] @ (J * y.w[-1]) - W0 @ (J * W0)) <= 1e-12 * (W0 @ (J * W0))
    assert np.max(np.abs(y.w[-1] - W0)) > 0.1  # it precesses
    assert np.max(np.abs(y.v[:-1])) < 1e-8


def test_a_ball_pendulum_closes_the_energy_balance_and_the_backends_agree():
    """A body on a ball joint at the arm's tip (t_frame's section, soft), its centre off the
    joint along d1, d2 and d3, under gravity and a force, started swinging: over 0.2 s
    (RKMK4) the kinetic, strain and potential energy less the work of the loads stays at
    1.0e-13 and 1.4e-13 J (h = 1e-5, 5e-6) against 0.40 J of work; asserted 1e-10 J. At the
    final state the NumPy twin's rates agree with the compiled ones to round-off."""
    body = {"joint": "ball", "offset": [0.03, -L_ARM, 0.05], "force": [0.5, 0.2, 0.1]}
    over = {"loads.gravity": [0.0, 0.0, -9.81]}
    pc, pn = _problem(body, "numba", **over), _problem(body, "numpy", **over)
    y0 = pc.initial_state()
    y0.w[-1] = [1.0, -2.0, 0.5]
    res = integrate(pc, y0, (0.0, 0.2), dt=1e-5)
    defect = pc.mechanical_energy(res.y_final) - pc.mechanical_energy(y0) - res.stats.quadrature
    print("energy defect", defect, "work", res.stats.quadrature)
    assert abs(defect) <= 1e-10 and res.stats.quadrature > 0.1
    kn, kc = pn.vector_field(0.2, res.y_final), pc.vector_field(0.2, res.y_final)
    assert np.max(np.abs(kn - kc)) <= 1e-10 * np.max(np.abs(kn))


def test_a_run_with_a_hinged_body_writes_its_outputs(tmp_path):
    """``run`` of the arm with a hinged, sprung body: the history (tip, energy balance,
    reactions, the joints' reactions, the body's centre and angular velocity), ParaView frames
    and plots are written, the centreline without the body's node; the body's centre stays
    0.2 m from the tip, the joint (to round-off), and shapes.npz holds both for the shape
    plot. The energy balance stays at RKMK4's error at the scene's automatic step (gravity
    switched on at t = 0 excites the top modes, as on the built-in t_frame): 4.3e-7 J
    measured; asserted 1e-5 J."""
    sc = _scene({"joint": "hinge", "axis": [0.0, 1.0, 0.0], "stiffness": 3.0, "offset": [0.0, -L_ARM, 0.0]},
                **{"loads.gravity": [0.0, 0.0, -9.81], "t_end": 0.02, "output.every": 0.01,
                   "output.quantities": ["tip", "energy_balance", "reactions", "joint_reactions", "bodies"],
                   "output.paraview": True})
    res = run_scene(sc, tmp_path)
    assert res.summary["status"] == "ok"
    h = read_history(tmp_path / "history.csv")
    assert np.max(np.abs(h["energy_balance"])) < 1e-5
    assert {"tip_z", "reaction_start_fz"} <= set(h) and any(k.startswith("joint") for k in h)
    # the body's centre starts 0.2 m below the tip, and stays 0.2 m from it (the hinge's point)
    centre = np.stack([h[f"body0_{q}"] for q in "xyz"], axis=1)
    tip = np.stack([h[f"tip_{q}"] for q in "xyz"], axis=1)
    assert np.allclose(centre[0], [1.0, 0.0, -L_ARM], atol=1e-12)
    assert np.allclose(np.linalg.norm(centre - tip, axis=1), L_ARM, rtol=1e-12)
    with np.load(tmp_path / "shapes.npz") as z:  # the shape plot draws the body: its centre and joint point
        assert np.allclose(np.linalg.norm(z["body_centre"] - z["body_joint"], axis=-1), L_ARM, rtol=1e-12)
        assert np.allclose(z["body_centre"][-1, 0], centre[-1], atol=1e-12)
    assert list(tmp_path.glob("*.vtu")) or list(tmp_path.rglob("*.vtu"))


@pytest.mark.parametrize("body, over, match", [
    ({"joint": "hinge"}, {}, "key 'axis': a body on a hinge needs a non-zero axis"),
    ({"joint": "ball", "axis": [1.0, 0.0, 0.0]}, {}, "key 'axis': only a body on a hinge"),
    ({"joint": "ball", "inertia": [0.0, 0.0, 0.0], "offset": [0.0, 0.1, 0.0]}, {},
     "key 'inertia': a body on a ball turns on its own"),
    ({"joint": "ball"}, {"loads.distributed_couple": [0.0, 0.0, 1.0]}, "distributed_couple"),
    ({"joint": "ball"}, {"bodies": [{"at": "end", "mass": M, "inertia": list(J), "joint": "ball"},
                                    {"at": "end", "mass": M}]}, "one body per end when one is on a ball or hinge"),
])
def test_refusals_are_one_line(body, over, match):
    with pytest.raises(SceneError, match=match) as exc:
        KINDS["beam"].build(_scene(body, **over))
    assert "\n" not in str(exc.value)


def test_statics_refuse_a_body_on_a_ball_joint():
    """A body on a ball joint turns freely about the line of its loads through the joint (its
    static tangent is singular): static analyses refuse it in one line naming the hinge."""
    pb = _problem({"joint": "ball", "offset": [0.0, -L_ARM, 0.0]}, **{"loads.gravity": [0.0, 0.0, -9.81]})
    with pytest.raises(ValueError, match="a body on a ball joint turns freely .* put it on a hinge") as exc:
        solve_static(pb)
    assert "\n" not in str(exc.value)


def test_a_ball_payload_on_a_driven_hub_closes_the_energy_balance():
    """A body on a ball joint at the start of the soft arm, whose clamp spins up (5 rad/s over
    0.05 s about a skew axis): the node is joined to a prescribed row. The drive's work closes
    the energy balance over 0.1 s (RKMK4, h = 1e-5): measured 1.8e-13 J of 14.7 J; asserted
    1e-10 J. The compiled and NumPy powers agree to 1e-12 relative at the end."""
    drive = {"motion.start.kind": "spin_up", "motion.start.rate": 5.0, "motion.start.time": 0.05,
             "motion.start.axis": [0.0, 0.6, 0.8]}
    body = {"at": "start", "joint": "ball", "offset": [0.03, -0.1, 0.02]}
    pc, pn = (KINDS["beam"].build(load_scene("t_frame", {**ARM, **drive, "integrator.backend": b, "bodies": [
        {"mass": M, "inertia": list(J), **body}]})).problem for b in ("numba", "numpy"))
    y0 = pc.initial_state()
    res = integrate(pc, y0, (0.0, 0.1), dt=1e-5)
    defect = pc.mechanical_energy(res.y_final) - pc.mechanical_energy(y0) - res.stats.quadrature
    assert abs(defect) <= 1e-10 and res.stats.quadrature > 1.0
    pc.increment_rate(0.1, res.y_final, np.zeros((4, pc.n, 3)))
    assert float(pc._nb._pw[0]) == pytest.approx(pn.quadrature_rate(0.1, res.y_final), rel=1e-12)
