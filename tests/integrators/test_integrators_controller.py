"""The step-size controller: one object, the same arithmetic in Python and compiled code."""

import math

import numpy as np
import pytest

from liegroup_int.integrators import integrate_adaptive, resolve_method
from liegroup_int.integrators.controller import DEFAULT_CONTROLLER, PIController, h_accepted, h_rejected
from liegroup_int.problems import RigidBody


def test_gains_follow_the_pair():
    tab = resolve_method("rkmk45")  # Dormand-Prince 5(4): k = 5
    g = DEFAULT_CONTROLLER.gains(tab)
    assert g == (0.9, 0.2, 5.0, 0.7 / 5, 0.4 / 5, -1.0 / 5, 1e-4)
    with pytest.raises(ValueError, match="no embedded pair"):
        DEFAULT_CONTROLLER.gains(resolve_method("rkmk4"))


@pytest.mark.parametrize("field, value", [("safety", 0.0), ("safety", 1.5), ("fac_min", 1.0), ("fac_max", 1.0),
                                          ("beta1", 0.0), ("beta2", -0.1), ("err_floor", 0.0)])
def test_invalid_fields_are_refused(field, value):
    with pytest.raises(ValueError, match=field):
        PIController(**{field: value})


def test_compiled_rules_equal_the_python_rules():
    """The engine compiles h_accepted/h_rejected from the same source: bit-identical
    results on errors across 24 orders of magnitude, zero, inf, and angles on both sides of
    the bound."""
    from liegroup_int.integrators.controller import rotation_cap, rotation_rate
    from liegroup_int.integrators.engine import _h_accepted, _h_rejected, _rotation_cap, _rotation_rate

    g = DEFAULT_CONTROLLER.gains(resolve_method("rkmk65"))
    ga = np.asarray(g)
    rng = np.random.default_rng(3)
    errs = np.concatenate([10.0 ** rng.uniform(-12, 12, 200), [0.0, 1.0, math.inf]])
    for err in errs:
        for prev in (1e-4, 0.3, 2.0):
            assert h_accepted(err, prev, 0.01, 0.05, g) == _h_accepted(err, prev, 0.01, 0.05, ga)
        for ang in (0.2, 1.0, 3.0):
            assert h_rejected(err, ang, 0.01, 1.0, g) == _h_rejected(err, ang, 0.01, 1.0, ga)
            for rate in (0.0, 7.5):
                assert rotation_rate(ang, 0.01, 1.0, rate) == _rotation_rate(ang, 0.01, 1.0, rate)
                assert rotation_cap(err if math.isfinite(err) else 1.0, rate, 1.0, g) == _rotation_cap(
                    err if math.isfinite(err) else 1.0, rate, 1.0, ga)


def test_the_rules():
    g = DEFAULT_CONTROLLER.gains(resolve_method("rkmk45"))
    h, prev = h_accepted(0.0, 1e-4, 0.1, 1.0, g)  # exact step: the largest growth
    assert h == pytest.approx(0.5) and prev == 1e-4
    assert h_accepted(1e-30, 1.0, 0.1, 0.3, g)[0] == 0.3  # capped by h_max
    assert h_rejected(math.inf, 0.0, 0.1, 1.0, g) == pytest.approx(0.02)  # non-finite: fac_min
    assert h_rejected(1.5, 2.0, 0.1, 1.0, g) == pytest.approx(0.1 * 0.25)  # angle bound: max_angle / (2 angle)
    assert h_rejected(1.5, 4.0, 0.1, 1.0, g) == pytest.approx(0.1 * 0.2)  # ... never below fac_min


@pytest.mark.parametrize("monitor", [None, lambda *a: None], ids=["compiled", "generic"])
def test_a_more_cautious_controller_takes_more_steps(monitor):
    """The controller object reaches both loops: a lower safety factor means smaller steps."""
    body = RigidBody(inertia=(1.0, 1.0, 0.5), mass=1.0, com=(0.0, 0.0, 0.5))
    y0 = body.state(np.eye(3), np.array([0.3, 0.0, 10.0]))
    tab = resolve_method("rkmk45")
    steps = [integrate_adaptive(body.problem(), tab, (0.0, 1.0), y0, rtol=1e-8, atol=1e-10, monitor=monitor,
                                controller=PIController(safety=s))[2].steps for s in (0.9, 0.5)]
    assert steps[1] > 1.1 * steps[0], steps


@pytest.mark.parametrize("monitor", [None, lambda *a: None], ids=["compiled", "generic"])
@pytest.mark.parametrize("method", ["rkmk45", "rkmk65"])
def test_the_rotation_cap_stops_alternating_rejections(method, monitor):
    """Heavy top spinning at 10 rad/s, loose tolerance (the error allows steps far beyond the
    1 rad guard): without the rotation-rate cap 50 of 248 (rkmk45) and 82 of 265 (rkmk65)
    attempts were guard rejections; with it one rejection teaches the rate (measured: 1 of
    224). Bound: at most 2 % of the accepted steps."""
    top = RigidBody(inertia=(1.0, 1.0, 0.5), mass=1.0, com=(0.0, 0.0, 0.5))
    y0 = top.state(np.eye(3), np.array([0.3, 0.0, 10.0]))
    _, _, st = integrate_adaptive(top.problem(), resolve_method(method), (0.0, 20.0), y0, rtol=1e-4, atol=1e-4,
                                  monitor=monitor)
    assert st.rejected <= 0.02 * st.steps, st


def test_rotation_rate_and_cap_rules():
    from liegroup_int.integrators.controller import rotation_cap, rotation_rate

    g = DEFAULT_CONTROLLER.gains(resolve_method("rkmk45"))
    assert rotation_rate(0.5, 0.1, 1.0, 0.0) == 0.0  # no guard rejection yet: nothing learned
    assert rotation_rate(2.0, 0.1, 1.0, 0.0) == pytest.approx(20.0)  # a rejection measures the rate
    assert rotation_rate(0.5, 0.1, 1.0, 20.0) == pytest.approx(5.0)  # then it follows the rate
    assert rotation_cap(1.0, 0.0, 1.0, g) == 1.0
    assert rotation_cap(1.0, 20.0, 1.0, g) == pytest.approx(0.9 / 20.0)
    assert rotation_cap(0.01, 20.0, 1.0, g) == 0.01
