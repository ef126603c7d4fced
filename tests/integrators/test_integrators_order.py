"""Generic convergence-order test: every fixed-step method on a non-abelian problem.

The heavy top (SO(3) x R^3, gravity torque, asymmetric inertia) has no closed form; the
reference is RKMK6 at h = 1e-3, whose own error (~1e-16 by the measured RKMK6 constant)
is far below the smallest error fitted here. Each method is measured over three step
sizes in its asymptotic range, with errors well above round-off (>= 1e-11).
"""

import numpy as np
import pytest

from liegroup_int import SO3, integrate
from liegroup_int.problems import RigidBody

TOP = RigidBody(inertia=(1.0, 0.8, 0.5), mass=1.0, com=(0.0, 0.0, 0.5))
Y0 = TOP.state(SO3.exp(np.array([0.5, 0.1, 0.0])), np.array([0.3, -0.2, 8.0]))
T = 1.0

# method -> (nominal order, step sizes)
CASES = {
    "rkmk1": (1, [0.01, 0.005, 0.0025]),
    "rkmk2": (2, [0.02, 0.01, 0.005]),
    "rkmk3": (3, [0.02, 0.01, 0.005]),
    "rkmk4": (4, [0.02, 0.01, 0.005]),
    "rkmk6": (6, [0.04, 0.02, 0.01]),
}


@pytest.fixture(scope="module")
def reference():
    return integrate(TOP.problem(), Y0, (0.0, T), method="rkmk6", dt=1e-3).y_final


def fitted_order(hs, errs):
    """Least-squares slope of log(err) against log(h)."""
    return np.polyfit(np.log(hs), np.log(errs), 1)[0]


@pytest.mark.parametrize("method", sorted(CASES))
def test_fixed_step_order(method, reference):
    order, hs = CASES[method]
    errs = [np.abs(integrate(TOP.problem(), Y0, (0.0, T), method=method, dt=h).y_final - reference).max() for h in hs]
    assert min(errs) > 1e-11, f"{method}: errors {errs} too close to round-off to fit an order"
    slope = fitted_order(hs, errs)
    # 0.3: the tolerance of the time-order studies (docs/verification.md) for a fit over three
    # steps in the asymptotic range
    assert abs(slope - order) < 0.3, f"{method}: fitted order {slope:.3f}, errors {errs}"


# the embedded pairs by their propagated weights, on the same problem; this checks the
# weights as implemented in floating point, including the cancellation-safe stage sums
# that Verner's pair (|a_ij| up to 208) needs. Each pair has its own window (order, low,
# high): the nominal order - 0.3 below, and above it what the pair's error constants give
# in the range of steps where its error is well above round-off (measured fits: rkmk32
# 2.94; rkmk45 5.38, Dormand-Prince's small fifth-order constant lets the sixth-order term
# show at these steps; rkmk65 7.08, Verner's sixth-order constants are smaller still), with
# 0.2-0.3 of margin for the fit.
PAIR_CASES = {
    "rkmk32": (3, [0.02, 0.01, 0.005], 2.7, 3.3),
    "rkmk45": (5, [0.04, 0.02, 0.01], 4.7, 5.6),
    "rkmk65": (6, [0.08, 0.04, 0.02], 5.7, 7.3),
}


@pytest.mark.parametrize("method", sorted(PAIR_CASES))
def test_pair_propagated_order(method, reference):
    order, hs, low, high = PAIR_CASES[method]
    errs = [np.abs(integrate(TOP.problem(), Y0, (0.0, T), method=method, dt=h).y_final - reference).max() for h in hs]
    assert min(errs) > 1e-11, errs
    slope = fitted_order(hs, errs)
    assert low < slope < high, f"{method}: fitted order {slope:.3f} outside ({low}, {high}), errors {errs}"
