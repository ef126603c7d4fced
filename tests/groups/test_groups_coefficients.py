"""Accuracy of the SO(3)/SE(3) coefficient functions and of the SO(3) log near pi.

Run with ``-s`` to print the measured errors.

Reference values: the closed-form definitions of the module docstring of
``liegroup_int.groups.so3_coefficients``, evaluated with mpmath to (at least) 50
significant digits. The closed forms of C, D, E, F cancel catastrophically at small
theta (E, F, B1, C1 lose about 4 log10(1/theta) digits), so the working precision is
raised to ``50 + 6 log10(1/theta) + 10`` digits; ``test_reference_has_50_digits``
checks that against a run with 30 more digits.
"""

from __future__ import annotations

import math
from fractions import Fraction

import mpmath as mp
import numpy as np
import pytest

from liegroup_int.groups import SO3
from liegroup_int.groups.so3 import exp_so3, log_so3
from liegroup_int.groups.so3_coefficients import (
    COEFFICIENTS,
    N_TERMS,
    TAYLOR,
    TAYLOR_THRESHOLD,
    coefficients,
)

DEFINITIONS = {
    "A": lambda t: mp.sin(t) / t,
    "B": lambda t: (1 - mp.cos(t)) / t**2,
    "C": lambda t: (t - mp.sin(t)) / t**3,
    "D": lambda t: (1 - (t / 2) * mp.cot(t / 2)) / t**2,
    "E": lambda t: (t**2 + 2 * mp.cos(t) - 2) / (2 * t**4),
    "F": lambda t: (2 * t - 3 * mp.sin(t) + t * mp.cos(t)) / (2 * t**5),
    # derivatives along a curve (beam curvature update): B1 = B'(t)/t, C1 = C'(t)/t
    "B1": lambda t: (t * mp.sin(t) + 2 * mp.cos(t) - 2) / t**4,
    "C1": lambda t: (3 * mp.sin(t) - 2 * t - t * mp.cos(t)) / t**5,
}
#: theta -> 0 limits
LIMITS = {
    "A": Fraction(1),
    "B": Fraction(1, 2),
    "C": Fraction(1, 6),
    "D": Fraction(1, 12),
    "E": Fraction(1, 24),
    "F": Fraction(1, 120),
    "B1": Fraction(-1, 12),
    "C1": Fraction(-1, 60),
}
KEYS = sorted(COEFFICIENTS)


def test_every_coefficient_has_a_reference():
    # a new coefficient function must come with its closed-form definition here
    assert set(COEFFICIENTS) == set(DEFINITIONS) == set(LIMITS) == set(TAYLOR)


def reference(key: str, theta: float, extra_digits: int = 0) -> mp.mpf:
    """``key``'s closed form at the double ``theta``, to >= 50 significant digits."""
    if theta == 0.0:
        return mp.mpf(LIMITS[key].numerator) / LIMITS[key].denominator
    guard = int(6 * max(0.0, -math.log10(theta))) + 10
    with mp.workdps(50 + guard + extra_digits):
        return +DEFINITIONS[key](mp.mpf(theta))


def _grid() -> np.ndarray:
    thr = TAYLOR_THRESHOLD
    pieces = [
        [0.0, 1e-12, 1e-8, 1e-4, 0.5, 0.999999, 1.0, 1.000001, math.pi - 1e-8, math.pi],
        np.logspace(-12, 0, 121),                          # small angles, every decade
        np.linspace(0.0, math.pi, 315)[1:],                # uniform over (0, pi]
        np.linspace(thr - 0.05, thr + 0.05, 401),          # dense around the branch switch
        thr + np.logspace(-15, -2, 27),                    # just above the threshold
        thr - np.logspace(-15, -2, 27),                    # just below the threshold
        np.nextafter(thr, [0.0, 2.0]),                     # the neighbouring doubles
        math.pi - np.logspace(-15, -1, 15),                # approaching pi
    ]
    g = np.unique(np.concatenate([np.asarray(p, dtype=float) for p in pieces]))
    return g[(g >= 0.0) & (g <= math.pi)]


GRID = _grid()


def relative_errors(key: str) -> np.ndarray:
    values = COEFFICIENTS[key](GRID)
    ref = [reference(key, float(t)) for t in GRID]
    return np.array([float(abs((mp.mpf(float(v)) - r) / r)) for v, r in zip(values, ref)])


def test_grid_covers_required_points():
    for t in [0.0, 1e-12, 1e-8, 1e-4, 0.5, 0.999999, 1.0, 1.000001, math.pi - 1e-8, math.pi]:
        assert t in GRID
    # dense around the 1 rad switch: at least 400 points within 0.05 rad
    assert np.count_nonzero(np.abs(GRID - TAYLOR_THRESHOLD) < 0.05) >= 400


@pytest.mark.parametrize("key", KEYS)
def test_coefficient_relative_error(key):
    err = relative_errors(key)
    i = int(np.argmax(err))
    print(f"\ncoefficient {key}: max relative error {err[i]:.3e} at theta = {GRID[i]!r} "
          f"({GRID.size} angles in [0, pi])")
    # 1e-12: the requirement. The design (module docstring) predicts <= ~1e-13: Taylor
    # truncation < 1e-17 below 1 rad, closed-form cancellation eps/theta^4 above it.
    assert err.max() <= 1e-12


@pytest.mark.parametrize("key", KEYS)
def test_limit_at_zero_and_shapes(key):
    f = COEFFICIENTS[key]
    assert float(f(np.float64(0.0))) == float(LIMITS[key])
    assert TAYLOR[key][0] == LIMITS[key]
    assert len(TAYLOR[key]) == N_TERMS
    x = np.linspace(0.0, 3.0, 12).reshape(2, 3, 2)
    out = f(x)
    assert out.shape == x.shape
    # elementwise: batched == scalar calls, exactly
    for i in np.ndindex(*x.shape):
        assert out[i] == f(np.float64(x[i]))


def test_stacked_coefficients_equal_single_ones():
    """``coefficients(theta, keys)`` (one stacked Horner pass) == the single functions."""
    keys = "".join(KEYS)  # e.g. "ABB1CC1DEF"
    theta = GRID.reshape(-1, 1)[: (GRID.size // 2) * 2].reshape(-1, 2)
    out = coefficients(theta, keys)
    names = list(KEYS)
    assert len(out) == len(names)
    for k, val in zip(names, out):
        assert val.shape == theta.shape
        # exact: the same floating-point operations in the same order.
        np.testing.assert_array_equal(val, COEFFICIENTS[k](theta), err_msg=k)
    for t in [0.0, 0.5, 1.0, 3.0]:
        for k, val in zip(names, coefficients(np.float64(t), keys)):
            assert np.shape(val) == () and val == COEFFICIENTS[k](np.float64(t))


@pytest.mark.parametrize("key", KEYS)
def test_reference_has_50_digits(key):
    for t in [1e-12, 1e-6, 0.3, 1.0, 3.0]:
        a, b = reference(key, t), reference(key, t, extra_digits=30)
        assert abs((a - b) / b) < mp.mpf(10) ** -49


# ----------------------------------------------------------------- SO(3) log near pi
DELTAS = [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12]


def _axes(n_random: int = 64, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    r = rng.normal(size=(n_random, 3))
    special = np.array(
        [[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 0], [0, 1, -1], [1, 1, 1], [1, -2, 3], [-1, 1e-9, 0]],
        dtype=float,
    )
    a = np.concatenate([special, r])
    return a / np.linalg.norm(a, axis=-1, keepdims=True)


AXES = _axes()


@pytest.mark.parametrize("delta", DELTAS, ids=[f"{d:.0e}" for d in DELTAS])
def test_so3_log_near_pi(delta):
    xi = (math.pi - delta) * AXES
    R = exp_so3(xi)
    L = log_so3(R)
    err_R = float(np.max(np.abs(exp_so3(L) - R)))
    err_xi = float(np.max(np.abs(L - xi)))
    print(f"\ndelta={delta:.0e}: max|exp(log R) - R| = {err_R:.2e}, max|log R - xi| = {err_xi:.2e}")
    # 1e-14 (~45 ulps): exp o log is the identity on SO(3) and the quaternion log has
    # no division by sin(theta). Measured <= 1.2e-15.
    assert err_R <= 1e-14
    # The quaternion log is also well conditioned here (w = cos(theta/2) ~ delta/2 is
    # computed to absolute accuracy ~u, theta = 2 atan2(|v|, w)): 1e-13, measured ~1e-15.
    assert err_xi <= 1e-13
    assert np.all(np.linalg.norm(L, axis=-1) <= math.pi)


@pytest.mark.parametrize("delta", [1e-14, 1e-15, 0.0], ids=["1e-14", "1e-15", "0"])
def test_so3_log_at_and_beyond_round_off_of_pi(delta):
    """Within round-off of pi the axis sign is arbitrary, exp(log R) must still be R."""
    xi = (math.pi - delta) * AXES
    R = exp_so3(xi)
    L = log_so3(R)
    # 1e-14: as above.
    assert np.max(np.abs(exp_so3(L) - R)) <= 1e-14
    # |log R| = pi - delta up to ~1e-15 rad, and log R is +-xi (either sign at pi).
    np.testing.assert_allclose(np.linalg.norm(L, axis=-1), math.pi - delta, rtol=0, atol=2e-15)
    err = np.minimum(np.max(np.abs(L - xi), axis=-1), np.max(np.abs(L + xi), axis=-1))
    assert np.max(err) <= 1e-13


def test_so3_log_exactly_pi_exact_matrices():
    """Rotations by exactly pi built without rounding: R = 2 n n^T - I."""
    for n in [(1, 0, 0), (0, 1, 0), (0, 0, 1), (3, 4, 0), (2, 3, 6), (1, 2, 2), (0, -3, 4)]:
        n = np.array(n, dtype=float)
        n = n / np.linalg.norm(n)  # (3,4,0)/5 etc.: nearly exact
        R = 2.0 * np.outer(n, n) - np.eye(3)
        L = SO3.log(R)
        # 4e-16: pi itself is rounded; |L| is 2 atan2(|v|, w) with w ~ 0.
        assert abs(np.linalg.norm(L) - math.pi) <= 4e-16 * math.pi
        # either sign of the axis; 1e-15: a few ulps of pi.
        assert min(np.max(np.abs(L - math.pi * n)), np.max(np.abs(L + math.pi * n))) <= 1e-15
        np.testing.assert_allclose(SO3.exp(L), R, rtol=0, atol=1e-15)
