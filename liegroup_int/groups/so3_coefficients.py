"""Scalar coefficient functions of the SO(3) and SE(3) closed forms, with Taylor branches.

Every coefficient ``f(theta)`` used by exp, dexp, dexpinv and the SE(3) Jacobian is an
even function of ``theta = |xi|``. Each is evaluated by

* its closed form for ``theta >= TAYLOR_THRESHOLD`` (1 rad), and
* a Taylor polynomial in ``theta**2`` with ``N_TERMS`` (12) exact rational coefficients
  below it.

Why 1 rad: the closed forms of ``C``, ``D``, ``E``, ``F`` subtract nearly equal numbers.
Their relative rounding error grows like ``eps / theta**k`` (k = 2 for ``C`` and ``D``,
4 for ``E`` and ``F``); at ``theta = 1`` the worst of them (``F``) is about 7e-14, and it
is smaller for larger angles. Below 1 rad the 12-term Taylor polynomials have truncation
error below 1e-17 (``D`` has radius of convergence ``2 pi``; its terms shrink by
``(theta / 2 pi)**2`` each, i.e. 0.025 at 1 rad). ``tests/groups`` measures the relative
error of every coefficient against 50-digit mpmath values on ``[0, pi]`` and asserts
<= 1e-12; ``tests/groups/test_series_sympy.py`` checks the Taylor coefficients against
sympy expansions of the closed forms.

Definitions (theta = |xi|)::

    A = sin(t)/t                     exp, Rodrigues
    B = (1 - cos t)/t^2              exp and dexp
    C = (t - sin t)/t^3              dexp (left Jacobian)
    D = (1 - (t/2) cot(t/2))/t^2     dexpinv (inverse left Jacobian)
    E = (t^2 + 2 cos t - 2)/(2 t^4)  SE(3) Jacobian block Q
    F = (2 t - 3 sin t + t cos t)/(2 t^5)
"""

from __future__ import annotations

from fractions import Fraction
from math import factorial

import numpy as np

from ._series import bernoulli_fractions

TAYLOR_THRESHOLD = 1.0
N_TERMS = 12


def _coeffs_A() -> list[Fraction]:
    return [Fraction((-1) ** k, factorial(2 * k + 1)) for k in range(N_TERMS)]


def _coeffs_B() -> list[Fraction]:
    return [Fraction((-1) ** k, factorial(2 * k + 2)) for k in range(N_TERMS)]


def _coeffs_C() -> list[Fraction]:
    return [Fraction((-1) ** k, factorial(2 * k + 3)) for k in range(N_TERMS)]


def _coeffs_D() -> list[Fraction]:
    bern = bernoulli_fractions(2 * N_TERMS + 2)
    return [(-1) ** k * bern[2 * k + 2] / factorial(2 * k + 2) for k in range(N_TERMS)]


def _coeffs_E() -> list[Fraction]:
    return [Fraction((-1) ** k, factorial(2 * k + 4)) for k in range(N_TERMS)]


def _coeffs_F() -> list[Fraction]:
    return [Fraction((-1) ** k * (k + 1), factorial(2 * k + 5)) for k in range(N_TERMS)]


#: Exact Taylor coefficients in powers of ``theta**2`` (index k multiplies theta**(2k)).
TAYLOR = {
    "A": _coeffs_A(),
    "B": _coeffs_B(),
    "C": _coeffs_C(),
    "D": _coeffs_D(),
    "E": _coeffs_E(),
    "F": _coeffs_F(),
}
_TAYLOR_F = {k: np.array([float(c) for c in v]) for k, v in TAYLOR.items()}


def _horner(coeffs: np.ndarray, t2: np.ndarray) -> np.ndarray:
    out = np.full_like(t2, coeffs[-1])
    for c in coeffs[-2::-1]:
        out = out * t2 + c
    return out


def _branch(theta: np.ndarray, key: str, closed) -> np.ndarray:
    theta = np.asarray(theta, dtype=float)
    small = theta < TAYLOR_THRESHOLD
    series = _horner(_TAYLOR_F[key], theta * theta)
    if not np.any(~small):
        return series
    t = np.where(small, 2.0 * TAYLOR_THRESHOLD, theta)
    return np.where(small, series, closed(t))


def coeff_A(theta: np.ndarray) -> np.ndarray:
    """``sin(theta)/theta``, shape of ``theta``."""
    return _branch(theta, "A", lambda t: np.sin(t) / t)


def coeff_B(theta: np.ndarray) -> np.ndarray:
    """``(1 - cos(theta))/theta**2`` (evaluated as ``2 sin^2(theta/2)/theta**2``)."""
    return _branch(theta, "B", lambda t: 2.0 * (np.sin(0.5 * t) / t) ** 2)


def coeff_C(theta: np.ndarray) -> np.ndarray:
    """``(theta - sin(theta))/theta**3``."""
    return _branch(theta, "C", lambda t: (t - np.sin(t)) / t**3)


def coeff_D(theta: np.ndarray) -> np.ndarray:
    """``(1 - (theta/2) cot(theta/2))/theta**2``; pole at ``theta = 2 pi``."""
    return _branch(theta, "D", lambda t: (1.0 - 0.5 * t / np.tan(0.5 * t)) / t**2)


def coeff_E(theta: np.ndarray) -> np.ndarray:
    """``(theta**2 + 2 cos(theta) - 2)/(2 theta**4)``."""
    return _branch(theta, "E", lambda t: (t * t + 2.0 * np.cos(t) - 2.0) / (2.0 * t**4))


def coeff_F(theta: np.ndarray) -> np.ndarray:
    """``(2 theta - 3 sin(theta) + theta cos(theta))/(2 theta**5)``."""
    return _branch(
        theta, "F", lambda t: (2.0 * t - 3.0 * np.sin(t) + t * np.cos(t)) / (2.0 * t**5)
    )


COEFFICIENTS = {
    "A": coeff_A,
    "B": coeff_B,
    "C": coeff_C,
    "D": coeff_D,
    "E": coeff_E,
    "F": coeff_F,
}
