"""The N-fold 3D pendulum on (TS^2)^N (:class:`liegroup_int.problems.NPendulum`): energy and
constraints with RKMK, and its RATTLE splitting (orders, bounded energy, constraints)."""

from __future__ import annotations

import numpy as np
import pytest

from liegroup_int import integrate
from liegroup_int.integrators import BlowUpError
from liegroup_int.problems import NPendulum


def _double():
    pend = NPendulum(2)
    return pend, pend.problem(), pend.initial_state()


def test_double_pendulum_energy_drift_shrinks_at_rkmk4s_order():
    """N = 2, unit masses and links, T = 1: energy drift 9.2e-5, 3.3e-6, 1.2e-7 J at dt =
    0.02, 0.01, 0.005 (fitted slope 4.8; at least 3.7 required), constraints to 1e-13
    (measured 2e-15). A wrong force or mass matrix would not conserve energy at all."""
    pend, pb, y0 = _double()
    E0 = pend.energy(y0)
    dts = np.array([0.02, 0.01, 0.005])
    drift = []
    for dt in dts:
        y = integrate(pb, y0, (0.0, 1.0), method="rkmk4", dt=dt).y_final
        assert pend.space.constraint(y) <= 1e-13
        drift.append(abs(pend.energy(y) - E0))
    slope = np.polyfit(np.log(dts), np.log(drift), 1)[0]
    assert slope >= 3.7, (drift, slope)


def test_variable_steps_and_ten_links():
    """The adaptive RKMK45 pair (tolerance 1e-8, T = 1) on the double pendulum: energy
    within 1e-6 J (measured 6.5e-9 over 0.5 s with the example's settings); the 10-fold
    pendulum, RKMK4 at dt = 2e-3 over 0.1 s: energy within 1e-8 J (measured 1.1e-10 over
    0.2 s), constraints to 1e-13."""
    pend, pb, y0 = _double()
    sol = integrate(pb, y0, (0.0, 1.0), method="rkmk45", rtol=1e-8, atol=1e-8)
    assert sol.stats.steps > 10 and abs(pend.energy(sol.y_final) - pend.energy(y0)) <= 1e-6
    pend = NPendulum(10)
    y0 = pend.initial_state()
    y = integrate(pend.problem(), y0, (0.0, 0.1), method="rkmk4", dt=2e-3).y_final
    assert pend.space.constraint(y) <= 1e-13
    assert abs(pend.energy(y) - pend.energy(y0)) <= 1e-8


def test_sizes_must_match():
    with pytest.raises(ValueError, match="expected 2 positive values each"):
        NPendulum(2, masses=[1.0, 1.0, 1.0])


@pytest.fixture(scope="module")
def reference():
    """The double pendulum at T = 1: RKMK6 at dt = 5e-3, independent of the splitting. It
    differs from RKMK6 at dt = 1e-3 (itself within 1.6e-14 of dt = 5e-4) by 2.1e-11, 3.7e-4
    of the smallest error measured below (5.6e-8); the fitted slopes are the same to 4
    digits with either reference."""
    _, pb, y0 = _double()
    return integrate(pb, y0, (0.0, 1.0), method="rkmk6", dt=5e-3).y_final


@pytest.mark.parametrize("method, order, steps", [("strang", 2, (0.02, 0.01, 0.005)),
                                                   ("yoshida4", 4, (0.02, 0.01, 0.005)),
                                                   ("yoshida6", 6, (0.04, 0.02, 0.01))])
def test_rattle_compositions_have_their_order(method, order, steps, reference):
    """The double pendulum at T = 1 against the RKMK6 reference: measured slopes 2.00, 4.06
    and 6.17 (the errors 1.0e-2 .. 5.6e-8), asserted within 0.3; the constraints hold to
    round-off at the end of every run."""
    pend, pb, y0 = _double()
    ref = reference
    errs = []
    for h in steps:
        y = integrate(pb, y0, (0.0, 1.0), method=method, dt=h).y_final
        assert pend.space.constraint(y) <= 1e-14
        errs.append(np.abs(y - ref).max())
    slope = np.polyfit(np.log(steps), np.log(errs), 1)[0]
    assert abs(slope - order) <= 0.3 and min(errs) > 1e-10, (errs, slope)


def test_rattle_energy_stays_bounded_over_long_runs():
    """500 s of the double pendulum (about 250 swings; energy -19.44 J): the energy error of
    strang (dt = 0.01) and yoshida4 (0.02) stays below 0.02 and 0.01 J (measured 0.011 and
    0.005) with no trend: a linear fit of the error over the run changes it by less than 5 %
    of its largest value (measured 0.8 % and 0.4 %; RKMK4 at dt = 0.02, through the generic
    loop, drifts by 0.020 J, 106 %, in 120 s of CPU, so it is not run here)."""
    pend, pb, y0 = _double()
    E0 = pend.energy(y0)
    t = np.linspace(0.0, 500.0, 501)
    for method, dt, bound in (("strang", 0.01, 0.02), ("yoshida4", 0.02, 0.01)):
        err = []
        integrate(pb, y0, (0.0, 500.0), method=method, dt=dt, t_eval=t,
                  observer=lambda s, y: err.append(pend.energy(y) - E0))
        err = np.array(err)
        trend = np.polyfit(t, err, 1)[0] * 500.0
        assert np.abs(err).max() <= bound and abs(trend) <= 0.05 * np.abs(err).max(), (method, err.max(), trend)


def test_a_step_too_large_for_the_constraints_is_a_blow_up():
    """yoshida6 at dt = 0.1 takes substeps of 0.18 s, where Newton's iteration on the
    constraints does not converge: the run stops with BlowUpError, not a wrong state."""
    _, pb, y0 = _double()
    with pytest.raises(BlowUpError, match="non-finite state"):
        integrate(pb, y0, (0.0, 1.0), method="yoshida6", dt=0.1)
