"""Quadrature space of a beam centreline for the Galerkin (weak) form.

The trial and test functions are the collocation space's basis; integrals are sums over
Gauss points, ``p + 1`` per knot interval (exact for the mass matrix of a straight beam).
With ``reduced = True`` the axial and shear terms use ``p`` points per interval instead
(reduced integration against shear and membrane locking).

Fields that are not splines (rotations, curvatures) live at the *points* of this space:
the Gauss points of both rules, sorted along the beam, plus the two ends (weight 0;
they carry the end sections' rotations for end loads, reactions and output).
"""

from __future__ import annotations

import numpy as np

from .bspline import band_widths
from .collocation import CollocationSpace

__all__ = ["GalerkinSpace", "BandedSPD", "gauss_points"]


def _frozen(a: np.ndarray) -> np.ndarray:
    a = np.ascontiguousarray(a)
    a.setflags(write=False)
    return a


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


class BandedSPD:
    """A symmetric positive definite banded matrix with some unknowns prescribed,
    Cholesky-factored once (LAPACK ``pbtrf``).

    ``solve(rhs, fixed_values)`` returns ``x`` with ``x[fixed] = fixed_values`` and the other
    rows solving ``(A x)[free] = rhs[free]``.

    Parameters
    ----------
    A : numpy.ndarray, shape (n, n)
    fixed : numpy.ndarray of bool, shape (n,)
    """

    def __init__(self, A: np.ndarray, fixed: np.ndarray):
        import scipy.linalg

        A = np.asarray(A, dtype=float)
        self.n = A.shape[0]
        self.fixed = _frozen(np.asarray(fixed, dtype=bool))
        self.coupling = _frozen(A[:, self.fixed])  # columns of the prescribed unknowns
        Am = A.copy()
        Am[self.fixed, :] = 0.0
        Am[:, self.fixed] = 0.0
        Am[self.fixed, self.fixed] = 1.0
        lower, _ = band_widths(Am)
        self.bandwidth = int(lower)
        ab = np.zeros((lower + 1, self.n))  # upper form: ab[lower + i - j, j] = A[i, j], i <= j
        for d in range(lower + 1):
            ab[lower - d, d:] = np.diagonal(Am, d)
        self.factor = _frozen(scipy.linalg.cholesky_banded(ab, lower=False))
        self._solve = scipy.linalg.cho_solve_banded

    def solve(self, rhs: np.ndarray, fixed_values=0.0) -> np.ndarray:
        """``x`` of shape ``rhs.shape`` (``(n,)`` or ``(n, m)``)."""
        b = np.array(rhs, dtype=float, copy=True)
        if np.any(self.fixed):
            xd = np.broadcast_to(np.asarray(fixed_values, dtype=float), b[self.fixed].shape)
            if np.any(xd):
                b -= self.coupling @ xd
            b[self.fixed] = xd
        return self._solve((self.factor, False), b, check_finite=False)


def _patch_points(space: CollocationSpace, reduced: bool) -> dict:
    """Points, weights, basis and reference frames of one patch (local parameter)."""
    p = space.degree
    knots = space.curve.knots
    uf, wf = gauss_points(knots, p + 1)
    parts = [(uf, wf, np.zeros_like(wf))]
    if reduced:
        ur, wr = gauss_points(knots, p)
        parts.append((ur, np.zeros_like(wr), wr))
    parts.append((np.array([0.0, 1.0]), np.zeros(2), np.zeros(2)))
    u = np.concatenate([x[0] for x in parts])
    wb = np.concatenate([x[1] for x in parts])
    wa = np.concatenate([x[2] for x in parts])
    order = np.argsort(u, kind="stable")
    u, wb, wa = u[order], wb[order], wa[order]
    basis = space.basis_s(u)
    jac = np.linalg.norm(space.curve.evaluate(u, 1)[1], axis=1)
    R0, K0, _ = space.frame(u)
    t = space.curve.evaluate(u, 1)[1] / jac[:, None]
    return {"u": u, "B0": basis[0], "B1": basis[1], "w_full": wb * jac,
            "w_axial": (wa if reduced else wb) * jac, "R0": R0, "K0": K0,
            "gamma0": np.einsum("nji,nj->ni", R0, t), "s": space.arc_length(u)}


def _block_diag(blocks) -> np.ndarray:
    rows, cols = sum(b.shape[0] for b in blocks), sum(b.shape[1] for b in blocks)
    out = np.zeros((rows, cols))
    i = j = 0
    for b in blocks:
        out[i:i + b.shape[0], j:j + b.shape[1]] = b
        i, j = i + b.shape[0], j + b.shape[1]
    return out


class GalerkinSpace:
    """Gauss points, weights and basis matrices of a collocation space's basis.

    Parameters
    ----------
    space : CollocationSpace or PatchedSpace
        Basis and reference geometry; a :class:`~liegroup_int.iga.patches.PatchedSpace`
        (a chain of members) gives each patch its own points, in chain order, with the
        global parameter and arc length of the chain.
    reduced : bool
        ``p`` Gauss points per interval for the axial and shear terms (else ``p + 1``).

    Attributes
    ----------
    u : numpy.ndarray, shape (m,)
        Parameters of the points (sorted; each patch starts and ends with a point of weight 0).
    s : numpy.ndarray, shape (m,)
        Their reference arc length.
    B0, B1 : numpy.ndarray, shape (m, n)
        Basis values and arc-length derivatives there (block-diagonal over patches).
    w_full, w_axial : numpy.ndarray, shape (m,)
        Arc-length weights of the full rule (bending, inertia, loads) and of the axial and
        shear terms (the full or the reduced rule); zero at the other points.
    R0 : numpy.ndarray, shape (m, 3, 3)
        Reference material frames; ``K0`` ``(m, 3)`` their curvature, and ``gamma0``
        ``(m, 3)`` = ``R0^T c0_s`` (``e3``).
    point_patch : numpy.ndarray of int, shape (m,)
        Patch of each point.
    patch_ends : tuple of (int, int)
        First and last point of each patch.
    mass : numpy.ndarray, shape (n, n)
        ``M_ij = int N_i N_j ds`` (full rule), banded with half-bandwidth ``p``.
    """

    def __init__(self, space, reduced: bool = False):
        self.space = space
        self.reduced = bool(reduced)
        patches = getattr(space, "patches", None)
        if patches is None:
            parts = [_patch_points(space, self.reduced)]
        else:
            parts = [_patch_points(sp, self.reduced) for sp in patches]
            edges = np.asarray(space._u_edges, dtype=float)
            s_edges = np.concatenate([[0.0], np.cumsum([sp.length for sp in patches])])
            for k, d in enumerate(parts):
                d["u"] = edges[k] + (edges[k + 1] - edges[k]) * d["u"]
                d["s"] = s_edges[k] + d["s"]
        cat = {k: np.concatenate([d[k] for d in parts]) for k in ("u", "w_full", "w_axial", "R0", "K0", "gamma0", "s")}
        self.u = _frozen(cat["u"])
        self.B0 = _frozen(_block_diag([d["B0"] for d in parts]))
        self.B1 = _frozen(_block_diag([d["B1"] for d in parts]))
        self.w_full = _frozen(cat["w_full"])
        self.w_axial = _frozen(cat["w_axial"])
        self.R0 = _frozen(cat["R0"])
        self.K0 = _frozen(cat["K0"])
        self.gamma0 = _frozen(cat["gamma0"])
        self.s = _frozen(cat["s"])
        sizes = [d["u"].size for d in parts]
        self.point_patch = _frozen(np.repeat(np.arange(len(parts)), sizes))
        first = np.concatenate([[0], np.cumsum(sizes)[:-1]])
        self.patch_ends = tuple((int(a), int(a + m - 1)) for a, m in zip(first, sizes))
        self.m = self.u.size
        self.n = space.n_ctrl
        self.mass = _frozen(self.weighted_mass(np.ones(self.m)))

    def weighted_mass(self, density: np.ndarray) -> np.ndarray:
        """``int rho N_i N_j ds`` with ``rho`` given at the points, ``(n, n)``."""
        return (self.B0 * (self.w_full * density)[:, None]).T @ self.B0

    def project(self, values: np.ndarray) -> np.ndarray:
        """L2 projection onto the basis of values at the points, ``(m, k) -> (n, k)``."""
        import scipy.linalg

        return scipy.linalg.solve(self.mass, self.B0.T @ (self.w_full[:, None] * values), assume_a="pos")
