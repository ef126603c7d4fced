"""Symplectic splitting compositions (``strang``, ``yoshida4``, ``yoshida6``) on the rigid
body: checked coefficients, measured orders, exact invariants and bounded energy over long
runs where RKMK drifts."""

from __future__ import annotations

import numpy as np
import pytest

from liegroup_int import integrate
from liegroup_int.groups import SO3
from liegroup_int.problems.rigid_body import RigidBody
from liegroup_int.tableaux import COMPOSITIONS, Composition

TOP = RigidBody(inertia=(1.0, 1.0, 0.5), mass=1.0, com=(0.0, 0.0, 0.5))
Y0 = TOP.state(SO3.exp(np.array([0.3, 0.0, 0.0])), np.array([0.0, 0.5, 10.0]))


def test_the_coefficients_are_checked():
    assert {c.name: c.order for c in COMPOSITIONS.values()} == {"strang": 2, "yoshida4": 4, "yoshida6": 6}
    g = COMPOSITIONS["yoshida4"].gammas_f
    with pytest.raises(ValueError, match="h\\^3 term"):  # the middle weight off by 1e-6, the sum kept
        Composition("x", (float(g[0] - 5e-7), float(g[1] + 1e-6), float(g[2] - 5e-7)), 4)
    with pytest.raises(ValueError, match="not a palindrome"):
        Composition("x", ("0.5", "0.3", "0.2"), 2)
    with pytest.raises(ValueError, match="sum to"):
        Composition("x", ("0.5", "0.6", "0.5"), 2)
    with pytest.raises(ValueError, match="claimed order 4 but its error has an h\\^3 term"):
        Composition("x", ("1",), 4)


@pytest.mark.parametrize("name, order", [("strang", 2), ("yoshida4", 4), ("yoshida6", 6)])
def test_measured_order_on_the_heavy_top(name, order):
    """Error at t = 1 against RKMK6 at dt = 1e-4 (its own error below 1e-13), fitted over
    dt = 0.02, 0.01, 0.005: measured slopes 2.00, 3.97, 6.01."""
    pb = TOP.problem()
    ref = integrate(pb, Y0, (0.0, 1.0), method="rkmk6", dt=1e-4).y_final
    dts = np.array([0.02, 0.01, 0.005])
    err = [np.max(np.abs(integrate(pb, Y0, (0.0, 1.0), method=name, dt=dt).y_final - ref)) for dt in dts]
    assert np.polyfit(np.log(dts), np.log(err), 1)[0] == pytest.approx(order, abs=0.25)


def test_long_runs_keep_the_energy_bounded_where_rkmk4_drifts():
    """Heavy top over 500 s (25,000 steps of 0.02 s; it spins at 10 rad/s): the splitting's
    energy error oscillates with no trend (the fitted drift over the run is below 5 % of the
    largest error; measured 1.6 % strang, 0.5 % yoshida4, 0.8 % yoshida6), while
    RKMK4's is a drift (fit over the run above 90 % of the largest error; measured 100 %). The
    vertical angular momentum is kept to round-off by every flow of the splitting (measured
    2.6e-13; RKMK4: 2.4e-4)."""
    pb, T = TOP.problem(), 500.0
    t_eval = np.linspace(0.0, T, 251)
    for name, trend in (("strang", False), ("yoshida4", False), ("yoshida6", False), ("rkmk4", True)):
        sol = integrate(pb, Y0, (0.0, T), method=name, dt=0.02, t_eval=t_eval)
        e = np.array([TOP.energy(y) for y in sol.y]) - TOP.energy(Y0)
        drift = abs(np.polyfit(sol.t, e, 1)[0] * T)
        assert (drift > 0.9 * np.max(np.abs(e))) if trend else (drift < 0.05 * np.max(np.abs(e))), (name, drift)
        if not trend:
            h = np.array([TOP.casimir(y) for y in sol.y])
            assert np.max(np.abs(h - h[0])) < 1e-11 and np.max([TOP.orth_error(y) for y in sol.y]) < 1e-12


def test_free_body_keeps_its_momentum_magnitude():
    """Free body (no gravity): the turns rotate M = I W, so |M|^2 (the Casimir) is kept to
    round-off; the axisymmetric closed form is met at the method's accuracy."""
    body = RigidBody(inertia=(1.0, 1.0, 0.5))
    y0 = body.state(np.eye(3), np.array([0.3, 0.0, 2.0]))
    sol = integrate(body.problem(), y0, (0.0, 10.0), method="yoshida6", dt=0.01, t_eval=np.linspace(0, 10, 11))
    c = np.array([body.casimir(y) for y in sol.y])
    assert np.max(np.abs(c - c[0])) < 1e-13 * c[0]
    from liegroup_int.problems.rigid_body import axisymmetric_free_rotation

    R_exact, W_exact = axisymmetric_free_rotation(1.0, 0.5, np.eye(3), np.array([0.3, 0.0, 2.0]), sol.t)
    R, W = body.split(np.array(sol.y))
    assert np.max(np.abs(R - R_exact)) < 1e-9 and np.max(np.abs(W - W_exact)) < 1e-9


@pytest.mark.parametrize("kwargs, match", [
    ({"dt": 0.03, "t_eval": [0.5, 1.0]}, "t = 0.5 is"),
    ({"rtol": 1e-6}, "fixed steps only"),
    ({"dt": 0.01, "dense_output": True}, "fixed steps only"),
])
def test_splitting_refusals(kwargs, match):
    with pytest.raises(ValueError, match=match):
        integrate(TOP.problem(), Y0, (0.0, 1.0), method="yoshida4", **kwargs)


def test_a_vector_field_is_refused():
    with pytest.raises(ValueError, match="pass a problem with exactly integrable flows"):
        integrate(TOP.vector_field, Y0, (0.0, 1.0), method="strang", dt=0.01)
