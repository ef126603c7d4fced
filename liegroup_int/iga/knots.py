"""Knot vectors on the unit parameter interval.

All knot vectors of this package are *open* (clamped): the first and the
last knot, 0 and 1, are repeated ``degree + 1`` times, so that the curve
interpolates its first and last control points and the parameter ``u``
ranges over ``[0, 1]``.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "validate_degree",
    "validate_knots",
    "open_uniform_knots",
    "greville",
    "unique_interior_knots",
]


def validate_degree(degree: int) -> int:
    """Check that ``degree`` is an integer >= 1 and return it as ``int``.

    Parameters
    ----------
    degree : int
        Polynomial degree ``p``.

    Returns
    -------
    int
        The degree.

    Raises
    ------
    ValueError
        If the degree is not an integer or is smaller than 1.
    """
    if isinstance(degree, bool) or int(degree) != degree:
        raise ValueError(f"degree must be an integer, got {degree!r}")
    degree = int(degree)
    if degree < 1:
        raise ValueError(f"degree must be >= 1, got {degree}")
    return degree


def validate_knots(knots, degree: int, n_ctrl: int | None = None) -> np.ndarray:
    """Validate an open knot vector on ``[0, 1]`` and return it as an array.

    Parameters
    ----------
    knots : array_like, shape (n_ctrl + degree + 1,)
        Knot vector.
    degree : int
        Polynomial degree ``p >= 1``.
    n_ctrl : int, optional
        Expected number of basis functions; when given, the length of the
        knot vector must be ``n_ctrl + degree + 1``.

    Returns
    -------
    numpy.ndarray, shape (n_ctrl + degree + 1,)
        The knots as a float array (a copy).

    Raises
    ------
    ValueError
        If the knots are not finite, not non-decreasing, do not start with
        ``degree + 1`` zeros / end with ``degree + 1`` ones, have an interior
        knot of multiplicity larger than ``degree``, or have the wrong length.
    """
    degree = validate_degree(degree)
    knots = np.array(knots, dtype=float)
    if knots.ndim != 1:
        raise ValueError(f"knot vector must be 1-D, got shape {knots.shape}")
    if not np.all(np.isfinite(knots)):
        raise ValueError("knot vector contains non-finite values")
    if knots.size < 2 * (degree + 1):
        raise ValueError(
            f"knot vector of length {knots.size} too short for degree {degree} "
            f"(need at least {2 * (degree + 1)})"
        )
    if n_ctrl is not None and knots.size != n_ctrl + degree + 1:
        raise ValueError(
            f"knot vector length {knots.size} != n_ctrl + degree + 1 = "
            f"{n_ctrl + degree + 1}"
        )
    if np.any(np.diff(knots) < 0.0):
        raise ValueError("knot vector must be non-decreasing")
    if not (np.all(knots[: degree + 1] == 0.0) and knots[degree + 1] > 0.0):
        raise ValueError(
            f"knot vector must start with exactly degree + 1 = {degree + 1} zeros"
        )
    if not (np.all(knots[-degree - 1:] == 1.0) and knots[-degree - 2] < 1.0):
        raise ValueError(
            f"knot vector must end with exactly degree + 1 = {degree + 1} ones"
        )
    interior = knots[degree + 1: -degree - 1]
    if interior.size:
        _, counts = np.unique(interior, return_counts=True)
        if counts.max() > degree:
            raise ValueError(
                f"interior knot multiplicity {counts.max()} exceeds degree {degree}"
            )
    return knots


def open_uniform_knots(degree: int, n_ctrl: int) -> np.ndarray:
    """Open uniform knot vector on ``[0, 1]``.

    Parameters
    ----------
    degree : int
        Polynomial degree ``p >= 1``.
    n_ctrl : int
        Number of basis functions, ``n_ctrl >= degree + 1``.

    Returns
    -------
    numpy.ndarray, shape (n_ctrl + degree + 1,)
        ``[0]*(p+1) + linspace(0, 1, n_ctrl - p + 1)[1:-1] + [1]*(p+1)``.

    Raises
    ------
    ValueError
        If ``n_ctrl < degree + 1``.
    """
    degree = validate_degree(degree)
    if int(n_ctrl) != n_ctrl or n_ctrl < degree + 1:
        raise ValueError(
            f"n_ctrl must be an integer >= degree + 1 = {degree + 1}, got {n_ctrl!r}"
        )
    n_ctrl = int(n_ctrl)
    interior = np.linspace(0.0, 1.0, n_ctrl - degree + 1)[1:-1]
    return np.concatenate([np.zeros(degree + 1), interior, np.ones(degree + 1)])


def greville(knots, degree: int) -> np.ndarray:
    """Greville abscissae ``gamma_j = (U[j+1] + ... + U[j+p]) / p``.

    Parameters
    ----------
    knots : array_like, shape (n_ctrl + degree + 1,)
        Open knot vector on ``[0, 1]`` (validated).
    degree : int
        Polynomial degree ``p``.

    Returns
    -------
    numpy.ndarray, shape (n_ctrl,)
        Strictly increasing abscissae with ``gamma_0 = 0`` and
        ``gamma_{n-1} = 1`` exactly.
    """
    knots = validate_knots(knots, degree)
    windows = np.lib.stride_tricks.sliding_window_view(knots[1:-1], degree)
    g = windows.mean(axis=1)
    g[0], g[-1] = 0.0, 1.0
    return g


def unique_interior_knots(knots, degree: int) -> tuple[np.ndarray, np.ndarray]:
    """Distinct interior knots and their multiplicities.

    Parameters
    ----------
    knots : array_like, shape (m,)
        Open knot vector on ``[0, 1]`` (validated).
    degree : int
        Polynomial degree ``p``.

    Returns
    -------
    values : numpy.ndarray, shape (k,)
        Distinct interior knot values in ``(0, 1)``.
    counts : numpy.ndarray of int, shape (k,)
        Their multiplicities.
    """
    knots = validate_knots(knots, degree)
    return np.unique(knots[degree + 1: -degree - 1], return_counts=True)
