"""Exact (sympy) checks of the SO(3) closed forms, and the paper's errata.

* The closed-form coefficients of ``dexp = I + B X + C X^2`` and
  ``dexpinv = I - X/2 + D X^2`` (X = hat(xi), theta = |xi|) are the Bernoulli operator
  series ``sum_k ad^k/(k+1)!`` and ``sum_k B_k ad^k/k!`` (B_1 = -1/2) reduced with
  ``X^3 = -theta^2 X`` (on so(3), ad = hat), through theta^20.
* The exact Taylor tables ``so3_coefficients.TAYLOR`` equal sympy's series of the
  closed forms, term by term.
* Errata of Ferri & Marino, Appendix B (eqs. 60-62), recorded as assertions that the
  printed formulas FAIL the identities they are meant to satisfy.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest
import sympy as sp

from liegroup_int.groups.so3 import hat, left_jacobian, left_jacobian_inv
from liegroup_int.groups.so3_coefficients import N_TERMS, TAYLOR, coeff_B, coeff_C, coeff_D

t = sp.symbols("t", positive=True)

CLOSED = {
    "A": sp.sin(t) / t,
    "B": (1 - sp.cos(t)) / t**2,
    "C": (t - sp.sin(t)) / t**3,
    "D": (1 - (t / 2) * sp.cot(t / 2)) / t**2,
    "E": (t**2 + 2 * sp.cos(t) - 2) / (2 * t**4),
    "F": (2 * t - 3 * sp.sin(t) + t * sp.cos(t)) / (2 * t**5),
    "B1": (t * sp.sin(t) + 2 * sp.cos(t) - 2) / t**4,
    "C1": (3 * sp.sin(t) - 2 * t - t * sp.cos(t)) / t**5,
}

MAX_POWER = 20  # compare scalar coefficients through theta^20


def series_coeffs(expr, n: int) -> list[sp.Rational]:
    """Coefficients of t^0 .. t^(n-1) of the Taylor series of ``expr``."""
    s = sp.series(expr, t, 0, n).removeO()
    poly = sp.Poly(s, t)
    return [poly.coeff_monomial(t**j) for j in range(n)]


def bernoulli(k: int) -> sp.Rational:
    """B_k with B_1 = -1/2 (sympy >= 1.12 returns +1/2 for k = 1)."""
    return sp.Rational(-1, 2) if k == 1 else sp.bernoulli(k)


def sym_hat(a) -> sp.Matrix:
    return sp.Matrix([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])


# ---------------------------------------------------------------- operator series
def test_hat_cubed_is_minus_theta_squared_hat_symbolically():
    a = sp.symbols("a0:3", real=True)
    X = sym_hat(a)
    theta2 = a[0] ** 2 + a[1] ** 2 + a[2] ** 2
    assert (X**3 + theta2 * X).expand() == sp.zeros(3, 3)
    # and hat(a) h = a x h
    h = sp.Matrix(sp.symbols("h0:3", real=True))
    assert (X * h - sp.Matrix(a).cross(h)).expand() == sp.zeros(3, 1)


def reduce_operator_series(c) -> tuple[sp.Expr, sp.Expr, sp.Expr]:
    """``sum_k c(k) X^k`` -> coefficients (of I, X, X^2) using X^3 = -t^2 X.

    X^(2m+1) = (-t^2)^m X and X^(2m+2) = (-t^2)^m X^2; keeping m <= MAX_POWER/2 gives
    the X and X^2 coefficients exactly through t^MAX_POWER.
    """
    M = MAX_POWER // 2
    cI = c(0)
    cX = sum(c(2 * m + 1) * (-(t**2)) ** m for m in range(M + 1))
    cX2 = sum(c(2 * m + 2) * (-(t**2)) ** m for m in range(M + 1))
    return sp.expand(cI), sp.expand(cX), sp.expand(cX2)


def poly_coeffs(expr, n: int) -> list[sp.Rational]:
    poly = sp.Poly(expr, t)
    return [poly.coeff_monomial(t**j) for j in range(n)]


def test_dexp_closed_form_is_the_operator_series():
    """dexp = sum_k ad^k/(k+1)!  <=>  I + B X + C X^2."""
    cI, cX, cX2 = reduce_operator_series(lambda k: sp.Rational(1, sp.factorial(k + 1)))
    assert cI == 1
    n = MAX_POWER + 1
    assert poly_coeffs(cX, n) == series_coeffs(CLOSED["B"], n)
    assert poly_coeffs(cX2, n) == series_coeffs(CLOSED["C"], n)


def test_dexpinv_closed_form_is_the_bernoulli_series():
    """dexpinv = sum_k B_k ad^k/k! (B_1 = -1/2)  <=>  I - X/2 + D X^2."""
    cI, cX, cX2 = reduce_operator_series(lambda k: bernoulli(k) / sp.factorial(k))
    assert cI == 1
    # B_k = 0 for odd k >= 3: the X coefficient is exactly -1/2
    assert cX == sp.Rational(-1, 2)
    n = MAX_POWER + 1
    assert poly_coeffs(cX2, n) == series_coeffs(CLOSED["D"], n)


@pytest.mark.parametrize("n_vec", [(2, 3, 6), (1, 2, 2), (0, 0, 7)], ids=["2-3-6", "1-2-2", "z"])
def test_matrix_series_match_closed_forms(n_vec):
    """The same, with matrices: xi = t n for a rational unit vector n (|n| = 1 exactly),
    sum_{k<=K} X^k c_k against I + B X + C X^2 (and I - X/2 + D X^2) through t^K."""
    n = [sp.Rational(x, sp.sqrt(sum(y * y for y in n_vec))) for x in n_vec]
    N = sym_hat(n)
    assert sum(x * x for x in n) == 1
    K = MAX_POWER + 1
    Npow = [sp.eye(3)]
    for _ in range(K):
        Npow.append(Npow[-1] * N)

    def truncated(expr_matrix):
        return expr_matrix.applyfunc(lambda e: sum(sp.expand(e).coeff(t, j) * t**j for j in range(K + 1)))

    def series_expr(key):
        return sum(c * t**j for j, c in enumerate(series_coeffs(CLOSED[key], K + 1)))

    dexp_series = sum((Npow[k] * t**k / sp.factorial(k + 1) for k in range(K + 1)), sp.zeros(3, 3))
    dexp_closed = sp.eye(3) + series_expr("B") * t * N + series_expr("C") * t**2 * Npow[2]
    assert (truncated(dexp_series) - truncated(dexp_closed)).applyfunc(sp.expand) == sp.zeros(3, 3)

    dinv_series = sum(
        (Npow[k] * t**k * bernoulli(k) / sp.factorial(k) for k in range(K + 1)), sp.zeros(3, 3)
    )
    dinv_closed = sp.eye(3) - t * N / 2 + series_expr("D") * t**2 * Npow[2]
    assert (truncated(dinv_series) - truncated(dinv_closed)).applyfunc(sp.expand) == sp.zeros(3, 3)


# ------------------------------------------------------------------ Taylor tables
def test_every_table_has_a_closed_form():
    assert set(TAYLOR) == set(CLOSED)


@pytest.mark.parametrize("key", sorted(TAYLOR))
def test_taylor_table_equals_sympy_series(key):
    coeffs = series_coeffs(CLOSED[key], 2 * N_TERMS)
    table = TAYLOR[key]
    assert len(table) == N_TERMS
    for k in range(N_TERMS):
        c = coeffs[2 * k]
        assert isinstance(table[k], Fraction)
        assert table[k] == Fraction(int(c.p), int(c.q)), (key, k, table[k], c)
        assert coeffs[2 * k + 1] == 0  # even functions of theta


# ------------------------------------------------------------------ paper errata
G_VEC = np.array([0.3, -0.5, 0.8])  # generic, |g| = 0.98995
THETA = float(np.linalg.norm(G_VEC))


def paper_eq60(g: np.ndarray) -> np.ndarray:
    """Eq. (60) as a matrix, reading its X^2 coefficient as (1 - sin(t)/t)/t^2."""
    th = np.linalg.norm(g)
    G = hat(g)
    return np.eye(3) - (1 - np.cos(th)) / th**2 * G + ((1 - np.sin(th) / th) / th**2) * (G @ G)


def paper_eq61(g: np.ndarray) -> np.ndarray:
    """Eq. (61) as printed: a + 1/2 g^ a + (t cot(t/2) - 2)/(2 t^2) g^ g^ a."""
    th = np.linalg.norm(g)
    G = hat(g)
    return np.eye(3) + 0.5 * G + (th / np.tan(th / 2) - 2) / (2 * th**2) * (G @ G)


def test_paper_eq60_is_the_right_jacobian():
    """Eq. (60) is J_r(g) = J_l(-g) = J_l(g)^T, the *right*-trivialized dexp."""
    P60 = paper_eq60(G_VEC)
    # 1e-15: both sides evaluate the same closed form, a few ulps.
    np.testing.assert_allclose(P60, left_jacobian(-G_VEC), rtol=0, atol=1e-15)
    np.testing.assert_allclose(P60, left_jacobian(G_VEC).T, rtol=0, atol=1e-15)


def test_paper_eq60_literal_parenthesization_is_a_typo():
    """Printed literally, the X^2 coefficient of (60) is ((1 - sin t)/t)/t^2, which is
    not (t - sin t)/t^3 = C (off by +0.0104 at t = 0.990)."""
    literal = ((1 - np.sin(THETA)) / THETA) / THETA**2
    assert abs(literal - float(coeff_C(THETA))) > 1e-2


def test_paper_eq61_is_not_inverse_of_eq60():
    P60, P61 = paper_eq60(G_VEC), paper_eq61(G_VEC)
    defect = P60 @ P61 - np.eye(3)
    # Eq. (61) has the sign of its X^2 coefficient flipped: (t cot(t/2) - 2)/(2 t^2) = -D,
    # whereas J_r^-1 = I + X/2 + D X^2. Hence P61 - J_r^-1 = -2 D X^2 and the defect is
    # exactly -2 D J_r X^2, of size ~2 D t^2 (D(0.990) = 0.0847): spectral norm 0.1594,
    # largest entry 0.1274.
    D = float(coeff_D(THETA))
    G = hat(G_VEC)
    np.testing.assert_allclose(defect, -2 * D * P60 @ G @ G, rtol=0, atol=1e-15)
    assert np.linalg.norm(defect, 2) > 0.15
    with pytest.raises(AssertionError):
        np.testing.assert_allclose(P60 @ P61, np.eye(3), atol=1e-3)


def test_paper_eq61_is_not_an_inverse_under_any_sign_convention():
    """Neither J_l(+-g) nor J_r(+-g) has eq. (61) at +-g as inverse."""
    for s1 in (1.0, -1.0):
        for s2 in (1.0, -1.0):
            J = left_jacobian(s1 * G_VEC)  # J_l(-g) = J_r(g)
            P61 = paper_eq61(s2 * G_VEC)
            assert np.max(np.abs(J @ P61 - np.eye(3))) > 0.05, (s1, s2)


def test_paper_eq60_true_inverse_is_dexpinv_at_minus_g():
    """The inverse of eq. (60) is J_l(-g)^-1 = I + X/2 + D X^2, i.e. eq. (61) with the
    sign of its last term flipped."""
    P60 = paper_eq60(G_VEC)
    # 1e-15: J_r is well conditioned (cond ~ 1.2) at |g| ~ 1.
    np.testing.assert_allclose(P60 @ left_jacobian_inv(-G_VEC), np.eye(3), rtol=0, atol=1e-15)
    G = hat(G_VEC)
    eq61_fixed = np.eye(3) + 0.5 * G - (THETA / np.tan(THETA / 2) - 2) / (2 * THETA**2) * (G @ G)
    np.testing.assert_allclose(eq61_fixed, left_jacobian_inv(-G_VEC), rtol=0, atol=1e-15)


def test_paper_eq62_dexpinv_series_is_wrong():
    """(62): dexp^-1 ~ sum (-1)^i B_i/(i+1)! ad^i. The correct series are
    sum B_i/i! ad^i (left, B_1 = -1/2) and sum (-1)^i B_i/i! ad^i (right, = J_r^-1)."""

    def paper(i, b1):
        b = b1 if i == 1 else sp.bernoulli(i)
        return (-1) ** i * b / sp.factorial(i + 1)

    left = [bernoulli(i) / sp.factorial(i) for i in range(6)]
    right = [(-1) ** i * bernoulli(i) / sp.factorial(i) for i in range(6)]
    assert left[:3] == [1, sp.Rational(-1, 2), sp.Rational(1, 12)]
    assert right[:3] == [1, sp.Rational(1, 2), sp.Rational(1, 12)]
    for b1 in (sp.Rational(-1, 2), sp.Rational(1, 2)):  # whichever B_1 the paper meant
        assert paper(0, b1) == 1
        # i = 1: +-1/4 instead of -+1/2
        assert abs(paper(1, b1)) == sp.Rational(1, 4)
        assert paper(1, b1) not in (left[1], right[1])
        # i = 2: B_2/3! = 1/36 instead of B_2/2! = 1/12
        assert paper(2, b1) == sp.Rational(1, 36) != left[2] == right[2] == sp.Rational(1, 12)


def test_paper_eq62_dexp_series_is_the_right_jacobian_and_dexpinv_series_is_not_its_inverse():
    X = hat(G_VEC)
    Xk = [np.eye(3)]
    for _ in range(40):
        Xk.append(Xk[-1] @ X)
    fact = [float(sp.factorial(k)) for k in range(42)]
    dexp62 = sum((-1) ** i / fact[i + 1] * Xk[i] for i in range(40))
    # 1e-15: the paper's dexp series converges to eq. (60) = J_r (terms ~ 1/(i+1)!).
    np.testing.assert_allclose(dexp62, paper_eq60(G_VEC), rtol=0, atol=1e-15)
    for b1 in (-0.5, 0.5):
        B = [float(sp.bernoulli(i)) if i != 1 else b1 for i in range(40)]
        dinv62 = sum((-1) ** i * B[i] / fact[i + 1] * Xk[i] for i in range(40))
        assert np.max(np.abs(dinv62 @ dexp62 - np.eye(3))) > 0.1
    # whereas the right-trivialized Bernoulli series is the inverse of eq. (60):
    Bm = [float(bernoulli(i)) for i in range(40)]
    right = sum((-1) ** i * Bm[i] / fact[i] * Xk[i] for i in range(40))
    np.testing.assert_allclose(right @ dexp62, np.eye(3), rtol=0, atol=1e-15)
    # and the left one is dexpinv (J_l^-1), consistent with so3.dexpinv_so3
    left = sum(Bm[i] / fact[i] * Xk[i] for i in range(40))
    np.testing.assert_allclose(left, left_jacobian_inv(G_VEC), rtol=0, atol=1e-15)
    np.testing.assert_allclose(
        np.eye(3) + float(coeff_B(THETA)) * X + float(coeff_C(THETA)) * X @ X, left_jacobian(G_VEC), atol=1e-15
    )
