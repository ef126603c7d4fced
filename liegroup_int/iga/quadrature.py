"""Quadrature rules of the Galerkin beam on one patch: which points carry the stiffness.

A rule gives, on one :class:`~liegroup_int.iga.collocation.CollocationSpace`, sorted
parameters and two sets of arc-length weights at them: the *bending* weights (bending
energy, gyroscopic and distributed loads, projections of point values onto the basis)
and the *axial* weights (axial and shear energy). Every term of the strain energy is a
weighted sum over the same points, so any rule keeps the semi-discrete Galerkin beam
Hamiltonian; the rules differ in cost (number of points), accuracy and rank.

Registered rules (:data:`RULES`):

* ``"gauss"``: ``p + 1`` Gauss points per knot interval for bending, ``p`` for the axial
  and shear terms (reduced integration against shear and membrane locking);
* ``"gauss-full"``: ``p + 1`` per interval for both;
* ``"gauss-p"``, ``"gauss-pm1"``, ``"gauss-2"``: ``p``, ``p - 1`` or 2 Gauss points per
  interval, shared by both sets of terms (``p`` points integrate the bending energy of a
  straight beam at rest exactly and the axial and shear terms as ``"gauss"``);
* ``"greville"``: one point per control point, at the Greville abscissae, with the weights
  that integrate every basis function exactly (Greville quadrature in the sense of Zou et
  al., CMAME 380, 2021);
* ``"gauss-spline"``: the Gaussian rule of the space of products ``N_i' N_j``
  (:mod:`.spline_quadrature`): exact where ``gauss-p`` is exact on a straight beam, with about
  ``(p + 1) / 2`` points per knot interval;
* ``"gauss-spline-reduced"``: the Gaussian rule of the space of products ``N_i' N_j'``: exact
  on the bending and axial stiffness of a straight beam at rest, reduced on the shear's
  ``N_i' N_j`` terms, with about ``p / 2`` points per knot interval;
* ``"auto"`` (:data:`DEFAULT_RULE`): ``gauss-spline-reduced`` for p = 3..6, else
  ``gauss-spline``, else ``gauss-p`` (:func:`_auto_rule`).

The consistent mass matrix does not depend on the rule (:func:`exact_mass_rule`, ``p + 1``
Gauss points per interval).
"""

from __future__ import annotations

from typing import Callable, NamedTuple

import numpy as np

from .bspline import band_widths
from .knots import greville
from .spline_quadrature import SplineQuadratureError, gaussian_spline_rule, product_knots

__all__ = ["DEFAULT_RULE", "PatchRule", "RULES", "RULE_DESCRIPTIONS", "exact_mass_rule", "gauss_points", "patch_rule"]


class PatchRule(NamedTuple):
    """Points of one patch and their arc-length weights.

    Attributes
    ----------
    u : numpy.ndarray, shape (k,)
        Parameters in ``[0, 1]``, sorted.
    w_bending, w_axial : numpy.ndarray, shape (k,)
        Arc-length weights of the bending and of the axial/shear terms (zero where a
        point belongs to the other set only).
    name : str
        The rule that made the points (``"auto"`` names the one it chose).
    """

    u: np.ndarray
    w_bending: np.ndarray
    w_axial: np.ndarray
    name: str = ""


def gauss_points(knots, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre points and weights in parameter space, ``n`` per non-empty knot interval.

    Returns
    -------
    u, w : numpy.ndarray, shape (n_el * n,)
    """
    kv = np.unique(np.asarray(knots, dtype=float))
    x, gw = np.polynomial.legendre.leggauss(int(n))
    a, b = kv[:-1, None], kv[1:, None]
    return (0.5 * (b - a) * x + 0.5 * (a + b)).ravel(), (0.5 * (b - a) * gw).ravel()


def _speed(space, u: np.ndarray) -> np.ndarray:
    """``ds/du`` of the reference centreline at ``u``."""
    return np.linalg.norm(space.curve.evaluate(u, 1)[1], axis=1)


def _gauss_arc(space, n: int) -> tuple[np.ndarray, np.ndarray]:
    """``n`` Gauss points per interval with arc-length weights."""
    u, w = gauss_points(space.curve.knots, n)
    return u, w * _speed(space, u)


def exact_mass_rule(space) -> tuple[np.ndarray, np.ndarray]:
    """``p + 1`` Gauss points per interval (exact for ``int N_i N_j ds`` on a straight
    B-spline beam): parameters and arc-length weights."""
    return _gauss_arc(space, space.degree + 1)


def _gauss_split(n_bending: int, n_axial: int) -> PatchRule:
    """Two Gauss rules merged (bending points weighted for bending only, and so on)."""
    def rule(space):
        ub, wb = _gauss_arc(space, n_bending)
        if n_axial == n_bending:
            return PatchRule(ub, wb, wb.copy())
        ua, wa = _gauss_arc(space, n_axial)
        u = np.concatenate([ub, ua])
        order = np.argsort(u, kind="stable")
        return PatchRule(u[order], np.concatenate([wb, np.zeros_like(wa)])[order],
                         np.concatenate([np.zeros_like(wb), wa])[order])
    return rule


def _gauss_per_interval(count: Callable[[int], tuple[int, int]]):
    """A Gauss rule whose point counts per interval depend on the degree."""
    return lambda space: _gauss_split(*count(space.degree))(space)


def _greville_rule(space) -> PatchRule:
    """Greville abscissae, weights solving ``sum_k w_k N_i(u_k) = int N_i ds`` for every
    basis function ``N_i`` (a square, nonsingular system: Schoenberg-Whitney)."""
    u = greville(space.curve.knots, space.degree)
    um, wm = exact_mass_rule(space)
    moments = space.point_matrix(um).T @ wm
    w = np.linalg.solve(space.point_matrix(u).T, moments)
    return PatchRule(u, w, w.copy())


#: Smallest squared Cholesky pivot, relative to its diagonal entry, of a point mass that
#: determines the basis (a B-spline Gram matrix has pivots of order one; a rule with too
#: few points leaves one at round-off, of either sign).
DEFINITE_PIVOT = 1e-10


def gram(B: np.ndarray, w: np.ndarray) -> np.ndarray:
    """``B^T diag(w) B`` ``(n, n)`` of a basis matrix ``B`` ``(m, n)`` with ``p + 1`` non-zeros
    per row, through sparse products (``O(m p^2)``, not the dense ``O(m n^2)``)."""
    import scipy.sparse

    S = scipy.sparse.csr_matrix(B)
    return np.asarray((S.T @ (scipy.sparse.diags(w) @ S)).todense())


def determines_basis(A: np.ndarray) -> bool:
    """Whether a point mass ``A`` ``(n, n)`` (banded, symmetric) is positive definite with
    every squared Cholesky pivot above :data:`DEFINITE_PIVOT` of its diagonal entry."""
    import scipy.linalg

    lower = band_widths(A)[0]
    ab = np.zeros((lower + 1, A.shape[0]))  # upper form: ab[lower + i - j, j] = A[i, j]
    for d in range(lower + 1):
        ab[lower - d, d:] = np.diagonal(A, d)
    try:
        pivots = scipy.linalg.cholesky_banded(ab, lower=False)[-1]
    except np.linalg.LinAlgError:
        return False
    return bool(np.min(pivots ** 2 / np.diag(A)) >= DEFINITE_PIVOT)


#: The names of the Gaussian spline rules, by ``both_derivatives``.
_SPLINE_RULES = {False: "gauss-spline", True: "gauss-spline-reduced"}


def _spline_points(space, both_derivatives: bool = False) -> PatchRule:
    """The Gaussian rule of the products ``N_i' N_j`` (of ``N_i' N_j'`` with
    ``both_derivatives``), arc-length weights; raises
    :class:`.spline_quadrature.SplineQuadratureError` where it is not found."""
    p = space.degree
    u, w = gaussian_spline_rule(product_knots(space.curve.knots, p, both_derivatives),
                                2 * p - 2 if both_derivatives else 2 * p - 1)
    w = w * _speed(space, u)
    return PatchRule(u, w, w.copy(), _SPLINE_RULES[both_derivatives])


def _spline_rule(both_derivatives: bool):
    """:func:`_spline_points`, or a one-line error naming the fallback."""
    def rule(space) -> PatchRule:
        try:
            return _spline_points(space, both_derivatives)
        except SplineQuadratureError as exc:
            name = _SPLINE_RULES[both_derivatives]
            raise ValueError(f"quadrature rule {name!r} at p = {space.degree}: {exc}; choose "
                             f"space.quadrature = \"gauss-p\"") from None
    return rule


def _auto_rule(space) -> PatchRule:
    """``gauss-spline-reduced`` for p = 3..6 where it is found and its points determine the
    basis, else ``gauss-spline`` for p = 3..7 where it is found (p = 3..6 always), else
    ``gauss-p`` (at p = 2 the spline rules are less accurate in the first modes, or miss the
    basis; at p >= 8 their iteration does not converge); ``gauss`` on a patch of one or two
    knot intervals, where those rules have fewer points than basis functions (a frame's
    short piece next to a point load)."""
    for reduced in (True, False):
        if 3 <= space.degree <= (6 if reduced else 7):
            try:
                rule = _spline_points(space, reduced)
            except SplineQuadratureError:
                continue
            if rule.u.size >= space.n_ctrl and determines_basis(gram(space.point_matrix(rule.u), rule.w_bending)):
                return rule
    rule = RULES["gauss-p"](space)._replace(name="gauss-p")
    return rule if rule.u.size >= space.n_ctrl else RULES["gauss"](space)._replace(name="gauss")


#: The stiffness rule of the Galerkin beam unless one is chosen (``space.quadrature``).
DEFAULT_RULE = "auto"

#: Named rules: ``space -> PatchRule``.
RULES: dict[str, Callable] = {
    "gauss": _gauss_per_interval(lambda p: (p + 1, p)),
    "gauss-full": _gauss_per_interval(lambda p: (p + 1, p + 1)),
    "gauss-p": _gauss_per_interval(lambda p: (p, p)),
    "gauss-pm1": _gauss_per_interval(lambda p: (p - 1, p - 1)),
    "gauss-2": _gauss_per_interval(lambda p: (2, 2)),
    "greville": _greville_rule,
    "gauss-spline": _spline_rule(False),
    "gauss-spline-reduced": _spline_rule(True),
    "auto": _auto_rule,
}

#: One line per rule (scene key help, benchmarks).
RULE_DESCRIPTIONS = {
    "gauss": "p + 1 Gauss points per knot interval for bending, p for axial and shear",
    "gauss-full": "p + 1 Gauss points per knot interval for every term",
    "gauss-p": "p Gauss points per knot interval for every term",
    "gauss-pm1": "p - 1 Gauss points per knot interval for every term",
    "gauss-2": "2 Gauss points per knot interval for every term",
    "greville": "one point per control point (Greville abscissae), weights exact for the basis",
    "gauss-spline": "Gaussian rule of the products N_i' N_j (exact as gauss-p, about (p + 1) / 2 points per interval)",
    "gauss-spline-reduced": "Gaussian rule of the products N_i' N_j' (about p / 2 points per interval; the shear's "
                            "N_i' N_j terms reduced)",
    "auto": "gauss-spline-reduced for p = 3..6, else gauss-spline for p = 3..7, where found and determining "
            "the basis; else gauss-p; gauss on a patch too short for these",
}


def patch_rule(space, name: str) -> PatchRule:
    """The rule ``name`` (a key of :data:`RULES`) on one patch."""
    if name not in RULES:
        raise ValueError(f"quadrature rule: expected one of {', '.join(RULES)}, got {name!r}")
    r = RULES[name](space)
    return r if r.name else r._replace(name=name)
