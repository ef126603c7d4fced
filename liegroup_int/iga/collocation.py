"""Collocation space of a beam centreline: basis matrices and reference geometry.

Conventions
-----------
* Collocation points ``u_c``: Greville abscissae of the geometry's basis.
* The unknown fields use the (rational) basis ``R_j`` of the geometry.
* Arc-length derivatives: ``d/ds = (1/J) d/du`` with ``J = |dc0/du|`` and
  ``d2/ds2 = (1/J^2) d2/du2 - (J_u/J^3) d/du``, ``J_u = t . c0_uu``.
* Material frame ``R0 = [d1 | d2 | d3]`` (columns) - a *projection frame*:

  - ``d3 = t = c0_u / |c0_u|`` (unit tangent; the beam axis is material
    axis 3),
  - ``d1 = (a - (a.t) t) / |a - (a.t) t|`` for a fixed reference vector
    ``a`` (unit vector),
  - ``d2 = d3 x d1``.

  Default ``a`` (:func:`default_reference_vector`): the global axis
  ``e_i`` least aligned with the tangent at ``u = 0`` (smallest ``|t_i|``);
  ties are broken in the cyclic order ``i_max + 1, i_max + 2`` (mod 3)
  after the most aligned axis ``i_max``.  Hence a straight beam along
  ``+e1`` gets ``R0 = [e2 | e3 | e1]``, along ``+e3`` gets the identity,
  and the planar arch (tangent ``+e2`` at ``u = 0``) gets ``d1 = e3`` (the
  binormal) and ``d2`` = inward principal normal, so its curvature is
  ``K0 = (-1/R, 0, 0)``.
* ``K0 = vee(R0^T dR0/ds)`` with ``vee(S) = (S[2,1], S[0,2], S[1,0])`` and
  ``K0_s = dK0/ds = vee(skew(R0^T d2R0/ds2))``; both are computed
  analytically from ``c0_u, c0_uu, c0_uuu``.
"""

from __future__ import annotations

import numpy as np

from .bspline import as_parameters, band_widths, to_banded
from .nurbs import NurbsCurve

__all__ = [
    "DEFAULT_MIN_ANGLE",
    "vee",
    "default_reference_vector",
    "tangent_derivatives",
    "projection_frame",
    "arc_length",
    "CollocationSpace",
]

#: Smallest admissible angle (rad) between the reference vector and the tangent.
DEFAULT_MIN_ANGLE = np.deg2rad(1.0)



def _linalg():
    """``scipy.linalg``, imported on first use (the CLI's listing commands need no LAPACK)."""
    import scipy.linalg

    return scipy.linalg

def vee(s: np.ndarray) -> np.ndarray:
    """Axial vector of (the skew part of) 3x3 matrices.

    Parameters
    ----------
    s : numpy.ndarray, shape (..., 3, 3)
        Matrices.

    Returns
    -------
    numpy.ndarray, shape (..., 3)
        ``(S[2,1], S[0,2], S[1,0])`` of ``S = (s - s^T) / 2``.
    """
    return 0.5 * np.stack(
        [
            s[..., 2, 1] - s[..., 1, 2],
            s[..., 0, 2] - s[..., 2, 0],
            s[..., 1, 0] - s[..., 0, 1],
        ],
        axis=-1,
    )


def default_reference_vector(tangent) -> np.ndarray:
    """Global axis least aligned with a tangent (ties broken cyclically).

    Parameters
    ----------
    tangent : array_like, shape (3,)
        Tangent (need not be normalized).

    Returns
    -------
    numpy.ndarray, shape (3,)
        ``e_i`` minimizing ``|t_i|``; among ties (within ``1e-12``) the first
        of ``i_max + 1, i_max + 2`` (mod 3), ``i_max = argmax |t_i|``.
    """
    t = np.asarray(tangent, dtype=float)
    t = np.abs(t / np.linalg.norm(t))
    i_max = int(np.argmax(t))
    for i in ((i_max + 1) % 3, (i_max + 2) % 3):
        if t[i] <= t.min() + 1e-12:
            return np.eye(3)[i]
    raise AssertionError("unreachable")  # pragma: no cover


def tangent_derivatives(c_u: np.ndarray, c_uu: np.ndarray, c_uuu: np.ndarray):
    """Unit tangent, its arc-length derivatives and the metric ``J``.

    Uses ``c_u = J t``, ``c_uu = J_u t + J^2 t_s`` and
    ``c_uuu = J_uu t + 3 J J_u t_s + J^3 t_ss``.

    Parameters
    ----------
    c_u, c_uu, c_uuu : numpy.ndarray, shape (n, 3)
        First three u-derivatives of the curve.

    Returns
    -------
    t, t_s, t_ss : numpy.ndarray, shape (n, 3)
        Unit tangent and its first two arc-length derivatives.
    jac, jac_u : numpy.ndarray, shape (n,)
        ``J = |c_u|`` and ``dJ/du``.
    """
    jac = np.linalg.norm(c_u, axis=-1)
    if np.any(jac <= 0.0):
        raise ValueError("degenerate parametrization: |dc/du| = 0 somewhere")
    j = jac[:, None]
    t = c_u / j
    jac_u = np.einsum("ij,ij->i", t, c_uu)
    jac_uu = (
        np.einsum("ij,ij->i", c_uu, c_uu) + np.einsum("ij,ij->i", c_u, c_uuu) - jac_u**2
    ) / jac
    t_s = (c_uu - jac_u[:, None] * t) / j**2
    t_ss = (c_uuu - jac_uu[:, None] * t - 3.0 * (jac * jac_u)[:, None] * t_s) / j**3
    return t, t_s, t_ss, jac, jac_u


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.einsum("ij,ij->i", a, b)[:, None]


def projection_frame(
    t: np.ndarray,
    t_s: np.ndarray,
    t_ss: np.ndarray,
    reference_vector,
    min_angle: float = DEFAULT_MIN_ANGLE,
):
    """Projection frame, its curvature and the curvature's derivative.

    Parameters
    ----------
    t, t_s, t_ss : numpy.ndarray, shape (n, 3)
        Unit tangent and its arc-length derivatives
        (see :func:`tangent_derivatives`).
    reference_vector : array_like, shape (3,)
        Vector ``a`` (normalized internally) projected to give ``d1``.
    min_angle : float, optional
        Smallest admissible angle (rad) between ``a`` and ``t``.

    Returns
    -------
    r0 : numpy.ndarray, shape (n, 3, 3)
        Rotations with columns ``d1, d2, d3``.
    k0 : numpy.ndarray, shape (n, 3)
        Material curvature ``vee(R0^T dR0/ds)``.
    k0_s : numpy.ndarray, shape (n, 3)
        Its arc-length derivative.

    Raises
    ------
    ValueError
        If ``a`` comes within ``min_angle`` of being parallel to ``t``.
    """
    a = np.asarray(reference_vector, dtype=float)
    if a.shape != (3,) or not np.all(np.isfinite(a)) or np.linalg.norm(a) == 0.0:
        raise ValueError("reference_vector must be a finite non-zero vector of shape (3,)")
    a = a / np.linalg.norm(a)
    at, at_s, at_ss = t @ a, t_s @ a, t_ss @ a
    v = a - at[:, None] * t
    nv = np.linalg.norm(v, axis=1)
    if np.any(nv < np.sin(min_angle)):
        angle = np.rad2deg(np.arcsin(min(1.0, float(nv.min()))))
        raise ValueError(
            f"reference vector {a} is within {angle:.3g} deg of the tangent; "
            "pass another reference_vector"
        )
    v_s = -at_s[:, None] * t - at[:, None] * t_s
    v_ss = -at_ss[:, None] * t - 2.0 * at_s[:, None] * t_s - at[:, None] * t_ss
    n = nv[:, None]
    d1 = v / n
    n_s = _dot(d1, v_s)
    d1_s = (v_s - d1 * n_s) / n
    n_ss = _dot(d1_s, v_s) + _dot(d1, v_ss)
    d1_ss = (v_ss - d1 * n_ss) / n - 2.0 * n_s * d1_s / n
    d2 = np.cross(t, d1)
    d2_s = np.cross(t_s, d1) + np.cross(t, d1_s)
    d2_ss = np.cross(t_ss, d1) + 2.0 * np.cross(t_s, d1_s) + np.cross(t, d1_ss)
    r0 = np.stack([d1, d2, t], axis=-1)
    r0_s = np.stack([d1_s, d2_s, t_s], axis=-1)
    r0_ss = np.stack([d1_ss, d2_ss, t_ss], axis=-1)
    rt = np.swapaxes(r0, -1, -2)
    return r0, vee(rt @ r0_s), vee(rt @ r0_ss)


def arc_length(curve: NurbsCurve, u, n_gauss: int = 16) -> np.ndarray:
    """Arc length ``s(u) = int_0^u |dc/du| du`` by composite Gauss-Legendre.

    The quadrature intervals are delimited by the distinct knots and the
    requested parameters, so the integrand is smooth on each interval.

    Parameters
    ----------
    curve : NurbsCurve
        The curve.
    u : float or array_like, shape (m,)
        Parameters in ``[0, 1]`` (any order).
    n_gauss : int, optional
        Gauss points per interval.

    Returns
    -------
    numpy.ndarray, shape (m,)
        Arc lengths.
    """
    if int(n_gauss) != n_gauss or n_gauss < 1:
        raise ValueError(f"n_gauss must be a positive integer, got {n_gauss!r}")
    u = as_parameters(u)
    edges = np.unique(np.concatenate([curve.knots, u, [0.0, 1.0]]))
    x, w = np.polynomial.legendre.leggauss(int(n_gauss))
    lo, hi = edges[:-1, None], edges[1:, None]
    nodes = 0.5 * (lo + hi) + 0.5 * (hi - lo) * x[None, :]
    jac = np.linalg.norm(curve.evaluate(nodes.ravel(), 1)[1], axis=1).reshape(nodes.shape)
    pieces = 0.5 * (hi[:, 0] - lo[:, 0]) * (jac @ w)
    cumulative = np.concatenate([[0.0], np.cumsum(pieces)])
    return cumulative[np.searchsorted(edges, u)]


def _arc_length_basis(basis_u: np.ndarray, jac: np.ndarray, jac_u: np.ndarray) -> np.ndarray:
    """Convert u-derivatives ``(3, m, n)`` of the basis to s-derivatives."""
    j = jac[:, None]
    return np.stack(
        [
            basis_u[0],
            basis_u[1] / j,
            basis_u[2] / j**2 - basis_u[1] * (jac_u / jac**3)[:, None],
        ]
    )


def _frozen(a: np.ndarray) -> np.ndarray:
    a = np.ascontiguousarray(a, dtype=float)
    a.setflags(write=False)
    return a


class CollocationSpace:
    """Collocation matrices and reference geometry of a beam centreline.

    Built once from the geometry; all arrays are read-only.

    Parameters
    ----------
    curve : NurbsCurve
        Reference centreline ``c0(u)``, ``u in [0, 1]``; its (rational) basis
        is the trial basis of the beam fields.
    reference_vector : array_like, shape (3,), optional
        Vector ``a`` defining ``d1`` (see the module docstring); ``None``
        picks :func:`default_reference_vector` of the tangent at ``u = 0``.
    min_angle : float, optional
        Smallest admissible angle (rad) between ``a`` and the tangent,
        checked at the collocation points and on a fine grid.
    solver : {"banded", "lu"}, optional
        Factorization of ``M_c = N0``: banded LU (LAPACK ``gbtrf``) or dense
        LU (:func:`scipy.linalg.lu_factor`).
    n_gauss : int, optional
        Gauss points per interval for the arc length.

    Attributes
    ----------
    curve : NurbsCurve
    degree, n_ctrl : int
    u_c : numpy.ndarray, shape (n,)
        Collocation points (Greville abscissae), ``u_c[0] = 0``, ``u_c[-1] = 1``.
    N0, N1, N2 : numpy.ndarray, shape (n, n)
        ``N_k[i, j] = d^k R_j / ds^k (u_c[i])``.
    jac : numpy.ndarray, shape (n,)
        ``J = |dc0/du|`` at ``u_c``.
    c0, c0_s, c0_ss : numpy.ndarray, shape (n, 3)
        Centreline and its arc-length derivatives at ``u_c``.
    R0 : numpy.ndarray, shape (n, 3, 3)
        Material frames (columns ``d1, d2, d3``).
    K0, K0_s : numpy.ndarray, shape (n, 3)
        Material curvature and its arc-length derivative.
    reference_vector : numpy.ndarray, shape (3,)
        Unit reference vector ``a`` used.
    length : float
        Total arc length ``L``.
    s_c : numpy.ndarray, shape (n,)
        Arc length of the collocation points.
    l_s_start, l_s_end : float
        ``(s_c[1] - s_c[0]) / 2`` and ``(s_c[-1] - s_c[-2]) / 2``.
    bandwidths : tuple of int
        ``(lower, upper)`` band widths of ``M_c``.
    """

    def __init__(
        self,
        curve: NurbsCurve,
        reference_vector=None,
        min_angle: float = DEFAULT_MIN_ANGLE,
        solver: str = "banded",
        n_gauss: int = 16,
    ) -> None:
        if not isinstance(curve, NurbsCurve):
            raise ValueError(f"curve must be a NurbsCurve, got {type(curve).__name__}")
        if solver not in ("banded", "lu"):
            raise ValueError(f"solver must be 'banded' or 'lu', got {solver!r}")
        self.curve = curve
        self.degree = curve.degree
        self.n_ctrl = curve.n_ctrl
        self.solver = solver
        u_c = curve.greville()
        self.u_c = _frozen(u_c)

        geo = curve.evaluate(u_c, 3)
        t, t_s, t_ss, jac, jac_u = tangent_derivatives(geo[1], geo[2], geo[3])
        n_s = _arc_length_basis(curve.basis(u_c, 2), jac, jac_u)
        self.jac = _frozen(jac)
        self.N0 = _frozen(n_s[0])
        self.N1 = _frozen(n_s[1])
        self.N2 = _frozen(n_s[2])
        self.c0 = _frozen(geo[0])
        self.c0_s = _frozen(t)
        self.c0_ss = _frozen(t_s)

        if reference_vector is None:
            a = default_reference_vector(geo[1][0])
        else:
            a = np.asarray(reference_vector, dtype=float)
            if a.shape != (3,) or not np.all(np.isfinite(a)) or not np.any(a):
                raise ValueError(
                    "reference_vector must be a finite non-zero vector of shape (3,)"
                )
            a = a / np.linalg.norm(a)
        self.reference_vector = _frozen(a)
        self._min_angle = float(min_angle)
        self._check_reference_vector(a, min_angle)
        r0, k0, k0_s = projection_frame(t, t_s, t_ss, a, min_angle)
        self.R0 = _frozen(r0)
        self.K0 = _frozen(k0)
        self.K0_s = _frozen(k0_s)

        self._n_gauss = int(n_gauss)
        s_all = arc_length(curve, np.concatenate([u_c, [1.0]]), self._n_gauss)
        self.s_c = _frozen(s_all[:-1])
        self.length = float(s_all[-1])
        self.l_s_start = 0.5 * float(self.s_c[1] - self.s_c[0])
        self.l_s_end = 0.5 * float(self.s_c[-1] - self.s_c[-2])

        self.bandwidths = band_widths(self.N0)
        self._factorize()

    # ------------------------------------------------------------------
    def _check_reference_vector(self, a: np.ndarray, min_angle: float) -> None:
        """Raise if ``a`` is nearly parallel to the tangent on a fine grid."""
        grid = np.linspace(0.0, 1.0, 8 * self.n_ctrl + 1)
        tangent = self.curve.evaluate(grid, 1)[1]
        tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
        sin_angle = np.linalg.norm(np.cross(tangent, a), axis=1)
        if np.any(sin_angle < np.sin(min_angle)):
            i = int(np.argmin(sin_angle))
            raise ValueError(
                f"reference vector {a} is within {np.rad2deg(min_angle):.3g} deg of the "
                f"tangent near u = {grid[i]:.4g}; pass another reference_vector"
            )

    def _factorize(self) -> None:
        linalg = _linalg()
        if self.solver == "lu":
            self._lu = linalg.lu_factor(self.N0)
            return
        lower, upper = self.bandwidths
        ab = to_banded(self.N0, lower, upper, extra_rows=lower)
        lu, piv, info = linalg.lapack.dgbtrf(ab, lower, upper)
        if info != 0:
            raise ValueError(f"collocation matrix is singular (dgbtrf info = {info})")
        self._lu = (lu, piv)

    def solve(self, rhs) -> np.ndarray:
        """Solve ``M_c x = rhs`` with the stored factorization.

        Parameters
        ----------
        rhs : array_like, shape (n,) or (n, m)
            Right-hand side(s), e.g. field values at the collocation points.

        Returns
        -------
        numpy.ndarray, same shape as ``rhs``
            Control coefficients.
        """
        b = np.asarray(rhs, dtype=float)
        if b.shape[:1] != (self.n_ctrl,) or b.ndim > 2:
            raise ValueError(
                f"rhs must have shape ({self.n_ctrl},) or ({self.n_ctrl}, m), got {b.shape}"
            )
        if self.solver == "lu":
            return _linalg().lu_solve(self._lu, b)
        lower, upper = self.bandwidths
        b2 = b.reshape(self.n_ctrl, -1)
        x, info = _linalg().lapack.dgbtrs(self._lu[0], lower, upper, b2, self._lu[1])
        if info != 0:  # pragma: no cover - argument error
            raise ValueError(f"dgbtrs failed (info = {info})")
        return x.reshape(b.shape)

    def point_matrix(self, u) -> np.ndarray:
        """Basis values at arbitrary parameters.

        Parameters
        ----------
        u : float or array_like, shape (m,)
            Parameters in ``[0, 1]`` (e.g. ``1.0`` for the tip).

        Returns
        -------
        numpy.ndarray, shape (m, n_ctrl)
            ``R_j(u_i)``; multiply by control coefficients ``(n_ctrl, k)``.
        """
        return self.curve.basis(u, 0)[0]

    def basis_s(self, u) -> np.ndarray:
        """Basis and its first two arc-length derivatives at arbitrary parameters.

        Parameters
        ----------
        u : float or array_like, shape (m,)
            Parameters in ``[0, 1]``.

        Returns
        -------
        numpy.ndarray, shape (3, m, n_ctrl)
            ``[R_j, dR_j/ds, d2R_j/ds2]`` at ``u``; at ``u_c`` these are
            ``N0, N1, N2``.
        """
        geo = self.curve.evaluate(u, 2)
        _, _, _, jac, jac_u = tangent_derivatives(geo[1], geo[2], np.zeros_like(geo[2]))
        return _arc_length_basis(self.curve.basis(u, 2), jac, jac_u)

    def frame(self, u):
        """Reference frame, curvature and its derivative at arbitrary parameters.

        Uses the same reference vector as the collocation data.

        Parameters
        ----------
        u : float or array_like, shape (m,)
            Parameters in ``[0, 1]``.

        Returns
        -------
        r0 : numpy.ndarray, shape (m, 3, 3)
        k0 : numpy.ndarray, shape (m, 3)
        k0_s : numpy.ndarray, shape (m, 3)
        """
        geo = self.curve.evaluate(u, 3)
        t, t_s, t_ss, _, _ = tangent_derivatives(geo[1], geo[2], geo[3])
        return projection_frame(t, t_s, t_ss, self.reference_vector, self._min_angle)

    def arc_length(self, u) -> np.ndarray:
        """Arc length ``s(u)`` of the reference centreline.

        Parameters
        ----------
        u : float or array_like, shape (m,)
            Parameters in ``[0, 1]``.

        Returns
        -------
        numpy.ndarray, shape (m,)
        """
        return arc_length(self.curve, u, self._n_gauss)
