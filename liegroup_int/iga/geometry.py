"""Reference centrelines used by the beam benchmarks.

* :func:`straight` - straight B-spline with linear (arc-length) parametrization.
* :func:`arc_nurbs_quadratic` - exact quadratic NURBS of the 60-degree arch
  (circle of radius ``3/pi``, length 1), optionally k-refined.
* :func:`helix_quarter` - quarter turn of a helix, interpolated at the
  Greville points (a helix is not a NURBS curve).
"""

from __future__ import annotations

import numpy as np

from .knots import greville, open_uniform_knots
from .nurbs import NurbsCurve, interpolate_at_greville, k_refine

__all__ = [
    "ARCH_RADIUS",
    "HELIX_RADIUS",
    "straight",
    "arc_nurbs_quadratic",
    "arc_exact",
    "helix_quarter",
    "helix_quarter_exact",
]

#: Radius ``R = 3/pi`` of the 60-degree arch (its length is ``R pi/3 = 1``).
ARCH_RADIUS = 3.0 / np.pi
#: Radius ``R = 3/(2 pi)`` of the quarter helix.
HELIX_RADIUS = 3.0 / (2.0 * np.pi)


def straight(
    length: float,
    direction=(1.0, 0.0, 0.0),
    degree: int = 4,
    n_ctrl: int = 31,
    origin=(0.0, 0.0, 0.0),
) -> NurbsCurve:
    """Straight B-spline centreline ``c(u) = origin + length * u * e``.

    The control points sit at the Greville abscissae,
    ``P_j = origin + length * g_j * e`` (``e`` = normalized ``direction``);
    by the linear precision of B-splines this makes the parametrization
    exactly linear, so ``u`` is proportional to arc length
    (``|dc/du| = length``).  Control points spaced uniformly in ``j`` would
    *not* do that for an open knot vector.

    Parameters
    ----------
    length : float
        Beam length ``> 0``.
    direction : array_like, shape (3,), optional
        Axis direction (normalized internally).
    degree : int, optional
        Degree ``p``.
    n_ctrl : int, optional
        Number of control points (open uniform knot vector).
    origin : array_like, shape (3,), optional
        Position of the end ``u = 0``.

    Returns
    -------
    NurbsCurve
        Non-rational straight curve.
    """
    if not np.isfinite(length) or length <= 0.0:
        raise ValueError(f"length must be a finite positive number, got {length!r}")
    e = np.asarray(direction, dtype=float)
    origin = np.asarray(origin, dtype=float)
    if e.shape != (3,) or origin.shape != (3,):
        raise ValueError("direction and origin must have shape (3,)")
    norm = np.linalg.norm(e)
    if not np.isfinite(norm) or norm == 0.0:
        raise ValueError("direction must be a finite non-zero vector")
    knots = open_uniform_knots(degree, n_ctrl)
    g = greville(knots, degree)
    return NurbsCurve(degree, knots, origin + length * g[:, None] * (e / norm))


def arc_nurbs_quadratic(degree: int = 2, n_ctrl: int = 3) -> NurbsCurve:
    """Exact NURBS of the 60-degree arch of radius ``R = 3/pi`` and length 1.

    The base curve has degree 2, knots ``[0, 0, 0, 1, 1, 1]``, control
    points ``(0, 0, 0)``, ``(0, sqrt(3)/pi, 0)``,
    ``(3/(2 pi), 3 sqrt(3)/(2 pi), 0)`` and weights ``(1, sqrt(3)/2, 1)``:
    the circle of centre ``(R, 0, 0)`` in the plane ``x3 = 0`` from the
    origin (leaving along ``+x2``) through the angle ``pi/3``.  When
    ``(degree, n_ctrl) != (2, 3)`` it is k-refined exactly with
    :func:`~liegroup_int.iga.nurbs.k_refine` (open uniform knots).

    Parameters
    ----------
    degree : int, optional
        Target degree, ``>= 2``.
    n_ctrl : int, optional
        Target number of control points, ``>= degree + 1``.

    Returns
    -------
    NurbsCurve
        Rational curve.
    """
    s3 = np.sqrt(3.0)
    ctrl = np.array(
        [[0.0, 0.0, 0.0], [0.0, s3 / np.pi, 0.0], [1.5 / np.pi, 1.5 * s3 / np.pi, 0.0]]
    )
    base = NurbsCurve(2, [0.0, 0.0, 0.0, 1.0, 1.0, 1.0], ctrl, [1.0, s3 / 2.0, 1.0])
    if (degree, n_ctrl) == (2, 3):
        return base
    return k_refine(base, degree, n_ctrl)


def arc_exact(theta) -> np.ndarray:
    """Points of the arch circle at polar angle ``theta`` (arc length ``R theta``).

    Parameters
    ----------
    theta : array_like, shape (m,)
        Angles in ``[0, pi/3]``.

    Returns
    -------
    numpy.ndarray, shape (m, 3)
        ``(R (1 - cos theta), R sin theta, 0)``.
    """
    theta = np.atleast_1d(np.asarray(theta, dtype=float))
    r = ARCH_RADIUS
    return np.stack([r * (1.0 - np.cos(theta)), r * np.sin(theta), 0.0 * theta], axis=-1)


def helix_quarter_exact(u) -> np.ndarray:
    """Exact quarter helix ``c0(s) = (R (cos s - 1), R sin s, -s/pi)``, ``s = u pi/2``.

    Parameters
    ----------
    u : array_like, shape (m,)
        Parameters in ``[0, 1]``.

    Returns
    -------
    numpy.ndarray, shape (m, 3)
        Points, with ``R = 3/(2 pi)``; the length of the curve is
        ``(pi/2) sqrt(R^2 + 1/pi^2) = sqrt(13)/4``.
    """
    s = 0.5 * np.pi * np.atleast_1d(np.asarray(u, dtype=float))
    r = HELIX_RADIUS
    return np.stack([r * (np.cos(s) - 1.0), r * np.sin(s), -s / np.pi], axis=-1)


def helix_quarter(degree: int = 4, n_ctrl: int = 31) -> NurbsCurve:
    """B-spline interpolant of :func:`helix_quarter_exact` at the Greville points.

    Parameters
    ----------
    degree : int, optional
        Degree of the open uniform basis.
    n_ctrl : int, optional
        Number of control points.

    Returns
    -------
    NurbsCurve
        Non-rational curve; the interpolation error is ``O(h^(p+1))``.
    """
    return interpolate_at_greville(helix_quarter_exact, degree, n_ctrl)
