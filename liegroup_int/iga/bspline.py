"""Vectorized B-spline basis functions and banded collocation matrices.

The basis functions ``N_{j,p}`` of an open knot vector on ``[0, 1]`` and
their derivatives are computed with Piegl & Tiller's algorithm A2.3
("DersBasisFuns"), vectorized over the evaluation points: the only Python
loops run over the degree and the derivative order.
"""

from __future__ import annotations

import numpy as np

from .knots import validate_knots

__all__ = [
    "as_parameters",
    "find_spans",
    "basis_derivatives_local",
    "scatter_local",
    "basis_derivatives",
    "band_widths_from_spans",
    "band_widths",
    "to_banded",
]

#: Parameters outside ``[0, 1]`` by at most this much are clipped silently.
PARAMETER_TOLERANCE = 1e-12


def as_parameters(u) -> np.ndarray:
    """Convert parameters to a 1-D float array inside ``[0, 1]``.

    Parameters
    ----------
    u : float or array_like, shape (n_points,)
        Curve parameters.

    Returns
    -------
    numpy.ndarray, shape (n_points,)
        Parameters, clipped to ``[0, 1]`` when they lie outside by at most
        ``PARAMETER_TOLERANCE``.

    Raises
    ------
    ValueError
        If ``u`` is more than 1-D, not finite, or outside ``[0, 1]``.
    """
    u = np.atleast_1d(np.asarray(u, dtype=float))
    if u.ndim != 1:
        raise ValueError(f"parameters must be a scalar or 1-D array, got shape {u.shape}")
    if not np.all(np.isfinite(u)):
        raise ValueError("parameters must be finite")
    if u.size and (u.min() < -PARAMETER_TOLERANCE or u.max() > 1.0 + PARAMETER_TOLERANCE):
        raise ValueError(
            f"parameters must lie in [0, 1], got range [{u.min()}, {u.max()}]"
        )
    return np.clip(u, 0.0, 1.0)


def find_spans(knots: np.ndarray, degree: int, u: np.ndarray) -> np.ndarray:
    """Knot span index ``k`` with ``U[k] <= u < U[k+1]`` (last span for ``u = 1``).

    Parameters
    ----------
    knots : numpy.ndarray, shape (n_ctrl + degree + 1,)
        Validated open knot vector.
    degree : int
        Polynomial degree ``p``.
    u : numpy.ndarray, shape (n_points,)
        Parameters in ``[0, 1]``.

    Returns
    -------
    numpy.ndarray of int, shape (n_points,)
        Span indices in ``[p, n_ctrl - 1]``.
    """
    n_ctrl = knots.size - degree - 1
    spans = np.searchsorted(knots, u, side="right") - 1
    return np.clip(spans, degree, n_ctrl - 1)


def basis_derivatives_local(knots, degree: int, u, nder: int = 0):
    """Non-zero B-spline basis functions and derivatives (vectorized A2.3).

    Parameters
    ----------
    knots : array_like, shape (n_ctrl + degree + 1,)
        Open knot vector on ``[0, 1]``.
    degree : int
        Polynomial degree ``p``.
    u : float or array_like, shape (n_points,)
        Parameters in ``[0, 1]``.
    nder : int, optional
        Highest derivative order (``>= 0``); orders above ``p`` are zero.

    Returns
    -------
    spans : numpy.ndarray of int, shape (n_points,)
        Knot span of each parameter; the non-zero functions at ``u[i]`` are
        ``N_{spans[i]-p}, ..., N_{spans[i]}``.
    ders : numpy.ndarray, shape (nder + 1, n_points, degree + 1)
        ``ders[k, i, r] = d^k N_{spans[i]-p+r} / du^k (u[i])``.
    """
    knots = validate_knots(knots, degree)
    p = int(degree)
    if int(nder) != nder or nder < 0:
        raise ValueError(f"nder must be a non-negative integer, got {nder!r}")
    nder = int(nder)
    u = as_parameters(u)
    npts = u.size
    spans = find_spans(knots, p, u)

    # ndu[j, r] (upper triangle incl. diagonal): basis functions of degree j;
    # ndu[j, r] for r < j (lower triangle): knot differences.
    ndu = np.zeros((p + 1, p + 1, npts))
    ndu[0, 0] = 1.0
    left = np.zeros((p + 1, npts))
    right = np.zeros((p + 1, npts))
    for j in range(1, p + 1):
        left[j] = u - knots[spans + 1 - j]
        right[j] = knots[spans + j] - u
        saved = np.zeros(npts)
        for r in range(j):
            ndu[j, r] = right[r + 1] + left[j - r]
            temp = ndu[r, j - 1] / ndu[j, r]
            ndu[r, j] = saved + right[r + 1] * temp
            saved = left[j - r] * temp
        ndu[j, j] = saved

    ders = np.zeros((nder + 1, npts, p + 1))
    ders[0] = ndu[:, p].T
    kmax = min(nder, p)
    for r in range(p + 1):
        a = np.zeros((2, p + 1, npts))
        a[0, 0] = 1.0
        s1, s2 = 0, 1
        for k in range(1, kmax + 1):
            d = np.zeros(npts)
            rk, pk = r - k, p - k
            if r >= k:
                a[s2, 0] = a[s1, 0] / ndu[pk + 1, rk]
                d = a[s2, 0] * ndu[rk, pk]
            j1 = 1 if rk >= -1 else -rk
            j2 = k - 1 if r - 1 <= pk else p - r
            for j in range(j1, j2 + 1):
                a[s2, j] = (a[s1, j] - a[s1, j - 1]) / ndu[pk + 1, rk + j]
                d = d + a[s2, j] * ndu[rk + j, pk]
            if r <= pk:
                a[s2, k] = -a[s1, k - 1] / ndu[pk + 1, r]
                d = d + a[s2, k] * ndu[r, pk]
            ders[k, :, r] = d
            s1, s2 = s2, s1
    factor = float(p)
    for k in range(1, kmax + 1):
        ders[k] *= factor
        factor *= p - k
    return spans, ders


def scatter_local(spans: np.ndarray, local: np.ndarray, degree: int, n_ctrl: int) -> np.ndarray:
    """Scatter local basis values into dense rows.

    Parameters
    ----------
    spans : numpy.ndarray of int, shape (n_points,)
        Knot spans from :func:`basis_derivatives_local`.
    local : numpy.ndarray, shape (m, n_points, degree + 1)
        Local values.
    degree : int
        Polynomial degree ``p``.
    n_ctrl : int
        Number of basis functions.

    Returns
    -------
    numpy.ndarray, shape (m, n_points, n_ctrl)
        Dense array with ``out[:, i, spans[i]-p+r] = local[:, i, r]``.
    """
    m, npts, _ = local.shape
    out = np.zeros((m, npts, n_ctrl))
    rows = np.arange(npts)[:, None]
    cols = spans[:, None] - degree + np.arange(degree + 1)[None, :]
    out[:, rows, cols] = local
    return out


def basis_derivatives(knots, degree: int, u, nder: int = 0) -> np.ndarray:
    """Dense B-spline basis functions and their derivatives.

    Parameters
    ----------
    knots : array_like, shape (n_ctrl + degree + 1,)
        Open knot vector on ``[0, 1]``.
    degree : int
        Polynomial degree ``p``.
    u : float or array_like, shape (n_points,)
        Parameters in ``[0, 1]``.
    nder : int, optional
        Highest derivative order.

    Returns
    -------
    numpy.ndarray, shape (nder + 1, n_points, n_ctrl)
        ``out[k, i, j] = d^k N_{j,p} / du^k (u[i])``.
    """
    knots = validate_knots(knots, degree)
    n_ctrl = knots.size - degree - 1
    spans, local = basis_derivatives_local(knots, degree, u, nder)
    return scatter_local(spans, local, degree, n_ctrl)


def band_widths_from_spans(spans: np.ndarray, degree: int) -> tuple[int, int]:
    """Band widths of a square collocation matrix from its rows' knot spans.

    Row ``i`` of the matrix holds the basis functions at the ``i``-th point,
    supported in columns ``spans[i]-p .. spans[i]``.  This is a structural
    bound: at parameters that coincide with knots some of these entries
    vanish, and :func:`band_widths` of the assembled matrix may be smaller.

    Parameters
    ----------
    spans : numpy.ndarray of int, shape (n,)
        Knot span of each collocation point (one per row).
    degree : int
        Polynomial degree ``p``.

    Returns
    -------
    (lower, upper) : tuple of int
        Number of sub- and super-diagonals, as for
        :func:`scipy.linalg.solve_banded`.
    """
    rows = np.arange(spans.size)
    lower = int(max(0, np.max(rows - (spans - degree))))
    upper = int(max(0, np.max(spans - rows)))
    return lower, upper


def band_widths(matrix: np.ndarray) -> tuple[int, int]:
    """Band widths ``(lower, upper)`` from the non-zero pattern of a matrix.

    Parameters
    ----------
    matrix : numpy.ndarray, shape (n, n)
        Square matrix.

    Returns
    -------
    (lower, upper) : tuple of int
        Largest ``i - j`` and ``j - i`` over the non-zero entries ``(i, j)``.
    """
    i, j = np.nonzero(matrix)
    if i.size == 0:
        return 0, 0
    return int(max(0, np.max(i - j))), int(max(0, np.max(j - i)))


def to_banded(matrix: np.ndarray, lower: int, upper: int, extra_rows: int = 0) -> np.ndarray:
    """Diagonal-ordered form of a banded matrix.

    Parameters
    ----------
    matrix : numpy.ndarray, shape (n, n)
        Square matrix with zeros outside the band.
    lower, upper : int
        Number of sub- and super-diagonals.
    extra_rows : int, optional
        Zero rows prepended (use ``lower`` for LAPACK ``gbtrf`` fill-in).

    Returns
    -------
    numpy.ndarray, shape (extra_rows + lower + upper + 1, n)
        ``ab[extra_rows + upper + i - j, j] = matrix[i, j]``; with
        ``extra_rows = 0`` this is the ``ab`` argument of
        :func:`scipy.linalg.solve_banded` with ``(l, u) = (lower, upper)``.

    Raises
    ------
    ValueError
        If the matrix has non-zero entries outside the band.
    """
    matrix = np.asarray(matrix, dtype=float)
    n = matrix.shape[0]
    if matrix.shape != (n, n):
        raise ValueError(f"matrix must be square, got shape {matrix.shape}")
    lo, up = band_widths(matrix)
    if lo > lower or up > upper:
        raise ValueError(
            f"matrix band ({lo}, {up}) exceeds requested band ({lower}, {upper})"
        )
    ab = np.zeros((extra_rows + lower + upper + 1, n))
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    mask = (i - j <= lower) & (j - i <= upper)
    ab[extra_rows + upper + i[mask] - j[mask], j[mask]] = matrix[mask]
    return ab
