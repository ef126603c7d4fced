"""The Galerkin beam linearized at its reference state: strain-energy Hessian and natural
frequencies, for any quadrature rule of the stiffness.

The Hessian of the quadrature strain energy over the ``(eta, Theta)`` control values is
``S^T S`` with ``S = sqrt(w C) J`` (``J`` the linearized strains at the points,
:func:`~liegroup_int.iga.galerkin.reference_strain_jacobian`). A free beam has six
rigid motions in its null space; any further null vector is a zero-energy (hourglass)
mode of the rule.
"""

from __future__ import annotations

import numpy as np

from ...iga.galerkin import reference_strain_jacobian

__all__ = ["distinct_frequencies", "energy_nullity", "natural_frequencies", "strain_operator"]


def strain_operator(pb) -> np.ndarray:
    """``S``, ``(6 m, 6 n)``: ``S^T S`` is the Hessian of the strain energy of the
    :class:`~.galerkin.GalerkinBeamProblem` ``pb`` at its reference state, columns
    ordered ``(eta | Theta, control value, component)``."""
    J = reference_strain_jacobian(pb.gs)
    m, n = pb.m, pb.n
    sg = np.sqrt(pb.wa[:, None] * pb.CN)[:, :, None, None, None] * J.gamma
    sk = np.sqrt(pb.wf[:, None] * pb.CM)[:, :, None, None, None] * J.kappa
    return np.concatenate([sg.reshape(3 * m, 6 * n), sk.reshape(3 * m, 6 * n)])


def energy_nullity(pb, tol: float = 1e-10) -> tuple[int, float]:
    """Null-space dimension of the strain-energy Hessian over all control values (no
    supports) and the smallest nonzero singular value of ``S`` over the largest; rotation
    columns are scaled by the length. ``tol``: singular values below ``tol`` times the
    largest count as zero."""
    S = strain_operator(pb)
    S[:, 3 * pb.n:] /= pb.space.length
    sv = np.linalg.svd(S, compute_uv=False)
    null = int(np.sum(sv < tol * sv[0]))
    return null, float(sv[-null - 1] / sv[0])


def natural_frequencies(pb, rotary_inertia_scale: float = 1.0) -> np.ndarray:
    """Natural frequencies [rad/s] of ``pb`` linearized at rest, ascending:
    ``K x = omega^2 M x`` with the consistent masses (``mu M`` for ``eta``, ``J_d M`` for
    ``Theta_d``) and the supported rows removed. ``rotary_inertia_scale`` multiplies the
    bending rotary inertia ``J_1, J_2`` (as
    :meth:`~.model.SectionConstants.with_rotary_inertia_scale` does)."""
    import scipy.linalg

    gs, n = pb.gs, pb.n
    S = strain_operator(pb)
    M = np.zeros((6 * n, 6 * n))
    M[:3 * n, :3 * n] = np.kron(gs.weighted_mass(pb.mu), np.eye(3))
    for d in range(3):
        scale = rotary_inertia_scale if d < 2 else 1.0
        M[3 * n:, 3 * n:] += np.kron(gs.weighted_mass(scale * pb.Jm[:, d]), np.diag(np.eye(3)[d]))
    free = ~np.concatenate([np.repeat(pb.fix_position, 3), np.repeat(pb.fix_rotation, 3)])
    K = (S.T @ S)[np.ix_(free, free)]
    w2 = scipy.linalg.eigh(K, M[np.ix_(free, free)], eigvals_only=True)
    return np.sqrt(np.clip(w2, 0.0, None))


def distinct_frequencies(w: np.ndarray, k: int) -> np.ndarray:
    """The ``k`` smallest distinct frequencies above 1 rad/s of ``w`` (pairs of equal bending
    frequencies of a symmetric section counted once: relative gap above 1e-6)."""
    w = np.sort(w[w > 1.0])
    out = [w[0]]
    for x in w[1:]:
        if x > out[-1] * (1 + 1e-6):
            out.append(x)
    return np.array(out[:k])
