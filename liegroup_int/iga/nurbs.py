"""NURBS curves, exact k-refinement and Greville interpolation.

A :class:`NurbsCurve` of degree ``p`` with control points ``P_j`` and
weights ``w_j > 0`` is ``c(u) = sum_j R_{j,p}(u) P_j`` with the rational basis
``R_{j,p} = w_j N_{j,p} / W``, ``W = sum_i w_i N_{i,p}``.  A B-spline curve is
the special case ``w_j = 1`` (then ``R_{j,p} = N_{j,p}``).

Refinement (knot insertion, degree elevation) is exact and is carried out in
homogeneous coordinates ``(w_j P_j, w_j)`` with Piegl & Tiller's algorithms
A5.1 (single knot insertion, Boehm) and A5.9 (degree elevation).
"""

from __future__ import annotations

from dataclasses import dataclass
from math import comb
from typing import Callable

import numpy as np

from .bspline import as_parameters, basis_derivatives, basis_derivatives_local
from .knots import (
    greville,
    open_uniform_knots,
    unique_interior_knots,
    validate_degree,
    validate_knots,
)

__all__ = [
    "NurbsCurve",
    "rational_derivatives",
    "insert_knots",
    "elevate_degree",
    "k_refine",
    "interpolate_at_greville",
    "max_geometric_error",
]

#: Highest derivative order supported by :meth:`NurbsCurve.basis`.
MAX_NDER = 3


def _readonly(a: np.ndarray) -> np.ndarray:
    a = np.array(a, dtype=float)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class NurbsCurve:
    """Immutable NURBS curve in 3-D on the parameter interval ``[0, 1]``.

    Parameters
    ----------
    degree : int
        Polynomial degree ``p >= 1``.
    knots : array_like, shape (n_ctrl + degree + 1,)
        Open knot vector on ``[0, 1]``.
    control_points : array_like, shape (n_ctrl, 3)
        Control points ``P_j``.
    weights : array_like, shape (n_ctrl,), optional
        Positive weights ``w_j``; ``None`` (default) means all ones
        (a B-spline curve).

    Raises
    ------
    ValueError
        On an invalid knot vector, wrong shapes, non-finite data or a
        non-positive weight.

    Notes
    -----
    The arrays are stored as read-only float copies.
    """

    degree: int
    knots: np.ndarray
    control_points: np.ndarray
    weights: np.ndarray | None = None

    def __post_init__(self) -> None:
        degree = validate_degree(self.degree)
        pts = np.array(self.control_points, dtype=float)
        if pts.ndim != 2 or pts.shape[1] != 3:
            raise ValueError(f"control_points must have shape (n_ctrl, 3), got {pts.shape}")
        if not np.all(np.isfinite(pts)):
            raise ValueError("control_points contain non-finite values")
        n_ctrl = pts.shape[0]
        knots = validate_knots(self.knots, degree, n_ctrl)
        if self.weights is None:
            w = np.ones(n_ctrl)
        else:
            w = np.array(self.weights, dtype=float)
            if w.shape != (n_ctrl,):
                raise ValueError(f"weights must have shape ({n_ctrl},), got {w.shape}")
            if not np.all(np.isfinite(w)) or np.any(w <= 0.0):
                raise ValueError("weights must be finite and > 0")
        object.__setattr__(self, "degree", degree)
        object.__setattr__(self, "knots", _readonly(knots))
        object.__setattr__(self, "control_points", _readonly(pts))
        object.__setattr__(self, "weights", _readonly(w))

    @property
    def n_ctrl(self) -> int:
        """Number of control points / basis functions."""
        return self.control_points.shape[0]

    @property
    def is_rational(self) -> bool:
        """``True`` unless all weights are equal (then ``R_j = N_j``)."""
        return bool(np.any(self.weights != self.weights[0]))

    def homogeneous(self) -> np.ndarray:
        """Homogeneous control points ``(w_j P_j, w_j)``, shape ``(n_ctrl, 4)``."""
        return np.hstack([self.control_points * self.weights[:, None], self.weights[:, None]])

    @classmethod
    def from_homogeneous(cls, degree: int, knots, pw) -> "NurbsCurve":
        """Build a curve from homogeneous control points.

        Parameters
        ----------
        degree : int
            Polynomial degree.
        knots : array_like, shape (n_ctrl + degree + 1,)
            Knot vector.
        pw : array_like, shape (n_ctrl, 4)
            Homogeneous control points ``(w P, w)``.

        Returns
        -------
        NurbsCurve
        """
        pw = np.asarray(pw, dtype=float)
        return cls(degree, knots, pw[:, :3] / pw[:, 3:], pw[:, 3])

    def greville(self) -> np.ndarray:
        """Greville abscissae of the basis, shape ``(n_ctrl,)``."""
        return greville(self.knots, self.degree)

    def bspline_basis(self, u, nder: int = 0) -> np.ndarray:
        """Non-rational B-spline basis ``N_{j,p}`` and u-derivatives.

        Parameters
        ----------
        u : float or array_like, shape (n_points,)
            Parameters in ``[0, 1]``.
        nder : int, optional
            Highest derivative order.

        Returns
        -------
        numpy.ndarray, shape (nder + 1, n_points, n_ctrl)
        """
        return basis_derivatives(self.knots, self.degree, u, nder)

    def basis(self, u, nder: int = 0) -> np.ndarray:
        """Rational basis ``R_{j,p}`` and its u-derivatives.

        Parameters
        ----------
        u : float or array_like, shape (n_points,)
            Parameters in ``[0, 1]``.
        nder : int, optional
            Highest derivative order, ``0 <= nder <= 3``.

        Returns
        -------
        numpy.ndarray, shape (nder + 1, n_points, n_ctrl)
            ``out[k, i, j] = d^k R_{j,p} / du^k (u[i])``; equal to the
            B-spline basis when all weights are 1.
        """
        if int(nder) != nder or not 0 <= nder <= MAX_NDER:
            raise ValueError(f"nder must be an integer in [0, {MAX_NDER}], got {nder!r}")
        n = basis_derivatives(self.knots, self.degree, u, int(nder))
        if not self.is_rational:
            return n
        return rational_derivatives(n, self.weights)

    def evaluate(self, u, nder: int = 0) -> np.ndarray:
        """Curve points and their u-derivatives.

        Parameters
        ----------
        u : float or array_like, shape (n_points,)
            Parameters in ``[0, 1]``.
        nder : int, optional
            Highest derivative order, ``0 <= nder <= 3``.

        Returns
        -------
        numpy.ndarray, shape (nder + 1, n_points, 3)
            ``out[k, i] = d^k c / du^k (u[i])``.

        Notes
        -----
        Uses only the ``p + 1`` non-zero basis functions per point (no dense
        basis), then the quotient rule in homogeneous coordinates
        (Piegl & Tiller A4.2).
        """
        if int(nder) != nder or not 0 <= nder <= MAX_NDER:
            raise ValueError(f"nder must be an integer in [0, {MAX_NDER}], got {nder!r}")
        nder = int(nder)
        p = self.degree
        spans, local = basis_derivatives_local(self.knots, p, u, nder)
        idx = spans[:, None] - p + np.arange(p + 1)[None, :]
        aw = np.einsum("kir,ird->kid", local, self.homogeneous()[idx])
        a, w = aw[..., :3], aw[..., 3:]
        c = np.empty_like(a)
        for k in range(nder + 1):
            acc = a[k].copy()
            for i in range(1, k + 1):
                acc -= comb(k, i) * w[i] * c[k - i]
            c[k] = acc / w[0]
        return c


def rational_derivatives(n: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Rational basis derivatives from B-spline basis derivatives.

    With ``A_j = w_j N_j`` and ``W = sum_j A_j``, Leibniz' rule on
    ``A_j = W R_j`` gives
    ``R_j^(k) = (A_j^(k) - sum_{i=1..k} C(k, i) W^(i) R_j^(k-i)) / W``.

    Parameters
    ----------
    n : numpy.ndarray, shape (nder + 1, n_points, n_ctrl)
        B-spline basis and u-derivatives.
    weights : numpy.ndarray, shape (n_ctrl,)
        Positive weights.

    Returns
    -------
    numpy.ndarray, shape (nder + 1, n_points, n_ctrl)
        Rational basis and u-derivatives.
    """
    a = n * weights
    w = a.sum(axis=2, keepdims=True)
    r = np.empty_like(a)
    for k in range(a.shape[0]):
        acc = a[k].copy()
        for i in range(1, k + 1):
            acc -= comb(k, i) * w[i] * r[k - i]
        r[k] = acc / w[0]
    return r


# --------------------------------------------------------------------------
# refinement (homogeneous coordinates)
# --------------------------------------------------------------------------


def _insert_one(knots: np.ndarray, p: int, pw: np.ndarray, u: float):
    """Insert the knot ``u`` once (A5.1 with r = 1, Boehm's algorithm)."""
    k = int(np.searchsorted(knots, u, side="right") - 1)
    n = pw.shape[0]
    q = np.empty((n + 1, pw.shape[1]))
    q[: k - p + 1] = pw[: k - p + 1]
    q[k + 1:] = pw[k:]
    i = np.arange(k - p + 1, k + 1)
    alpha = ((u - knots[i]) / (knots[i + p] - knots[i]))[:, None]
    q[i] = alpha * pw[i] + (1.0 - alpha) * pw[i - 1]
    new_knots = np.insert(knots, k + 1, u)
    return new_knots, q


def insert_knots(curve: NurbsCurve, new_knots) -> NurbsCurve:
    """Exact knot insertion (Piegl & Tiller A5.1, one knot at a time).

    Parameters
    ----------
    curve : NurbsCurve
        Curve to refine.
    new_knots : array_like, shape (m,)
        Knots to insert, in ``(0, 1)``; repeated values are inserted
        repeatedly.

    Returns
    -------
    NurbsCurve
        Same curve with ``n_ctrl + m`` control points.

    Raises
    ------
    ValueError
        If a knot is outside the open interval ``(0, 1)`` or the resulting
        interior multiplicity would exceed the degree.
    """
    new = np.sort(np.atleast_1d(np.asarray(new_knots, dtype=float)).ravel())
    if new.size == 0:
        return curve
    if not np.all(np.isfinite(new)) or new[0] <= 0.0 or new[-1] >= 1.0:
        raise ValueError("inserted knots must lie in the open interval (0, 1)")
    p = curve.degree
    merged = np.sort(np.concatenate([curve.knots[p + 1: -p - 1], new]))
    if merged.size:
        _, counts = np.unique(merged, return_counts=True)
        if counts.max() > p:
            raise ValueError(
                f"knot insertion would create multiplicity {counts.max()} > degree {p}"
            )
    knots = np.array(curve.knots)
    pw = curve.homogeneous()
    for u in new:
        knots, pw = _insert_one(knots, p, pw, float(u))
    return NurbsCurve.from_homogeneous(p, knots, pw)


def _bezier_elevation_coefficients(p: int, t: int) -> np.ndarray:
    """``bezalfs[i, j] = C(p, j) C(t, i - j) / C(p + t, i)`` (zero elsewhere)."""
    ph = p + t
    coef = np.zeros((ph + 1, p + 1))
    for i in range(ph + 1):
        for j in range(max(0, i - t), min(p, i) + 1):
            coef[i, j] = comb(p, j) * comb(t, i - j) / comb(ph, i)
    return coef


def _elevate_homogeneous(knots: np.ndarray, p: int, pw: np.ndarray, t: int):
    """Degree elevation by ``t`` in homogeneous coordinates: every distinct knot's
    multiplicity grows by ``t``, and the control points of the same curve in that space
    solve the interpolation at its Greville abscissae (the curve lies in the elevated space,
    and Greville abscissae satisfy the Schoenberg-Whitney conditions, so the system is
    nonsingular and its solution exact up to round-off).

    Parameters
    ----------
    knots : numpy.ndarray, shape (n + p + 2,)
    p : int
        Degree.
    pw : numpy.ndarray, shape (n + 1, d)
        Homogeneous control points.
    t : int
        Degree increment ``>= 1``.

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        The elevated knot vector and homogeneous control points.
    """
    values, counts = np.unique(knots, return_counts=True)
    uh = np.repeat(values, counts + t)
    x = greville(uh, p + t)
    rhs = basis_derivatives(knots, p, x)[0] @ pw
    return uh, np.linalg.solve(basis_derivatives(uh, p + t, x)[0], rhs)


def elevate_degree(curve: NurbsCurve, new_degree: int) -> NurbsCurve:
    """Exact degree elevation (the same curve in the space of degree ``new_degree``).

    Every distinct knot's multiplicity grows by ``new_degree - degree``.

    Parameters
    ----------
    curve : NurbsCurve
        Curve to elevate.
    new_degree : int
        Target degree, ``>= curve.degree``.

    Returns
    -------
    NurbsCurve
        Same curve of degree ``new_degree`` (``curve`` itself if unchanged).

    Raises
    ------
    ValueError
        If ``new_degree < curve.degree``.
    """
    new_degree = validate_degree(new_degree)
    t = new_degree - curve.degree
    if t < 0:
        raise ValueError(
            f"cannot lower the degree from {curve.degree} to {new_degree}"
        )
    if t == 0:
        return curve
    uh, qw = _elevate_homogeneous(np.array(curve.knots), curve.degree, curve.homogeneous(), t)
    return NurbsCurve.from_homogeneous(new_degree, uh, qw)


def _split_spans(knots: np.ndarray, degree: int, count: int) -> np.ndarray:
    """Choose ``count`` new knots, splitting each non-empty span uniformly.

    Knots are dealt one at a time to the span whose current sub-interval
    length ``h / (n_new + 1)`` is largest (leftmost on ties), which gives
    the uniform grid ``k / (count + 1)`` for a single span.
    """
    edges = np.concatenate([[0.0], unique_interior_knots(knots, degree)[0], [1.0]])
    h = np.diff(edges)
    n_new = np.zeros(h.size, dtype=int)
    for _ in range(count):
        n_new[int(np.argmax(h / (n_new + 1)))] += 1
    parts = [
        np.linspace(edges[s], edges[s + 1], n_new[s] + 2)[1:-1] for s in range(h.size)
    ]
    return np.concatenate(parts) if parts else np.zeros(0)


def k_refine(curve: NurbsCurve, degree: int, n_ctrl: int) -> NurbsCurve:
    """Exact k-refinement: degree elevation, then knot insertion.

    The degree is elevated to ``degree`` first (raising the multiplicity of
    the existing knots), then ``n_ctrl - n`` single knots are inserted,
    splitting every existing non-empty knot span into uniformly spaced
    sub-intervals (new knots never coincide with existing ones).  For a
    curve without interior knots the result has the open uniform knot
    vector of ``(degree, n_ctrl)``.

    Parameters
    ----------
    curve : NurbsCurve
        Curve to refine.
    degree : int
        Target degree, ``>= curve.degree``.
    n_ctrl : int
        Target number of control points.

    Returns
    -------
    NurbsCurve
        The same geometric curve with the requested degree and size.

    Raises
    ------
    ValueError
        If ``degree < curve.degree`` or ``n_ctrl`` is smaller than the
        number of control points after degree elevation.
    """
    elevated = elevate_degree(curve, degree)
    if int(n_ctrl) != n_ctrl:
        raise ValueError(f"n_ctrl must be an integer, got {n_ctrl!r}")
    missing = int(n_ctrl) - elevated.n_ctrl
    if missing < 0:
        raise ValueError(
            f"cannot reach n_ctrl = {n_ctrl}: the degree-{degree} curve already has "
            f"{elevated.n_ctrl} control points"
        )
    if missing == 0:
        return elevated
    return insert_knots(elevated, _split_spans(elevated.knots, elevated.degree, missing))


# --------------------------------------------------------------------------
# interpolation of parametric curves
# --------------------------------------------------------------------------


def _call_curve(func: Callable[[np.ndarray], np.ndarray], u: np.ndarray) -> np.ndarray:
    pts = np.asarray(func(u), dtype=float)
    if pts.shape != (u.size, 3):
        raise ValueError(
            f"func(u) must return shape ({u.size}, 3) for u of shape ({u.size},), "
            f"got {pts.shape}"
        )
    return pts


def interpolate_at_greville(
    func: Callable[[np.ndarray], np.ndarray], degree: int, n_ctrl: int
) -> NurbsCurve:
    """B-spline interpolant of a parametric curve at the Greville points.

    Parameters
    ----------
    func : callable
        ``func(u)`` with ``u`` of shape ``(m,)`` in ``[0, 1]`` returns the
        curve points, shape ``(m, 3)``.
    degree : int
        Degree ``p`` of the open uniform basis.
    n_ctrl : int
        Number of control points.

    Returns
    -------
    NurbsCurve
        Non-rational curve ``c`` with ``c(g_j) = func(g_j)`` at the Greville
        abscissae ``g_j`` of ``open_uniform_knots(degree, n_ctrl)``.
    """
    knots = open_uniform_knots(degree, n_ctrl)
    g = greville(knots, degree)
    a = basis_derivatives(knots, degree, g, 0)[0]
    ctrl = np.linalg.solve(a, _call_curve(func, g))
    return NurbsCurve(degree, knots, ctrl)


def max_geometric_error(
    curve: NurbsCurve, func: Callable[[np.ndarray], np.ndarray], n_samples: int = 2001
) -> float:
    """Maximum parametric distance ``max_u |curve(u) - func(u)|`` on a grid.

    Parameters
    ----------
    curve : NurbsCurve
        Approximating curve.
    func : callable
        Reference parametrization ``func(u) -> (m, 3)`` on ``[0, 1]``.
    n_samples : int, optional
        Number of uniformly spaced samples in ``[0, 1]``.

    Returns
    -------
    float
        The maximum distance (an upper bound of the Hausdorff distance on
        the sampled points, since both curves share the parameter).
    """
    u = as_parameters(np.linspace(0.0, 1.0, int(n_samples)))
    return float(np.max(np.linalg.norm(curve.evaluate(u)[0] - _call_curve(func, u), axis=1)))
