"""The rotation group SO(3): points ``(..., 3, 3)``, algebra ``(..., 3)``."""

from __future__ import annotations

import numpy as np

from .base import LieGroup
from .so3_coefficients import coeff_D, coefficients


def hat(a: np.ndarray) -> np.ndarray:
    """Skew matrix with ``hat(a) @ h == cross(a, h)``; ``(..., 3) -> (..., 3, 3)``."""
    a = np.asarray(a, dtype=float)
    out = np.zeros(a.shape[:-1] + (3, 3))
    out[..., 0, 1] = -a[..., 2]
    out[..., 0, 2] = a[..., 1]
    out[..., 1, 0] = a[..., 2]
    out[..., 1, 2] = -a[..., 0]
    out[..., 2, 0] = -a[..., 1]
    out[..., 2, 1] = a[..., 0]
    return out


def vee(m: np.ndarray) -> np.ndarray:
    """Axial vector of the skew part of ``m``; ``(..., 3, 3) -> (..., 3)``."""
    m = np.asarray(m, dtype=float)
    return 0.5 * np.stack(
        (m[..., 2, 1] - m[..., 1, 2], m[..., 0, 2] - m[..., 2, 0], m[..., 1, 0] - m[..., 0, 1]),
        axis=-1,
    )


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross product over the last axis, ``(..., 3) x (..., 3) -> (..., 3)``.

    Same result as ``np.cross`` without its axis bookkeeping (faster on small batches).
    """
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = a1 * b2 - a2 * b1
    out[..., 1] = a2 * b0 - a0 * b2
    out[..., 2] = a0 * b1 - a1 * b0
    return out


def angle(xi: np.ndarray) -> np.ndarray:
    """Rotation angle ``|xi|``, shape ``(...)``."""
    return np.sqrt(np.einsum("...i,...i->...", xi, xi))


def exp_so3(xi: np.ndarray) -> np.ndarray:
    """Rodrigues' formula ``I + A hat(xi) + B hat(xi)^2``; ``(..., 3) -> (..., 3, 3)``."""
    xi = np.asarray(xi, dtype=float)
    a, b = coefficients(angle(xi), "AB")
    a, b = a[..., None, None], b[..., None, None]
    X = hat(xi)
    return np.eye(3) + a * X + b * (X @ X)


def rotation_to_quaternion(R: np.ndarray) -> np.ndarray:
    """Unit quaternion ``(w, x, y, z)`` with ``w >= 0`` (Shepperd's method), ``(..., 4)``.

    Picks, per matrix, the largest of ``(trace, R00, R11, R22)`` as pivot, so no
    division by a small number occurs anywhere, including near ``pi``.
    """
    R = np.asarray(R, dtype=float)
    r00, r11, r22 = R[..., 0, 0], R[..., 1, 1], R[..., 2, 2]
    tr = r00 + r11 + r22
    d21, d02, d10 = R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0], R[..., 1, 0] - R[..., 0, 1]
    s01, s02, s12 = R[..., 0, 1] + R[..., 1, 0], R[..., 0, 2] + R[..., 2, 0], R[..., 1, 2] + R[..., 2, 1]
    piv = np.argmax(np.stack((tr, r00, r11, r22), axis=-1), axis=-1)
    # four candidate (unnormalized, scaled by 4*pivot) quaternions
    q0 = np.stack((1.0 + tr, d21, d02, d10), axis=-1)
    q1 = np.stack((d21, 1.0 + r00 - r11 - r22, s01, s02), axis=-1)
    q2 = np.stack((d02, s01, 1.0 - r00 + r11 - r22, s12), axis=-1)
    q3 = np.stack((d10, s02, s12, 1.0 - r00 - r11 + r22), axis=-1)
    cand = np.stack((q0, q1, q2, q3), axis=-2)
    q = np.take_along_axis(cand, piv[..., None, None], axis=-2)[..., 0, :]
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    return np.where(q[..., :1] < 0.0, -q, q)


def log_so3(R: np.ndarray) -> np.ndarray:
    """Principal logarithm, ``|log R| <= pi``; ``(..., 3, 3) -> (..., 3)``.

    Goes through the quaternion ``(w, v)`` of ``R``: ``theta = 2 atan2(|v|, w)``
    and ``log R = theta v / |v|``. Accurate to round-off at small angles and at
    ``pi`` (no division by ``sin(theta)``).
    """
    q = rotation_to_quaternion(R)
    w, v = q[..., 0], q[..., 1:]
    nv = np.linalg.norm(v, axis=-1)
    tiny = nv < 1e-300
    scale = np.where(tiny, 2.0 / np.where(w > 0, w, 1.0), 2.0 * np.arctan2(nv, w) / np.where(tiny, 1.0, nv))
    return scale[..., None] * v


def dexp_so3(xi: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Left Jacobian applied to ``v``: ``v + B xi x v + C xi x (xi x v)``."""
    b, c = coefficients(angle(xi), "BC")
    xv = cross(xi, v)
    return v + b[..., None] * xv + c[..., None] * cross(xi, xv)


def dexpinv_so3(xi: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Inverse left Jacobian applied to ``v``: ``v - xi x v / 2 + D xi x (xi x v)``."""
    t = angle(xi)
    xv = cross(xi, v)
    return v - 0.5 * xv + coeff_D(t)[..., None] * cross(xi, xv)


def left_jacobian(xi: np.ndarray) -> np.ndarray:
    """Matrix ``J_l(xi) = dexp_xi``, shape ``(..., 3, 3)``; ``J_r(xi) = J_l(xi).T``."""
    b, c = coefficients(angle(xi), "BC")
    X = hat(xi)
    return np.eye(3) + b[..., None, None] * X + c[..., None, None] * (X @ X)


def left_jacobian_inv(xi: np.ndarray) -> np.ndarray:
    """Matrix ``J_l(xi)^-1 = dexpinv_xi``, shape ``(..., 3, 3)``."""
    t = angle(xi)
    X = hat(xi)
    return np.eye(3) - 0.5 * X + coeff_D(t)[..., None, None] * (X @ X)


class _SO3(LieGroup):
    """SO(3) with spatial (left) increments ``R <- exp(hat(xi)) R``.

    Points are rotation matrices ``(..., 3, 3)``; algebra elements are axial vectors
    ``(..., 3)`` with ``hat(a) @ h == cross(a, h)``.
    """

    dim = 3
    point_shape = (3, 3)
    act_shape = (3,)
    name = "SO3"

    def identity(self, batch_shape=()):
        return np.broadcast_to(np.eye(3), tuple(batch_shape) + (3, 3)).copy()

    def compose(self, g, h):
        return np.matmul(g, h)

    def inverse(self, g):
        return np.swapaxes(g, -1, -2).copy()

    def exp(self, xi):
        return exp_so3(xi)

    def log(self, g):
        return log_so3(g)

    def hat(self, xi):
        return hat(xi)

    def vee(self, m):
        return vee(m)

    def ad(self, xi):
        return hat(xi)

    def Ad(self, g):
        return np.array(g, dtype=float, copy=True)

    def act(self, g, p):
        return np.einsum("...ij,...j->...i", g, p)

    def normalize(self, g):
        """One Newton-Schulz step toward the nearest rotation (see :meth:`LieGroup.normalize`)."""
        R = np.asarray(g, dtype=float)
        return 0.5 * R @ (3.0 * np.eye(3) - np.swapaxes(R, -1, -2) @ R)

    def dexp(self, xi, v):
        return dexp_so3(xi, v)

    def dexpinv(self, xi, v):
        return dexpinv_so3(xi, v)

    def rotation_angle(self, xi):
        return angle(xi)


SO3 = _SO3()
