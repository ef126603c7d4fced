"""Gaussian quadrature for spline spaces: the fewest points that integrate a spline space
exactly.

A spline space ``S`` of degree ``q`` and even dimension ``D`` on ``[0, 1]`` has a quadrature
rule with ``D / 2`` points and positive weights that integrates every function of ``S``
exactly (Micchelli and Pinkus; the generalized Gauss rules of Hughes, Reali and Sangalli,
CMAME 199, 2010; Bartoň and Calo, CMAME 305, 2016). Its nodes and weights solve the moment
equations

    sum_k w_k B_i(x_k) = int_0^1 B_i du = (t_{i+q+1} - t_i) / (q + 1),   i = 1..D,

``2 (D / 2)`` unknowns for ``D`` equations, solved here by a bounded Gauss-Newton
(trust-region) iteration from the Greville abscissae taken in pairs. A space of odd dimension
is enlarged by one knot in its middle interval first.

For the Galerkin beam the space is the one of the products ``N_i' N_j`` of the beam's basis
(degree ``2p - 1``, continuity one less than the beam's at each knot): the rule integrates the
stiffness of a straight beam at rest exactly, like ``p`` Gauss points per knot interval, with
about ``(p + 1) / 2`` points per interval instead of ``p``. The space of the products
``N_i' N_j'`` (degree ``2p - 2``, the bending stiffness) has about ``p`` functions per
interval, so its rule has about ``p / 2`` points per interval.
"""

from __future__ import annotations

import numpy as np

from .bspline import basis_derivatives_local
from .knots import greville

__all__ = ["SplineQuadratureError", "gaussian_spline_rule", "product_knots"]

#: Largest relative moment error of an accepted rule (the iteration's round-off floor
#: is about 1e-12 at 10^4 moments).
MOMENT_TOL = 1e-10
#: Largest space dimension for the trust-region fallback (seconds beyond).
LSQ_MAX_DIM = 200


class SplineQuadratureError(ValueError):
    """The moment equations of a spline space were not solved (the iteration stalled)."""


def product_knots(knots, degree: int, both_derivatives: bool = False) -> np.ndarray:
    """Knot vector of the space of products ``N_i' N_j`` of a degree-``p`` basis (degree
    ``2p - 1``), or of ``N_i' N_j'`` with ``both_derivatives`` (degree ``2p - 2``): continuity
    ``p - r - 1`` at a knot of multiplicity ``r``.

    Parameters
    ----------
    knots : array_like, shape (n_ctrl + p + 1,)
        Open knot vector on ``[0, 1]``.
    degree : int
        ``p``.
    both_derivatives : bool
        The products of two derivatives (one degree lower).

    Returns
    -------
    numpy.ndarray
        Open knot vector of degree ``2 p - 1`` (``2 p - 2``).

    Raises
    ------
    SplineQuadratureError
        At an interior knot of multiplicity ``p`` (products discontinuous there).
    """
    p = int(degree)
    q = 2 * p - 2 if both_derivatives else 2 * p - 1
    kv, mult = np.unique(np.asarray(knots, dtype=float), return_counts=True)
    if np.any(mult[1:-1] >= p):
        raise SplineQuadratureError(f"a knot of multiplicity {p} (a C0 joint of the degree-{p} basis) splits the "
                                    "product space; one patch per C0 span is not supported")
    inner = [np.full(q - (p - r - 1), x) for x, r in zip(kv[1:-1], mult[1:-1])]
    return np.concatenate([np.zeros(q + 1), *inner, np.ones(q + 1)])


def _design(T: np.ndarray, q: int, x: np.ndarray, nder: int) -> list:
    """Sparse ``(D, m)`` matrices of ``d^k B_i / du^k (x_j)``, ``k = 0..nder``."""
    import scipy.sparse as sp

    spans, ders = basis_derivatives_local(T, q, np.clip(x, 0.0, 1.0), nder)
    D = T.size - q - 1
    rows = (spans[:, None] - q + np.arange(q + 1)).ravel()
    cols = np.repeat(np.arange(x.size), q + 1)
    return [sp.csr_matrix((ders[k].ravel(), (rows, cols)), shape=(D, x.size)) for k in range(nder + 1)]


def _even(T: np.ndarray, q: int) -> np.ndarray:
    """``T``, with one knot added in the middle of its middle interval if the space's
    dimension is odd."""
    if (T.size - q - 1) % 2 == 0:
        return T
    kv = np.unique(T)
    k = (kv.size - 1) // 2
    return np.sort(np.append(T, 0.5 * (kv[k] + kv[k + 1])))


def _moments(T: np.ndarray, q: int) -> np.ndarray:
    """``int_0^1 B_i du`` of every B-spline of ``T``."""
    D = T.size - q - 1
    return (T[q + 1:] - T[:D]) / (q + 1)


def _greville_start(T: np.ndarray, q: int, I: np.ndarray) -> np.ndarray:
    """Start ``(x, w)``: the Greville abscissae in pairs, the pair's integrals."""
    g = greville(T, q)
    return np.concatenate([0.5 * (g[0::2] + g[1::2]), I[0::2] + I[1::2]])


def _gauss_start(T: np.ndarray, q: int, I: np.ndarray) -> np.ndarray:
    """Start ``(x, w)``: Gauss-Legendre nodes in every knot interval, as many as half the
    basis functions' mass there (cumulative rounding to ``D / 2`` in all)."""
    m = I.size // 2
    kv = np.unique(T)
    a, b = kv[:-1, None], kv[1:, None]
    xs, ws = np.polynomial.legendre.leggauss(q + 1)
    B = _design(T, q, (0.5 * (b - a) * xs + 0.5 * (a + b)).ravel(), 0)[0]
    mass = np.asarray(B.multiply(1.0 / I[:, None]).sum(axis=0)).ravel() * (0.5 * (b - a) * ws).ravel()
    share = mass.reshape(kv.size - 1, q + 1).sum(axis=1)
    counts = np.diff(np.r_[0, np.round(np.cumsum(share) * m / share.sum()).astype(int)])
    nodes = [np.polynomial.legendre.leggauss(c) for c in counts if c]
    lo, hi = a[counts > 0], b[counts > 0]
    x = [0.5 * (h - l) * gx + 0.5 * (l + h) for (gx, _), l, h in zip(nodes, lo, hi)]
    w = [0.5 * (h - l) * gw for (_, gw), l, h in zip(nodes, lo, hi)]
    return np.concatenate(x + w)


def _residual(T, q, I, z) -> np.ndarray:
    """Relative moment errors ``sum_k w_k B_i(x_k) / I_i - 1`` of ``z = (x, w)``."""
    m = I.size // 2
    return _design(T, q, z[:m], 0)[0] @ z[m:] / I - 1.0


def _jacobian(T, q, I, z):
    """Sparse ``(D, 2 m)`` derivative of :func:`_residual` by ``(x, w)``."""
    import scipy.sparse as sp

    m = I.size // 2
    B, dB = _design(T, q, z[:m], 1)
    return sp.hstack([dB @ sp.diags(z[m:]), B]).multiply(1.0 / I[:, None])


def _newton(T, q, I, z, max_iter=40):
    """Damped Newton on the moment equations from ``z = (x, w)``: each step halved until
    the nodes stay ordered in ``[0, 1]``, the weights positive and the residual falls.
    Returns the last iterate and its relative moment error."""
    from scipy.sparse.linalg import splu

    m = I.size // 2
    r = _residual(T, q, I, z)
    err = np.abs(r).max()
    for _ in range(max_iter):
        if err <= 1e-13:
            break
        try:
            dz = splu(_jacobian(T, q, I, z).tocsc()).solve(-r)
        except RuntimeError:  # singular Jacobian
            break
        for lam in 0.5 ** np.arange(30):
            zn = z + lam * dz
            x, w = zn[:m], zn[m:]
            if x[0] >= 0.0 and x[-1] <= 1.0 and np.all(np.diff(x) > 0.0) and np.all(w > 0.0):
                rn = _residual(T, q, I, zn)
                en = np.abs(rn).max()
                if en < err:
                    r, z, err = rn, zn, en
                    break
        else:
            break
    return z, err


def _least_squares(T, q, I, z):
    """Bounded trust-region Gauss-Newton from ``z`` (slower, wider basin than
    :func:`_newton`); returns the iterate and its relative moment error."""
    from scipy.optimize import least_squares

    m = I.size // 2
    lo, hi = np.zeros(2 * m), np.r_[np.ones(m), np.full(m, np.inf)]
    sol = least_squares(lambda z: _residual(T, q, I, z), np.clip(z, lo, hi),
                        jac=lambda z: _jacobian(T, q, I, z).tocsr(), bounds=(lo, hi), method="trf",
                        tr_solver="lsmr", xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=100)
    return sol.x, float(np.abs(_residual(T, q, I, sol.x)).max())


def gaussian_spline_rule(T, q: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes and weights of the Gaussian rule of the degree-``q`` spline space on ``T``.

    Damped Newton from the Greville abscissae taken in pairs, then from Gauss nodes spread
    as the basis functions' mass; for a small space (``D <= LSQ_MAX_DIM``) a bounded
    trust-region least-squares solve last. For the Galerkin beam's product space: found
    for p = 2..6 on every mesh tried, on most at p = 7 and 9, not at p = 8 and 10.

    Parameters
    ----------
    T : array_like
        Open knot vector on ``[0, 1]``.
    q : int
        Degree.

    Returns
    -------
    x, w : numpy.ndarray, shape (ceil(D / 2),)
        Increasing nodes in ``[0, 1]`` and positive weights (parameter space).

    Raises
    ------
    SplineQuadratureError
        When both end with a relative moment error above :data:`MOMENT_TOL`, nodes out of
        order or a non-positive weight.
    """
    T = _even(np.asarray(T, dtype=float), int(q))
    I = _moments(T, q)
    m = I.size // 2
    z0 = _greville_start(T, q, I)
    z, err = _newton(T, q, I, z0)
    if err > MOMENT_TOL:
        z, err = _newton(T, q, I, _gauss_start(T, q, I))
    if err > MOMENT_TOL and I.size <= LSQ_MAX_DIM:
        z, err = _least_squares(T, q, I, z0)
    x, w = z[:m], z[m:]
    if not (err <= MOMENT_TOL and np.all(np.diff(x) > 0.0) and np.all(w > 0.0)):
        raise SplineQuadratureError(f"Gaussian spline rule of degree {q} with {m} nodes not found "
                                    f"(relative moment error {err:.1e})")
    return x, w
