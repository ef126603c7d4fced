"""Compiled (numba) kernels of the Galerkin beam: ``GalerkinBeamProblem(..., backend="numba")``.

Same mathematics as the NumPy path of :mod:`.galerkin`, one loop over the points per call:

* :func:`galerkin_action`: ``Theta, Theta_s`` at every point from the control values
  (basis windows ``B0, B1`` of width ``p + 1``), ``R <- R exp(hat(Theta))``,
  ``K <- exp(-Theta) K + J_r(Theta) Theta_s``; ``c, v, w`` plus their increments.
* :func:`galerkin_rates`: strains, resultants, the weak-form forces and the projected
  ``dexpinv`` scattered onto the control values in the same loop, end loads, then the
  banded Cholesky solves with the supported rows prescribed, and the power of the loads.
* ``engine_*``: the compiled engine's kernels, the state as the tuple ``(c, v, w, R, K)``.

The SO(3) coefficients share the branches and series tables of :mod:`.kernels_numba`.

Data (one tuple ``g``, built by :class:`NumbaGalerkinKernels`)::

    ints (n, m, ends), flt (tau, threshold, flags), B0, B1 (m, p + 1), j0 (m,), wf, wa (m,),
    gam0, K0 (m, 3), sec (m, 9) section per point (C_N, C_M, J), lv (n, 3) distributed load,
    U (5, p + 1, n) Cholesky factors (mu M; M; J_1 M, J_2 M, J_3 M), Cp (n, kp), Cth (n, kr),
    Crot (3, n, kr) mass columns of the supported rows fp (kp,), fr (kr,), ser, lf, keep,
    lpt (nl, 5) loaded points, jab (J, 2), jq (J, 3, 3), Y (3, 3 J, n, 3), S (3, 3 J, 3 J)
    joint constraints of the position, Theta and W fields, jr (2, 3 J) work

``lf`` holds the loads at the stage time (:func:`~.kernels_numba._set_loads` writes
``vector * profile(t)`` into its slots: the distributed load's profile (first entry), the
distributed couple, the supports' prescribed accelerations, then a force and a couple per
loaded point).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ...groups.so3_coefficients import TAYLOR, TAYLOR_THRESHOLD
from ...integrators.engine import CompiledProblem, EngineKernels
from .kernels_numba import (  # the state's first array is c, its fourth R: the collocation ones apply
    _SERIES_KEYS,
    _coef_ABC,
    _coef_D,
    _cross,
    _set_loads,
    engine_end_step,
    engine_scale,
    profile_row,
)

_FM = {"contract"}

# ---- ints: n, m, then per end (2): index, point, prescribed rotation, prescribed displacement
_I_N, _I_M, _I_END, _NEI = 0, 1, 2, 4
# ---- flt: tau, threshold, has_q, has_m, power
_F_TAU, _F_THR, _F_HASQ, _F_HASM, _F_POW, _NF = 0, 1, 2, 3, 4, 5
#: Slots of ``lf`` (3 floats each): the distributed load's profile (first entry), the
#: distributed couple, per end: prescribed acceleration, prescribed angular acceleration
#: (material); then a force and a couple per loaded point (:data:`_LF_POINTS` + 6 k).
SLOTS = {"q": 0, "m": 3, "acc0": 6, "alpha0": 9, "acc1": 12, "alpha1": 15}
_LF_POINTS = 18
SLOT_ACC, SLOT_ALPHA = SLOTS["acc0"], SLOTS["alpha0"]


@njit(cache=True, fastmath=False)
def _chol_solve(U, b, col0, ncol):
    """Solve ``U^T U x = b`` in place on columns ``col0 .. col0 + ncol`` of ``b`` (n, k);
    ``U`` in LAPACK's upper band form ``(q + 1, n)``."""
    q = U.shape[0] - 1
    n = b.shape[0]
    for j in range(n):
        d = U[q, j]
        i0 = max(0, j - q)
        for c in range(col0, col0 + ncol):
            s = b[j, c]
            for i in range(i0, j):
                s -= U[q + i - j, j] * b[i, c]
            b[j, c] = s / d
    for i in range(n - 1, -1, -1):
        d = U[q, i]
        j1 = min(n - 1, i + q)
        for c in range(col0, col0 + ncol):
            s = b[i, c]
            for j in range(i + 1, j1 + 1):
                s -= U[q + i - j, j] * b[j, c]
            b[i, c] = s / d


@njit(cache=True, fastmath=False)
def _prescribe(b, C, rows, vals, d):
    """Move the prescribed values ``vals[:, d]`` of ``rows`` to the right-hand side of
    column ``d``: ``b[:, d] -= C vals[:, d]``, then ``b[rows, d] = vals[:, d]``."""
    n = b.shape[0]
    for k in range(rows.shape[0]):
        x = vals[k, d]
        if x != 0.0:
            for j in range(n):
                b[j, d] -= C[j, k] * x
    for k in range(rows.shape[0]):
        b[rows[k], d] = vals[k, d]


@njit(cache=True, fastmath=False)
def _constrain(x, jab, jq, Y, Sinv, rotational, r):
    """``x <- x - Y S^-1 C x`` (rigid joints: ``x[b] = Q^T x[a]``, or ``x[b] = x[a]``)."""
    nj = jab.shape[0]
    if nj == 0:
        return
    for j in range(nj):
        a, b = jab[j, 0], jab[j, 1]
        for e in range(3):
            if rotational:
                r[3 * j + e] = x[b, e] - (jq[j, 0, e] * x[a, 0] + jq[j, 1, e] * x[a, 1] + jq[j, 2, e] * x[a, 2])
            else:
                r[3 * j + e] = x[b, e] - x[a, e]
    k = 3 * nj
    n = x.shape[0]
    for l in range(k):
        lam = 0.0
        for q in range(k):
            lam += Sinv[l, q] * r[q]
        if lam != 0.0:
            for i in range(n):
                for d in range(3):
                    x[i, d] -= lam * Y[l, i, d]


@njit(cache=True, fastmath=_FM)
def galerkin_action(u, c, v, w, R, K, c2, v2, w2, R2, K2, B0, B1, j0, ser, thr):
    """``Lambda(u, y)`` into the preallocated ``c2, v2, w2, R2, K2``."""
    n, m, W = c.shape[0], B0.shape[0], B0.shape[1]
    for j in range(n):
        for d in range(3):
            c2[j, d] = c[j, d] + u[0, j, d]
            v2[j, d] = v[j, d] + u[2, j, d]
            w2[j, d] = w[j, d] + u[3, j, d]
    for i in range(m):
        t0 = t1 = t2 = s0 = s1 = s2 = 0.0
        js = j0[i]
        for k in range(W):
            j = js + k
            b0, b1 = B0[i, k], B1[i, k]
            x0, x1, x2 = u[1, j, 0], u[1, j, 1], u[1, j, 2]
            t0 += b0 * x0
            t1 += b0 * x1
            t2 += b0 * x2
            s0 += b1 * x0
            s1 += b1 * x1
            s2 += b1 * x2
        ang = math.sqrt(t0 * t0 + t1 * t1 + t2 * t2)
        cA, cB, cC = _coef_ABC(ang, ser, thr)
        # E = exp(hat(theta)) = I + A X + B X X
        e00 = 1.0 - cB * (t1 * t1 + t2 * t2)
        e11 = 1.0 - cB * (t0 * t0 + t2 * t2)
        e22 = 1.0 - cB * (t0 * t0 + t1 * t1)
        e01 = -cA * t2 + cB * t0 * t1
        e10 = cA * t2 + cB * t0 * t1
        e02 = cA * t1 + cB * t0 * t2
        e20 = -cA * t1 + cB * t0 * t2
        e12 = -cA * t0 + cB * t1 * t2
        e21 = cA * t0 + cB * t1 * t2
        for a in range(3):
            r0, r1, r2 = R[i, a, 0], R[i, a, 1], R[i, a, 2]
            R2[i, a, 0] = r0 * e00 + r1 * e10 + r2 * e20
            R2[i, a, 1] = r0 * e01 + r1 * e11 + r2 * e21
            R2[i, a, 2] = r0 * e02 + r1 * e12 + r2 * e22
        k0, k1, k2 = K[i, 0], K[i, 1], K[i, 2]
        # J_r(theta) theta_s = s - B theta x s + C theta x (theta x s)
        g0, g1, g2 = _cross(t0, t1, t2, s0, s1, s2)
        h0, h1, h2 = _cross(t0, t1, t2, g0, g1, g2)
        K2[i, 0] = e00 * k0 + e10 * k1 + e20 * k2 + s0 - cB * g0 + cC * h0
        K2[i, 1] = e01 * k0 + e11 * k1 + e21 * k2 + s1 - cB * g1 + cC * h1
        K2[i, 2] = e02 * k0 + e12 * k1 + e22 * k2 + s2 - cB * g2 + cC * h2


@njit(cache=True, fastmath=_FM)
def galerkin_rates(c, v, w, R, K, u, out, g, pw):
    """Stage rate ``(4, n, 3)`` into ``out`` (the loads already in ``g``'s ``lf`` at the
    stage time); the power of the loads and supports minus the dissipation into ``pw[0]``
    when the problem computes it."""
    (ints, flt, B0, B1, j0, wf, wa, gam0, K0, sec, lv, U, Cp, Cth, Crot, fp, fr, ser, lf, keep, lpt,
     jab, jq, Y, Sinv, jr) = g
    n, m, W = c.shape[0], B0.shape[0], B0.shape[1]
    tau, thr = flt[_F_TAU], flt[_F_THR]
    has_m = flt[_F_HASM] != 0.0
    want_power = flt[_F_POW] != 0.0
    md0, md1, md2 = lf[3], lf[4], lf[5]
    power = 0.0
    for j in range(n):
        for d in range(3):
            out[0, j, d] = v[j, d]
            out[1, j, d] = 0.0
            out[2, j, d] = 0.0
            out[3, j, d] = 0.0
    for i in range(m):
        wfi, wai = wf[i], wa[i]
        if wfi == 0.0 and wai == 0.0:
            continue
        js = j0[i]
        CN0, CN1, CN2, CM0, CM1, CM2 = sec[i, 0], sec[i, 1], sec[i, 2], sec[i, 3], sec[i, 4], sec[i, 5]
        J0, J1, J2 = sec[i, 6], sec[i, 7], sec[i, 8]
        # only the sums a point's terms read: bending points (wf) theta and Omega, axial
        # points (wa) c_s; Omega_s, v_s (and Omega at axial points) with damping only
        t0 = t1 = t2 = o0 = o1 = o2 = os0 = os1 = os2 = cs0 = cs1 = cs2 = vs0 = vs1 = vs2 = 0.0
        bend, axial = wfi != 0.0, wai != 0.0
        if bend or tau > 0.0:
            for k in range(W):
                j = js + k
                b0 = B0[i, k]
                t0 += b0 * u[1, j, 0]
                t1 += b0 * u[1, j, 1]
                t2 += b0 * u[1, j, 2]
                o0 += b0 * w[j, 0]
                o1 += b0 * w[j, 1]
                o2 += b0 * w[j, 2]
        if axial or tau > 0.0:
            for k in range(W):
                j = js + k
                b1 = B1[i, k]
                cs0 += b1 * c[j, 0]
                cs1 += b1 * c[j, 1]
                cs2 += b1 * c[j, 2]
        if tau > 0.0:
            for k in range(W):
                j = js + k
                b1 = B1[i, k]
                os0 += b1 * w[j, 0]
                os1 += b1 * w[j, 1]
                os2 += b1 * w[j, 2]
                vs0 += b1 * v[j, 0]
                vs1 += b1 * v[j, 1]
                vs2 += b1 * v[j, 2]
        r00, r01, r02 = R[i, 0, 0], R[i, 0, 1], R[i, 0, 2]
        r10, r11, r12 = R[i, 1, 0], R[i, 1, 1], R[i, 1, 2]
        r20, r21, r22 = R[i, 2, 0], R[i, 2, 1], R[i, 2, 2]
        k0, k1, k2 = K[i, 0], K[i, 1], K[i, 2]
        # rotation rate dexpinv_{-theta}(Omega) = Omega + theta x Omega / 2 + D theta x (theta x Omega)
        d0 = d1 = d2 = 0.0
        p0 = p1 = p2 = 0.0  # point torque (material)
        M0 = M1 = M2 = 0.0
        n0 = n1 = n2 = 0.0
        if wfi != 0.0:
            ang = math.sqrt(t0 * t0 + t1 * t1 + t2 * t2)
            cD = _coef_D(ang, ser, thr)
            x0, x1, x2 = _cross(t0, t1, t2, o0, o1, o2)
            y0, y1, y2 = _cross(t0, t1, t2, x0, x1, x2)
            d0 = wfi * (o0 + 0.5 * x0 + cD * y0)
            d1 = wfi * (o1 + 0.5 * x1 + cD * y1)
            d2 = wfi * (o2 + 0.5 * x2 + cD * y2)
            e0, e1, e2 = k0 - K0[i, 0], k1 - K0[i, 1], k2 - K0[i, 2]
            if tau > 0.0:  # dK/dt = Omega_s + K x Omega
                q0, q1, q2 = _cross(k0, k1, k2, o0, o1, o2)
                kd0, kd1, kd2 = os0 + q0, os1 + q1, os2 + q2
                e0 += tau * kd0
                e1 += tau * kd1
                e2 += tau * kd2
                if want_power:
                    power -= tau * wfi * (CM0 * kd0 * kd0 + CM1 * kd1 * kd1 + CM2 * kd2 * kd2)
            M0, M1, M2 = CM0 * e0, CM1 * e1, CM2 * e2
            a0, a1, a2 = _cross(M0, M1, M2, k0, k1, k2)
            b0_, b1_, b2_ = _cross(o0, o1, o2, J0 * o0, J1 * o1, J2 * o2)
            p0 = -wfi * (a0 + b0_)
            p1 = -wfi * (a1 + b1_)
            p2 = -wfi * (a2 + b2_)
            if has_m:  # R^T m_d
                z0 = r00 * md0 + r10 * md1 + r20 * md2
                z1 = r01 * md0 + r11 * md1 + r21 * md2
                z2 = r02 * md0 + r12 * md1 + r22 * md2
                p0 += wfi * z0
                p1 += wfi * z1
                p2 += wfi * z2
                if want_power:
                    power += wfi * (z0 * o0 + z1 * o1 + z2 * o2)
            M0, M1, M2 = wfi * M0, wfi * M1, wfi * M2
        if wai != 0.0:
            g0 = r00 * cs0 + r10 * cs1 + r20 * cs2
            g1 = r01 * cs0 + r11 * cs1 + r21 * cs2
            g2 = r02 * cs0 + r12 * cs1 + r22 * cs2
            e0, e1, e2 = g0 - gam0[i, 0], g1 - gam0[i, 1], g2 - gam0[i, 2]
            if tau > 0.0:  # dGamma/dt = R^T v_s - Omega x Gamma~
                q0, q1, q2 = _cross(o0, o1, o2, g0, g1, g2)
                gd0 = r00 * vs0 + r10 * vs1 + r20 * vs2 - q0
                gd1 = r01 * vs0 + r11 * vs1 + r21 * vs2 - q1
                gd2 = r02 * vs0 + r12 * vs1 + r22 * vs2 - q2
                e0 += tau * gd0
                e1 += tau * gd1
                e2 += tau * gd2
                if want_power:
                    power -= tau * wai * (CN0 * gd0 * gd0 + CN1 * gd1 * gd1 + CN2 * gd2 * gd2)
            N0_, N1_, N2_ = CN0 * e0, CN1 * e1, CN2 * e2
            a0, a1, a2 = _cross(g0, g1, g2, N0_, N1_, N2_)
            p0 += wai * a0
            p1 += wai * a1
            p2 += wai * a2
            n0 = wai * (r00 * N0_ + r01 * N1_ + r02 * N2_)
            n1 = wai * (r10 * N0_ + r11 * N1_ + r12 * N2_)
            n2 = wai * (r20 * N0_ + r21 * N1_ + r22 * N2_)
        for k in range(W):
            j = js + k
            b0, b1 = B0[i, k], B1[i, k]
            if bend:
                out[1, j, 0] += b0 * d0
                out[1, j, 1] += b0 * d1
                out[1, j, 2] += b0 * d2
            if axial:
                out[2, j, 0] -= b1 * n0
                out[2, j, 1] -= b1 * n1
                out[2, j, 2] -= b1 * n2
            out[3, j, 0] += b0 * p0 - b1 * M0
            out[3, j, 1] += b0 * p1 - b1 * M1
            out[3, j, 2] += b0 * p2 - b1 * M2
    # distributed force (profile in lf[0])
    if flt[_F_HASQ] != 0.0:
        fq = lf[0]
        for j in range(n):
            for d in range(3):
                out[2, j, d] += fq * lv[j, d]
                if want_power:
                    power += fq * lv[j, d] * v[j, d]
    # point loads at ends and joints
    for l in range(lpt.shape[0]):
        idx, pt = lpt[l, 0], lpt[l, 1]
        fo = _LF_POINTS + 6 * l
        if lpt[l, 2] != 0:  # force (spatial; follower: R_end f)
            f0, f1, f2 = lf[fo], lf[fo + 1], lf[fo + 2]
            if lpt[l, 4] != 0:
                f0, f1, f2 = (R[pt, 0, 0] * f0 + R[pt, 0, 1] * f1 + R[pt, 0, 2] * f2,
                              R[pt, 1, 0] * f0 + R[pt, 1, 1] * f1 + R[pt, 1, 2] * f2,
                              R[pt, 2, 0] * f0 + R[pt, 2, 1] * f1 + R[pt, 2, 2] * f2)
            out[2, idx, 0] += f0
            out[2, idx, 1] += f1
            out[2, idx, 2] += f2
            if want_power:
                power += f0 * v[idx, 0] + f1 * v[idx, 1] + f2 * v[idx, 2]
        if lpt[l, 3] != 0:  # couple (material: R_end^T C; follower: C)
            f0, f1, f2 = lf[fo + 3], lf[fo + 4], lf[fo + 5]
            if lpt[l, 4] == 0:
                f0, f1, f2 = (R[pt, 0, 0] * f0 + R[pt, 1, 0] * f1 + R[pt, 2, 0] * f2,
                              R[pt, 0, 1] * f0 + R[pt, 1, 1] * f1 + R[pt, 2, 1] * f2,
                              R[pt, 0, 2] * f0 + R[pt, 1, 2] * f1 + R[pt, 2, 2] * f2)
            out[3, idx, 0] += f0
            out[3, idx, 1] += f1
            out[3, idx, 2] += f2
            if want_power:
                power += f0 * w[idx, 0] + f1 * w[idx, 1] + f2 * w[idx, 2]
    # forces of the supported rows (their residuals are the reactions)
    for k in range(fp.shape[0]):
        for d in range(3):
            keep[k, d] = out[2, fp[k], d]
    for k in range(fr.shape[0]):
        for d in range(3):
            keep[2 + k, d] = out[3, fr[k], d]
    # prescribed rows: Theta' = W (parallel), accelerations from lf
    for k in range(fr.shape[0]):
        e = 0 if fr[k] == 0 else 1
        for d in range(3):
            keep[4 + k, d] = w[fr[k], d]
            keep[6 + k, d] = lf[SLOT_ALPHA + 6 * e + d]
    for k in range(fp.shape[0]):
        e = 0 if fp[k] == 0 else 1
        for d in range(3):
            keep[8 + k, d] = lf[SLOT_ACC + 6 * e + d]
    kr, kp = fr.shape[0], fp.shape[0]
    b = out[1]
    for d in range(3):
        _prescribe(b, Cth, fr, keep[4:4 + kr], d)
    _chol_solve(U[1], b, 0, 3)
    _constrain(b, jab, jq, Y[1], Sinv[1], True, jr)
    b = out[3]
    for d in range(3):
        _prescribe(b, Crot[d], fr, keep[6:6 + kr], d)
        _chol_solve(U[2 + d], b, d, 1)
    _constrain(b, jab, jq, Y[2], Sinv[2], True, jr)
    b = out[2]
    for d in range(3):
        _prescribe(b, Cp, fp, keep[8:8 + kp], d)
    _chol_solve(U[0], b, 0, 3)
    _constrain(b, jab, jq, Y[0], Sinv[0], False, jr)
    if want_power:  # moving supports: reaction . velocity
        for e in range(2):
            row = _I_END + _NEI * e
            idx = ints[row]
            if ints[row + 3] != 0:
                for k in range(kp):
                    if fp[k] == idx:
                        for d in range(3):
                            s = 0.0
                            for j in range(n):
                                s += Cp[j, k] * out[2, j, d]
                            power += (s - keep[k, d]) * v[idx, d]
            if ints[row + 2] != 0:
                for k in range(kr):
                    if fr[k] == idx:
                        for d in range(3):
                            s = 0.0
                            for j in range(n):
                                s += Crot[d, j, k] * out[3, j, d]
                            power += (s - keep[2 + k, d]) * w[idx, d]
        pw[0] = power


@njit(cache=True, fastmath=False)
def galerkin_angle(u, B0, j0):
    """Largest ``|Theta|`` at the points of the increment ``u``."""
    m, W = B0.shape[0], B0.shape[1]
    best = 0.0
    for i in range(m):
        t0 = t1 = t2 = 0.0
        for k in range(W):
            j = j0[i] + k
            t0 += B0[i, k] * u[1, j, 0]
            t1 += B0[i, k] * u[1, j, 1]
            t2 += B0[i, k] * u[1, j, 2]
        a = math.sqrt(t0 * t0 + t1 * t1 + t2 * t2)
        if a > best or a != a:
            best = a
    return best


# ====================================================================== engine kernels
# data = (g, lpos, lvec, lprof, pw)
@njit(cache=True, fastmath=False, inline="always")
def engine_rate(data, t, y, u, out):
    g, lpos, lvec, lprof, pw = data
    _set_loads(g[18], lpos, lvec, lprof, t)
    c, v, w, R, K = y
    galerkin_rates(c, v, w, R, K, u, out, g, pw)
    return pw[0]


@njit(cache=True, fastmath=False, inline="always")
def engine_action(data, u, y0, y1):
    g = data[0]
    c0, v0, w0, R0, K0 = y0
    c1, v1, w1, R1, K1 = y1
    galerkin_action(u, c0, v0, w0, R0, K0, c1, v1, w1, R1, K1, g[2], g[3], g[4], g[17], g[1][_F_THR])


@njit(cache=True, fastmath=False, inline="always")
def engine_angle(data, u):
    g = data[0]
    return galerkin_angle(u, g[2], g[4])


@njit(cache=True, fastmath=False, inline="always")
def engine_increment_view(data, u):
    return u.reshape((4, data[0][0][_I_N], 3))


@njit(cache=True, fastmath=False, inline="always")
def engine_increment_views(data, K):
    return K.reshape((K.shape[0], 4, data[0][0][_I_N], 3))


@njit(cache=True, fastmath=False, inline="always")
def engine_new_state(data, y):
    return (np.empty_like(y[0]), np.empty_like(y[1]), np.empty_like(y[2]), np.empty_like(y[3]),
            np.empty_like(y[4]))


@njit(cache=True, fastmath=False, inline="always")
def engine_copy_state(data, src, dst):
    dst[0][:] = src[0]
    dst[1][:] = src[1]
    dst[2][:] = src[2]
    dst[3][:] = src[3]
    dst[4][:] = src[4]


ENGINE_KERNELS = EngineKernels("beam_galerkin", engine_rate, engine_action, engine_angle, engine_scale,
                               end_step=engine_end_step, new_state=engine_new_state, copy_state=engine_copy_state,
                               increment_view=engine_increment_view, increment_views=engine_increment_views)


# ====================================================================== Python side
def _windows(mats, width: int):
    """Row windows ``(m, width)`` of each matrix and their common first columns ``(m,)``,
    for basis matrices whose rows have at most ``width`` consecutive non-zeros together
    (kept inside ``[0, n)``)."""
    nz_all = np.zeros(mats[0].shape, dtype=bool)
    for B in mats:
        nz_all |= B != 0.0
    m, n = nz_all.shape
    j0 = np.zeros(m, dtype=np.int64)
    for i in range(m):
        nz = np.flatnonzero(nz_all[i])
        j0[i] = min(int(nz[0]) if nz.size else 0, n - width)
        if nz.size and nz[-1] >= j0[i] + width:  # pragma: no cover - B-spline supports are p + 1 wide
            raise ValueError("basis row wider than its window")
    idx = j0[:, None] + np.arange(width)[None, :]
    return [np.ascontiguousarray(np.take_along_axis(B, idx, axis=1)) for B in mats], j0


def _c(a):
    return np.ascontiguousarray(a, dtype=np.float64)


class NumbaGalerkinKernels:
    """Constant data and thin wrappers of the compiled kernels for one
    :class:`~.galerkin.GalerkinBeamProblem`."""

    def __init__(self, pb):
        from .model import Profile

        self.pb = pb
        gs = pb.gs
        n, m = pb.n, pb.m
        self.n = n
        width = pb.space.degree + 1
        (B0, B1), j0 = _windows([np.asarray(gs.B0, float), np.asarray(gs.B1, float)], width)
        ints = np.zeros(_I_END + 2 * _NEI, dtype=np.int64)
        ints[_I_N], ints[_I_M] = n, m
        lvec, lprof, lpos = [], [], []

        def slot(pos, vec, prof):
            lpos.append(pos)
            lvec.append(np.asarray(vec, float))
            lprof.append(prof)

        const = Profile()
        dprof = pb.loads.distributed_profile
        slot(SLOTS["q"], (1.0, 0.0, 0.0), dprof)
        slot(SLOTS["m"], pb.m_dist, dprof)
        for e_i, e in enumerate(pb.ends):
            row = _I_END + _NEI * e_i
            ints[row], ints[row + 1] = e.index, e.point
            ints[row + 2] = int(e.motion is not None)
            ints[row + 3] = int(e.translation is not None)
            if e.translation is not None:
                scale, prof = e.translation.acceleration_profile()
                slot(SLOTS[f"acc{e_i}"], scale * e.translation.unit_axis, prof)
            else:
                slot(SLOTS[f"acc{e_i}"], np.zeros(3), const)
            if e.motion is not None:
                scale, prof = e.motion.acceleration_profile()
                slot(SLOTS[f"alpha{e_i}"], scale * (gs.R0[e.point].T @ e.motion.unit_axis), prof)
            else:
                slot(SLOTS[f"alpha{e_i}"], np.zeros(3), const)
        lpt = np.zeros((len(pb.point_loads), 5), dtype=np.int64)
        for k, (row, point, ld) in enumerate(pb.point_loads):
            lpt[k] = (row, point, int(bool(np.any(ld.force))), int(bool(np.any(ld.couple))), int(bool(ld.follower)))
            slot(_LF_POINTS + 6 * k, ld.force, ld.force_profile)
            slot(_LF_POINTS + 6 * k + 3, ld.couple, ld.couple_profile)
        flt = np.zeros(_NF)
        flt[_F_TAU], flt[_F_THR] = pb.tau, float(TAYLOR_THRESHOLD)
        flt[_F_HASQ], flt[_F_HASM], flt[_F_POW] = float(pb.has_q), float(pb.has_m), float(pb.has_quadrature)
        ser = np.array([[float(x) for x in TAYLOR[k]] for k in _SERIES_KEYS])
        masses = (pb.mass_position, pb.mass_theta) + tuple(pb.mass_rotation)
        U = np.array([mm.factor for mm in masses])
        fp = np.flatnonzero(pb.mass_position.fixed).astype(np.int64)
        fr = np.flatnonzero(pb.mass_theta.fixed).astype(np.int64)
        Crot = np.array([mm.coupling for mm in pb.mass_rotation]).reshape(3, n, fr.size)
        sec = np.concatenate([pb.CN, pb.CM, pb.Jm], axis=1)
        nj = len(pb.joints)
        jab = np.array([(j[0], j[1]) for j in pb.joints], dtype=np.int64).reshape(nj, 2)
        jq = np.array([j[3] for j in pb.joints], dtype=float).reshape(nj, 3, 3)
        if nj:
            cons = [pb._constraints[k] for k in ("position", "theta", "rotation")]
            Y = np.array([c[0] for c in cons])
            Sinv = np.array([c[1] for c in cons])
        else:
            Y, Sinv = np.zeros((3, 0, n, 3)), np.zeros((3, 0, 0))
        self._rows = [profile_row(p) for p in lprof]
        self._lprof_objs = lprof
        widthp = max((r.size for r in self._rows if r is not None), default=1)
        lp = np.zeros((len(lprof), widthp))
        for k, r in enumerate(self._rows):
            if r is not None:
                lp[k, :r.size] = r
        self.lpos = np.array(lpos, dtype=np.int64)
        self.lvec = np.array(lvec, dtype=float).reshape(-1, 3)
        self.lprof = lp
        self.compilable = all(r is not None for r in self._rows)
        lf = np.zeros(_LF_POINTS + 6 * len(pb.point_loads))
        self.g = (ints, flt, B0, B1, j0, _c(gs.w_full), _c(gs.w_axial), _c(gs.gamma0), _c(gs.K0), _c(sec),
                  _c(pb.load_vector), _c(U), _c(pb.mass_position.coupling), _c(pb.mass_theta.coupling), _c(Crot),
                  fp, fr, ser, lf, np.zeros((10, 3)), lpt, jab, _c(jq), _c(Y), _c(Sinv), np.zeros(3 * nj))
        self._t_loads = None
        self._pw = np.zeros(1)
        self._zero = np.zeros((4, n, 3))

    def _set_loads(self, t: float) -> None:
        if t == self._t_loads:
            return
        lf = self.g[18]
        for a, vec, prof in zip(self.lpos, self.lvec, self._lprof_objs):
            lf[a:a + 3] = vec * prof(t)
        self._t_loads = t

    def action(self, u, y):
        from .galerkin import GalerkinBeamState

        n, m = self.n, self.pb.m
        e = np.empty
        out = (e((n, 3)), e((n, 3)), e((n, 3)), e((m, 3, 3)), e((m, 3)))
        g = self.g
        galerkin_action(_c(u), _c(y.c), _c(y.v), _c(y.w), _c(y.R), _c(y.K), *out, g[2], g[3], g[4], g[17],
                        g[1][_F_THR])
        return GalerkinBeamState(*out)

    def increment_rate(self, t, y, u):
        self._set_loads(t)
        out = np.empty((4, self.n, 3))
        galerkin_rates(_c(y.c), _c(y.v), _c(y.w), _c(y.R), _c(y.K), _c(u), out, self.g, self._pw)
        return out

    def rotation_angle(self, u) -> float:
        return float(galerkin_angle(_c(u), self.g[2], self.g[4]))

    def compiled_problem(self):
        """What the compiled engine needs, or ``None`` when a load profile cannot be
        evaluated in compiled code."""
        if not self.compilable:
            return None
        from .galerkin import GalerkinBeamState

        g = tuple(a.copy() if isinstance(a, np.ndarray) else a for a in self.g)
        data = (g, self.lpos, self.lvec, self.lprof, np.zeros(1))
        n = self.n

        def pack(y):
            return tuple(_c(a) for a in (y.c, y.v, y.w, y.R, y.K))

        def unpack(arrays):
            return GalerkinBeamState(*arrays)

        return CompiledProblem(ENGINE_KERNELS, data, lambda packed: 12 * n, pack, unpack)
