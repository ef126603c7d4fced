"""The Galerkin (weak-form) beam: backends, spectrum at rest, locking, energy, statics,
scenes and long runs."""

from __future__ import annotations

import numpy as np
import pytest

from liegroup_int.integrators import eigenvalues, integrate_fixed, resolve_method, spectral_radius
from liegroup_int.scenes import load_scene
from liegroup_int.scenes.beam import problem

BEAM_SCENES = ["arch", "cantilever", "flying_spaghetti", "pendulum", "right_angle_cantilever", "rollup", "spin_up",
               "spinning_helix"]


def galerkin(name, **overrides):
    return problem(load_scene(name, {"space.formulation": "galerkin", **overrides}))


@pytest.mark.parametrize("name,extra", [(s, {}) for s in BEAM_SCENES] + [("pendulum", {"material.kelvin_voigt": 1e-4})])
def test_backends_agree(name, extra):
    """Action, stage rates and load power of both backends at a perturbed state and a
    random stage increment: equal to round-off (measured <= 2e-12 relative, the
    moving clamp of spin_up)."""
    a = galerkin(name, **{"integrator.backend": "numpy", **extra})
    b = galerkin(name, **{"integrator.backend": "numba", **extra})
    rng = np.random.default_rng(3)
    y = a.initial_state()
    u = 1e-3 * rng.standard_normal((4, a.n, 3))
    ya, yb = a.action(u, y), b.action(u, y)
    for k in "cvwRK":
        assert np.max(np.abs(getattr(ya, k) - getattr(yb, k))) <= 1e-14 * max(1.0, np.max(np.abs(getattr(ya, k))))
    u2 = 1e-3 * rng.standard_normal((4, a.n, 3))
    ka, kb = a.increment_rate(0.13, ya, u2), b.increment_rate(0.13, ya, u2)
    scale = np.max(np.abs(ka), axis=(1, 2))
    assert np.all(np.max(np.abs(ka - kb), axis=(1, 2)) <= 1e-11 * scale)
    if a.has_quadrature:
        b._nb.increment_rate(0.13, ya, u2)
        assert float(b._nb._pw[0]) == pytest.approx(a.quadrature_rate(0.13, ya), rel=1e-11)


@pytest.mark.parametrize("name,p,n", [("cantilever", 2, 11), ("cantilever", 3, 21), ("cantilever", 6, 61),
                                      ("cantilever", 8, 41), ("pendulum", 4, 31), ("arch", 4, 31),
                                      ("arch", 6, 81)])
def test_spectrum_at_rest_is_imaginary(name, p, n):
    """The weak form's stiffness is symmetric: linearized at rest, max Re(lambda) is
    finite-difference noise, below 1e-7 |lambda|max (measured <= 1.3e-8, the pendulum's
    double zero eigenvalue of its rigid swing). Collocation at p = 6, n_ctrl = 81 grows
    at +4.3e4 1/s (primal cantilever, docs/verification.md)."""
    pb = galerkin(name, **{"space.degree": p, "space.n_ctrl": n})
    ev = eigenvalues(pb, 0.0, pb.initial_state())
    lam = np.max(np.abs(ev))
    print(f"{name} p={p} n={n}: max Re {ev.real.max():.3g} 1/s, |lambda|max {lam:.4g}")
    assert ev.real.max() <= 1e-7 * lam


#: First bending frequency of the steel cantilever [rad/s], converged (p = 4, n_ctrl = 31
#: and 61 agree to 1e-7); Euler-Bernoulli gives 52.666.
OMEGA1 = 52.6616


def _omega1(pb):
    ev = eigenvalues(pb, 0.0, pb.initial_state())
    return float(np.min(np.abs(ev.imag[ev.imag > 1.0])))


def test_reduced_integration_removes_locking():
    """p = 2, n_ctrl = 11: full Gauss integration locks (first frequency +2.1 %), reduced
    integration of the axial and shear terms does not (+2e-4)."""
    from liegroup_int.problems.beam import GalerkinBeamProblem

    pb = galerkin("cantilever", **{"space.degree": 2, "space.n_ctrl": 11})
    full = GalerkinBeamProblem(pb.space, pb.constants, pb.bcs, pb.loads, pb.initial, integration="full")
    w_red, w_full = _omega1(pb), _omega1(full)
    print(f"omega1 reduced {w_red:.5f}, full {w_full:.5f}, converged {OMEGA1}")
    assert abs(w_red / OMEGA1 - 1) < 5e-4
    assert w_full / OMEGA1 - 1 > 0.01


def test_power_iteration_finds_the_largest_eigenvalue_of_a_stiff_frame():
    """The built-in portal (three members, rigid corners, EA / EI = 1e7 per m^2, n_ctrl =
    21 per member) at rest: the largest |lambda| (modes at the corners) is 5.129e5 1/s by
    the dense spectrum; the power iteration of dt = "auto" finds it to 1e-3 (measured
    2e-4 below; it converges from below through a cluster of four pairs within 1e-3). With
    one-sided products it stopped at 1.44e5, and a run at that step blew up from rest.
    Then RKMK4 at the step dt = "auto" takes keeps the frame at rest (no loads) over 2000
    steps: velocities stay at round-off (below 1e-9 m/s, from rates of 1e-4 at the start)."""
    pb = problem(load_scene("portal", {"point_loads": []}))
    y0 = pb.initial_state()
    lam = spectral_radius(pb, 0.0, y0)
    dense = float(np.max(np.abs(eigenvalues(pb, 0.0, y0))))
    print(f"power iteration {lam:.6g}, dense {dense:.6g}")
    assert abs(lam / dense - 1) < 1e-3
    _, y, _ = integrate_fixed(pb, resolve_method("rkmk4"), (0.0, 2000 * 2.26 / lam), y0, 2.26 / lam)
    print(f"largest velocity after 2000 steps: {np.abs(y.v).max():.3g} m/s")
    assert np.all(np.isfinite(y.v)) and np.abs(y.v).max() < 1e-9


def test_pendulum_energy_is_conserved():
    """The paper's pendulum (p = 4, n_ctrl = 31) over 0.2 s at the RKMK4 step |lambda| h = 2
    (dt = auto is 2.26): the energy drifts by 3.5e-11 J (target 1e-5 J). With RKMK3 over
    0.5 s the drift shrinks with dt: measured 9.6e-10, 4.1e-10 and 1.6e-10 J at |lambda| h =
    1.2, 0.85 and 0.6, slope 2.56 (2.43 over 1 s); the smallest stays 16x above the
    round-off floor, ~1e-11 J, that flattens the slope at smaller steps."""
    pb = galerkin("pendulum")
    y0 = pb.initial_state()
    lam = spectral_radius(pb, 0.0, y0)
    E0 = pb.energy(y0)
    rec = []
    integrate_fixed(pb, resolve_method("rkmk4"), (0.0, 0.2), y0, 2.0 / lam,
                    observer=lambda t, y: rec.append(pb.energy(y, t)), t_out=np.linspace(0.0, 0.2, 21)[1:])
    drift = np.max(np.abs(np.array(rec) - E0))
    print(f"energy drift over 0.2 s: {drift:.3g} J")
    assert drift < 1e-9
    drifts = []
    for y in (1.2, 0.85, 0.6):
        rec = []
        integrate_fixed(pb, resolve_method("rkmk3"), (0.0, 0.5), y0, y / lam,
                        observer=lambda t, y: rec.append(pb.energy(y, t)), t_out=np.linspace(0.0, 0.5, 21)[1:])
        drifts.append(np.max(np.abs(np.array(rec) - E0)))
    slope = np.polyfit(np.log([1.2, 0.85, 0.6]), np.log(drifts), 1)[0]
    print(f"RKMK3 drifts {drifts}, slope {slope:.2f}")
    assert 2.2 < slope < 3.5


def test_hanging_bar_is_static_and_reaction_is_weight():
    """A bar clamped at s = 0 with gravity along its axis: the exact static stretch
    ``u(s) = mu g (L s - s^2 / 2) / EA`` is quadratic, so it lies in the trial space and the
    weak form is exactly in equilibrium (accelerations at round-off, against g unbalanced);
    the consistent reaction equals the weight."""
    pb = galerkin("cantilever", **{"loads.gravity": [9.81, 0.0, 0.0], "loads.end.force": [0.0, 0.0, 0.0],
                                   "space.degree": 3, "space.n_ctrl": 9})
    y = pb.initial_state()
    L, EA, mu = pb.space.length, pb.CN[0, 2], pb.mu[0]
    s = pb.gs.s
    u = mu * 9.81 * (L * s - 0.5 * s**2) / EA
    y.c = y.c + pb.gs.project(np.outer(u, [1.0, 0.0, 0.0]))
    acc = pb.increment_rate(0.0, y, pb.zero_increment(y))[2]
    print(f"largest acceleration {np.max(np.abs(acc)):.3g} m/s^2")
    assert np.max(np.abs(acc)) < 1e-6 * 9.81
    f, c = pb.reactions(y)["start"]
    weight = mu * 9.81 * L
    assert f == pytest.approx([-weight, 0.0, 0.0], abs=1e-9 * weight)
    assert np.max(np.abs(c)) < 1e-9 * weight * L


@pytest.mark.parametrize("name", BEAM_SCENES)
def test_every_beam_scene_runs(name):
    """Every built-in beam scene builds and takes 20 steps of its own method
    with the Galerkin formulation (|lambda|max h = 0.1); the energy balance (kinetic + strain
    against the work of loads and supports) closes to 1e-6 of the largest term. The loads
    switched on at t = 0 make this a time error (the arch's shrinks 32x per halved step;
    1.4e-8 relative here)."""
    from liegroup_int.scenes.beam import build

    sim = build(load_scene(name, {"space.formulation": "galerkin", "space.n_ctrl": 15}))
    pb, y0 = sim.problem, sim.y0
    dt = 0.1 / spectral_radius(pb, 0.0, y0)
    _, y, stats = integrate_fixed(pb, resolve_method("rkmk4"), (0.0, 20 * dt), y0, dt)
    assert pb.is_finite(y) and pb.orth_error(y) < 1e-13
    E0, E1 = pb.mechanical_energy(y0), pb.mechanical_energy(y)
    work = stats.quadrature if pb.has_quadrature else 0.0
    scale = max(abs(E0), abs(E1), abs(work))
    print(f"{name}: E {E0:.6g} -> {E1:.6g} J, work {work:.6g} J")
    assert abs(E1 - E0 - work) < 1e-6 * scale + 1e-15  # spin_up starts from rest: ~1e-22 J


@pytest.mark.parametrize("tau", [0.0, 1e-3])
@pytest.mark.parametrize("sections", ["one", "two"])
def test_backends_agree_on_a_loaded_kink(tau, sections):
    """A right-angle frame (different degrees and sizes per member, anisotropic sections,
    one or one per member) under gravity and a distributed force with a time profile, with a
    force and couple at the kink: action, stage rates and load power of both backends at a
    perturbed state, to round-off (measured 9e-13 relative); the rates keep the members
    joined (``v_b = v_a``, ``W_b = Q^T W_a``)."""
    from liegroup_int.iga import CollocationSpace, straight
    from liegroup_int.iga.patches import PatchedSpace
    from liegroup_int.problems.beam import BoundaryConditions, EndLoad, GalerkinBeamProblem, Loads, Profile
    from liegroup_int.problems.beam import SectionConstants as SC

    pulse = Profile(kind="table", table=((0.0, 0.0), (1.0, 50.0), (2.0, 0.0)))
    A = SC(CN=(1e6, 1.2e6, 1e6), CM=(1e3, 2e3, 1.5e3), mu=1.0, Jm=(10.0, 12.0, 20.0))
    B = SC(CN=(4e5, 5e5, 8e5), CM=(3e2, 2e2, 4e2), mu=0.6, Jm=(3.0, 2.0, 5.0))
    sp = PatchedSpace([CollocationSpace(straight(10, (1, 0, 0), 4, 9)),
                       CollocationSpace(straight(10, (0, 1, 0), 3, 8, origin=(10, 0, 0)))])
    loads = Loads(joints=(EndLoad(force=(0, 0, 1.0), couple=(0.3, 0, 1), force_profile=pulse, couple_profile=pulse),),
                  gravity=(0.0, 0.0, -9.81), distributed_force=(0.5, 0.0, 0.2), distributed_profile=pulse)
    pbs = [GalerkinBeamProblem(sp, A if sections == "one" else (A, B), BoundaryConditions("clamped", "free"), loads,
                               backend=backend, kelvin_voigt=tau) for backend in ("numpy", "numba")]
    r = np.random.default_rng(1)
    u = 0.05 * r.standard_normal((4, pbs[0].n, 3))
    ys = [pb.action(u, pb.initial_state()) for pb in pbs]
    for k in "cvwRK":
        assert np.max(np.abs(getattr(ys[0], k) - getattr(ys[1], k))) <= 1e-13 * max(1.0, np.max(np.abs(getattr(ys[0], k))))
    y = ys[0]
    y.v += 0.1 * r.standard_normal(y.v.shape)
    y.w += 0.1 * r.standard_normal(y.w.shape)
    y.v, y.w = pbs[0].project_increment(np.stack([y.c, y.w, y.v, y.w]))[[2, 3]]
    rates = [pb.increment_rate(0.7, y, 0.1 * pbs[0].project_increment(u)) for pb in pbs]
    assert np.max(np.abs(rates[0] - rates[1])) <= 1e-11 * np.max(np.abs(rates[0]))
    pbs[1]._nb.increment_rate(0.7, y, np.zeros_like(u))
    assert float(pbs[1]._nb._pw[0]) == pytest.approx(pbs[0].quadrature_rate(0.7, y), rel=1e-11)
    a, b, _, Q = pbs[0].joints[0][:4]
    scale = np.max(np.abs(rates[0]))
    assert np.allclose(rates[0][[0, 2], b], rates[0][[0, 2], a], rtol=0, atol=1e-12 * scale)
    assert np.allclose(rates[0][[1, 3], b], rates[0][[1, 3], a] @ Q, rtol=0, atol=1e-12 * scale)


def test_pendulum_runs_past_the_collocation_blow_up():
    """p = 4, n_ctrl = 21, undamped: primal collocation blows up at 1.54 s
    (docs/verification.md); the Galerkin pendulum swings through 3 s with its energy kept
    to 1e-4 of the largest kinetic energy (measured 3.7e-5, a loss: RKMK4 at |lambda| h = 2
    damps the high modes that the axial compression bursts excite; collocation, whose
    semi-discretization does not conserve energy, feeds them instead: docs/theory.md
    section 16)."""
    pb = galerkin("pendulum", **{"space.n_ctrl": 21})
    y0 = pb.initial_state()
    dt = 2.0 / spectral_radius(pb, 0.0, y0)
    rec = []
    integrate_fixed(pb, resolve_method("rkmk4"), (0.0, 3.0), y0, dt,
                    observer=lambda t, y: rec.append((pb.energy(y, t), pb.energy_parts(y, t)["kinetic"])),
                    t_out=np.linspace(0.0, 3.0, 61)[1:])
    E = np.array(rec)
    drift = np.max(np.abs(E[:, 0] - pb.energy(y0)))
    print(f"3 s: energy drift {drift:.3g} J, largest kinetic energy {E[:, 1].max():.3g} J")
    assert drift < 1e-4 * E[:, 1].max()


def test_spin_up_support_work_balances_energy():
    """The hub of spin_up (a prescribed rotation of the clamped end) over its first second,
    n_ctrl = 11, at the RKMK4 step of dt = auto (|lambda| h = 2.26): kinetic + strain energy
    equals the work of the support's couple (the reaction of its supported rows times their
    angular velocity) to 1e-9 relative (measured 3.2e-14 of the 0.017 J at 1 s, round-off,
    and 1.2e-13 at |lambda| h = 1; 2e-10 J of 7205 J over the full 20 s run at n_ctrl = 21)."""
    from liegroup_int.scenes.beam import build

    sim = build(load_scene("spin_up", {"space.formulation": "galerkin", "space.n_ctrl": 11, "t_end": 1.0}))
    pb, y0 = sim.problem, sim.y0
    dt = 2.26 / spectral_radius(pb, 0.0, y0)
    _, y, stats = integrate_fixed(pb, resolve_method("rkmk4"), (0.0, 1.0), y0, dt)
    E1 = pb.mechanical_energy(y)
    print(f"energy {E1:.9g} J, support work {stats.quadrature:.9g} J")
    assert E1 > 1e-3
    assert abs(E1 - stats.quadrature) < 1e-9 * E1


@pytest.mark.parametrize("name", ["arch", "spinning_helix", "flying_spaghetti", "right_angle_cantilever"])
def test_rigid_motion_produces_no_strain(name):
    """The reference state rotated and shifted rigidly (free ends, no loads): no strain, so
    no acceleration beyond round-off (a wrong strain measure gives order-one strains)."""
    from liegroup_int.groups.so3 import SO3

    pb = galerkin(name, **{"loads.distributed_force": [0.0, 0.0, 0.0], "loads.gravity": [0.0, 0.0, 0.0],
                           "loads.end.couple": [0.0, 0.0, 0.0], "loads.end.force": [0.0, 0.0, 0.0],
                           "loads.start.force": [0.0, 0.0, 0.0], "loads.start.couple": [0.0, 0.0, 0.0],
                           "initial.omega": [0.0, 0.0, 0.0], "bc.start": "free", "bc.end": "free",
                           "point_loads": [], "output.quantities": ["tip"]})
    Q = SO3.exp(np.array([0.4, -1.1, 0.7]))
    y = pb.initial_state()
    y.c, y.R = y.c @ Q.T + np.array([0.3, -0.2, 0.5]), Q @ y.R
    k = pb.increment_rate(0.0, y, pb.zero_increment(y))
    moved = pb.initial_state()
    moved.c = moved.c + 1e-3 * np.random.default_rng(0).standard_normal(moved.c.shape)
    k_strained = pb.increment_rate(0.0, moved, pb.zero_increment(moved))
    print(f"{name}: rigid {np.abs(k[2:]).max():.3g}, strained {np.abs(k_strained[2:]).max():.3g}")
    assert np.abs(k[2:]).max() < 1e-9 * np.abs(k_strained[2:]).max()


@pytest.mark.parametrize("name", ["pendulum", "t_frame", "sprung_payload", "spinning_helix"])
def test_the_staged_rate_reads_what_the_action_left(name):
    """The engine's stages after the first call the stage rate with ``KIN_FROM_ACTION``: it
    takes ``Theta`` and its ``dexpinv`` coefficient at the points from the action that has
    just made the state from the same increment. Its rate and power are those computed from
    the increment, to the bit; after an action from another increment they are not (the
    reason the engine calls it only right after the action)."""
    from liegroup_int.problems.beam.kernels.adapters import KIN_COMPUTE, KIN_FROM_ACTION, c64

    pb = galerkin(name, **{"integrator.backend": "numba"})
    ks = pb._nb
    y = pb.initial_state()
    u = 1e-2 * np.random.default_rng(5).standard_normal((4, pb.n, 3))
    rates = ks.kernels()[1]
    ks._table.set(ks.data.loads, 0.1)

    def rate(y2, kin):
        out = np.empty((4, pb.n, 3))
        return out, rates(*ks._state(y2), c64(u), out, ks.flat, ks.head, kin)

    y2 = ks.action(u, y, type(y))
    (k1, p1), (k2, p2) = rate(y2, KIN_COMPUTE), rate(y2, KIN_FROM_ACTION)
    assert np.array_equal(k1, k2) and p1 == p2
    ks.action(2.0 * u, y, type(y))
    k3, _ = rate(y2, KIN_FROM_ACTION)
    assert not np.array_equal(k1[1], k3[1])
