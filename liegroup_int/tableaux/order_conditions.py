"""Rooted trees and Runge-Kutta order conditions (Butcher series).

A rooted tree is represented as a nested tuple of its children's subtrees,
so the single-node tree is ``()`` and ``[t, [t]]`` is ``((), ((),))``.  The
canonical form sorts the children recursively (Python's tuple ordering), so
two trees are equal iff their canonical tuples are equal.

For an explicit (or any) Runge-Kutta method with coefficient matrix ``A`` and
weights ``b`` the order conditions read ``Phi(t) = 1 / gamma(t)`` for every
tree ``t`` with ``|t| <= p``, where ``c = A 1`` is implied (row-sum
condition), ``gamma`` is the tree density and ``Phi`` the elementary weight
(Hairer, Norsett & Wanner, *Solving ODEs I*, Sec. II.2; Butcher,
*Numerical Methods for ODEs*, Ch. 3).

All functions work with exact ``fractions.Fraction`` (or ``int``) entries
and with floats.  With exact entries the residuals are exact rationals.
"""

from __future__ import annotations

import math
import numbers
from fractions import Fraction
from functools import lru_cache

Tree = tuple
"""A rooted tree: the tuple of its children (each a ``Tree``)."""

LEAF: Tree = ()
"""The single-node tree ``t`` (order 1)."""

#: Default absolute tolerance for float residuals (exact inputs use 0).
FLOAT_TOL = 1e-10

#: Number of rooted trees of order 1..8 (OEIS A000081).
KNOWN_TREE_COUNTS = (1, 1, 2, 4, 9, 20, 48, 115)


def canonical(tree: Tree) -> Tree:
    """Return the canonical form of a tree (children sorted recursively).

    Parameters
    ----------
    tree : tuple
        Nested tuple of children.

    Returns
    -------
    tuple
        The same tree with every child list sorted.
    """
    return tuple(sorted(canonical(child) for child in tree))


def tree_order(tree: Tree) -> int:
    """Number of nodes ``|t|`` of a tree."""
    return 1 + sum(tree_order(child) for child in tree)


def density(tree: Tree) -> int:
    """Tree density ``gamma(t) = |t| * prod_children gamma(child)``."""
    gamma = tree_order(tree)
    for child in tree:
        gamma *= density(child)
    return gamma


def tree_to_str(tree: Tree) -> str:
    """Butcher bracket notation, ``t`` for the leaf, e.g. ``[t,[t]]``."""
    if not tree:
        return "t"
    return "[" + ",".join(tree_to_str(child) for child in tree) + "]"


def _grow(tree: Tree):
    """Yield all trees obtained by attaching one new leaf to a node of ``tree``."""
    yield tree + (LEAF,)
    for i, child in enumerate(tree):
        for grown in _grow(child):
            yield tree[:i] + (grown,) + tree[i + 1:]


def _sort_key(tree: Tree):
    return (tree_order(tree), tree_to_str(tree))


@lru_cache(maxsize=None)
def trees_of_order(order: int) -> tuple[Tree, ...]:
    """All rooted trees with exactly ``order`` nodes, in canonical form.

    Parameters
    ----------
    order : int
        Number of nodes, ``>= 1``.

    Returns
    -------
    tuple of tuple
        Distinct canonical trees, deterministically sorted.
    """
    if order < 1:
        raise ValueError(f"tree order must be >= 1, got {order}")
    if order == 1:
        return (LEAF,)
    found = {canonical(grown)
             for smaller in trees_of_order(order - 1)
             for grown in _grow(smaller)}
    return tuple(sorted(found, key=_sort_key))


def trees_up_to(max_order: int) -> tuple[Tree, ...]:
    """All rooted trees with ``1 <= |t| <= max_order``, sorted by order."""
    return tuple(t for p in range(1, max_order + 1) for t in trees_of_order(p))


def _is_exact(value) -> bool:
    return isinstance(value, numbers.Rational)


def _as_rows(A) -> list[list]:
    return [list(row) for row in A]


def _stage_vector(A: list[list], tree: Tree, memo: dict) -> list:
    """Vector ``g(t)`` with ``g(leaf) = 1`` and ``g(t)_i = prod_u (A g(u))_i``.

    ``Phi(t) = b . g(t)``.  Results are memoised in ``memo`` (keyed by tree).
    """
    if tree in memo:
        return memo[tree]
    s = len(A)
    g = [1] * s
    for child in tree:
        h = _stage_vector(A, child, memo)
        for i in range(s):
            g[i] = g[i] * sum(A[i][j] * h[j] for j in range(s) if A[i][j] != 0)
    memo[tree] = g
    return g


def _stage_vector_int(A: list[list[int]], tree: Tree, memo: dict) -> list[int]:
    """:func:`_stage_vector` for integer ``A`` (``D`` times the tableau's): returns
    ``G(t) = g(t) D^(|t|-1)``, with ``G(leaf) = 1`` and ``G(t)_i = prod_u (A G(u))_i``."""
    if tree in memo:
        return memo[tree]
    s = len(A)
    g = [1] * s
    for child in tree:
        h = _stage_vector_int(A, child, memo)
        for i in range(s):
            row = A[i]
            g[i] *= sum(row[j] * h[j] for j in range(s) if row[j])
    memo[tree] = g
    return g


def elementary_weight(A, b, tree: Tree, memo: dict | None = None):
    """Elementary weight ``Phi(t) = sum_i b_i g(t)_i``.

    Parameters
    ----------
    A : sequence of sequences
        ``(s, s)`` coefficient matrix (Fractions, ints or floats).
    b : sequence
        ``(s,)`` weights.
    tree : tuple
        Rooted tree (any form; it is canonicalised).
    memo : dict, optional
        Cache of stage vectors for this ``A`` (reuse across calls with the
        same ``A`` only).

    Returns
    -------
    Fraction or float
        Exact when all entries are exact.
    """
    rows = _as_rows(A)
    g = _stage_vector(rows, canonical(tree), {} if memo is None else memo)
    return sum(bi * gi for bi, gi in zip(b, g))


def order_condition_residuals(A, b, max_order: int) -> list[tuple[Tree, int, object]]:
    """Residuals ``Phi(t) - 1/gamma(t)`` for every tree with ``|t| <= max_order``.

    Parameters
    ----------
    A : sequence of sequences
        ``(s, s)`` coefficient matrix; ``c = A 1`` is implied.
    b : sequence
        ``(s,)`` weights.
    max_order : int
        Largest tree order considered.

    Returns
    -------
    list of (tree, order, residual)
        Residuals are ``Fraction`` when ``A`` and ``b`` are exact, else float.
    """
    rows = _as_rows(A)
    weights = list(b)
    if len(rows) != len(weights) or any(len(r) != len(weights) for r in rows):
        raise ValueError("order_condition_residuals: A must be (s, s) and b (s,)")
    exact = all(_is_exact(x) for x in weights) and all(
        _is_exact(x) for row in rows for x in row)
    memo: dict = {}
    out = []
    if exact:
        # integers over a common denominator D of A: G(t) = g(t) D^(|t|-1), so that the
        # stage vectors need no Fraction arithmetic (same exact residuals, much faster)
        den = math.lcm(*(Fraction(x).denominator for row in rows for x in row)) if rows else 1
        ints = [[int(Fraction(x) * den) for x in row] for row in rows]
        for tree in trees_up_to(max_order):
            order = tree_order(tree)
            num = sum(Fraction(bi) * gi for bi, gi in zip(weights, _stage_vector_int(ints, tree, memo)))
            out.append((tree, order, num / den ** (order - 1) - Fraction(1, density(tree))))
        return out
    for tree in trees_up_to(max_order):
        phi = sum(bi * gi for bi, gi in zip(weights, _stage_vector(rows, tree, memo)))
        out.append((tree, tree_order(tree), phi - 1.0 / density(tree)))
    return out


def achieved_order(A, b, max_order: int = 8, tol: float | None = None) -> int:
    """Largest ``p <= max_order`` such that all conditions of order ``<= p`` hold.

    Parameters
    ----------
    A, b : sequences
        Tableau coefficients (``c = A 1`` implied).
    max_order : int, default 8
        Highest order tested.
    tol : float, optional
        Absolute tolerance on residuals.  Default: ``0`` (exact test) when
        every entry is a rational, ``FLOAT_TOL = 1e-10`` otherwise (float
        residuals of tableaux with large coefficients carry rounding errors:
        Verner 6(5), with ``|b_i|`` up to 176, shows ~3e-11).

    Returns
    -------
    int
        ``0`` if even ``sum(b) == 1`` fails.
    """
    residuals = order_condition_residuals(A, b, max_order)
    if tol is None:
        exact = all(isinstance(r, Fraction) for _, _, r in residuals)
        tol = 0 if exact else FLOAT_TOL
    for tree, order, residual in residuals:
        if abs(residual) > tol:
            return order - 1
    return max_order


def first_failed_condition(A, b, max_order: int,
                           tol: float | None = None) -> tuple[Tree, int, object] | None:
    """First ``(tree, order, residual)`` with a nonzero residual, or ``None``.

    Same tolerance rule as :func:`achieved_order`.
    """
    residuals = order_condition_residuals(A, b, max_order)
    if tol is None:
        exact = all(isinstance(r, Fraction) for _, _, r in residuals)
        tol = 0 if exact else FLOAT_TOL
    for item in residuals:
        if abs(item[2]) > tol:
            return item
    return None
