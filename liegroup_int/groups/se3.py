"""The rigid-motion group SE(3): points ``(..., 4, 4)``, algebra ``(..., 6)``.

Algebra elements are ordered ``xi = (rho, theta)``: translational part first, then the
rotation vector, so ``exp(xi) = [[exp(hat(theta)), J_l(theta) rho], [0, 1]]``.
"""

from __future__ import annotations

import numpy as np

from .base import LieGroup
from .so3 import angle, dexp_so3, dexpinv_so3, exp_so3, hat, left_jacobian, log_so3
from .so3_coefficients import coeff_C, coeff_E, coeff_F


def _assemble(R: np.ndarray, t: np.ndarray) -> np.ndarray:
    out = np.zeros(R.shape[:-2] + (4, 4))
    out[..., :3, :3] = R
    out[..., :3, 3] = t
    out[..., 3, 3] = 1.0
    return out


def q_block(rho: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Off-diagonal block ``Q(rho, theta)`` of the SE(3) left Jacobian, ``(..., 3, 3)``.

    ``Q = rho^/2 + C (T P + P T + T P T) + E (T T P + P T T - 3 T P T)
    + F (T P T T + T T P T)`` with ``P = hat(rho)``, ``T = hat(theta)`` and the
    coefficients of :mod:`.so3_coefficients` (Barfoot, State Estimation for Robotics,
    eq. 7.86, in the left-trivialized convention of this package).
    """
    t = angle(theta)
    P, T = hat(rho), hat(theta)
    TP, PT = T @ P, P @ T
    TPT = TP @ T
    c = coeff_C(t)[..., None, None]
    e = coeff_E(t)[..., None, None]
    f = coeff_F(t)[..., None, None]
    return 0.5 * P + c * (TP + PT + TPT) + e * (T @ TP + PT @ T - 3.0 * TPT) + f * (TPT @ T + T @ TPT)


class _SE3(LieGroup):
    """SE(3) with left increments ``g <- exp(xi) g``; ``xi = (rho, theta)``."""

    dim = 6
    point_shape = (4, 4)
    act_shape = (3,)
    name = "SE3"

    def identity(self, batch_shape=()):
        return np.broadcast_to(np.eye(4), tuple(batch_shape) + (4, 4)).copy()

    def compose(self, g, h):
        return np.matmul(g, h)

    def inverse(self, g):
        Rt = np.swapaxes(g[..., :3, :3], -1, -2)
        return _assemble(Rt, -np.einsum("...ij,...j->...i", Rt, g[..., :3, 3]))

    def exp(self, xi):
        xi = np.asarray(xi, dtype=float)
        rho, theta = xi[..., :3], xi[..., 3:]
        return _assemble(exp_so3(theta), dexp_so3(theta, rho))

    def log(self, g):
        theta = log_so3(g[..., :3, :3])
        rho = dexpinv_so3(theta, g[..., :3, 3])
        return np.concatenate((rho, theta), axis=-1)

    def hat(self, xi):
        xi = np.asarray(xi, dtype=float)
        out = np.zeros(xi.shape[:-1] + (4, 4))
        out[..., :3, :3] = hat(xi[..., 3:])
        out[..., :3, 3] = xi[..., :3]
        return out

    def vee(self, m):
        from .so3 import vee

        return np.concatenate((m[..., :3, 3], vee(m[..., :3, :3])), axis=-1)

    def ad(self, xi):
        xi = np.asarray(xi, dtype=float)
        out = np.zeros(xi.shape[:-1] + (6, 6))
        T = hat(xi[..., 3:])
        out[..., :3, :3] = T
        out[..., 3:, 3:] = T
        out[..., :3, 3:] = hat(xi[..., :3])
        return out

    def Ad(self, g):
        R, t = g[..., :3, :3], g[..., :3, 3]
        out = np.zeros(g.shape[:-2] + (6, 6))
        out[..., :3, :3] = R
        out[..., 3:, 3:] = R
        out[..., :3, 3:] = hat(t) @ R
        return out

    def act(self, g, p):
        return np.einsum("...ij,...j->...i", g[..., :3, :3], p) + g[..., :3, 3]

    def normalize(self, g):
        """Newton-Schulz step on the rotation block, exact bottom row."""
        from .so3 import SO3

        out = np.array(g, dtype=float, copy=True)
        out[..., :3, :3] = SO3.normalize(out[..., :3, :3])
        out[..., 3, :] = (0.0, 0.0, 0.0, 1.0)
        return out

    def dexp(self, xi, v):
        xi, v = np.asarray(xi, dtype=float), np.asarray(v, dtype=float)
        rho, theta = xi[..., :3], xi[..., 3:]
        top = dexp_so3(theta, v[..., :3]) + np.einsum("...ij,...j->...i", q_block(rho, theta), v[..., 3:])
        return np.concatenate((top, dexp_so3(theta, v[..., 3:])), axis=-1)

    def dexpinv(self, xi, v):
        # [[J, Q], [0, J]]^-1 = [[J^-1, -J^-1 Q J^-1], [0, J^-1]]
        xi, v = np.asarray(xi, dtype=float), np.asarray(v, dtype=float)
        rho, theta = xi[..., :3], xi[..., 3:]
        w = dexpinv_so3(theta, v[..., 3:])
        top = dexpinv_so3(theta, v[..., :3] - np.einsum("...ij,...j->...i", q_block(rho, theta), w))
        return np.concatenate((top, w), axis=-1)

    def magnitude(self, g):
        t = np.abs(g[..., :3, 3])
        return np.concatenate((t, np.ones_like(t)), axis=-1)

    def rotation_angle(self, xi):
        return angle(np.asarray(xi)[..., 3:])


SE3 = _SE3()

__all__ = ["SE3", "q_block", "left_jacobian"]
