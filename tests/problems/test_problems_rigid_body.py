"""Rigid bodies: closed form of the axisymmetric top, invariants, orthogonality."""

import numpy as np
import pytest

from liegroup_int import SO3, integrate
from liegroup_int.problems import RigidBody, axisymmetric_free_rotation

R0 = SO3.exp(np.array([0.3, -0.2, 0.5]))
W0 = np.array([1.0, 0.5, 3.0])


def test_axisymmetric_top_matches_closed_form():
    body = RigidBody(inertia=(2.0, 2.0, 1.0))
    sol = integrate(body.problem(), body.state(R0, W0), (0.0, 2.0), method="rkmk6", dt=1e-2)
    R, W = body.split(sol.y_final)
    Re, We = axisymmetric_free_rotation(2.0, 1.0, R0, W0, 2.0)
    # RKMK6 at h = 1e-2 over 200 steps: measured ~1e-12; 1e-10 allows machine variation
    assert np.abs(R - Re).max() < 1e-10 and np.abs(W - We).max() < 1e-10


def test_closed_form_satisfies_the_equations():
    # the reference itself: finite-difference derivative of R(t) equals R hat(W)
    t, eps = 0.7, 1e-6
    Rp, _ = axisymmetric_free_rotation(2.0, 1.0, R0, W0, t + eps)
    Rm, _ = axisymmetric_free_rotation(2.0, 1.0, R0, W0, t - eps)
    R, W = axisymmetric_free_rotation(2.0, 1.0, R0, W0, t)
    np.testing.assert_allclose((Rp - Rm) / (2 * eps), R @ SO3.hat(W), atol=1e-8)


@pytest.mark.parametrize("body", [
    RigidBody(inertia=(1.0, 2.0, 2.5)),
    RigidBody(inertia=(1.0, 0.8, 0.5), mass=1.0, com=(0.0, 0.0, 0.5)),
])
def test_invariants_converge_with_order(body):
    # energy and Casimir errors of RKMK4 fall like h^4 (fitted over 3 steps)
    y0 = body.state(R0, W0)
    e0, c0 = body.energy(y0), body.casimir(y0)
    hs = [0.04, 0.02, 0.01]
    de = []
    for h in hs:
        y = integrate(body.problem(), y0, (0.0, 2.0), method="rkmk4", dt=h).y_final
        de.append(abs(body.energy(y) - e0) + abs(body.casimir(y) - c0))
    slope = np.polyfit(np.log(hs), np.log(de), 1)[0]
    assert slope > 3.7, (slope, de)


def test_orthogonality_after_1e5_steps():
    # Lie-Euler keeps R on SO(3) by construction; 1e5 steps of exp products accumulate
    # only round-off. The bound 1e-12 is 50x the measured ~2e-14: a drift would exceed it.
    body = RigidBody(inertia=(1.0, 0.8, 0.5), mass=1.0, com=(0.0, 0.0, 0.5))
    y = integrate(body.problem(), body.state(R0, W0), (0.0, 10.0), method="rkmk1", dt=1e-4).y_final
    assert body.orth_error(y) <= 1e-12


def test_bad_inertia_is_rejected():
    with pytest.raises(ValueError, match="triangle"):
        RigidBody(inertia=(1.0, 1.0, 5.0))
    with pytest.raises(ValueError, match="positive"):
        RigidBody(inertia=(1.0, -1.0, 1.0))
