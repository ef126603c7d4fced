"""Pointwise beam kinematics as small pure functions over collocation points.

Shapes: ``n`` collocation points; vectors ``(n, 3)``, rotations ``(n, 3, 3)``.
"""

from __future__ import annotations

import numpy as np

from ...groups.so3 import angle, cross
from ...groups.so3_coefficients import coefficients


def rot_T(R: np.ndarray, a: np.ndarray) -> np.ndarray:
    """``R^T a`` pointwise, ``(n, 3, 3), (n, 3) -> (n, 3)``."""
    return np.einsum("nji,nj->ni", R, a)


def rot(R: np.ndarray, a: np.ndarray) -> np.ndarray:
    """``R a`` pointwise."""
    return np.einsum("nij,nj->ni", R, a)


def jr_times(theta: np.ndarray, a: np.ndarray) -> np.ndarray:
    """``J_r(theta) a = a - B theta x a + C theta x (theta x a)``, ``(n, 3)``.

    ``J_r(theta) = J_l(-theta) = dexp_{-theta}``: the right-trivialized derivative of exp,
    ``d/ds exp(hat(theta(s))) = exp(hat(theta)) hat(J_r(theta) theta_s)``.
    """
    B, C = coefficients(angle(theta), "BC")
    ta = cross(theta, a)
    return a - B[:, None] * ta + C[:, None] * cross(theta, ta)


def jr_theta_s_derivative(theta: np.ndarray, theta_s: np.ndarray, theta_ss: np.ndarray) -> np.ndarray:
    """``d/ds [J_r(theta(s)) theta_s(s)]``, shape ``(n, 3)``.

    With ``g = theta_s``, ``tt = theta . theta_s`` and ``B1 = B'/t``, ``C1 = C'/t``::

        theta_ss - B1 tt (theta x g) - B (theta x theta_ss)
                 + C1 tt theta x (theta x g)
                 + C (g x (theta x g) + theta x (theta x theta_ss))

    ``B1`` and ``C1`` use Taylor series below 1 rad (their closed forms lose digits like
    ``eps / t^4`` at small angles).
    """
    return jr_and_derivative(theta, theta_s, theta_ss)[1]


def jr_and_derivative(theta: np.ndarray, theta_s: np.ndarray, theta_ss: np.ndarray):
    """``(J_r(theta) theta_s, d/ds[J_r(theta) theta_s])`` sharing one coefficient pass."""
    B, C, B1, C1 = (x[:, None] for x in coefficients(angle(theta), "BCB1C1"))
    tt = np.einsum("ni,ni->n", theta, theta_s)[:, None]
    tg = cross(theta, theta_s)
    ttg = cross(theta, tg)
    tss = cross(theta, theta_ss)
    g = theta_s - B * tg + C * ttg
    g_s = theta_ss - B1 * tt * tg - B * tss + C1 * tt * ttg + C * (cross(theta_s, tg) + cross(theta, tss))
    return g, g_s


def curvature_update(R: np.ndarray, K: np.ndarray, K_s: np.ndarray, theta: np.ndarray,
                     theta_s: np.ndarray, theta_ss: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Material curvature and its arc-length derivative after ``R' = exp(hat(theta)) R``.

    The update of the material curvature under a left rotation increment (docs/theory.md
    section 6), ``K' = K + R^T J_r(theta) theta_s``, and its derivative along s (eq. 53),
    ``K'_s = K_s - K x (R^T J_r theta_s) + R^T d/ds(J_r theta_s)``
    (using ``dR^T/ds = -hat(K) R^T``).

    Returns
    -------
    K_new, K_s_new : (n, 3)
    """
    g, g_s = jr_and_derivative(theta, theta_s, theta_ss)
    x, x_s = rot_T(R, g), rot_T(R, g_s)
    return K + x, K_s - cross(K, x) + x_s


def strains(R: np.ndarray, c_s: np.ndarray, c_ss: np.ndarray, K: np.ndarray, gamma0: np.ndarray):
    """Translational strain ``Gamma = R^T c_s - Gamma0`` and its derivative along s.

    ``Gamma_s = R^T c_ss - K x (R^T c_s)``, valid when ``Gamma0 = R0^T c0_s`` is constant
    along s (``c0_s = d3``, so ``Gamma0 = e3``).

    Returns
    -------
    Rt_cs, Gamma, Gamma_s : (n, 3)
    """
    Rt_cs = rot_T(R, c_s)
    return Rt_cs, Rt_cs - gamma0, rot_T(R, c_ss) - cross(K, Rt_cs)


def strain_rates(R: np.ndarray, c_s: np.ndarray, v_s: np.ndarray, w: np.ndarray, w_s: np.ndarray):
    """Objective material strain rates ``dGamma/dt = R^T (v_s - omega x c_s)`` and
    ``dK/dt = R^T omega_s`` (spatial ``omega``, ``dR/dt = hat(omega) R``), ``(n, 3)`` each."""
    return rot_T(R, v_s - cross(w, c_s)), rot_T(R, w_s)


def perpendicular_rows(a: np.ndarray) -> np.ndarray:
    """Two orthonormal rows perpendicular to the non-zero vector ``a`` ``(3,)``, ``(2, 3)``
    (completed from the coordinate axis least aligned with ``a``)."""
    a = np.asarray(a, dtype=float) / np.linalg.norm(a)
    e = np.zeros(3)
    e[int(np.argmin(np.abs(a)))] = 1.0
    p = e - (e @ a) * a
    p /= np.linalg.norm(p)
    return np.array([p, np.cross(a, p)])
