"""Pointwise beam physics, written once and called by every formulation's kernels.

Vectors are 3-tuples (:mod:`.vec3`); material quantities are capitalized (``Gamma``, ``K``,
``Omega``, ``N``, ``M``), spatial ones not (``c_s``, ``v``, ``w``, ``n``, ``m``). The NumPy
twins are :mod:`..kinematics` and the NumPy paths of the formulations. The helpers are
plain compiled functions that LLVM inlines into the kernels (as those of :mod:`.vec3`).
"""

from __future__ import annotations

from numba import njit

from .vec3 import add, axpy, cross, dot, mul, rot, scale, sub, wdot

# ---------------------------------------------------------------- SO(3) maps of an angle vector
@njit(cache=True)
def exp_rows(cA, cB, t):
    """``exp(hat(t)) = I + A T + B T T`` as its 9 entries row by row."""
    x, y, z = t
    return (1.0 + cB * (-z * z - y * y), cA * -z + cB * (x * y), cA * y + cB * (x * z),
            cA * z + cB * (x * y), 1.0 + cB * (-z * z - x * x), cA * -x + cB * (y * z),
            cA * -y + cB * (x * z), cA * x + cB * (y * z), 1.0 + cB * (-y * y - x * x))


@njit(cache=True)
def rows_T_times(E, a):
    """``E^T a`` for ``E`` given row by row (:func:`exp_rows`)."""
    return (E[0] * a[0] + E[3] * a[1] + E[6] * a[2], E[1] * a[0] + E[4] * a[1] + E[7] * a[2],
            E[2] * a[0] + E[5] * a[1] + E[8] * a[2])


@njit(cache=True)
def jr_times(cB, cC, t, a):
    """``J_r(t) a = a - B t x a + C t x (t x a)`` (``J_r(t) = dexp_{-t}``)."""
    ta = cross(t, a)
    return add(sub(a, scale(cB, ta)), scale(cC, cross(t, ta)))


@njit(cache=True)
def jr_times_s(cB, cC, cB1, cC1, t, ts, tss):
    """``d/ds [J_r(t(s)) t_s(s)]`` (:func:`..kinematics.jr_theta_s_derivative`), with
    ``B1 = B'/|t|``, ``C1 = C'/|t|``."""
    tt = dot(t, ts)
    tg = cross(t, ts)
    ttg = cross(t, tg)
    tq = cross(t, tss)
    h = add(cross(ts, tg), cross(t, tq))
    return add(sub(sub(tss, scale(cB1 * tt, tg)), scale(cB, tq)), add(scale(cC1 * tt, ttg), scale(cC, h)))


@njit(cache=True)
def dexpinv(cD, t, v):
    """``dexpinv_t(v) = v - t x v / 2 + D t x (t x v)`` (``dexpinv_{-t}``: pass ``-t``)."""
    tv = cross(t, v)
    return add(sub(v, scale(0.5, tv)), scale(cD, cross(t, tv)))


# ---------------------------------------------------------------- strains and resultants
@njit(cache=True)
def strain(Gt, ref):
    """``Gamma = R^T c_s - Gamma0`` from ``Gt = R^T c_s`` (also ``K - K0``)."""
    return sub(Gt, ref)


@njit(cache=True)
def gamma_rate(RTv_s, Omega, Gt):
    """Objective material rate ``dGamma/dt = R^T v_s - Omega x (R^T c_s)`` (``= R^T (v_s -
    w x c_s)``)."""
    return sub(RTv_s, cross(Omega, Gt))


@njit(cache=True)
def curvature_rate(Omega_s, K, Omega):
    """``dK/dt = Omega_s + K x Omega`` (``= R^T w_s``)."""
    return add(Omega_s, cross(K, Omega))


@njit(cache=True)
def resultant(C, strain_value, tau, rate):
    """Material resultant ``C (strain + tau rate)`` (Kelvin-Voigt with retardation time
    ``tau``; pass ``tau = 0`` without damping)."""
    return mul(C, axpy(tau, rate, strain_value))


@njit(cache=True)
def gyroscopic(Omega, J):
    """``Omega x (J Omega)``."""
    return cross(Omega, mul(J, Omega))


# ---------------------------------------------------------------- loads and power
@njit(cache=True)
def point_load(R, i, a, follower):
    """A spatial end load: dead (``a``) or turned by the end rotation (``R[i] a``)."""
    return rot(R, i, a) if follower else a


@njit(cache=True)
def load_power(f, v, m, w):
    """Power ``f . v + m . w`` of a force and a couple."""
    return dot(f, v) + dot(m, w)


@njit(cache=True)
def dissipation(tau, C, rate):
    """Viscous dissipation ``tau rate . C rate`` of one strain, per length."""
    return tau * wdot(C, rate)
