"""Linear stability of explicit Runge-Kutta tableaux.

For ``y' = lambda y`` one step multiplies by ``R(z)``, ``z = h lambda``, with

    R(z) = 1 + z b^T (I - z A)^{-1} 1 = 1 + sum_{k>=1} (b^T A^{k-1} 1) z^k,

a polynomial of degree ``<= s`` for explicit methods.  Stability limits are
computed exactly: the relevant polynomial (``|R(iy)|^2 - 1`` in ``x = y^2``,
or ``+-R(-x) - 1``) is built with Fractions, its real roots are isolated with a
Sturm sequence and refined by exact bisection, and the first root at which the
polynomial turns positive is returned.  Roots where it only touches zero (even
multiplicity) do not end the stability interval.
"""

from __future__ import annotations

import math
from fractions import Fraction
from typing import Sequence

import numpy as np

from .base import ButcherTableau

Poly = list  # list of Fractions, increasing powers


# --------------------------------------------------------------------------
# exact polynomial helpers (coefficient lists in increasing powers)
# --------------------------------------------------------------------------

def _trim(p: Poly) -> Poly:
    p = list(p)
    while p and p[-1] == 0:
        p.pop()
    return p


def _eval(p: Poly, x: Fraction) -> Fraction:
    acc = Fraction(0)
    for coeff in reversed(p):
        acc = acc * x + coeff
    return acc


def _sign(value) -> int:
    return (value > 0) - (value < 0)


def _derivative(p: Poly) -> Poly:
    return _trim([k * p[k] for k in range(1, len(p))])


def _mul(p: Poly, q: Poly) -> Poly:
    if not p or not q:
        return []
    out = [Fraction(0)] * (len(p) + len(q) - 1)
    for i, pi in enumerate(p):
        if pi == 0:
            continue
        for j, qj in enumerate(q):
            out[i + j] += pi * qj
    return _trim(out)


def _add(p: Poly, q: Poly) -> Poly:
    n = max(len(p), len(q))
    return _trim([(p[k] if k < len(p) else 0) + (q[k] if k < len(q) else 0)
                  for k in range(n)])


def _divmod(p: Poly, q: Poly) -> tuple[Poly, Poly]:
    p, q = _trim(p), _trim(q)
    if not q:
        raise ZeroDivisionError("polynomial division by zero")
    quotient = [Fraction(0)] * max(len(p) - len(q) + 1, 0)
    rem = [Fraction(x) for x in p]
    while len(rem) >= len(q) and rem:
        shift = len(rem) - len(q)
        factor = rem[-1] / q[-1]
        quotient[shift] = factor
        for k, qk in enumerate(q):
            rem[shift + k] -= factor * qk
        rem = _trim(rem)
    return _trim(quotient), rem


def _monic(p: Poly) -> Poly:
    return [x / p[-1] for x in p]


def _gcd(p: Poly, q: Poly) -> Poly:
    """Monic greatest common divisor (Euclid over the rationals)."""
    p, q = _trim(p), _trim(q)
    while q:
        p, q = q, _divmod(p, q)[1]
    return _monic(p) if p else p


def _odd_multiplicity_part(p: Poly) -> Poly:
    """Square-free polynomial whose roots are the odd-multiplicity roots of ``p``.

    Yun's square-free factorisation ``p = const * prod_i f_i^i``; returns the
    product of ``f_i`` over odd ``i``.  These are exactly the real points where
    ``p`` changes sign.
    """
    dp = _derivative(p)
    a = _gcd(p, dp)
    b = _divmod(p, a)[0]
    c = _divmod(dp, a)[0]
    d = _add(c, [-x for x in _derivative(b)])
    odd: Poly = [Fraction(1)]
    i = 1
    while len(b) > 1:
        f = _gcd(b, d)
        b = _divmod(b, f)[0]
        c = _divmod(d, f)[0]
        d = _add(c, [-x for x in _derivative(b)])
        if i % 2 == 1:
            odd = _mul(odd, f)
        i += 1
    return _monic(odd)


def _sturm_chain(p: Poly) -> list[Poly]:
    """Sturm sequence of a square-free polynomial (remainders scaled by > 0)."""
    chain = [p, _derivative(p)]
    while len(chain[-1]) > 1:
        rem = _divmod(chain[-2], chain[-1])[1]
        if not rem:
            break
        scale = abs(rem[-1])
        chain.append([-x / scale for x in rem])
    return chain


def _variations(chain: list[Poly], x: Fraction) -> int:
    signs = [s for s in (_sign(_eval(p, x)) for p in chain) if s != 0]
    return sum(1 for u, v in zip(signs, signs[1:]) if u != v)


def _cauchy_bound(p: Poly) -> Fraction:
    lead = abs(p[-1])
    return 1 + max(abs(x) / lead for x in p[:-1])


def _smallest_positive_root(p: Poly, rel_tol: Fraction = Fraction(1, 10**17)) -> Fraction | None:
    """Smallest root in ``(0, inf)`` of a square-free ``p`` (Sturm + bisection)."""
    if len(p) <= 1:
        return None
    chain = _sturm_chain(p)
    lo, hi = Fraction(0), _cauchy_bound(p)
    v_lo = _variations(chain, lo)
    if v_lo - _variations(chain, hi) == 0:
        return None
    # invariant: no root in (0, lo], at least one root in (lo, hi]
    while hi - lo > rel_tol * hi:
        mid = (lo + hi) / 2
        if v_lo - _variations(chain, mid) > 0:
            hi = mid
        else:
            lo = mid
    return (lo + hi) / 2


def _first_positive_crossing(p: Poly) -> float:
    """``inf {x > 0 : p(x) > 0}`` for an exact polynomial with ``p(0) <= 0``.

    Returns ``0.0`` when ``p > 0`` immediately to the right of 0, ``math.inf``
    when ``p <= 0`` on all of ``(0, inf)``.  Roots of even multiplicity (where
    ``p`` touches 0 without changing sign) are skipped.
    """
    p = _trim([Fraction(x) for x in p])
    if not p:
        return math.inf
    lowest = next(k for k, coeff in enumerate(p) if coeff != 0)
    q = p[lowest:]                       # p = x^lowest * q, q(0) != 0
    if q[0] > 0:
        return 0.0
    # q(0) < 0, so the first sign change of q on (0, inf) is where it turns positive
    root = _smallest_positive_root(_odd_multiplicity_part(q))
    return math.inf if root is None else float(root)


# --------------------------------------------------------------------------
# public API
# --------------------------------------------------------------------------

def stability_polynomial_exact(tab: ButcherTableau,
                               weights: Sequence | None = None) -> tuple[Fraction, ...]:
    """Exact coefficients of ``R(z)`` in increasing powers (trailing zeros trimmed).

    Parameters
    ----------
    tab : ButcherTableau
        Explicit tableau.
    weights : sequence, optional
        Weights replacing ``tab.b`` (e.g. ``tab.b_hat``).  Floats are taken
        at their exact binary value.

    Returns
    -------
    tuple of Fraction
        ``(1, b.1, b.A.1, b.A^2.1, ...)``.
    """
    w = tab.b if weights is None else tuple(Fraction(x) for x in weights)
    if len(w) != tab.stages:
        raise ValueError(f"stability_polynomial: len(weights)={len(w)} != stages={tab.stages}")
    s = tab.stages
    v = [Fraction(1)] * s                    # A^{k-1} 1
    coeffs = [Fraction(1)]
    for _ in range(s):
        coeffs.append(sum(wi * vi for wi, vi in zip(w, v)))
        v = [sum(tab.A[i][j] * v[j] for j in range(s)) for i in range(s)]
    return tuple(_trim(coeffs))


def stability_polynomial(tab: ButcherTableau, weights: Sequence | None = None) -> np.ndarray:
    """Coefficients of ``R(z) = 1 + z b^T (I - zA)^{-1} 1``, increasing powers.

    Computed exactly (see :func:`stability_polynomial_exact`) and returned as
    a float64 array, e.g. ``[1, 1, 0.5]`` for explicit midpoint.
    """
    return np.array([float(x) for x in stability_polynomial_exact(tab, weights)])


def _abs2_minus_one_in_y2(r: Sequence[Fraction]) -> Poly:
    """Coefficients in ``x = y^2`` of ``|R(iy)|^2 - 1``."""
    re_part = [Fraction(0)] * len(r)       # polynomials in y
    im_part = [Fraction(0)] * len(r)
    for k, coeff in enumerate(r):
        sign = -1 if (k // 2) % 2 else 1   # i^k = (+1, i, -1, -i, ...)
        if k % 2 == 0:
            re_part[k] = sign * coeff
        else:
            im_part[k] = sign * coeff
    in_y = _add(_add(_mul(re_part, re_part), _mul(im_part, im_part)), [Fraction(-1)])
    return [in_y[k] for k in range(0, len(in_y), 2)]   # odd powers vanish


def imaginary_axis_limit(tab: ButcherTableau, weights: Sequence | None = None) -> float:
    """Largest ``y >= 0`` with ``|R(i y')| <= 1`` for all ``0 <= y' <= y``.

    ``0.0`` when the method is unstable for every small ``y > 0`` (Euler,
    explicit midpoint, Butcher's RK6); e.g. ``2*sqrt(2)`` for RK4 and
    ``sqrt(3)`` for Kutta's RK3.
    """
    x_limit = _first_positive_crossing(
        _abs2_minus_one_in_y2(stability_polynomial_exact(tab, weights)))
    return math.sqrt(x_limit)


def real_axis_limit(tab: ButcherTableau, weights: Sequence | None = None) -> float:
    """Largest ``x >= 0`` with ``|R(-x')| <= 1`` for all ``0 <= x' <= x``.

    E.g. ``2`` for Euler and midpoint, about ``2.785`` for RK4.
    """
    r = stability_polynomial_exact(tab, weights)
    r_neg = [coeff * (-1) ** k for k, coeff in enumerate(r)]        # R(-x)
    above = _add(r_neg, [Fraction(-1)])                              # R - 1
    below = _add([-coeff for coeff in r_neg], [Fraction(-1)])        # -R - 1
    return min(_first_positive_crossing(above), _first_positive_crossing(below))


def imaginary_axis_growth(tab: ButcherTableau, y, weights: Sequence | None = None):
    """``|R(i y)|`` (scalar or array ``y``); values above 1 mean amplification.

    Explicit midpoint has ``|R(iy)| = sqrt(1 + y^4/4) ~ 1 + y^4/8``.
    """
    coeffs = stability_polynomial(tab, weights)
    z = 1j * np.asarray(y, dtype=float)
    value = np.polynomial.polynomial.polyval(z, coeffs)
    return np.abs(value)
