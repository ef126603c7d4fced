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
<= 1e-12; ``tests/groups/test_groups_series_sympy.py`` checks the Taylor coefficients against
sympy expansions of the closed forms.

Definitions (theta = |xi|)::

    A = sin(t)/t                     exp, Rodrigues
    B = (1 - cos t)/t^2              exp and dexp
    C = (t - sin t)/t^3              dexp (left Jacobian)
    D = (1 - (t/2) cot(t/2))/t^2     dexpinv (inverse left Jacobian)
    E = (t^2 + 2 cos t - 2)/(2 t^4)  SE(3) Jacobian block Q
    F = (2 t - 3 sin t + t cos t)/(2 t^5)
    B1 = B'(t)/t = (t sin t + 2 cos t - 2)/t^4      derivative of dexp along a curve
    C1 = C'(t)/t = (3 sin t - 2 t - t cos t)/t^5     (K_s update, docs/theory.md section 3)

``B1`` and ``C1`` lose about ``24 eps / t^4`` and ``90 eps / t^4`` to cancellation in
closed form (5e-15 and 2e-14 at 1 rad), which is why the curvature-derivative update of the
beam must not use them below the threshold.
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


def _coeffs_B1() -> list[Fraction]:
    return [Fraction((-1) ** (k + 1) * 2 * (k + 1), factorial(2 * k + 4)) for k in range(N_TERMS)]


def _coeffs_C1() -> list[Fraction]:
    return [Fraction((-1) ** (k + 1) * 2 * (k + 1), factorial(2 * k + 5)) for k in range(N_TERMS)]


#: Exact Taylor coefficients in powers of ``theta**2`` (index k multiplies theta**(2k)).
TAYLOR = {
    "A": _coeffs_A(),
    "B": _coeffs_B(),
    "C": _coeffs_C(),
    "D": _coeffs_D(),
    "E": _coeffs_E(),
    "F": _coeffs_F(),
    "B1": _coeffs_B1(),
    "C1": _coeffs_C1(),
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


def coeff_B1(theta: np.ndarray) -> np.ndarray:
    """``B'(theta)/theta = (theta sin(theta) + 2 cos(theta) - 2)/theta**4``."""
    return _branch(theta, "B1", lambda t: (t * np.sin(t) + 2.0 * np.cos(t) - 2.0) / t**4)


def coeff_C1(theta: np.ndarray) -> np.ndarray:
    """``C'(theta)/theta = (3 sin(theta) - 2 theta - theta cos(theta))/theta**5``."""
    return _branch(theta, "C1", lambda t: (3.0 * np.sin(t) - 2.0 * t - t * np.cos(t)) / t**5)


def coefficients(theta: np.ndarray, keys: str) -> tuple[np.ndarray, ...]:
    """Several coefficients at once, e.g. ``coefficients(t, "BCB1C1")`` -> ``(B, C, B1, C1)``.

    One Horner pass over a stacked coefficient table serves every requested series, so
    evaluating four coefficients costs about as much as one; closed forms are evaluated
    only at the angles ``>= TAYLOR_THRESHOLD``.
    """
    theta = np.asarray(theta, dtype=float)
    if theta.ndim == 0:
        return tuple(x[0] for x in coefficients(theta.reshape(1), keys))
    names, table = _stacked(keys)
    t2 = theta * theta
    shape = (-1,) + (1,) * theta.ndim
    out = np.empty((len(names),) + theta.shape)
    out[...] = table[:, -1].reshape(shape)
    for j in range(table.shape[1] - 2, -1, -1):
        out *= t2
        out += table[:, j].reshape(shape)
    large = theta >= TAYLOR_THRESHOLD
    if np.any(large):
        tl = theta[large]
        for i, k in enumerate(names):
            out[i][large] = COEFFICIENTS[k](tl)
    return tuple(out)


_STACKED: dict[str, tuple] = {}


def _stacked(keys: str) -> tuple[list[str], np.ndarray]:
    if keys not in _STACKED:
        names = _split_keys(keys)
        _STACKED[keys] = (names, np.stack([_TAYLOR_F[k] for k in names]))
    return _STACKED[keys]


def _split_keys(keys: str) -> list[str]:
    """``"BCB1C1"`` -> ``["B", "C", "B1", "C1"]``."""
    names, i = [], 0
    while i < len(keys):
        if i + 1 < len(keys) and keys[i + 1] == "1":
            names.append(keys[i : i + 2])
            i += 2
        else:
            names.append(keys[i])
            i += 1
    return names


COEFFICIENTS = {
    "A": coeff_A,
    "B": coeff_B,
    "C": coeff_C,
    "D": coeff_D,
    "E": coeff_E,
    "F": coeff_F,
    "B1": coeff_B1,
    "C1": coeff_C1,
}
