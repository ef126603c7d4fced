"""Quadrature space of a beam centreline for the Galerkin (weak) form.

The trial and test functions are the collocation space's basis; the strain energy and the
terms that follow the rotations are sums over the points of a quadrature rule
(:mod:`.quadrature`: by default ``p + 1`` Gauss points per knot interval for bending and
``p`` for the axial and shear terms). The consistent mass matrix is integrated exactly
(``p + 1`` Gauss points per interval), whatever the rule.

Fields that are not splines (rotations, curvatures) live at the *points* of this space:
the points of the rule, sorted along the beam, plus the two ends unless the rule has a
point there (weight 0; they carry the end sections' rotations for end loads, reactions
and output).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .bspline import band_widths
from .collocation import CollocationSpace
from .quadrature import determines_basis, exact_mass_rule, gauss_points, gram, patch_rule

__all__ = ["GalerkinSpace", "BandedSPD", "StrainJacobian", "gauss_points", "reference_strain_jacobian"]


def _frozen(a: np.ndarray) -> np.ndarray:
    a = np.ascontiguousarray(a)
    a.setflags(write=False)
    return a


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


def _patch_points(space: CollocationSpace, rule: str) -> dict:
    """Points, weights, basis and reference frames of one patch (local parameter)."""
    r = patch_rule(space, rule)
    ends = np.array([x for x in (0.0, 1.0) if not np.any(r.u == x)])
    u = np.concatenate([r.u, ends])
    wb = np.concatenate([r.w_bending, np.zeros(ends.size)])
    wa = np.concatenate([r.w_axial, np.zeros(ends.size)])
    order = np.argsort(u, kind="stable")
    u, wb, wa = u[order], wb[order], wa[order]
    basis = space.basis_s(u)
    R0, K0, _ = space.frame(u)
    c_u = space.curve.evaluate(u, 1)[1]
    t = c_u / np.linalg.norm(c_u, axis=1)[:, None]
    um, wm = exact_mass_rule(space)
    return {"rule": r.name, "u": u, "B0": basis[0], "B1": basis[1], "w_full": wb, "w_axial": wa, "R0": R0, "K0": K0,
            "gamma0": np.einsum("nji,nj->ni", R0, t), "s": space.arc_length(u),
            "mass_basis": space.basis_s(um)[0], "mass_weights": wm}


def _block_diag(blocks) -> np.ndarray:
    rows, cols = sum(b.shape[0] for b in blocks), sum(b.shape[1] for b in blocks)
    out = np.zeros((rows, cols))
    i = j = 0
    for b in blocks:
        out[i:i + b.shape[0], j:j + b.shape[1]] = b
        i, j = i + b.shape[0], j + b.shape[1]
    return out


class GalerkinSpace:
    """Quadrature points, weights and basis matrices of a collocation space's basis.

    Parameters
    ----------
    space : CollocationSpace or PatchedSpace
        Basis and reference geometry; a :class:`~liegroup_int.iga.patches.PatchedSpace`
        (a chain of members) gives each patch its own points, in chain order, with the
        global parameter and arc length of the chain.
    rule : str
        Quadrature rule of the stiffness, a key of :data:`~liegroup_int.iga.quadrature.RULES`
        (``"gauss"``: ``p + 1`` Gauss points per interval for bending, ``p`` for the axial
        and shear terms).

    Attributes
    ----------
    u : numpy.ndarray, shape (m,)
        Parameters of the points (sorted; each patch starts and ends with a point at its end).
    s : numpy.ndarray, shape (m,)
        Their reference arc length.
    B0, B1 : numpy.ndarray, shape (m, n)
        Basis values and arc-length derivatives there (block-diagonal over patches).
    w_full, w_axial : numpy.ndarray, shape (m,)
        Arc-length weights of the bending terms (bending, gyroscopic and distributed loads,
        projections) and of the axial and shear terms; zero at points outside that set.
    R0 : numpy.ndarray, shape (m, 3, 3)
        Reference material frames; ``K0`` ``(m, 3)`` their curvature, and ``gamma0``
        ``(m, 3)`` = ``R0^T c0_s`` (``e3``).
    point_patch : numpy.ndarray of int, shape (m,)
        Patch of each point.
    patch_ends : tuple of (int, int)
        First and last point of each patch.
    mass : numpy.ndarray, shape (n, n)
        ``M_ij = int N_i N_j ds`` (exact rule, whatever ``rule``), banded with half-bandwidth ``p``.
    point_mass : numpy.ndarray, shape (n, n)
        ``sum_k w_k N_i(u_k) N_j(u_k)`` with the bending weights: the matrix of
        :meth:`project` (the rotation increment's projection); positive definite (checked).
    """

    def __init__(self, space, rule: str = "gauss"):
        self.space = space
        self.rule = rule
        patches = getattr(space, "patches", None)
        if patches is None:
            parts = [_patch_points(space, rule)]
        else:
            parts = [_patch_points(sp, rule) for sp in patches]
            edges = np.asarray(space._u_edges, dtype=float)
            s_edges = np.concatenate([[0.0], np.cumsum([sp.length for sp in patches])])
            for k, d in enumerate(parts):
                d["u"] = edges[k] + (edges[k + 1] - edges[k]) * d["u"]
                d["s"] = s_edges[k] + d["s"]
        cat = {k: np.concatenate([d[k] for d in parts]) for k in ("u", "w_full", "w_axial", "R0", "K0", "gamma0", "s")}
        #: the rule each patch used (``"auto"`` resolved)
        self.rules_used = tuple(d["rule"] for d in parts)
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
        self._mass_rule = tuple((d["mass_basis"], d["mass_weights"]) for d in parts)
        self.mass = _frozen(self.weighted_mass(np.ones(self.m)))
        self.point_mass = _frozen(gram(self.B0, self.w_full))
        _check_definite(self.point_mass, rule)

    def weighted_mass(self, density: np.ndarray) -> np.ndarray:
        """``int rho N_i N_j ds`` (exact rule) with ``rho`` given at the points, one value
        per patch, ``(n, n)``."""
        density = np.asarray(density, dtype=float)
        blocks = []
        for k, (a, b) in enumerate(self.patch_ends):
            rho = density[a]
            if np.any(density[a:b + 1] != rho):
                raise ValueError(f"density: expected one value per patch, patch {k} has several")
            Bm, wm = self._mass_rule[k]
            blocks.append(gram(Bm, rho * wm))
        return _block_diag(blocks)

    def project(self, values: np.ndarray) -> np.ndarray:
        """Projection onto the basis of values at the points (the rule's discrete L2
        product), ``(m, k) -> (n, k)``."""
        import scipy.linalg

        return scipy.linalg.solve(self.point_mass, self.B0.T @ (self.w_full[:, None] * values), assume_a="pos")


class StrainJacobian(NamedTuple):
    """Linearized strains at the points about the reference state, per unit control value
    of the position increment ``eta`` and the rotation increment ``Theta``.

    Attributes
    ----------
    gamma, kappa : numpy.ndarray, shape (m, 3, 2, n, 3)
        ``d Gamma_k[a] / d x[b, i, d]`` and ``d K_k[a] / d x[b, i, d]`` with ``b = 0`` for
        ``eta`` and ``b = 1`` for ``Theta`` (material strains, ``R = R0 exp(hat(B0 Theta))``).
    """

    gamma: np.ndarray
    kappa: np.ndarray


def reference_strain_jacobian(gs: "GalerkinSpace") -> StrainJacobian:
    """:class:`StrainJacobian` of ``gs``: ``dGamma = R0^T B1 eta + Gamma0 x B0 Theta`` and
    ``dK = B1 Theta + K0 x B0 Theta`` (the Hessian of a quadrature strain energy at rest
    is ``J^T diag(w C) J``)."""
    m, n = gs.B0.shape
    eye = np.eye(3)
    g = np.zeros((m, 3, 2, n, 3))
    k = np.zeros((m, 3, 2, n, 3))
    g[:, :, 0] = np.einsum("kda,ki->kaid", gs.R0, gs.B1)
    g[:, :, 1] = np.einsum("kda,ki->kaid", np.cross(gs.gamma0[:, None, :], eye[None]), gs.B0)
    k[:, :, 1] = (np.einsum("da,ki->kaid", eye, gs.B1)
                  + np.einsum("kda,ki->kaid", np.cross(gs.K0[:, None, :], eye[None]), gs.B0))
    return StrainJacobian(g, k)


def _check_definite(A: np.ndarray, rule: str) -> None:
    """One-line error if the rule's point mass is not positive definite (too few points
    to determine a spline of the basis)."""
    if not determines_basis(A):
        raise ValueError(f"quadrature rule {rule!r}: its points do not determine the basis "
                         f"(point mass not positive definite); choose a rule with more points")
