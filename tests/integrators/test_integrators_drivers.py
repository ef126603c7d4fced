"""Drivers: fixed and adaptive stepping, output times, statistics and error paths."""

import numpy as np
import pytest

from liegroup_int import SO3, DiagnosticsRecorder, Product, Rn, integrate
from liegroup_int.integrators import (
    METHODS,
    BlowUpError,
    StepSizeError,
    integrate_fixed,
    resolve_method,
)
from liegroup_int.problems import RigidBody

TOP = RigidBody(inertia=(1.0, 0.8, 0.5), mass=1.0, com=(0.0, 0.0, 0.5))
Y0 = TOP.state(SO3.exp(np.array([0.5, 0.1, 0.0])), np.array([0.3, -0.2, 8.0]))


def test_classical_rk_on_rn_is_rk4():
    # y' = -y on R^2 with RK4 at h = 0.1: per-step factor is the degree-4 Taylor polynomial
    sol = integrate(lambda t, y: -y, np.array([1.0, 2.0]), (0.0, 1.0), method="rkmk4", dt=0.1)
    z = -0.1
    factor = 1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24
    np.testing.assert_allclose(sol.y_final, np.array([1.0, 2.0]) * factor**10, rtol=1e-14)
    assert sol.stats.steps == 10 and sol.stats.rhs_evals == 40


def test_output_times_are_hit_exactly():
    sol = integrate(lambda t, y: np.ones(1), np.zeros(1), (0.0, 1.0), dt=0.3, t_eval=[0.25, 0.5, 1.0])
    np.testing.assert_array_equal(sol.t, [0.0, 0.25, 0.5, 1.0])
    # y = t exactly for a constant field
    np.testing.assert_allclose(np.concatenate(sol.y), sol.t, atol=1e-15)


@pytest.mark.parametrize("method", ["rkmk32", "rkmk45", "rkmk65"])
def test_adaptive_error_tracks_tolerance(method):
    ref = integrate(TOP.problem(), Y0, (0.0, 1.0), method="rkmk6", dt=1e-3).y_final
    errs = []
    for tol in (1e-5, 1e-8):
        sol = integrate(TOP.problem(), Y0, (0.0, 1.0), method=method, rtol=tol, atol=tol)
        errs.append(np.abs(sol.y_final - ref).max())
        tab = resolve_method(method)
        attempts = sol.stats.steps + sol.stats.rejected
        # FSAL pairs evaluate one stage less per attempt after the first
        assert sol.stats.steps > 0 and sol.stats.rhs_evals == (tab.stages - tab.fsal) * attempts + tab.fsal
    # a 1000x tighter tolerance must buy at least 30x accuracy (local-error control,
    # global error ~ tol^(p/(p+1)) >= tol^(2/3) -> 100x; 30x leaves margin)
    assert errs[1] < errs[0] / 30, errs
    assert errs[0] < 1e-2


def test_adaptive_counts_rejections_and_guards_rotation():
    # a body spinning at 200 rad/s: the first trial steps carry too large a rotation,
    # the guard rejects them and every accepted step stays below the limit
    b = RigidBody(inertia=(1.0, 1.0, 1.0))
    y0 = b.state(np.eye(3), np.array([0.0, 0.0, 200.0]))
    angles = []

    def monitor(t, y, stats):
        angles.append(stats.h_max * 200.0)

    sol = integrate(b.problem(), y0, (0.0, 0.2), method="rkmk45", rtol=1e-3, atol=1e-3, monitor=monitor,
                    max_increment_angle=0.5)
    assert max(angles) <= 0.5 + 1e-12
    # after the first guard rejection the steps are capped at 0.9 * 0.5 rad / (200 rad/s)
    # (controller.rotation_cap): 89 steps for 0.2 s and no more rejections (before the cap
    # every accepted step followed a rejection: 159 and 159)
    assert sol.stats.rejected <= 2 and sol.stats.steps <= int(np.ceil(0.2 / (0.9 * 0.5 / 200.0))) + 1, sol.stats
    R, _ = b.split(sol.y_final)
    np.testing.assert_allclose(R, SO3.exp(np.array([0.0, 0.0, 40.0])), atol=1e-3)


def test_fixed_step_rotation_guard_raises():
    b = RigidBody(inertia=(1.0, 1.0, 1.0))
    y0 = b.state(np.eye(3), np.array([0.0, 0.0, 200.0]))
    with pytest.raises(StepSizeError, match="rotation increment"):
        integrate(b.problem(), y0, (0.0, 1.0), method="rkmk4", dt=0.01)


def test_blow_up_is_reported_with_time_and_step():
    rec = DiagnosticsRecorder({"y": lambda t, y: float(y[0])})
    with pytest.raises(BlowUpError) as info:
        # y' = -1000 y with h = 0.01: |1 + z| = 9 per Euler step -> overflow
        integrate(lambda t, y: -1000.0 * y, np.ones(1), (0.0, 10.0), method="rkmk1", dt=0.01,
                  t_eval=np.linspace(0.0, 10.0, 101)[1:], observer=rec)
    assert 0 < info.value.t < 10.0 and info.value.step > 0
    assert len(rec.t) >= 2 and all(np.isfinite(rec.values["y"]))  # what was recorded stays


@pytest.mark.parametrize("kwargs, match", [
    ({"method": "rk5"}, "unknown method"),
    ({"method": "rkmk4", "dt": -0.1}, "dt must be positive"),
    ({"method": "rkmk4"}, "give a step size"),
    ({"method": "rkmk4", "rtol": 1e-6}, "no embedded pair"),
    ({"method": "rkmk45", "dt": 0.1, "rtol": 1e-3}, "either dt"),
])
def test_bad_arguments(kwargs, match):
    with pytest.raises((ValueError, KeyError), match=match):
        integrate(lambda t, y: -y, np.ones(1), (0.0, 1.0), **kwargs)


def test_product_tuple_initial_state():
    space = Product(SO3, Rn(3))
    sol = integrate(lambda t, y: np.array([0, 0, 1.0, 0, 0, 0]), (np.eye(3), np.zeros(3)), (0.0, 1.0), space=space, dt=0.1)
    R, v = space.split(sol.y_final)
    np.testing.assert_allclose(R, SO3.exp(np.array([0, 0, 1.0])), atol=1e-14)


def test_every_named_method_resolves():
    """Each method name resolves to the tableau registered under it (name round trip), in
    any case, with one weight per stage."""
    for name in METHODS:
        tab = resolve_method(name)
        assert tab.method == name and resolve_method(name.upper()) is tab
        assert len(tab.b_f) == tab.stages == len(tab.c_f)


def test_batched_bodies_match_single_runs():
    # 5 heavy tops with different initial spins integrated in one call
    W = np.array([[0.0, 0.0, s] for s in (1.0, 3.0, 5.0, 7.0, 9.0)])
    R = SO3.exp(np.tile([0.4, 0.0, 0.0], (5, 1)))
    yb = TOP.state(R, W)
    batched = integrate(TOP.problem(), yb, (0.0, 0.5), method="rkmk4", dt=0.01).y_final
    for i in range(5):
        single = integrate(TOP.problem(), yb[i], (0.0, 0.5), method="rkmk4", dt=0.01).y_final
        np.testing.assert_allclose(batched[i], single, rtol=0, atol=1e-14)


def test_integrate_fixed_observer_called_at_outputs():
    calls = []
    integrate_fixed(TOP.problem(), resolve_method("rkmk4"), (0.0, 0.1), Y0, 0.01, observer=lambda t, y: calls.append(t),
                    t_out=[0.05, 0.1])
    np.testing.assert_allclose(calls, [0.0, 0.05, 0.1])
