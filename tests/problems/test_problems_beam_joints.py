"""Rigid joints of patches (PatchedSpace): both backends, and a straight joint against one
patch."""

from __future__ import annotations

import numpy as np
import pytest

from liegroup_int import integrate
from liegroup_int.iga import CollocationSpace, straight
from liegroup_int.iga.patches import PatchedSpace
from liegroup_int.problems.beam import (
    BeamProblem,
    BoundaryConditions,
    EndLoad,
    Loads,
    Profile,
    SectionConstants,
    beam_problem,
)

SECTION = SectionConstants(CN=(1e6, 1e6, 1e6), CM=(1e3, 1e3, 1e3), mu=1.0, Jm=(10.0, 10.0, 20.0))
PULSE = Profile(kind="table", table=((0.0, 0.0), (1.0, 50.0), (2.0, 0.0)))


SEC_A = SectionConstants(CN=(1e6, 1.2e6, 1e6), CM=(1e3, 2e3, 1.5e3), mu=1.0, Jm=(10.0, 12.0, 20.0))
SEC_B = SectionConstants(CN=(4e5, 5e5, 8e5), CM=(3e2, 2e2, 4e2), mu=0.6, Jm=(3.0, 2.0, 5.0))


@pytest.mark.parametrize("formulation", ["primal"])
@pytest.mark.parametrize("tau", [0.0, 1e-3])
@pytest.mark.parametrize("sections", [SEC_A, (SEC_A, SEC_B)], ids=["one_section", "two_sections"])
def test_backends_agree_on_a_loaded_kink(formulation, tau, sections):
    """A right-angle frame (different degrees and sizes per patch, anisotropic sections, one
    or one per patch) under gravity and a distributed force with a time profile, with a
    force and couple at the kink: stage rates and load power of both backends at a random
    state, to round-off (measured 2e-15 relative)."""
    sp = PatchedSpace([CollocationSpace(straight(10, (1, 0, 0), 4, 9)),
                       CollocationSpace(straight(10, (0, 1, 0), 3, 8, origin=(10, 0, 0)))])
    loads = Loads(joints=(EndLoad(force=(0, 0, 1.0), couple=(0.3, 0, 1), force_profile=PULSE, couple_profile=PULSE),),
                  gravity=(0.0, 0.0, -9.81), distributed_force=(0.5, 0.0, 0.2), distributed_profile=PULSE)
    rates, powers = [], []
    for backend in ("numpy", "numba"):
        pb = BeamProblem(sp, sections, BoundaryConditions("clamped", "free"), loads, backend=backend,
                         formulation=formulation, kelvin_voigt=tau)
        r = np.random.default_rng(1)
        u = 0.05 * r.standard_normal((4, pb.n, 3))
        u[:, 9] = u[:, 8]  # one increment at the joint
        y = pb.action(u, pb.initial_state())
        y.v += 0.1 * r.standard_normal(y.v.shape)
        y.w += 0.1 * r.standard_normal(y.w.shape)
        y.v[9], y.w[9] = y.v[8], y.w[8]
        rates.append(pb.increment_rate(0.7, y, 0.1 * u))
        if backend == "numba":  # the compiled kernels' own power (what the engine integrates)
            pw = pb._nb._pw
            pb._nb.increment_rate(0.7, y, np.zeros_like(u))
            powers += [pb.quadrature_rate(0.7, y), float(pw[0])]
    assert np.max(np.abs(rates[0] - rates[1])) <= 1e-12 * np.max(np.abs(rates[0]))
    assert powers[1] == pytest.approx(powers[0], rel=1e-12)
    # the joint's two rows share one rate
    assert np.allclose(rates[0][:, 8], rates[0][:, 9], rtol=0, atol=1e-12 * np.max(np.abs(rates[0])))


def _tips(space, formulation, dt, t_end=1.0):
    end = EndLoad(force=(0, 0, 0.5), couple=(2.0, 0, 1.0), force_profile=PULSE, couple_profile=PULSE)
    pb = beam_problem(space, SECTION, BoundaryConditions("clamped", "free"), Loads(end=end), formulation=formulation,
                      backend="numba")
    tips = []
    integrate(pb, pb.initial_state(), (0.0, t_end), dt=dt, t_eval=np.linspace(0.0, t_end, 5),
              observer=lambda t, y: tips.append(y.c[-1].copy()))
    return np.array(tips)


@pytest.mark.parametrize("formulation", ["galerkin"])
def test_straight_joint_converges_like_one_patch(formulation):
    """Two collinear 10 m patches of n control points each against one 20 m patch of
    2n - 1 (the same spacing), both against one patch of 81: a 20 m cantilever (the
    right-angle frame's section) under a tip force and torsion-bending couple pulse, tip
    error over 0.5 s. Steps of 1e-4 s (RKMK4's stability limit is 1.6e-4 s on 41 control
    points), the reference 5e-5 s (limit 7.6e-5 s on 81): the errors equal those with steps
    of 2e-5 s to 6e-10 (0.5 % of the smallest), the reference to 5e-11, so they are the
    space errors. Measured (n = 11, 21), Galerkin: one patch 4.1e-6, 1.1e-7; two patches
    9.6e-6, 1.6e-7: the joint (a C^0 break instead of C^3 continuity) costs 2.4x the error
    at n = 11, 1.5x at n = 21, and converges faster than one patch (log2 of the error ratio
    5.9). The reference's own error, from the one-patch rate, is below 5 % of the smallest
    error measured."""
    T, dt_ref, dt = 0.5, 5e-5, 1e-4
    ref = _tips(CollocationSpace(straight(20, (1, 0, 0), 4, 81)), formulation, dt_ref, T)
    err = {}
    for n in (11, 21):
        one = _tips(CollocationSpace(straight(20, (1, 0, 0), 4, 2 * n - 1)), formulation, dt, T)
        two = _tips(PatchedSpace([CollocationSpace(straight(10, (1, 0, 0), 4, n)),
                                  CollocationSpace(straight(10, (1, 0, 0), 4, n, origin=(10, 0, 0)))]), formulation,
                    dt, T)
        err[n] = (np.abs(one - ref).max(), np.abs(two - ref).max())
    print(formulation, err)
    for n in (11, 21):
        assert err[n][1] <= 6.0 * err[n][0], err
    assert np.log2(err[11][1] / err[21][1]) >= 3.0, err


def _stepped_euler_bernoulli(members, k):
    """The ``k`` lowest natural frequencies [Hz] of a clamped-free stepped Euler-Bernoulli
    beam, members ``(EI, mu, L)`` from the clamp: transfer matrices of ``(w, w', M, V)``
    with Krylov functions, roots of the free end's 2x2 determinant."""
    from scipy.optimize import brentq

    def transfer(EI, mu, L, w):
        b = (mu * w * w / EI) ** 0.25
        x = b * L
        S, T = (np.cosh(x) + np.cos(x)) / 2, (np.sinh(x) + np.sin(x)) / 2
        U, V = (np.cosh(x) - np.cos(x)) / 2, (np.sinh(x) - np.sin(x)) / 2
        return np.array([[S, T / b, U / (EI * b**2), V / (EI * b**3)], [b * V, S, T / (EI * b), U / (EI * b**2)],
                         [EI * b**2 * U, EI * b * V, S, T / b], [EI * b**3 * T, EI * b**2 * U, b * V, S]])

    def det(w):
        M = np.eye(4)
        for m in members:
            M = transfer(*m, w) @ M
        return np.linalg.det(M[2:, 2:])

    ws = np.linspace(1e-3, 200.0, 20001)
    d = np.array([det(w) for w in ws])
    roots = [brentq(det, ws[i], ws[i + 1], xtol=1e-14) for i in np.flatnonzero(np.sign(d[:-1]) != np.sign(d[1:]))]
    return np.array(roots[:k]) / (2 * np.pi)


@pytest.mark.parametrize("formulation", ["galerkin"])
def test_stepped_cantilever_frequencies(formulation):
    """Two collinear 5 m members with different sections (EI 1e3 and 250 N m^2, mu 1 and
    0.5 kg/m; stiff in shear and extension, negligible rotary inertia), one section per
    patch: the three lowest bending frequencies from the modal analysis against the
    stepped Euler-Bernoulli beam (transfer matrices: 0.228346, 0.923111, 2.674436 Hz).
    Measured at p = 4, 11 control points per member, Galerkin: -5.2e-6, 8.9e-6, 3.1e-4
    relative (each bending pair's mean). 1e-3 allowed. (Primal collocation misses by 1.7 %,
    13 % and 13 % here: its joint rows enforce the balance only weakly.)"""
    from liegroup_int.integrators.spectrum import modal_analysis

    A = SectionConstants(CN=(1e7, 1e7, 1e7), CM=(1e3, 1e3, 1e3), mu=1.0, Jm=(1e-6, 1e-6, 2e-6))
    B = SectionConstants(CN=(1e7, 1e7, 1e7), CM=(250.0, 250.0, 1e3), mu=0.5, Jm=(1e-6, 1e-6, 2e-6))
    ref = _stepped_euler_bernoulli([(1e3, 1.0, 5.0), (250.0, 0.5, 5.0)], 3)
    sp = PatchedSpace([CollocationSpace(straight(5, (1, 0, 0), 4, 11)),
                       CollocationSpace(straight(5, (1, 0, 0), 4, 11, origin=(5, 0, 0)))])
    pb = beam_problem(sp, (A, B), BoundaryConditions("clamped", "free"), formulation=formulation)
    f = np.array([m.freq_hz for m in modal_analysis(pb, 0.0, pb.initial_state(), 6).modes])
    bending = 0.5 * (f[0::2] + f[1::2])  # isotropic sections: a pair per bending mode
    print(formulation, bending / ref - 1)
    assert np.allclose(bending, ref, rtol=1e-3, atol=0), (bending, ref)


@pytest.mark.parametrize("formulation", ["primal", "galerkin"])
@pytest.mark.parametrize("patches", [1, 2])
@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_hanging_bar_at_rest_reaction_equals_weight(formulation, patches, backend):
    """A bar hanging from a clamp under gravity, in its static equilibrium: axial strain
    eps(s) = rhoA g (L - s) / EA, a quadratic centreline that the spline space holds
    exactly (p = 4). The stage rates vanish and the clamp's reaction force is the weight
    rhoA g L, to round-off (one patch, and two patches joined mid-length). Round-off here
    is that of the axial stiffness term, EA / (rhoA h^2) L = 6.5e7 m/s^2 at h = L / 14:
    the rates measured at most 2.2e-7 m/s^2 (3e-15 of it, where an unbalanced state has
    rates of g = 9.81), allowed 1e-13 of it. The reaction EA eps(0) carries the strain's
    round-off times EA: measured 4.1e-11 N against the weight 29.43 N, allowed
    1e-14 EA = 1e-9 N."""
    L, g, EA, rhoA = 2.0, 9.81, 1e5, 1.5
    sec = SectionConstants(CN=(4e4, 4e4, EA), CM=(50.0, 50.0, 40.0), mu=rhoA, Jm=(1e-3, 1e-3, 2e-3))
    down = (0.0, 0.0, -1.0)
    if patches == 1:
        sp = CollocationSpace(straight(L, down, 4, 15))
    else:
        sp = PatchedSpace([CollocationSpace(straight(L / 2, down, 4, 9)),
                           CollocationSpace(straight(L / 2, down, 4, 9, origin=(0, 0, -L / 2)))])
    pb = beam_problem(sp, sec, BoundaryConditions("clamped", "free"), Loads(gravity=(0.0, 0.0, -g)), backend=backend,
                      formulation=formulation)
    y = pb.initial_state()
    s = np.asarray(sp.s_c)
    z = -(s + rhoA * g * (L * s - 0.5 * s**2) / EA)  # integral of 1 + eps
    y.c = sp.solve(np.stack([0 * s, 0 * s, z], axis=1))
    f = pb.vector_field(0.0, y)
    h = float(np.min(np.diff(s)[np.diff(s) > 0]))
    assert np.max(np.abs(f)) <= 1e-13 * EA / (rhoA * h**2) * L, np.max(np.abs(f))
    y0 = pb.initial_state()  # unstretched: not in equilibrium, the bar falls at g
    assert np.max(np.abs(pb.vector_field(0.0, y0)[2])) >= g
    force, couple = pb.reactions(y)["start"]
    weight = rhoA * g * L
    assert np.allclose(force, [0.0, 0.0, weight], rtol=0, atol=1e-14 * EA), force
    assert np.max(np.abs(couple)) <= 1e-12 * weight * L
