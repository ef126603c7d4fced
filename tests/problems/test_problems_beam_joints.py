"""Rigid joints of patches (PatchedSpace): both backends, and a straight joint against one
patch."""

from __future__ import annotations

import numpy as np
import pytest

from liegroup_int import integrate
from liegroup_int.iga import CollocationSpace, straight
from liegroup_int.iga.patches import PatchedSpace
from liegroup_int.problems.beam import BeamProblem, BoundaryConditions, EndLoad, Loads, Profile, SectionConstants

SECTION = SectionConstants(CN=(1e6, 1e6, 1e6), CM=(1e3, 1e3, 1e3), mu=1.0, Jm=(10.0, 10.0, 20.0))
PULSE = Profile(kind="table", table=((0.0, 0.0), (1.0, 50.0), (2.0, 0.0)))


@pytest.mark.parametrize("formulation", ["primal", "mixed"])
@pytest.mark.parametrize("tau", [0.0, 1e-3])
def test_backends_agree_on_a_loaded_kink(formulation, tau):
    """A right-angle frame (different degrees and sizes per patch, anisotropic section) with a
    force and couple at the kink: stage rates of both backends at a random state, to
    round-off (measured 2e-15 relative)."""
    sp = PatchedSpace([CollocationSpace(straight(10, (1, 0, 0), 4, 9)),
                       CollocationSpace(straight(10, (0, 1, 0), 3, 8, origin=(10, 0, 0)))])
    sec = SectionConstants(CN=(1e6, 1.2e6, 1e6), CM=(1e3, 2e3, 1.5e3), mu=1.0, Jm=(10.0, 12.0, 20.0))
    loads = Loads(joints=(EndLoad(force=(0, 0, 1.0), couple=(0.3, 0, 1), force_profile=PULSE, couple_profile=PULSE),))
    rates = []
    for backend in ("numpy", "numba"):
        pb = BeamProblem(sp, sec, BoundaryConditions("clamped", "free"), loads, backend=backend,
                         formulation=formulation, kelvin_voigt=tau)
        r = np.random.default_rng(1)
        u = 0.05 * r.standard_normal((4, pb.n, 3))
        u[:, 9] = u[:, 8]  # one increment at the joint
        y = pb.action(u, pb.initial_state())
        y.v += 0.1 * r.standard_normal(y.v.shape)
        y.w += 0.1 * r.standard_normal(y.w.shape)
        y.v[9], y.w[9] = y.v[8], y.w[8]
        rates.append(pb.increment_rate(0.7, y, 0.1 * u))
    assert np.max(np.abs(rates[0] - rates[1])) <= 1e-12 * np.max(np.abs(rates[0]))
    # the joint's two rows share one rate
    assert np.allclose(rates[0][:, 8], rates[0][:, 9], rtol=0, atol=1e-12 * np.max(np.abs(rates[0])))


def _tips(space, formulation, dt, t_end=1.0):
    end = EndLoad(force=(0, 0, 0.5), couple=(2.0, 0, 1.0), force_profile=PULSE, couple_profile=PULSE)
    pb = BeamProblem(space, SECTION, BoundaryConditions("clamped", "free"), Loads(end=end), formulation=formulation,
                     backend="numba")
    tips = []
    integrate(pb, pb.initial_state(), (0.0, t_end), dt=dt, t_eval=np.linspace(0.0, t_end, 5),
              observer=lambda t, y: tips.append(y.c[-1].copy()))
    return np.array(tips)


def test_straight_joint_converges_like_one_patch():
    """Two collinear 10 m patches of n control points each against one 20 m patch of
    2n - 1 (the same spacing), both against one patch of 81: a 20 m cantilever (the
    right-angle frame's section) under a tip force and torsion-bending couple pulse, tip
    error over 1 s, mixed formulation. Measured (n = 11, 21): one patch 6.6e-5, 5.2e-6;
    two patches 2.9e-4, 6.6e-6: the joint (a C^0 break instead of C^3 continuity) costs
    4.4x the error at n = 11, 1.3x at n = 21, and converges faster than one patch (log2
    of the error ratio 5.4; over 2 s, docs/verification.md section 7b)."""
    ref = _tips(CollocationSpace(straight(20, (1, 0, 0), 4, 81)), "mixed", 1e-5)
    err = {}
    for n in (11, 21):
        one = _tips(CollocationSpace(straight(20, (1, 0, 0), 4, 2 * n - 1)), "mixed", 2e-5)
        two = _tips(PatchedSpace([CollocationSpace(straight(10, (1, 0, 0), 4, n)),
                                  CollocationSpace(straight(10, (1, 0, 0), 4, n, origin=(10, 0, 0)))]), "mixed", 2e-5)
        err[n] = (np.abs(one - ref).max(), np.abs(two - ref).max())
    for n in (11, 21):
        assert err[n][1] <= 6.0 * err[n][0], err
    assert np.log2(err[11][1] / err[21][1]) >= 3.0, err
