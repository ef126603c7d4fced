"""Continuous extensions (dense output) of explicit Runge-Kutta tableaux, exact and checked.

A continuous extension of order ``q`` replaces the weights ``b`` by polynomials
``b_i(theta) = sum_{m=1..q} W[i, m-1] theta^m`` such that, for every rooted tree ``t``
with ``|t| <= q``,

    sum_i b_i(theta) g(t)_i = theta^|t| / gamma(t)      for all theta in [0, 1]

(the continuous order conditions, Hairer-Norsett-Wanner I, II.6), with ``g(t)`` the
stage vectors of :mod:`.order_conditions`. Then ``h sum_i b_i(theta) k_i`` approximates
the solution at ``t_n + theta h`` with a local error ``O(h^(q+1))``. Power by power in
``theta`` the conditions are linear in the columns of ``W``: ``G W[:, m-1] = r_m`` with
``G`` the stage vectors of all trees up to order ``q`` and ``(r_m)_t = [|t| = m] /
gamma(t)``. The last column is fixed by continuity at the step end, ``b(1) = b``
(``W[:, q-1] = b - sum_{m<q} W[:, m-1]``), which satisfies its block because ``b``
has order ``>= q``.

When the method's own stages cannot carry order ``q`` (Verner's 6(5) pair reaches 4,
Butcher's RK6 less), extra stages are added by bootstrapping (Enright, Jackson, Norsett
& Thomsen 1986): a stage at ``c* = theta*`` whose row is the lower-order extension at
``theta*``, ``A[s, :] = b^(q-1)(theta*)``, raises the attainable order by one.

Everything is solved and checked in exact rational arithmetic on first use.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from functools import lru_cache

import numpy as np

from .base import ButcherTableau
from .order_conditions import _stage_vector, canonical, density, tree_order, trees_up_to

#: Nodes ``theta*`` of the bootstrapped stages, in the order they are added.
BOOTSTRAP_NODES = (Fraction(1, 2), Fraction(2, 3), Fraction(1, 3), Fraction(3, 4))


def solve_exact(rows: list[list[Fraction]], rhs: list[Fraction]) -> list[Fraction] | None:
    """A solution of ``rows @ x = rhs`` in exact arithmetic (free unknowns 0), or ``None``
    if the system is inconsistent. Gauss-Jordan elimination with the first nonzero pivot."""
    m = [[Fraction(x) for x in r] + [Fraction(v)] for r, v in zip(rows, rhs)]
    n = len(rows[0]) if rows else 0
    pivots, r = [], 0
    for col in range(n):
        p = next((i for i in range(r, len(m)) if m[i][col] != 0), None)
        if p is None:
            continue
        m[r], m[p] = m[p], m[r]
        inv = 1 / m[r][col]
        m[r] = [v * inv for v in m[r]]
        for i in range(len(m)):
            if i != r and m[i][col] != 0:
                f = m[i][col]
                m[i] = [a - f * b for a, b in zip(m[i], m[r])]
        pivots.append(col)
        r += 1
    if any(row[-1] != 0 for row in m[r:]):
        return None
    x = [Fraction(0)] * n
    for i, col in enumerate(pivots):
        x[col] = m[i][-1]
    return x


def stage_vectors(A: list[list[Fraction]], order: int) -> list[tuple[object, list[Fraction]]]:
    """``(tree, g(tree))`` for every tree with ``|t| <= order``."""
    memo: dict = {}
    return [(t, _stage_vector(A, canonical(t), memo)) for t in trees_up_to(order)]


def solve_weights(A: list[list[Fraction]], b: list[Fraction], order: int) -> list[list[Fraction]] | None:
    """Columns ``W[:, m-1]``, ``m = 1..order``, of a continuous extension of order ``order``
    with ``b(1) = b`` on the stages ``A``, or ``None`` if these stages cannot carry it."""
    vectors = stage_vectors(A, order)
    G = [g for _, g in vectors]
    cols = []
    for m in range(1, order):
        rhs = [Fraction(1, density(t)) if tree_order(t) == m else Fraction(0) for t, _ in vectors]
        col = solve_exact(G, rhs)
        if col is None:
            return None
        cols.append(col)
    cols.append([bi - sum(c[i] for c in cols) for i, bi in enumerate(b)])
    return cols


def weights_at(cols: list[list[Fraction]], theta: Fraction) -> list[Fraction]:
    """``b(theta)``: the continuous weights at ``theta``."""
    return [sum(c[i] * theta ** (m + 1) for m, c in enumerate(cols)) for i in range(len(cols[0]))]


def continuous_residuals(A: list[list[Fraction]], cols: list[list[Fraction]]) -> list[tuple[object, int, Fraction]]:
    """``(tree, m, sum_i W[i, m-1] g(t)_i - [|t| = m] / gamma(t))`` for every tree up to the
    extension's order and every power ``m``: all zero for a valid extension."""
    out = []
    for t, g in stage_vectors(A, len(cols)):
        for m, c in enumerate(cols, start=1):
            target = Fraction(1, density(t)) if tree_order(t) == m else Fraction(0)
            out.append((t, m, sum(ci * gi for ci, gi in zip(c, g)) - target))
    return out


def _pad(A: list[list[Fraction]], row: list[Fraction]) -> list[list[Fraction]]:
    """``A`` with one more stage whose row is ``row``."""
    return [r + [Fraction(0)] for r in A] + [row + [Fraction(0)]]


def _highest_order(A, b, top: int) -> tuple[int, list]:
    """The largest order ``<= top`` the stages ``A`` carry, with its weight columns."""
    for q in range(top, 0, -1):
        cols = solve_weights(A, b, q)
        if cols is not None:
            return q, cols
    raise ValueError("no continuous extension of order 1 (sum(b) != 1?)")


@dataclass(frozen=True)
class ContinuousExtension:
    """Continuous weights of a tableau, with its bootstrapped stages (exact, checked).

    Attributes
    ----------
    name : str
        The tableau's name.
    order : int
        ``q``: local error ``O(h^(q+1))`` at every ``theta``.
    A : tuple of tuples of Fraction
        ``(s + e, s + e)``: the tableau's ``A`` and the ``e`` bootstrapped rows.
    c : tuple of Fraction
        Nodes of all stages.
    W : tuple of tuples of Fraction
        ``W[m-1]``: the coefficient vector of ``theta^m`` (length ``s + e``).
    stages : int
        ``s``, the tableau's own stages (the extra ones are ``A[s:]``).
    A_f, c_f, W_f : ndarray
        Float copies; ``W_f`` has shape ``(q, s + e)``.
    """

    name: str
    order: int
    A: tuple
    c: tuple
    W: tuple
    stages: int
    A_f: np.ndarray = field(repr=False, compare=False)
    c_f: np.ndarray = field(repr=False, compare=False)
    W_f: np.ndarray = field(repr=False, compare=False)

    @property
    def extra(self) -> int:
        """Number of bootstrapped stages."""
        return len(self.c) - self.stages

    def weights(self, theta: float) -> np.ndarray:
        """``b(theta)`` in floats, shape ``(s + e,)``."""
        powers = theta ** np.arange(1, self.order + 1)
        return powers @ self.W_f


def _build(tab: ButcherTableau, order: int) -> ContinuousExtension:
    A = [list(r) for r in tab.A]
    b = list(tab.b)
    c = list(tab.c)
    q, cols = _highest_order(A, b, order)
    for theta in BOOTSTRAP_NODES:
        if q >= order:
            break
        A, b, c = _pad(A, weights_at(cols, theta)), b + [Fraction(0)], c + [theta]
        q, cols = _highest_order(A, b, order)
    if q < order:
        raise ValueError(f"tableau {tab.name!r}: no continuous extension of order {order} with "
                         f"{len(BOOTSTRAP_NODES)} bootstrapped stages")
    bad = [r for r in continuous_residuals(A, cols) if r[2] != 0]
    if bad or any(x != y for x, y in zip(weights_at(cols, Fraction(1)), b)):
        raise ValueError(f"tableau {tab.name!r}: continuous extension fails its checks")
    n = len(c)
    return ContinuousExtension(
        name=tab.name, order=q, A=tuple(tuple(r) for r in A), c=tuple(c), W=tuple(tuple(col) for col in cols),
        stages=tab.stages, A_f=np.array([[float(x) for x in r] for r in A]).reshape(n, n),
        c_f=np.array([float(x) for x in c]), W_f=np.array([[float(x) for x in col] for col in cols]))


def default_order(tab: ButcherTableau) -> int:
    """``p`` for an embedded pair, ``max(1, p - 1)`` otherwise.

    A pair's steps are sized by its embedded error of order ``p - 1`` while it propagates the
    order-``p`` solution, so its step ends are far more accurate than the tolerance; an
    interpolant of order ``p - 1`` would be only tolerance-accurate between them (measured on
    the double pendulum at 1e-8: energy errors 1.4e-6 between the steps, 2.3e-8 at them; 5.6e-8
    with order ``p``). A fixed-step method's global error ``O(h^p)`` already matches
    an interpolant of order ``p - 1``."""
    return tab.order if tab.b_hat is not None else max(1, tab.order - 1)


@lru_cache(maxsize=None)
def continuous_extension(tab: ButcherTableau, order: int | None = None) -> ContinuousExtension:
    """The continuous extension of ``tab`` of order ``order`` (default :func:`default_order`),
    bootstrapping stages as needed; cached per tableau. Raises ``ValueError`` if none is found."""
    q = default_order(tab) if order is None else int(order)
    if not 1 <= q <= tab.order:
        raise ValueError(f"tableau {tab.name!r}: continuous order must be in [1, {tab.order}], got {order!r}")
    return _build(tab, q)
