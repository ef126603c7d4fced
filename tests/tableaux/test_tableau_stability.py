"""Linear stability polynomial and stability limits of the registry."""

from __future__ import annotations

import math
import re
from fractions import Fraction

import numpy as np
import pytest
import sympy as sp

from liegroup_int.tableaux import (
    BS32,
    DP54,
    EULER,
    REGISTRY,
    RK2,
    RK3,
    RK4,
    RK6,
    imaginary_axis_growth,
    imaginary_axis_limit,
    real_axis_limit,
    stability_polynomial,
    stability_polynomial_exact,
)
from liegroup_int.tableaux.stability import _first_positive_crossing

NAMES = sorted(REGISTRY)


def _exp_coeffs(n):
    return [Fraction(1, math.factorial(k)) for k in range(n + 1)]


# ---------------------------------------------------------------- R(z)

@pytest.mark.parametrize("name", NAMES)
def test_stability_polynomial_matches_exp_up_to_order(name):
    tab = REGISTRY[name]
    r = stability_polynomial_exact(tab)
    assert len(r) - 1 <= tab.stages
    assert list(r[: tab.order + 1]) == _exp_coeffs(tab.order)
    if tab.b_hat is not None:
        r_hat = stability_polynomial_exact(tab, tab.b_hat)
        assert list(r_hat[: tab.order_hat + 1]) == _exp_coeffs(tab.order_hat)


@pytest.mark.parametrize("name", NAMES)
def test_stability_polynomial_matches_resolvent_formula(name):
    tab = REGISTRY[name]
    coeffs = stability_polynomial(tab)
    s = tab.stages
    for z in (0.3 - 0.7j, -1.1 + 0.2j, 2.0j):
        direct = 1 + z * tab.b_f @ np.linalg.solve(np.eye(s) - z * tab.A_f, np.ones(s))
        poly = np.polynomial.polynomial.polyval(z, coeffs)
        # Verner's A has entries of size ~1e2, so the float solve loses a few digits
        assert abs(direct - poly) < 1e-10 * max(1.0, abs(direct))


@pytest.mark.parametrize("tab", [RK4, RK6, DP54], ids=lambda t: t.name)
def test_stability_polynomial_against_sympy_determinant(tab):
    z = sp.Symbol("z")
    s = tab.stages
    A = sp.Matrix(s, s, lambda i, j: sp.Rational(tab.A[i][j].numerator, tab.A[i][j].denominator))
    b = sp.Matrix(1, s, lambda _, j: sp.Rational(tab.b[j].numerator, tab.b[j].denominator))
    one = sp.ones(s, 1)
    R = sp.expand((sp.eye(s) - z * A + z * one * b).det() / (sp.eye(s) - z * A).det())
    coeffs = sp.Poly(R, z).all_coeffs()[::-1]
    assert [Fraction(int(sp.numer(c)), int(sp.denom(c))) for c in coeffs] == list(
        stability_polynomial_exact(tab))


def test_rk6_stability_polynomial_has_nonexp_last_term():
    r = stability_polynomial_exact(RK6)
    assert len(r) == 8 and r[7] == Fraction(-1, 2160)


# ---------------------------------------------------------------- imaginary axis

def test_imaginary_axis_limits_known_values():
    assert imaginary_axis_limit(RK4) == pytest.approx(2 * math.sqrt(2), abs=1e-12)
    assert imaginary_axis_limit(RK3) == pytest.approx(math.sqrt(3), abs=1e-12)
    assert imaginary_axis_limit(BS32) == pytest.approx(math.sqrt(3), abs=1e-12)
    for tab in (EULER, RK2, RK6):
        assert imaginary_axis_limit(tab) == 0.0


@pytest.mark.parametrize("tab", [EULER, RK2, RK6], ids=lambda t: t.name)
def test_unstable_near_origin_by_exact_leading_term(tab):
    """|R(iy)|^2 - 1 (computed independently with sympy) starts with a positive term."""
    y = sp.Symbol("y", real=True)
    R = sum(sp.Rational(c.numerator, c.denominator) * (sp.I * y) ** k
            for k, c in enumerate(stability_polynomial_exact(tab)))
    E = sp.Poly(sp.expand(R * sp.conjugate(R) - 1), y)
    lowest = [c for c in E.all_coeffs()[::-1] if c != 0][0]
    assert lowest > 0


@pytest.mark.parametrize("name", NAMES)
def test_imaginary_limit_brute_force(name):
    tab = REGISTRY[name]
    limit = imaginary_axis_limit(tab)
    if limit > 0:
        y = np.linspace(0, limit, 2001)
        assert np.all(imaginary_axis_growth(tab, y) <= 1 + 1e-12)
        beyond = limit * (1 + 1e-3)
        assert imaginary_axis_growth(tab, beyond) > 1
    else:
        assert np.all(imaginary_axis_growth(tab, np.array([0.3, 0.5])) > 1)


@pytest.mark.parametrize("name", NAMES)
def test_description_quotes_computed_imaginary_limit(name):
    tab = REGISTRY[name]
    match = re.search(r"imaginary-axis limit (\d+(?:\.\d+)?)", tab.description)
    assert match, tab.description
    quoted = float(match.group(1))
    assert quoted == pytest.approx(imaginary_axis_limit(tab), abs=6e-5)


def test_midpoint_growth_is_y4_over_8():
    y = np.array([1e-2, 3e-2, 1e-1])
    growth = imaginary_axis_growth(RK2, y) - 1
    np.testing.assert_allclose(growth, y ** 4 / 8, rtol=1e-3)
    np.testing.assert_allclose(imaginary_axis_growth(RK2, y), np.sqrt(1 + y ** 4 / 4),
                               rtol=1e-15)


def test_imaginary_axis_growth_shapes():
    assert np.ndim(imaginary_axis_growth(RK4, 1.0)) == 0
    assert imaginary_axis_growth(RK4, np.zeros((2, 3))).shape == (2, 3)
    assert imaginary_axis_growth(RK4, 0.0) == 1.0


# ---------------------------------------------------------------- real axis

def test_real_axis_limits_known_values():
    assert real_axis_limit(EULER) == pytest.approx(2.0, abs=1e-14)
    assert real_axis_limit(RK2) == pytest.approx(2.0, abs=1e-14)
    assert real_axis_limit(RK3) == pytest.approx(2.5127453266, abs=1e-9)
    assert real_axis_limit(RK4) == pytest.approx(2.7852935634, abs=1e-9)
    assert real_axis_limit(DP54) == pytest.approx(3.3066, abs=1e-4)


@pytest.mark.parametrize("name", NAMES)
def test_real_limit_brute_force(name):
    tab = REGISTRY[name]
    limit = real_axis_limit(tab)
    coeffs = stability_polynomial(tab)
    x = np.linspace(0, limit, 2001)
    assert np.all(np.abs(np.polynomial.polynomial.polyval(-x, coeffs)) <= 1 + 1e-12)
    assert abs(np.polynomial.polynomial.polyval(-limit * (1 + 1e-3), coeffs)) > 1


# ---------------------------------------------------------------- root-finding helper

@pytest.mark.parametrize("poly,expected", [
    ([0, -2, 1], 2.0),                                   # x (x - 2)
    ([0, -2, 5, -4, 1], 2.0),                            # x (x-1)^2 (x-2): touches at 1
    ([0, -1, 3, -3, 1], 1.0),                            # x (x-1)^3: triple root crosses
    ([0, 0, 1], 0.0),                                    # x^2 > 0 near 0
    ([-1], math.inf),
    ([0, -1, 0, -1], math.inf),                          # -x - x^3
    ([0, 0, -2, 0, 1], math.sqrt(2)),                    # x^2 (x^2 - 2), irrational root
    ([], math.inf),
])
def test_first_positive_crossing(poly, expected):
    assert _first_positive_crossing([Fraction(c) for c in poly]) == pytest.approx(
        expected, rel=1e-15)
