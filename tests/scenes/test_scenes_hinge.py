"""[[joints]] kind = "hinge": two collinear members along x, the first clamped at x = 0,
joined at x = 1 m by a hinge, on the Galerkin beam; checks against exact properties (the
deformed axes of both ends stay one line, energy, equivalence with the ball and rigid
joints where the hinge must act as them)."""

from __future__ import annotations

import numpy as np
import pytest

from liegroup_int.cli import main
from liegroup_int.scenes import SceneError, load_scene
from liegroup_int.scenes.beam import problem

from test_scenes_joints import TWO, _backends_agree, _run

#: a tip force in the bending plane (y) and out of it (z): the hinge turns and bends
SKEW = {"loads.end.force": [0.0, 50.0, 50.0], "loads.end.couple": [0.0, 0.0, 0.0]}


def _two(kind="hinge", axis=(0.0, 0.0, 1.0), backend="numba", spring=(0.0, 0.0), **over):
    joint = {"ends": ["a.end", "b.start"], "kind": kind, **({"axis": list(axis)} if kind == "hinge" else {})}
    if any(spring):
        joint.update(stiffness=spring[0], damping=spring[1])
    return problem(load_scene("t_frame", {**TWO, "joints": [joint], "integrator.backend": backend, **over}))


def _axes(pb, y):
    """The deformed hinge axis at the end of member a and at the start of member b, ``(3,)`` each."""
    j, ax = pb.joints[0], np.asarray(pb.space.joint_axes[0])
    return y.R[j.point] @ pb.gs.R0[j.point].T @ ax, y.R[j.point_b] @ pb.gs.R0[j.point_b].T @ ax


def _hinge_angle(pb, y):
    """Angle [rad] of the relative rotation of the two joined sections from their reference."""
    j = pb.joints[0]
    H = j.Q.T @ y.R[j.point].T @ y.R[j.point_b]
    return float(np.arccos(np.clip((np.trace(H) - 1.0) / 2.0, -1.0, 1.0)))


def test_the_hinge_keeps_the_two_axes_one_line():
    """A skew tip force (50 N along y and along z) turns the hinge by up to 54 degrees while
    both members bend out of plane. The constraints follow the state (``G = R_a^T R_b``,
    ``dexp`` of the increments), so the deformed axis seen from member a and from member b
    stays one line: |n_a x n_b| measured at most 2.5e-14 over 0.2 s at h = 2e-5 (10^4
    steps), the joined positions equal to 2.4e-15 m. Allowed 1e-12: round-off of ~1e-16
    per step accumulated over the steps. A constraint written with the reference relative
    rotation only (constant Q) drifts here by ~1e-3 rad at 6 degrees, whatever h."""
    pb = _two(**SKEW)
    j = pb.joints[0]
    out = _run(pb, 0.2, 2e-5, n_out=21)
    for _, y in out:
        na, nb = _axes(pb, y)
        assert np.linalg.norm(np.cross(na, nb)) <= 1e-12
        assert np.max(np.abs(y.c[j.b] - y.c[j.a])) <= 1e-12
    assert max(_hinge_angle(pb, y) for _, y in out) >= np.radians(30.0)  # 54 degrees measured


def test_hinge_energy_error_falls_at_the_step_to_the_fifth():
    """Kinetic + strain + load potential under the skew force: the hinge's constraint
    forces do no work, so only RKMK4's error is left, falling as h^5 (as for the rigid and
    ball joints, tests/scenes/test_scenes_joints.py). Largest |E - E0| over 0-0.1 s at
    h = 2e-5, 1e-5, 5e-6: measured 2.4e-6, 7.7e-8, 2.4e-9 J, slope 5.0, against 4 J of work
    done by the force. Fitted slope in [4.5, 5.5]."""
    pb = _two(**SKEW)
    steps = np.array([2e-5, 1e-5, 5e-6])
    errs = []
    for h in steps:
        out = _run(pb, 0.1, h)
        E0 = pb.energy(out[0][1], 0.0)
        errs.append(max(abs(pb.energy(y, t) - E0) for t, y in out))
    slope = np.polyfit(np.log(steps), np.log(errs), 1)[0]
    assert 4.5 <= slope <= 5.5, (errs, slope)
    assert errs[-1] <= 1e-8


@pytest.mark.parametrize("force, twin", [([0.0, 5.0, 0.0], "ball"), ([0.0, 0.0, 5.0], "rigid")])
def test_a_hinge_is_a_ball_in_its_plane_and_rigid_out_of_it(force, twin):
    """Hinge about z. A tip force along y bends the frame in the x-y plane, where every
    rotation is about z: the hinge transmits no moment about its axis and moves exactly as
    a ball joint (measured difference 0.0 in positions and angular velocities over 0.1 s at
    h = 2e-5 while the tip moves 8 cm). A tip force along z bends it about y, which the hinge
    transmits: it moves as a rigid joint (measured 8.7e-15 m and 1.3e-11 rad/s against
    0.68 rad/s: the two constraint sets solve the same rows with different arithmetic).
    Allowed 1e-12 m and 1e-9 of the largest angular velocity."""
    loads = {"loads.end.force": force, "loads.end.couple": [0.0, 0.0, 0.0]}
    hinge, other = _run(_two(**loads), 0.1, 2e-5), _run(_two(kind=twin, **loads), 0.1, 2e-5)
    wmax = max(np.max(np.abs(y.w)) for _, y in hinge)
    for (_, y1), (_, y2) in zip(hinge, other):
        assert np.max(np.abs(y1.c - y2.c)) <= 1e-12
        assert np.max(np.abs(y1.w - y2.w)) <= 1e-9 * wmax
    assert np.max(np.abs(hinge[-1][1].c - hinge[0][1].c)) >= 0.01  # the force acts (8 and 5 cm measured)


def test_torsion_passes_a_hinge_across_its_axis_only():
    """A torsion couple of 2 N m at the tip. Hinge about x (the members' axis): the second
    member twists alone, the first stays at rest (its angular velocities measured exactly 0,
    as behind a ball joint) and the angular momentum about x is C t (to 1.1e-16). Hinge
    about z: the torsion reaches the clamp through the hinge, the first member twists (its
    largest angular velocity that of the whole frame, ratio 1.0 measured)."""
    pb = _two(axis=(1.0, 0.0, 0.0))
    na = pb.space.offsets[1]
    for t, y in _run(pb, 0.1, 2e-5)[1:]:
        assert np.max(np.abs(y.w[:na])) <= 1e-14 * np.max(np.abs(y.w))
        assert pb.momentum(y)[1][0] == pytest.approx(2.0 * t, rel=1e-12, abs=1e-15)
    pb = _two()
    ratios = [np.max(np.abs(y.w[:na])) / np.max(np.abs(y.w)) for _, y in _run(pb, 0.1, 2e-5)[1:]]
    assert max(ratios) >= 0.5


def test_backends_agree_on_the_hinge_rates():
    """NumPy and numba stage rates and load power at a deformed moving state with a skew
    hinge axis, its spring and damper: to round-off (measured 1.4e-15 relative; 1e-12
    allowed as for the other joints). The rates satisfy the hinge's constraints: ``E (W_b' - G^T W_a')`` equals its
    right-hand side ``-E (W_b x G^T W_a)``, and the rotation rates keep the axis
    (``E (A_b Theta_b' - G^T A_a Theta_a') = 0``)."""
    from liegroup_int.groups.so3 import left_jacobian

    pbs = [_two(axis=(0.0, 1.0, 2.0), backend=b, spring=(3.0, 0.5), **SKEW) for b in ("numpy", "numba")]
    y, u, rates, scale = _backends_agree(pbs)
    h = pbs[0].hinges[0]
    G = y.R[h.point].T @ y.R[h.point_b]
    r = rates[0]
    acc = h.E @ (r[3, h.b] - G.T @ r[3, h.a]) + h.E @ np.cross(y.w[h.b], G.T @ y.w[h.a])
    turn = h.E @ (left_jacobian(-u[1, h.b]) @ r[1, h.b] - G.T @ left_jacobian(-u[1, h.a]) @ r[1, h.a])
    assert np.max(np.abs(acc)) <= 1e-12 * scale and np.max(np.abs(turn)) <= 1e-12 * scale
    assert np.max(np.abs(r[[0, 2], h.b] - r[[0, 2], h.a])) <= 1e-12 * scale
    assert abs(pbs[0]._hinge_springs(y)[0][2]) >= 1e-3  # the spring-damper acts: -0.069 N m measured


@pytest.mark.parametrize("joint, match", [
    ({"kind": "hinge"}, r"joints\[0\]: key 'axis' = \[0.0, 0.0, 0.0\]: a hinge needs a finite non-zero axis"),
    ({"kind": "hinge", "axis": [0, 0, 0]}, r"joints\[0\]: key 'axis' = \[0.0, 0.0, 0.0\]: a hinge needs"),
    ({"kind": "hinge", "axis": [0, 1]}, r"joints\[0\]: key 'axis'"),
    ({"kind": "ball", "axis": [0, 0, 1]}, r"joints\[0\]: key 'axis': only a hinge has an axis, a spring and a damper \(kind = 'ball'\)"),
    ({"stiffness": 2.0}, r"joints\[0\]: key 'stiffness': only a hinge has an axis, a spring and a damper"),
    ({"kind": "hinge", "axis": [0, 0, 1], "damping": -1.0}, r"joints\[0\]: key 'damping'"),
])
def test_bad_hinge_axes_are_one_line_errors(joint, match):
    with pytest.raises(SceneError, match=match):
        load_scene("t_frame", {**TWO, "joints": [{"ends": ["a.end", "b.start"], **joint}]})


def test_bad_hinge_axis_exits_2_in_one_line(tmp_path, capsys):
    rc = main(["run", "t_frame", "--out", str(tmp_path / "x"), "--set",
               'joints=[{ends = ["post.end", "left.start", "right.start"], kind = "hinge"}]'])
    err = capsys.readouterr().err
    assert rc == 2 and "joints[0]: key 'axis'" in err
    assert err.count("\n") == 1 and "Traceback" not in err


def _sprung(k, c, **over):
    joint = {"ends": ["a.end", "b.start"], "kind": "hinge", "axis": [0.0, 0.0, 1.0], "stiffness": k, "damping": c}
    return problem(load_scene("t_frame", {**TWO, "joints": [joint], "integrator.backend": "numba", **over}))


@pytest.mark.parametrize("damping", [0.0, 2.0])
def test_hinge_spring_and_damper_close_the_energy_balance(damping):
    """Hinge about z with a rotational spring (k = 20 N m/rad: the skew force turns it by
    0.6 rad) and without or with a damper (c = 2 N m s/rad): kinetic + strain energy (1/2 k
    phi^2 included) minus the work of the force and the damper's dissipation (the
    integrated power) is RKMK4's error only, falling as h^5: measured 2.4e-6, 7.7e-8,
    2.4e-9 J (c = 0) and 1.4e-6, 4.3e-8, 1.3e-9 J (c = 2) at h = 2e-5, 1e-5, 5e-6 over
    0.1 s, slopes 5.0, against 47 J of work. A couple that were not the gradient of the
    spring's energy, or a dissipation left out of the power, would leave a defect that does
    not fall with h. Fitted slope in [4.5, 5.5]."""
    from liegroup_int import integrate

    pb = _sprung(20.0, damping, **SKEW)
    steps = np.array([2e-5, 1e-5, 5e-6])
    errs = []
    for h in steps:
        y0 = pb.initial_state()
        res = integrate(pb, y0, (0.0, 0.1), dt=h)
        errs.append(abs(pb.mechanical_energy(res.y_final) - pb.mechanical_energy(y0) - res.stats.quadrature))
    slope = np.polyfit(np.log(steps), np.log(errs), 1)[0]
    assert 4.5 <= slope <= 5.5, (errs, slope)
    assert abs(pb._hinge_springs(res.y_final)[0][0]) >= 0.3  # the spring works: 0.6 rad measured


def test_hinge_spring_holds_the_tip_couple_at_rest():
    """A couple C = 0.5 N m about z at the tip, ramped on over 2 s; the hinge's spring
    (k = 1 N m/rad) and damper (c = 1.2 N m s/rad, about critical for the second member's
    swing, inertia 0.34 kg m^2 about the hinge) bring the frame to rest, where statics
    says that member b carries C unchanged to the hinge: k phi = C (phi = 0.5 rad, a
    finite rotation), and the joint's couple on b is -C about z. Measured over 16-20 s
    (h = 2e-4, 0.68 of RKMK4's stability limit 2.9e-4 s; h = 1e-4 gives the same figures):
    |k phi - C| <= 2.6e-8 N m and the couple within 2.5e-6 N m of -C: what is left are the
    undamped bending vibrations of the members (angular velocities ~1e-5 rad/s, through the
    damper c dphi/dt). Allowed 1e-6 C and 2e-5 C."""
    C = 0.5
    pb = _sprung(1.0, 1.2, **{"loads.end.couple": [0.0, 0.0, C], "loads.end.force": [0.0, 0.0, 0.0],
                              "loads.end.profile": "ramp", "loads.end.ramp": 2.0})
    out = _run(pb, 20.0, 2e-4, n_out=11)
    for t, y in out[-3:]:
        phi = pb._hinge_springs(y)[0][0]
        assert abs(1.0 * phi - C) <= 1e-6 * C
        couple = pb.joint_reactions(y, t)[0][1]
        assert np.max(np.abs(couple - [0.0, 0.0, -C])) <= 2e-5 * C


def _stiff(value):
    return {f"section.{k}": value for k in ("EA", "GA", "EI1", "EI2", "GJ")}


def test_static_hinge_with_a_spring_against_the_rigid_bar_formula():
    """Two 1 m members, the first clamped, joined by a hinge about z with a rotational spring
    k = 20 N m/rad; a dead 20 N force along y at the tip. As rigid bars: k phi = P L cos(phi),
    so phi = cos(phi), phi = 0.7390851332 (Dottie's number). Solved by `solve_static` (the
    hinge's angle is an unknown, its constraint exact at every iterate) with members of
    stiffness S = 1e5 and 1e6 (EA = GA = EI = GJ = S): the angle's distance to the formula is
    the members' own flexibility, so it falls as 1 / S (measured 1.196e-4 and 1.196e-5: ratio
    10.0; asserted 9 to 11, and below 2e-5 at 1e6). The axes stay one line to round-off, and
    the clamp's reaction balances the force to the Newton tolerance. Two load steps (13 and
    24 Newton iterations; ten steps take 46 and 56 and give the same figures)."""
    from liegroup_int import solve_static

    errs = []
    for stiffness in (1e5, 1e6):
        pb = _two(spring=(20.0, 0.0), backend="numpy", **_stiff(stiffness), **{"loads.end.force": [0.0, 20.0, 0.0]})
        res = solve_static(pb, load_steps=2)
        y = res.state
        errs.append(abs(pb._hinge_springs(y)[0][0] - 0.7390851332))
        na, nb = _axes(pb, y)
        assert res.converged and np.linalg.norm(np.cross(na, nb)) < 1e-12
        force, _ = pb.reactions(y)["start"]
        assert np.allclose(force, [0.0, -20.0, 0.0], atol=1e-6)
    print(f"distance to the rigid-bar angle: {errs[0]:.4g}, {errs[1]:.4g}; ratio {errs[0] / errs[1]:.3f}")
    assert 9.0 < errs[0] / errs[1] < 11.0 and errs[1] < 2e-5


def test_static_hinge_is_rigid_out_of_its_plane():
    """A force along z, across the hinge's plane: the hinge about z transmits the bending
    about y like a rigid joint, and the static tips agree to 1e-9 m (Newton tolerance; the
    hinge's twist about its own axis is not loaded)."""
    from liegroup_int import solve_static

    force = {"loads.end.force": [0.0, 0.0, 5.0], "loads.end.couple": [0.0, 0.0, 0.0]}
    tips = [pb.tip(solve_static(pb, load_steps=2).state) for pb in (_two(backend="numpy", **force),
                                                                     _two("rigid", backend="numpy", **force))]
    print(tips, tips[0] - tips[1])
    assert np.max(np.abs(tips[0] - tips[1])) < 1e-9 and abs(tips[0][2]) > 0.1
