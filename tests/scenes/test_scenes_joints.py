"""[[joints]]: frames that are not chains (a T-frame, a closed ring) and ball joints, on the
Galerkin beam; checks against exact properties (energy, momentum, symmetry, statics)."""

from __future__ import annotations

import numpy as np
import pytest

from liegroup_int import integrate
from liegroup_int.cli import main
from liegroup_int.problems.beam import beam_problem
from liegroup_int.problems.beam.statics import StaticDivergence, solve_static
from liegroup_int.scenes import SceneError, load_scene
from liegroup_int.scenes.beam import problem

T_JOINT = ["post.end", "left.start", "right.start"]
#: the built-in t_frame's tip force (down and sideways: bending and torsion of the post)
TIP_FORCE = np.array([0.0, 5.0, -20.0])

#: A free square ring of four 1 m members with rigid corners (the t_frame's section), pulled
#: apart at the middles of two opposite sides, with an out-of-plane part (net force 6 N
#: along z); n_ctrl = 9 so that the halves of a split member keep 5 control points.
RING = {"bc.start": "free", "bc.end": "free", "loads.end.force": [0.0, 0.0, 0.0], "space.n_ctrl": 9,
        "output.quantities": ["tip", "energy"],
        "beams": [{"name": "a", "kind": "straight", "length": 1.0, "direction": [1, 0, 0]},
                  {"name": "b", "kind": "straight", "length": 1.0, "direction": [0, 1, 0], "origin": [1, 0, 0]},
                  {"name": "c", "kind": "straight", "length": 1.0, "direction": [-1, 0, 0], "origin": [1, 1, 0]},
                  {"name": "d", "kind": "straight", "length": 1.0, "direction": [0, -1, 0], "origin": [0, 1, 0]}],
        "joints": [{"ends": ["a.end", "b.start"]}, {"ends": ["b.end", "c.start"]},
                   {"ends": ["c.end", "d.start"]}, {"ends": ["d.end", "a.start"]}],
        "point_loads": [{"s": 0.125, "force": [0.0, -10.0, 3.0]}, {"s": 0.625, "force": [0.0, 10.0, 3.0]}]}

#: Two collinear 1 m members, the first clamped, joined at x = 1 m, a torsion couple at the tip.
TWO = {"beams": [{"name": "a", "kind": "straight", "length": 1.0, "direction": [1, 0, 0]},
                 {"name": "b", "kind": "straight", "length": 1.0, "direction": [1, 0, 0], "origin": [1, 0, 0]}],
       "loads.end.force": [0.0, 0.0, 0.0], "loads.end.couple": [2.0, 0.0, 0.0]}


def _pb(over=None, kind="rigid", backend="numba"):
    joints = {"joints": [{"ends": T_JOINT, "kind": kind}]}
    return problem(load_scene("t_frame", {**joints, **(over or {}), "integrator.backend": backend}))


def _run(pb, t_end, dt, n_out=11):
    out = []
    integrate(pb, pb.initial_state(), (0.0, t_end), dt=dt, t_eval=np.linspace(0.0, t_end, n_out),
              observer=lambda t, y: out.append((t, y.copy())))
    return out


def _backends_agree(pbs):
    """Stage rates and load power of the NumPy and numba problems ``pbs`` at a random state,
    equal to 1e-12 relative; ``(y, u, rates, scale)``."""
    y, u = _random_state(pbs[0])
    rates = [pb.increment_rate(0.3, y, u) for pb in pbs]
    scale = np.max(np.abs(rates[0]))
    assert np.max(np.abs(rates[0] - rates[1])) <= 1e-12 * scale
    pbs[1]._nb.increment_rate(0.3, y, np.zeros_like(u))
    assert float(pbs[1]._nb._pw[0]) == pytest.approx(pbs[0].quadrature_rate(0.3, y), rel=1e-12)
    return y, u, rates, scale


def _random_state(pb, seed=1):
    """A deformed moving state that satisfies the joints (positions ~5e-3 m, rotations and
    velocities ~5e-2)."""
    r = np.random.default_rng(seed)
    u = 0.05 * r.standard_normal((4, pb.n, 3))
    u[0] *= 0.1
    V, W = 0.05 * r.standard_normal((2, pb.n, 3))
    for e in pb.ends:
        if e.fix_position or e.fix_rotation:
            u[:, e.index] = V[e.index] = W[e.index] = 0.0
    y = pb.action(u, pb.initial_state())
    y.v, y.w = pb.project_increment(np.stack([y.c, W, V, W]))[[2, 3]]
    return y, 0.1 * pb.project_increment(u)


@pytest.mark.parametrize("kind", ["rigid", "ball"])
def test_t_frame_energy_error_falls_at_the_step_to_the_fifth(kind):
    """The built-in t_frame (a clamped post, two arms joined at its top, a dead tip force
    switched on at t = 0) conserves kinetic + strain + load potential in the semi-discrete
    Galerkin form: the joints' constraint forces do no work (C v = 0). What is left is
    RKMK4's error: for an oscillation of frequency w, |R(i w h)|^2 = 1 - (w h)^6 / 72 + ...,
    so the energy falls by ~T w^6 h^5 / 72 over a time T: order 5 in h. Largest |E - E0|
    over 0-0.1 s at h = 1e-5, 5e-6, 2.5e-6 (w h <= 0.18 for the top mode, 1.8e4 rad/s):
    measured 1.9e-7, 5.9e-9, 1.9e-10 J, slope 5.0 (both kinds). A constraint doing work
    would leave an error that does not fall with h. Fitted slope in [4.5, 5.5]."""
    pb = _pb(kind=kind)
    E0 = pb.energy(pb.initial_state(), 0.0)
    steps = np.array([1e-5, 5e-6, 2.5e-6])
    errs = [max(abs(pb.energy(y, t) - E0) for t, y in _run(pb, 0.1, h)) for h in steps]
    slope = np.polyfit(np.log(steps), np.log(errs), 1)[0]
    assert 4.5 <= slope <= 5.5, (errs, slope)
    assert errs[-1] <= 1e-9  # 1.9e-10 J measured, against 1.3 J of work done by the force


@pytest.mark.parametrize("scene_over", ["t_frame", "ring"])
@pytest.mark.parametrize("kind", ["rigid", "ball"])
def test_backends_agree_on_the_stage_rates(kind, scene_over):
    """NumPy and numba stage rates and load power at a deformed moving state: the compiled
    kernels take the per-field constraint sets as they are (a ball joint's rotational rows
    zero): to round-off (measured 5e-16 relative; 1e-12 allowed as for the chain joints).
    The rates keep every joint's positions together, and the rotations of the rigid pairs
    only: at a ball joint the two ends' angular accelerations differ."""
    if scene_over == "ring":
        over = {**RING, "joints": [{**j, "kind": kind} for j in RING["joints"]]}
        pbs = [problem(load_scene("t_frame", {**over, "integrator.backend": b})) for b in ("numpy", "numba")]
    else:
        pbs = [_pb(kind=kind, backend=b) for b in ("numpy", "numba")]
    y, u, rates, scale = _backends_agree(pbs)
    for j in pbs[0].joints:
        assert np.allclose(rates[0][[0, 2], j.b], rates[0][[0, 2], j.a], rtol=0, atol=1e-12 * scale)
        turn = np.max(np.abs(rates[0][[1, 3], j.b] - rates[0][[1, 3], j.a] @ j.Q))
        assert (turn <= 1e-12 * scale) if j.rigid else (turn >= 1e-3 * scale)


def test_free_ring_keeps_momentum_symmetry_and_closure():
    """The free square ring pulled apart at two opposite sides (with 3 N each out of plane):
    linear momentum p = (0, 0, 6 t) exactly (a linear invariant of the Runge-Kutta step,
    the internal and constraint forces sum to zero), the shape symmetric under the half
    turn about the ring's axis that swaps the loaded sides (member c's control points are
    member a's turned, d's are b's), the angular momentum about the centre zero (the half
    turn and the mirror of the loaded sides) and the four corners closed, rigid: joined
    positions equal and the relative rotation of the two end sections kept at its reference
    value Q. 0.3 s at h = 5e-5 (6000 steps); measured 8e-16 (p), 6e-15 m (symmetry),
    1e-15 (h), 1e-15 (closure) while the ring deforms by 6.8 cm. Allowed 1e-12: round-off
    of ~1e-16 per step accumulated over the 6000 steps, twice."""
    pb = problem(load_scene("t_frame", {**RING, "integrator.backend": "numba"}))
    o = pb.space.offsets  # pieces a1 a2 b c1 c2 d (a and c split at their middles)
    half = np.diag([-1.0, -1.0, 1.0])
    ctr = np.array([0.5, 0.5, 0.0])
    out = _run(pb, 0.3, 5e-5, n_out=7)
    y0 = out[0][1]
    for t, y in out:
        p, h = pb.momentum(y)
        assert np.max(np.abs(p - [0.0, 0.0, 6.0 * t])) <= 1e-12
        assert np.max(np.abs(h - np.cross(ctr, p))) <= 1e-12
        rel = y.c - ctr
        assert np.max(np.abs(rel[o[3]:o[5]] @ half - rel[o[0]:o[2]])) <= 1e-12
        assert np.max(np.abs(rel[o[5]:o[6]] @ half - rel[o[2]:o[3]])) <= 1e-12
        for j in pb.joints:
            assert np.max(np.abs(y.c[j.b] - y.c[j.a])) <= 1e-12
            assert np.max(np.abs(y.R[j.point].T @ y.R[j.point_b] - j.Q)) <= 1e-12
    assert np.max(np.abs(out[-1][1].c - y0.c)) >= 0.05  # the loads act: 6.8 cm measured


def _torsion(kind):
    pb = problem(load_scene("t_frame", {**TWO, "joints": [{"ends": ["a.end", "b.start"], "kind": kind}],
                                        "integrator.backend": "numba"}))
    return pb, _run(pb, 0.1, 2e-5)


def test_a_ball_joint_transmits_no_couple():
    """Two collinear members, the first clamped, a torsion couple C = 2 N m at the far tip.
    Ball joint: the second member twists alone (torsion keeps the centreline straight, so
    the ball joint carries no force either): the first member stays at rest (angular
    velocity measured exactly 0; velocities at most 3.3e-11 m/s everywhere, the axial
    strain's round-off, against twist rates up to 11 rad/s) and the angular momentum about
    the axis is C t (the internal couples sum to zero over the member; measured to 7e-16
    relative). Rigid joint: the couple reaches the clamp through the joint, the first
    member twists (its largest angular velocity reaches that of the whole frame) and the
    joint reaction carries the torsion (up to 4.0 N m measured: the step's dynamic
    overshoot of C)."""
    pb, out = _torsion("ball")
    na = pb.space.offsets[1]
    for t, y in out:
        scale = max(np.max(np.abs(y.w)), 1e-300)
        assert np.max(np.abs(y.w[:na])) <= 1e-14 * scale
        # positions: only the round-off of the axial strain (Gamma_3 - 1 from control points
        # of size 2 m, ~1e-15, times EA = 1e5 N) moves them, randomly from step to step:
        # relative to the twist's surface speed |w| x 1 m: round-off level
        assert np.max(np.abs(y.v)) <= 1e-10 * scale * 1.0
        assert pb.momentum(y)[1][0] == pytest.approx(2.0 * t, rel=1e-12, abs=1e-15)
        force, couple = pb.joint_reactions(y, t)[0]
        assert not np.any(couple)  # no rotational multiplier at a ball joint
    assert np.max(np.abs(out[-1][1].w)) >= 1.0  # the couple acts (spin rates of ~100 rad/s)
    pb, out = _torsion("rigid")
    ratios = [np.max(np.abs(y.w[:na])) / np.max(np.abs(y.w)) for _, y in out[1:]]
    assert max(ratios) >= 0.1
    couples = [np.linalg.norm(pb.joint_reactions(y, t)[0][1]) for t, y in out[1:]]
    assert max(couples) >= 0.5  # of the order of C = 2 N m


def test_t_frame_statics_balance_at_the_joint():
    """Static equilibrium of the t_frame (rigid joint) under its tip force: the joint's
    reactions are the exact statics of each arm (the unloaded left arm gets nothing; the
    right arm gets -F and the couple -(tip - joint) x F), and the clamp reacts with -F and
    -(tip - foot) x F. Newton to a relative residual of 1e-12 (near its round-off floor,
    1e-16 EA / |F| ~ 5e-13; reached 1.7e-11, where the Newton correction stalls); measured
    at most 1.3e-10 N and 8.8e-10 N m against |F| = 20.6 N and |F| L = 22 N m. Allowed
    1e-10 |F| (N) and 1e-9 |F| (N m, moment arms of about 1 m): the residual left in the
    rows, spread by the mass solve into the multipliers, with margins of 16 and 23. The
    ball-jointed T-frame is a mechanism (the arms turn freely about the ball): its tangent
    is singular and the solver says so in one line."""
    pb = _pb(kind="rigid", backend="numpy")
    y = solve_static(pb, load_steps=2, tol=1e-12).state
    (f_left, c_left), (f_right, c_right) = pb.joint_reactions(y)
    tip, joint, foot = y.c[-1], y.c[pb.joints[1].b], y.c[0]
    F = np.linalg.norm(TIP_FORCE)
    assert np.max(np.abs(np.concatenate([f_left, f_right + TIP_FORCE]))) <= 1e-10 * F
    assert np.max(np.abs(np.concatenate([c_left, c_right + np.cross(tip - joint, TIP_FORCE)]))) <= 1e-9 * F
    f, c = pb.reactions(y)["start"]
    assert np.max(np.abs(f + TIP_FORCE)) <= 1e-10 * F
    assert np.max(np.abs(c + np.cross(tip - foot, TIP_FORCE))) <= 1e-9 * F
    with pytest.raises(StaticDivergence, match="no equilibrium at load factor"):
        solve_static(_pb(kind="ball", backend="numpy"), load_steps=2)


#: The square ring of :data:`RING` held by a 0.5 m post clamped below its corner (0, 0):
#: the post's end, a's start and d's end form one rigid joint (a closed loop: statically
#: indeterminate), loaded in and out of its plane at the middles of b and c.
POSTED_RING = {**RING, "bc.start": "clamped",
               "beams": [{"name": "post", "kind": "straight", "length": 0.5, "direction": [0, 0, 1],
                          "origin": [0, 0, -0.5]}] + RING["beams"],
               "joints": [{"ends": ["post.end", "a.start", "d.end"]}, {"ends": ["a.end", "b.start"]},
                          {"ends": ["b.end", "c.start"]}, {"ends": ["c.end", "d.start"]}],
               "point_loads": [{"s": 2.0 / 4.5, "force": [4.0, -2.0, -3.0]},
                               {"s": 3.0 / 4.5, "force": [0.0, 5.0, 2.0], "couple": [0.5, 0.0, 0.0]}]}


def test_closed_ring_statics_balance_at_the_clamp():
    """A closed ring (statically indeterminate) on a clamped post, loaded in and out of its
    plane at two points (one with a couple): at the static equilibrium (Newton to 1e-12) the
    clamp's force and couple balance the loads and their moments about the foot, taken at
    the deformed points of application, to the residual left in the free rows (round-off);
    measured 8.6e-11 N and 4e-14 N m against |F| = 5.1 N, asserted 1e-9 |F| in both. The
    reactions do not come from the loads: they are the clamp's rows of the internal forces,
    so the balance sees the joints and the loop closure."""
    pb = problem(load_scene("t_frame", {**POSTED_RING, "integrator.backend": "numpy"}))
    res = solve_static(pb, load_steps=2, tol=1e-12)
    y = res.state
    F = np.array([[4.0, -2.0, -3.0], [0.0, 5.0, 2.0]])
    rows = [row for row, *_ in pb.point_loads]
    foot = y.c[0]
    total = F.sum(axis=0)
    moment = sum(np.cross(y.c[r] - foot, f) for r, f in zip(rows, F)) + np.array([0.5, 0.0, 0.0])
    f, c = pb.reactions(y)["start"]
    scale = np.linalg.norm(total)
    print("ring statics: force", f + total, "couple", c + moment, "|F|", scale)
    assert res.converged and np.max(np.abs(f + total)) <= 1e-9 * scale
    assert np.max(np.abs(c + moment)) <= 1e-9 * scale
    assert np.max(np.abs(y.c[rows[0]] - pb.initial_state().c[rows[0]])) > 1e-4  # the ring deforms


#: A continuous 2 m beam along x, clamped at its start, and a 1 m post standing on its
#: middle: written with an interior joint end (``beam@0.5``) and, explicitly, as the beam's
#: two halves and the post joined at one point (the halves get the split's 7 + 7 control
#: points).
MID_POST = [{"name": "post", "kind": "straight", "length": 1.0, "direction": [0, 0, 1], "origin": [1, 0, 0],
             "n_ctrl": 7}]


def _mid_post(interior: bool, kind: str = "rigid", backend: str = "numpy"):
    """The frame of :data:`MID_POST` (a force on the post's top), written with the interior
    joint end ``beam@0.5`` (the post's joint of ``kind``) or, explicitly and rigid only,
    with the beam's two halves and the post joined at one point."""
    whole = [{"name": "beam", "kind": "straight", "length": 2.0, "direction": [1, 0, 0], "n_ctrl": 13}]
    halves = [{"name": "beam_a", "kind": "straight", "length": 1.0, "direction": [1, 0, 0], "n_ctrl": 7},
              {"name": "beam_b", "kind": "straight", "length": 1.0, "direction": [1, 0, 0], "origin": [1, 0, 0],
               "n_ctrl": 7}]
    over = ({"beams": whole + MID_POST, "joints": [{"ends": ["beam@0.5", "post.start"], "kind": kind}]} if interior
            else {"beams": halves + MID_POST, "joints": [{"ends": ["beam_a.end", "beam_b.start", "post.start"]}]})
    return problem(load_scene("t_frame", {**over, "integrator.backend": backend, "loads.end.force": [3.0, -2.0, 0.0]}))


def test_an_interior_joint_is_the_member_split_there():
    """A joint at an interior point of a member (``"beam@0.5"``) splits the member there, its
    two pieces joined rigidly (the member stays continuous), and joins the point to the
    other ends: the same joint rows, the same stage rates at a deformed moving state and
    the same static equilibrium under a force on the post's top as the frame written with
    the member's two halves and the post in one rigid joint, to round-off (the same
    arithmetic)."""
    a, b = _mid_post(True), _mid_post(False)
    assert a.space.joints == b.space.joints and a.n == b.n
    y, u = _random_state(a)
    ka, kb = a.increment_rate(0.2, y, u), b.increment_rate(0.2, y, u)
    assert np.max(np.abs(ka - kb)) <= 1e-14 * np.max(np.abs(ka))
    sa, sb = (solve_static(pb, load_steps=2, tol=1e-10).state for pb in (a, b))
    assert np.max(np.abs(sa.c - sb.c)) <= 1e-14 and np.max(np.abs(sa.c[-1] - a.initial_state().c[-1])) > 1e-4


def test_a_ball_at_an_interior_point_leaves_the_member_continuous():
    """A post on a ball joint at the middle of a continuous beam: a joint an explicit frame
    cannot write (an end joins one joint only). At a deformed moving state the rates keep
    the three rows' positions together, the beam's two halves turning together (rigid) and
    the post turning on its own (ball: its angular acceleration differs by more than 1e-3
    of the scale); the NumPy and numba rates agree to round-off (1e-12)."""
    pbs = [_mid_post(True, "ball", b) for b in ("numpy", "numba")]
    y, u, rates, scale = _backends_agree(pbs)
    (beam, post) = pbs[0].joints
    assert beam.rigid and not post.rigid
    for j in (beam, post):
        assert np.allclose(rates[0][[0, 2], j.b], rates[0][[0, 2], j.a], rtol=0, atol=1e-12 * scale)
    turn = [np.max(np.abs(rates[0][[1, 3], j.b] - rates[0][[1, 3], j.a] @ j.Q)) for j in (beam, post)]
    assert turn[0] <= 1e-12 * scale and turn[1] >= 1e-3 * scale


def test_two_continuous_members_crossing_at_their_middles():
    """An X: two continuous 2 m members crossing at their middles (``"a@0.5"``,
    ``"b@0.5"``, rigid), the first clamped at its start, a force and a couple at the
    second's end. Static equilibrium: the clamp's reaction balances the load and its moment
    about the foot at the deformed point of application to the residual's round-off
    (measured 7e-12 N and 4e-12 N m against |F| = 5.4 N; asserted 1e-9 |F|); both members
    stay continuous through the crossing (the pieces' end rotations equal to round-off)."""
    F, C = np.array([0.0, 2.0, -5.0]), np.array([0.3, 0.0, 0.0])
    over = {"beams": [{"name": "a", "kind": "straight", "length": 2.0, "direction": [1, 0, 0], "n_ctrl": 13},
                      {"name": "b", "kind": "straight", "length": 2.0, "direction": [0, 1, 0], "origin": [1, -1, 0],
                       "n_ctrl": 13}],
            "joints": [{"ends": ["a@0.5", "b@0.5"]}], "integrator.backend": "numpy",
            "loads.end.force": F.tolist(), "loads.end.couple": C.tolist()}
    pb = problem(load_scene("t_frame", over))
    assert len(pb.space.patches) == 4
    y = solve_static(pb, load_steps=2, tol=1e-12).state
    f, c = pb.reactions(y)["start"]
    tip, foot = y.c[-1], y.c[0]
    scale = np.linalg.norm(F)
    print("X statics: force", f + F, "couple", c + C + np.cross(tip - foot, F))
    assert np.max(np.abs(f + F)) <= 1e-9 * scale
    assert np.max(np.abs(c + C + np.cross(tip - foot, F))) <= 1e-9 * scale
    for j in pb.joints:
        assert np.allclose(y.c[j.a], y.c[j.b], rtol=0, atol=1e-14)


def test_a_pin_through_two_interior_points_is_refused():
    """Two continuous members joined by a ball or a hinge at interior points of both (a
    scissor's pin) would need each member's two pieces joined rigidly and to each other
    through the joint, which the joint graph (every pair from one first end) cannot hold:
    refused in one line naming the entry and the way out."""
    over = {"beams": [{"name": "a", "kind": "straight", "length": 2.0, "direction": [1, 0, 0], "n_ctrl": 13},
                      {"name": "b", "kind": "straight", "length": 2.0, "direction": [0, 1, 0], "origin": [1, -1, 0],
                       "n_ctrl": 13}], "joints": [{"ends": ["a@0.5", "b@0.5"], "kind": "ball"}]}
    with pytest.raises(SceneError, match=r"joints\[0\]: key 'kind' = 'ball': a ball joint takes one interior point"):
        load_scene("t_frame", over)


@pytest.mark.parametrize("ends, match", [
    (["beam@0", "post.start"], r"'beam@0': expected \"<member>@<fraction>\" with a fraction"),
    (["beam@1.2", "post.start"], r"'beam@1.2': expected \"<member>@<fraction>\""),
    (["beam@half", "post.start"], r"'beam@half': expected \"<member>@<fraction>\""),
    (["girder@0.5", "post.start"], r"'girder@0.5': no \[\[beams\]\] entry named 'girder'"),
    (["beam@0.5", "beam@0.50"], r"'beam@0.50' is already joined"),
    (["beam@0.25", "post.start"], r"'post.start' at \[1.0, 0.0, 0.0\] is 0.5 m from 'beam@0.25'"),
])
def test_bad_interior_joint_ends_are_one_line_errors(ends, match):
    over = {"beams": [{"name": "beam", "kind": "straight", "length": 2.0, "direction": [1, 0, 0], "n_ctrl": 13}]
            + MID_POST, "joints": [{"ends": ends}]}
    with pytest.raises(SceneError, match=match):
        load_scene("t_frame", over)


def test_a_chain_written_with_joints_is_the_chain():
    """A chain written with [[joints]] is the chain: the same joint rows and the same
    Galerkin vector field as the implied chain (to round-off: the same arithmetic)."""
    beams = [{"name": "a", "kind": "straight", "length": 1.0, "direction": [0, 0, 1]},
             {"name": "b", "kind": "straight", "length": 1.0, "direction": [1, 0, 0], "origin": [0, 0, 1]}]
    base = {"beams": beams, "integrator.backend": "numpy"}
    chain = problem(load_scene("t_frame", {**base, "joints": []}))
    graph = problem(load_scene("t_frame", {**base, "joints": [{"ends": ["a.end", "b.start"]}]}))
    assert chain.space.chain and not graph.space.chain and chain.space.joints == graph.space.joints == ((6, 7),)
    y, u = _random_state(chain)
    assert np.array_equal(chain.increment_rate(0.2, y, u), graph.increment_rate(0.2, y, u))
    twin = beam_problem(graph.space, graph.constants, graph.bcs, graph.loads, backend="numpy", formulation="galerkin")
    assert np.array_equal(twin.increment_rate(0.2, y, u), graph.increment_rate(0.2, y, u))


def _joints(*entries):
    return {"joints": list(entries)}


@pytest.mark.parametrize("over, match", [
    (_joints({"ends": ["post.end", "arm.start"]}),
     r"joints\[0\]: key 'ends': 'arm.start': no \[\[beams\]\] entry named 'arm' \(members: post, left, right\)"),
    (_joints({"ends": ["post.end", "left.middle"]}),
     r"joints\[0\]: key 'ends': 'left.middle': expected \"<member>.start\", \"<member>.end\" or "
     r"\"<member>@<fraction>\""),
    (_joints({"ends": ["post.end"]}), r"joints\[0\]: key 'ends': expected two or more member ends"),
    (_joints({"ends": ["left.end", "right.end"]}),
     r"joints\[0\]: key 'ends': 'right.end' at \[0.5, 0.0, 1.0\] is 1 m from 'left.end' at \[-0.5, 0.0, 1.0\]; "
     "joined ends must coincide"),
    (_joints({"ends": ["post.end", "left.start"]}, {"ends": ["right.start", "post.end"]}),
     r"joints\[1\]: key 'ends': 'post.end' is already joined \(joints\[0\]\)"),
    (_joints({"ends": ["post.end", "left.start", "left.start"]}),
     r"joints\[0\]: key 'ends': 'left.start' is already joined \(joints\[0\]\)"),
    (_joints({"ends": ["post.start", "left.end"]}),
     r"joints\[0\]: key 'ends': 'post.start' is supported \(bc.start = 'clamped'\); a joint takes free ends only"),
    (_joints({"ends": T_JOINT, "kind": "slider"}), r"joints\[0\]: key 'kind' = 'slider': expected one of"),
    (_joints({"ends": T_JOINT, "knd": "ball"}), r"joints\[0\]: unknown key 'knd'"),
    ({"space.formulation": "primal", "material.kelvin_voigt": 0.0},
     r"the collocation formulations join patches in a chain only"),
    ({"point_loads": [{"s": 0.5, "force": [0, 0, 1.0]}]},
     r"point_loads\[0\]: s = 0.5 is a member end; with \[\[joints\]\] a point load acts inside a member"),
    ({"beams": [{"kind": "straight", "length": 1.0}]}, r"beams\[0\]: key 'name' = '': \[\[joints\]\] needs a distinct"),
])
def test_bad_joints_are_one_line_errors(over, match):
    with pytest.raises(SceneError, match=match):
        load_scene("t_frame", over)


def test_bad_joints_exit_2_in_one_line(tmp_path, capsys):
    rc = main(["run", "t_frame", "--out", str(tmp_path / "x"), "--set", 'joints=[{ends = ["post.end", "arm.start"]}]'])
    err = capsys.readouterr().err
    assert rc == 2 and "joints[0]: key 'ends': 'arm.start'" in err
    assert err.count("\n") == 1 and "Traceback" not in err


def test_t_frame_pictures_do_not_join_members(tmp_path):
    """The ParaView series and the shape plot draw each member on its own: the VTU has one
    line cell per pair of consecutive points of the same member (points minus members, and
    none across), with the member as point data; the plotted centrelines carry a NaN point
    between members (no stroke from one arm's end to the next member's start)."""
    import glob

    import meshio

    from liegroup_int.runner import run_scene

    run_scene(load_scene("t_frame", {"t_end": 0.01, "output.every": 0.005, "output.paraview": True,
                                     "output.plots": False}), tmp_path)
    m = meshio.read(sorted(glob.glob(str(tmp_path / "paraview" / "*.vtu")))[-1])
    member = m.point_data["member"]
    cells = m.cells[0].data
    assert len(cells) == len(member) - len(np.unique(member)) and np.all(member[cells[:, 0]] == member[cells[:, 1]])
    from liegroup_int.scenes import KINDS

    sim = KINDS["beam"].build(load_scene("t_frame"))
    line = sim.snapshot.from_snapshots(np.array([0.0, 1.0]), {"c": np.stack([sim.y0.c, sim.y0.c])})["centreline"]
    assert np.sum(np.isnan(line[0, :, 0])) == len(np.unique(member)) - 1


def test_joint_reactions_are_recorded_per_joint(tmp_path):
    """``output.quantities = [..., "joint_reactions"]``: six columns per joint pair in
    history.csv, equal to the problem's joint_reactions at the recorded states (the final
    row against the final state, to round-off); refused in one line without joints."""
    from liegroup_int.io import read_history
    from liegroup_int.runner import run_scene
    from liegroup_int.scenes import KINDS

    sc = load_scene("t_frame", {"t_end": 0.01, "output.every": 0.005, "output.plots": False,
                                "output.quantities": ["tip", "joint_reactions"]})
    res = run_scene(sc, tmp_path)
    h = read_history(tmp_path / "history.csv")
    from liegroup_int.io.checkpoint import read_checkpoint

    sim = KINDS["beam"].build(sc)
    pb = sim.problem
    cols = [f"joint{k}_{q}" for k in range(len(pb.joints)) for q in ("fx", "fy", "fz", "cx", "cy", "cz")]
    assert len(pb.joints) == 2 and all(c in h for c in cols) and res.summary["status"] == "ok"
    ck = read_checkpoint(tmp_path / "checkpoint.npz")
    assert ck["t"] == h["t"][-1]
    want = np.concatenate([np.concatenate(fc) for fc in pb.joint_reactions(sim.from_arrays(ck["state"]), ck["t"])])
    got = np.array([h[c][-1] for c in cols])
    assert np.max(np.abs(got - want)) <= 1e-12 * np.max(np.abs(want)) + 1e-14
    assert np.max(np.abs(want)) > 0.1  # the tip force passes through the joint
    with pytest.raises(SceneError, match="'joint_reactions' needs a frame's joints"):
        load_scene("cantilever", {"output.quantities": ["joint_reactions"]})


def test_a_load_at_a_joint_is_carried_to_the_support(tmp_path):
    """A dead force at the T-frame's joint ([[joints]] force) with the arm's tip force off:
    in static equilibrium the post's clamp takes it all, force to the Newton tolerance
    (1e-8 of the load; measured below 1e-9) and the couple r x F of the joint's deformed
    position."""
    import json

    force = [3.0, 0.0, -20.0]
    joint = {"ends": ["post.end", "left.start", "right.start"], "force": force}
    out = tmp_path / "st"
    assert main(["static", "t_frame", "--set", f"joints=[{{ends={joint['ends']!r}, force={force!r}}}]".replace("'", '"'),
                 "--set", "loads.end.force=[0,0,0]", "--out", str(out), "--quiet"]) == 0
    s = json.loads((out / "summary.json").read_text())
    (name, r), = s["reactions"].items()
    assert np.max(np.abs(np.array(r["force"]) + force)) < 1e-7 * 20.0
    sim_pb = problem(load_scene("t_frame", {"joints": [joint], "loads.end.force": [0.0, 0.0, 0.0]}))
    assert len(sim_pb.point_loads) == 1 and sim_pb.point_loads[0][0] == sim_pb.joints[0].a
    x = np.load(out / "state.npz")["c"][sim_pb.joints[0].a]  # the joint at equilibrium
    base = sim_pb.space.patches[0].c0[0]  # the clamp at the post's start
    assert np.max(np.abs(np.array(r["couple"]) + np.cross(x - base, force))) < 1e-7 * 20.0
