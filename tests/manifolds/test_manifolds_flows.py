"""Flows on the built-in spaces against independent references: Landau-Lifshitz-Gilbert
spin dynamics on S^2 (scipy DOP853, tight), and Oja's subspace flow on a Stiefel
manifold (its limit from numpy.linalg.eigh)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from liegroup_int import Sphere, Stiefel, integrate

GAMMA, ALPHA, H_EXT, K, AXIS = 1.0, 0.1, np.array([0.2, 0.0, 1.0]), 0.5, np.array([1.0, 0.0, 0.0])


def _h_eff(m):
    return H_EXT + K * (m @ AXIS) * AXIS  # external field and uniaxial anisotropy


def _llg_generator(t, m):
    """LLG in Landau-Lifshitz form, m' = -g/(1+a^2) (m x H + a m x (m x H)) = w x m with
    w = g/(1+a^2) (H + a m x H)."""
    H = _h_eff(m)
    return GAMMA / (1 + ALPHA**2) * (H + ALPHA * np.cross(m, H))


def _llg_rhs(t, m):
    return np.cross(_llg_generator(t, m), m)


@pytest.mark.parametrize("method, order", [("rkmk4", 4), ("cf4", 4), ("rkmk3", 3)])
def test_llg_spin_orders_and_unit_length(method, order):
    """Against DOP853 at rtol = atol = 1e-13 over T = 5 (the spin relaxes toward the field):
    fitted order within 0.3 over dt = 0.1, 0.05, 0.025 (measured rkmk4 4.0, cf4 4.0,
    rkmk3 3.0); |m| = 1 to 1e-14 (DOP853 keeps it only to its tolerance)."""
    S = Sphere()
    m0 = S.project(np.array([0.0, 1.0, 0.3]))
    T = 5.0
    ref = solve_ivp(_llg_rhs, (0.0, T), m0, method="DOP853", rtol=1e-13, atol=1e-13).y[:, -1]
    dts = np.array([0.1, 0.05, 0.025])
    errs = []
    for dt in dts:
        m = integrate(_llg_generator, m0, (0.0, T), space=S, method=method, dt=dt).y_final
        assert S.constraint(m) <= 1e-14
        errs.append(np.max(np.abs(m - ref)))
    slope = np.polyfit(np.log(dts), np.log(errs), 1)[0]
    assert slope == pytest.approx(order, abs=0.3), (errs, slope)


def test_oja_flow_on_stiefel_finds_the_dominant_subspace():
    """Y' = (I - Y Y^T) A Y on V_2(R^6), as the generator Omega = A Y Y^T - Y Y^T A: Y stays
    orthonormal to round-off and Y Y^T tends to the projector on A's two dominant
    eigenvectors (eigh), here within 1e-8 at T = 40 (the gap lambda_2 - lambda_3 = 1 sets
    the rate exp(-gap t))."""
    rng = np.random.default_rng(3)
    Q = np.linalg.qr(rng.standard_normal((6, 6)))[0]
    A = Q @ np.diag([5.0, 4.0, 3.0, 1.0, 0.5, 0.0]) @ Q.T
    V = Stiefel(6, 2)
    G = V.group
    Y0 = V.sample(rng)
    sol = integrate(lambda t, Y: G.vee(A @ Y @ Y.T - Y @ Y.T @ A), Y0, (0.0, 40.0), space=V, method="rkmk4", dt=0.02)
    Y = sol.y_final
    assert V.constraint(Y) <= 1e-13
    w, U = np.linalg.eigh(A)
    P = U[:, -2:] @ U[:, -2:].T
    assert np.max(np.abs(Y @ Y.T - P)) <= 1e-8


def test_spherical_pendulum_on_the_tangent_sphere():
    """A spherical pendulum (g / L = 9.81 1/s^2) on TS^2 with SE(3) acting: generator
    (rho, theta) = ((g / L) e3, w), so q' = w x q, w' = (g / L) e3 x q. Against DOP853 at
    1e-13 over T = 3: fitted order of RKMK4 within 0.3 of 4 (measured 4.0), both
    constraints (|q| = 1, q . w = 0) to 1e-13 (measured 4e-15), energy w^2 / 2 + (g / L) q3
    drifting at the method's error: 1.1e-8, 2.9e-10, 6.4e-12 of its scale at dt = 0.02,
    0.01, 0.005 (1e-10 allowed at 0.005)."""
    from liegroup_int import TangentSphere

    g = 9.81
    e3 = np.array([0.0, 0.0, 1.0])
    TS = TangentSphere()

    def gen(t, y):
        return np.concatenate([g * e3, y[3:]])

    def rhs(t, y):
        q, w = y[:3], y[3:]
        return np.concatenate([np.cross(w, q), g * np.cross(e3, q)])

    y0 = TS.project(np.array([np.sin(1.0), 0.0, -np.cos(1.0), 0.0, 0.0, 2.5]))
    T = 3.0
    ref = solve_ivp(rhs, (0.0, T), y0, method="DOP853", rtol=1e-13, atol=1e-13).y[:, -1]
    energy = lambda y: 0.5 * y[3:] @ y[3:] + g * y[2]  # noqa: E731
    dts = np.array([0.02, 0.01, 0.005])
    errs = []
    for dt in dts:
        y = integrate(gen, y0, (0.0, T), space=TS, method="rkmk4", dt=dt).y_final
        assert TS.constraint(y) <= 1e-13
        errs.append(np.max(np.abs(y - ref)))
    slope = np.polyfit(np.log(dts), np.log(errs), 1)[0]
    assert slope == pytest.approx(4.0, abs=0.3), (errs, slope)
    assert abs(energy(y) - energy(y0)) <= 1e-10 * (g + 0.5 * y0[3:] @ y0[3:])
