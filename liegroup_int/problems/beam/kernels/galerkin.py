"""Compiled kernels of the Galerkin beam (``GalerkinBeamProblem(..., backend="numba")``),
built from :mod:`.physics`.

Same mathematics as the NumPy path of :mod:`..galerkin`, one loop over the points per call:

* :func:`action`: ``Theta, Theta_s`` at every point from the control values,
  ``R <- R exp(hat(Theta))``, ``K <- exp(-Theta) K + J_r(Theta) Theta_s``; ``c, v, w`` plus
  their increments.
* :func:`rates`: strains, resultants, the weak-form forces and the projected
  ``dexpinv`` scattered onto the control values in the same loop, end loads and hinge
  springs, then the banded Cholesky solves with the supported rows prescribed and the
  joints' constraints (the hinges' rebuilt from the state at every stage);
  returns the power of the loads and supports minus the dissipation.

The data: :class:`GalerkinData`, packed by :func:`.adapters.pack`. ``loads`` holds the
loads at the stage time: row :data:`Q` (the distributed load's profile in its first
entry), :data:`MD` (distributed couple), per end ``e`` rows ``ACC + 2 e`` (prescribed
acceleration) and ``ALPHA + 2 e`` (prescribed material angular acceleration), per loaded
point ``l`` rows ``POINTS + 2 l`` (force) and ``POINTS + 2 l + 1`` (couple).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from ....groups.kernels_numba import coef_ABC, coef_D, series_table
from ....groups.so3_coefficients import TAYLOR_THRESHOLD
from . import adapters as ad
from .adapters import F1, F2, F3, F4, I1, I2, KIN_COMPUTE, KIN_FROM_ACTION, KIN_NONE, c64
from .band import basis_windows, chol_solve9, dense_solve, window, window2
from .physics import (curvature_rate, dexpinv, dissipation, exp_rows, gamma_rate, gyroscopic, jr_times,
                      load_power, point_load, resultant, rows_T_times, strain)
from .profiles import LoadTable, set_loads
from .vec3 import add, axpy, col, cross, dot, neg, norm, put, put_col, rot, rot_T, row, scale, sub

FM = {"contract"}
Q, MD, ACC, ALPHA, POINTS = 0, 1, 2, 3, 6  # rows of ``loads`` (module docstring)


class GalerkinData(NamedTuple):
    """Constant data and work arrays of the Galerkin kernels (``n`` control values, ``m``
    points)."""

    band: F3  # (2, m, p + 1) basis windows B0, B1
    j0: I1  # (m,)
    wf: F1  # (m,) weights of the bending (full) and axial (reduced) quadratures
    wa: F1
    gamma0: F2  # (m, 3)
    K0: F2
    CN: F2  # (m, 3) section per point
    CM: F2
    J: F2
    lv: F2  # (n, 3) distributed load vector int N q ds
    U: F3  # (5, q + 1, n) Cholesky factors of mu M, M, J_1 M, J_2 M, J_3 M
    dinv: F2  # (5, n) reciprocals of their diagonals
    Cp: F2  # (n, kp) mass columns of the supported position rows fp
    Cth: F2  # (n, kr) and of the supported rotation rows fr (M, then J_d M)
    Crot: F3  # (3, n, kr)
    fp: I1
    fr: I1
    ser: F2
    thr: float
    tau: float
    power: bool
    has_q: bool
    has_m: bool
    loads: F2  # (rows, 3) at the stage time (module docstring)
    end_index: I1  # (2,) control row, moving support, sliding support
    end_moving: I1
    end_sliding: I1
    point_row: I1  # (nl,) loaded points: control row, point, has force, has couple,
    point_pt: I1  # follower
    point_force: I1
    point_couple: I1
    point_follower: I1
    point_arm: F2  # (nl, 3) point of application from the point (a body's offset, section frame)
    joint_ab: I2  # (J, 2) rows of each joint pair, Q = R0_a^T R0_b (J, 3, 3)
    joint_q: F3
    Y: F4  # (3, 3 J, n, 3) constraint columns of the position, Theta and W fields
    Sinv: F3  # (3, 3 J, 3 J) S^-1 D: ball joints and hinges are 0 in Y[1:], Sinv[1:] (lam = 0)
    keep: F2  # (10, 3) work: supported rows' forces, prescribed values
    jr: F1  # (3 J,) work
    body_row: I1  # (nb,) end bodies: control row, point, mass, offset (nb, 3), inertia about the
    body_pt: I1  # end point (nb, 3, 3) and weight m g (nb, 3), section frame
    body_m: F1
    body_c: F2
    body_J: F3
    body_wt: F2
    cpl_index: I1  # (k,) bodies off their end points: responses P (6 k, n, 3), G (6 k, 6 k)
    cpl_P: F3
    cpl_G: F2
    cpl_C: F2  # (6 k, 6 k) work: their mass blocks; (6 k, 6 k + 2) the capacitance, right side, U^T x
    cpl_S: F2
    cpl_Ph: F3  # work with hinges: P with the couples' columns on the hinges' constraints, G of it
    cpl_Gh: F2
    hinge_ab: I2  # (H, 4) hinges: rows a, b and points of a, b
    hinge_E: F3  # (H, 2, 3) rows perpendicular to the material axis at b
    hinge_Z: F3  # (12 H, n, 3) constrained responses, index ((h 2 + field) 2 + end) 3 + c
    hinge_C: F3  # (2 H, 2, 3) work: constraint rows on rows a, b
    hinge_S: F2  # (2 H, 2 H + 1) work: capacitance and right-hand side
    hinge_axis: F2  # (H, 3) material axis at b, Q = R0_a^T R0_b (H, 3, 3), stiffness and damping (H, 2)
    hinge_Q: F3
    hinge_kc: F2
    pts: F2  # (10, m) work: Theta, Theta_s, A, B, C, D per point: the action's, read by the next stage rate


@njit(cache=True, _nrt=False, inline="always")
def unpack(flat, head):
    """The :class:`GalerkinData` of :func:`.adapters.pack`'s arrays (views)."""
    return ad.unpack_as(GalerkinData, flat, head)


# ====================================================================== action
@njit(cache=True, fastmath=FM, _nrt=False)
def _windows2(B, j0, X, P):
    """``P[0:3, i], P[3:6, i]``: the windows of basis matrices 0 and 1 at every point."""
    for i in range(P.shape[1]):
        th, ts = window2(B, 0, 1, i, j0, X, 0)
        put_col(P, 0, i, th)
        put_col(P, 3, i, ts)


@njit(cache=True, fastmath=FM, _nrt=False)
def _coefficients(ser, thr, P):
    """``P[6:10, i]``: the coefficients ``A, B, C`` (the exponential, ``J_r``) and ``D``
    (``dexpinv``, for the next stage rate) of ``Theta = P[0:3, i]`` at every point."""
    for i in range(P.shape[1]):
        t = norm(col(P, 0, i))
        put_col(P, 6, i, coef_ABC(t, ser, thr))
        P[9, i] = coef_D(t, ser, thr)


@njit(cache=True, fastmath=FM, _nrt=False)
def _turn(R, K, R2, K2, P):
    """``R2 = R exp(hat(Theta))``, ``K2 = exp(-Theta) K + J_r(Theta) Theta_s`` at every point
    from ``P`` (:func:`_windows2`, :func:`_coefficients`)."""
    for i in range(R.shape[0]):
        th, cA, cB, cC = col(P, 0, i), P[6, i], P[7, i], P[8, i]
        E = exp_rows(cA, cB, th)
        for a in range(3):  # R2[i] = R[i] E
            r = (R[i, a, 0], R[i, a, 1], R[i, a, 2])
            R2[i, a, 0], R2[i, a, 1], R2[i, a, 2] = rows_T_times(E, r)
        put(K2, i, add(rows_T_times(E, row(K, i)), jr_times(cB, cC, th, col(P, 3, i))))


@njit(cache=True, fastmath=FM, inline="always")
def action(u, c, v, w, R, K, c2, v2, w2, R2, K2, d):
    """``Lambda(u, y)`` into the preallocated ``c2, v2, w2, R2, K2``. The points go through
    three passes (``Theta, Theta_s``; the coefficients; the rotations and curvatures, in
    ``d.pts``) rather than one: each point is a chain of dependent operations (sums, square
    root, series, products), and short passes let the processor overlap many points.
    ``d.pts`` keeps ``Theta`` and ``D`` for the stage rate of the state made here
    (``KIN_FROM_ACTION``)."""
    for j in range(c.shape[0]):
        for q in range(3):
            c2[j, q] = c[j, q] + u[0, j, q]
            v2[j, q] = v[j, q] + u[2, j, q]
            w2[j, q] = w[j, q] + u[3, j, q]
    _windows2(d.band, d.j0, u[1], d.pts)
    _coefficients(d.ser, d.thr, d.pts)
    _turn(R, K, R2, K2, d.pts)


# ====================================================================== stage rates
@njit(cache=True, fastmath=FM, inline="always")
def _point_forces(d, i, c, v, w, R, K, u1, kin):
    """The weak-form terms of point ``i``: the weighted ``dexpinv_{-Theta} Omega`` (zero
    with ``kin`` :data:`~.adapters.KIN_NONE`; ``Theta`` and its coefficient ``D`` from
    ``u1``, or from ``d.pts`` where the action left them), torque ``p``, moment ``M`` and
    spatial force ``n``, and the power at the point."""
    wfi, wai, tau, B, j0 = d.wf[i], d.wa[i], d.tau, d.band, d.j0
    zero = (0.0, 0.0, 0.0)
    th = Om = cs = Oms = vs = dth = p = Mw = nw = zero
    power = 0.0
    if wfi != 0.0 or tau > 0.0:
        Om = window(B, 0, i, j0, w, 0)
        if kin == KIN_COMPUTE:
            th = window(B, 0, i, j0, u1, 0)
    if wai != 0.0 or tau > 0.0:
        cs = window(B, 1, i, j0, c, 0)
    if tau > 0.0:
        Oms, vs = window(B, 1, i, j0, w, 0), window(B, 1, i, j0, v, 0)
    if wfi != 0.0:
        k = row(K, i)
        if kin == KIN_COMPUTE:
            dth = scale(wfi, dexpinv(coef_D(norm(th), d.ser, d.thr), neg(th), Om))
        elif kin == KIN_FROM_ACTION:
            dth = scale(wfi, dexpinv(d.pts[9, i], neg(col(d.pts, 0, i)), Om))
        kd = curvature_rate(Oms, k, Om) if tau > 0.0 else zero
        M = resultant(row(d.CM, i), strain(k, row(d.K0, i)), tau, kd)
        p = scale(-wfi, add(cross(M, k), gyroscopic(Om, row(d.J, i))))
        if d.has_m:  # R^T m_d
            z = rot_T(R, i, row(d.loads, MD))
            p = axpy(wfi, z, p)
            power += wfi * dot(z, Om)
        if tau > 0.0:
            power -= wfi * dissipation(tau, row(d.CM, i), kd)
        Mw = scale(wfi, M)
    if wai != 0.0:
        Gt = rot_T(R, i, cs)
        gd = gamma_rate(rot_T(R, i, vs), Om, Gt) if tau > 0.0 else zero
        N = resultant(row(d.CN, i), strain(Gt, row(d.gamma0, i)), tau, gd)
        p = axpy(wai, cross(Gt, N), p)
        nw = scale(wai, rot(R, i, N))
        if tau > 0.0:
            power -= wai * dissipation(tau, row(d.CN, i), gd)
    return dth, p, Mw, nw, power


@njit(cache=True, fastmath=FM, inline="always")
def _point_loads(d, v, w, R, out):
    """Distributed force and the loads of the loaded points into ``out``; their power."""
    power = 0.0
    if d.has_q:
        fq = d.loads[Q, 0]
        for j in range(v.shape[0]):
            f = scale(fq, row(d.lv, j))
            put(out[2], j, add(row(out[2], j), f))
            power += dot(f, row(v, j))
    for l in range(d.point_row.shape[0]):
        idx, pt, fol = d.point_row[l], d.point_pt[l], d.point_follower[l]
        f = point_load(R, pt, row(d.loads, POINTS + 2 * l), fol) if d.point_force[l] else (0.0, 0.0, 0.0)
        m = row(d.loads, POINTS + 2 * l + 1)  # material: R^T C, follower: C
        m = (m if fol else rot_T(R, pt, m)) if d.point_couple[l] else (0.0, 0.0, 0.0)
        if d.point_force[l]:  # the force's moment about the point: arm x R^T f
            m = add(m, cross(row(d.point_arm, l), rot_T(R, pt, f)))
        put(out[2], idx, add(row(out[2], idx), f))
        put(out[3], idx, add(row(out[3], idx), m))
        power += load_power(f, row(v, idx), m, row(w, idx))
    return power


@njit(cache=True, fastmath=False, inline="always")
def _prescribe(b, C, rows, keep, at, q):
    """Move the prescribed values ``keep[at + k, q]`` of ``rows`` to the right-hand side of
    column ``q``: ``b[:, q] -= C vals[:, q]``, then ``b[rows, q] = vals[:, q]``."""
    for k in range(rows.shape[0]):
        x = keep[at + k, q]
        if x != 0.0:
            for j in range(b.shape[0]):
                b[j, q] -= C[j, k] * x
    for k in range(rows.shape[0]):
        b[rows[k], q] = keep[at + k, q]


@njit(cache=True, fastmath=False, _nrt=False)
def _constrain(x, jab, jq, Y, Sinv, rotational, r):
    """``x <- x - Y S^-1 C x`` (joints: ``x[b] = Q^T x[a]``, or ``x[b] = x[a]``; rows of
    ``S^-1`` that are zero leave their constraint out)."""
    nj = jab.shape[0]
    for j in range(nj):
        a, b = jab[j, 0], jab[j, 1]
        xa = row(x, a)
        ta = rot_T(jq, j, xa) if rotational else xa
        r[3 * j], r[3 * j + 1], r[3 * j + 2] = x[b, 0] - ta[0], x[b, 1] - ta[1], x[b, 2] - ta[2]
    for l in range(3 * nj):
        lam = 0.0
        for q in range(3 * nj):
            lam += Sinv[l, q] * r[q]
        if lam != 0.0:
            for i in range(x.shape[0]):
                for q in range(3):
                    x[i, q] -= lam * Y[l, i, q]


@njit(cache=True, fastmath=False, inline="always")
def _hinge_springs(d, R, w, out):
    """The hinges' spring-damper couples ``m = k phi + c dphi/dt`` into ``out[3]`` (``-m
    axis`` on row b, ``m G axis`` on row a); their power (``-c dphi/dt^2``)
    (:meth:`GalerkinBeamProblem._hinge_springs`)."""
    power = 0.0
    for h in range(d.hinge_ab.shape[0]):
        k, c = d.hinge_kc[h, 0], d.hinge_kc[h, 1]
        if k == 0.0 and c == 0.0:
            continue
        a, b, pa, pb = d.hinge_ab[h, 0], d.hinge_ab[h, 1], d.hinge_ab[h, 2], d.hinge_ab[h, 3]
        e0 = (d.hinge_E[h, 0, 0], d.hinge_E[h, 0, 1], d.hinge_E[h, 0, 2])
        e1 = (d.hinge_E[h, 1, 0], d.hinge_E[h, 1, 1], d.hinge_E[h, 1, 2])
        ax = row(d.hinge_axis, h)
        He = rot_T(d.hinge_Q, h, rot_T(R, pa, rot(R, pb, e0)))
        phi = np.arctan2(dot(e1, He), dot(e0, He))
        rate = dot(ax, sub(row(w, b), rot_T(R, pb, rot(R, pa, row(w, a)))))
        m = k * phi + c * rate
        put(out[3], b, axpy(-m, ax, row(out[3], b)))
        put(out[3], a, axpy(m, rot_T(R, pa, rot(R, pb, ax)), row(out[3], a)))
        power -= c * rate * rate
    return power


@njit(cache=True, fastmath=False, inline="always")
def _hinge_rows(d, R, w, u1, field):
    """The hinges' constraint rows on one rotational field (0: Theta', 1: W) into
    ``hinge_C`` and their right-hand sides into the last column of ``hinge_S``: W:
    ``E (W_b - G^T W_a) = -E (W_b x G^T W_a)``; Theta': ``E (A_b Theta'_b - G^T A_a Theta'_a)
    = 0`` with ``G = R_a^T R_b``, ``A = dexp_{-Theta}`` (:meth:`GalerkinBeamProblem._hinge_rows`)."""
    m = d.hinge_S.shape[0]
    for h in range(d.hinge_ab.shape[0]):
        a, b, pa, pb = d.hinge_ab[h, 0], d.hinge_ab[h, 1], d.hinge_ab[h, 2], d.hinge_ab[h, 3]
        ta, tb = row(u1, a), row(u1, b)
        _, Ba, Ca = coef_ABC(norm(ta), d.ser, d.thr)
        _, Bb, Cb = coef_ABC(norm(tb), d.ser, d.thr)
        for k in range(2):
            e = (d.hinge_E[h, k, 0], d.hinge_E[h, k, 1], d.hinge_E[h, k, 2])
            Ge = rot_T(R, pa, rot(R, pb, e))
            g = 0.0
            if field == 1:
                cb, ca = e, neg(Ge)
                g = -dot(e, cross(row(w, b), rot_T(R, pb, rot(R, pa, row(w, a)))))
            else:  # A^T = J_l(Theta) = J_r(-Theta)
                cb, ca = jr_times(Bb, Cb, neg(tb), e), neg(jr_times(Ba, Ca, neg(ta), Ge))
            put(d.hinge_C[2 * h + k], 0, ca)
            put(d.hinge_C[2 * h + k], 1, cb)
            d.hinge_S[2 * h + k, m] = g


@njit(cache=True, fastmath=False, inline="always")
def _hinge_apply(d, l, x):
    """``C_l x`` of hinge row ``l`` (``hinge_C``) on a field ``x`` ``(n, 3)``."""
    h = l // 2
    a, b = d.hinge_ab[h, 0], d.hinge_ab[h, 1]
    return dot(row(d.hinge_C[l], 0), row(x, a)) + dot(row(d.hinge_C[l], 1), row(x, b))


@njit(cache=True, fastmath=False, _nrt=False)
def _constrain_hinges(x, d, R, w, u1, field, g_weight):
    """``x <- x - Y S^-1 (C x - g_weight g)`` for the hinges on one rotational field, ``Y =
    M_c^-1 C^T`` from the constrained responses ``hinge_Z`` (the constant joints kept);
    ``g_weight`` 1.0, or 0.0 for the constraints' linear part. Its callers pass ``field`` and
    ``g_weight`` as values numba does not type as literals (a loop index, a computed int, a
    float), so one compiled copy serves them all (a copy compiles in about 5 s)."""
    m = d.hinge_S.shape[0]
    if m == 0:
        return
    _hinge_rows(d, R, w, u1, field)
    Z, C, S = d.hinge_Z, d.hinge_C, d.hinge_S
    for k in range(m):
        S[k, m] = _hinge_apply(d, k, x) - g_weight * S[k, m]
        for l in range(m):
            s = 0.0
            for e in range(2):
                for c in range(3):
                    if C[l, e, c] != 0.0:
                        s += C[l, e, c] * _hinge_apply(d, k, Z[((l // 2 * 2 + field) * 2 + e) * 3 + c])
            S[k, l] = s
    dense_solve(S, m)  # lambda into S[:, m]
    for l in range(m):
        for e in range(2):
            for c in range(3):
                f = S[l, m] * C[l, e, c]
                if f != 0.0:
                    zi = ((l // 2 * 2 + field) * 2 + e) * 3 + c
                    for i in range(x.shape[0]):
                        for q in range(3):
                            x[i, q] -= f * Z[zi, i, q]


@njit(cache=True, fastmath=False, inline="always")
def _solve(d, w, out, R, u1):
    """Supported rows' forces into ``keep``, prescribed values, then the three mass solves
    (nine columns in one sweep) with the joints' constraints."""
    keep, fp, fr = d.keep, d.fp, d.fr
    kp, kr = fp.shape[0], fr.shape[0]
    for k in range(kp):
        put(keep, k, row(out[2], fp[k]))
        put(keep, 8 + k, row(d.loads, ACC + 2 * (0 if fp[k] == 0 else 1)))
    for k in range(kr):  # Theta' = W (parallel) at a clamp; prescribed angular accelerations
        put(keep, 2 + k, row(out[3], fr[k]))
        put(keep, 4 + k, row(w, fr[k]))
        put(keep, 6 + k, row(d.loads, ALPHA + 2 * (0 if fr[k] == 0 else 1)))
    for q in range(3):
        _prescribe(out[1], d.Cth, fr, keep, 4, q)
        _prescribe(out[3], d.Crot[q], fr, keep, 6, q)
        _prescribe(out[2], d.Cp, fp, keep, 8, q)
    chol_solve9(d.U, d.dinv, out[2], out[1], out[3])
    if d.joint_ab.shape[0]:  # calls skipped when there is nothing to constrain (a stage's fixed cost)
        for k in range(3):  # Theta', W, then the positions; one compiled copy (``k < 2`` is not a literal)
            _constrain(out[(1, 3, 2)[k]], d.joint_ab, d.joint_q, d.Y[(1, 2, 0)[k]], d.Sinv[(1, 2, 0)[k]], k < 2, d.jr)
    if d.hinge_S.shape[0]:
        for field in range(2):  # one compiled copy for both fields (a loop index is not a literal)
            _constrain_hinges(out[1 + 2 * field], d, R, w, u1, field, 1.0)


@njit(cache=True, fastmath=FM, inline="always")
def _body_terms(d, w, R, out):
    """The end bodies' gyroscopic couple ``-W x J W``; off the end point their centripetal
    force ``-m R (W x (W x c))`` and their weight's moment ``c x R^T (f m g)`` (``f`` the
    distributed profile) into ``out``; returns the moment's power
    (:meth:`GalerkinBeamProblem._body_terms`)."""
    power = 0.0
    for k in range(d.body_row.shape[0]):
        r, pt, J = d.body_row[k], d.body_pt[k], d.body_J[k]
        W = row(w, r)
        JW = (dot(row(J, 0), W), dot(row(J, 1), W), dot(row(J, 2), W))
        put(out[3], r, sub(row(out[3], r), cross(W, JW)))
        c = row(d.body_c, k)
        if dot(c, c) != 0.0:
            put(out[2], r, axpy(-d.body_m[k], rot(R, pt, cross(W, cross(W, c))), row(out[2], r)))
            if d.has_q:
                mo = scale(d.loads[Q, 0], cross(c, rot_T(R, pt, row(d.body_wt, k))))
                put(out[3], r, add(row(out[3], r), mo))
                power += dot(mo, W)
    return power


@njit(cache=True, fastmath=False, inline="always")
def _hinge_responses(d, R, w, u1):
    """``cpl_Ph, cpl_Gh``: the couples' columns of ``cpl_P`` projected on the hinges'
    constraints at the state, ``x - Y S^-1 C x``, and their read-back on the bodies' rows
    (:meth:`GalerkinBeamProblem._responses`)."""
    P, G = d.cpl_Ph, d.cpl_Gh
    for l in range(P.shape[0]):
        for j in range(P.shape[1]):
            for q in range(3):
                P[l, j, q] = d.cpl_P[l, j, q]
        if l % 6 >= 3:  # a couple's column, on the W field (1, computed: not a literal)
            _constrain_hinges(P[l], d, R, w, u1, l % 6 // 3, 0.0)
    for l in range(P.shape[0]):
        for a in range(P.shape[0]):
            r = d.body_row[d.cpl_index[a // 6]]
            G[a, l] = P[l, r, a % 3] if (a % 6 < 3) == (l % 6 < 3) else 0.0


@njit(cache=True, fastmath=False, _nrt=False)
def _couple_bodies(d, R, w, u1, out):
    """The accelerations ``out[2], out[3]`` corrected for the mass blocks of the bodies off
    their end points, ``[[0, -m R hat(c)], [m hat(c) R^T, J - diag J]]``: ``x <- x - P z``
    with ``(I + C G) z = C U^T x`` (:meth:`GalerkinBeamProblem._couple_bodies`; with hinges
    ``P, G`` of :func:`_hinge_responses`)."""
    nk = d.cpl_index.shape[0]
    m6 = 6 * nk
    C, S, G, P = d.cpl_C, d.cpl_S, d.cpl_G, d.cpl_P
    if d.hinge_S.shape[0]:
        _hinge_responses(d, R, w, u1)
        G, P = d.cpl_Gh, d.cpl_Ph
    C[:] = 0.0
    for k in range(nk):
        i = d.cpl_index[k]
        r, pt, mass, c, J = d.body_row[i], d.body_pt[i], d.body_m[i], row(d.body_c, i), d.body_J[i]
        for b in range(3):  # column b of -m R hat(c): -m R (c x e_b)
            e = (1.0 if b == 0 else 0.0, 1.0 if b == 1 else 0.0, 1.0 if b == 2 else 0.0)
            col = scale(-mass, rot(R, pt, cross(c, e)))
            for a in range(3):
                C[6 * k + a, 6 * k + 3 + b] = col[a]
                C[6 * k + 3 + b, 6 * k + a] = col[a]
                if a != b:
                    C[6 * k + 3 + a, 6 * k + 3 + b] = J[a, b]
        for e in range(3):  # U^T x into the last column
            S[6 * k + e, m6 + 1] = out[2][r, e]
            S[6 * k + 3 + e, m6 + 1] = out[3][r, e]
    for a in range(m6):  # S[:, :m6 + 1] = [I + C G | C U^T x]
        x = 0.0
        for q in range(m6):
            x += C[a, q] * S[q, m6 + 1]
        for b in range(m6):
            s = 1.0 if a == b else 0.0
            for q in range(m6):
                s += C[a, q] * G[q, b]
            S[a, b] = s
        S[a, m6] = x
    dense_solve(S, m6)
    for l in range(m6):
        z = S[l, m6]
        f = out[2] if l % 6 < 3 else out[3]
        for j in range(f.shape[0]):
            for q in range(3):
                f[j, q] -= z * P[l, j, q]


@njit(cache=True, fastmath=False, inline="always")
def _column_dot(C, k, x, q):
    """``C[:, k] . x[:, q]``."""
    s = 0.0
    for j in range(x.shape[0]):
        s += C[j, k] * x[j, q]
    return s


@njit(cache=True, fastmath=False, inline="always")
def _coupling_force(d, idx, at, q):
    """Component ``q`` of the coupling force (``at = 0``) or couple (``at = 3``) of the body
    off its end point on row ``idx`` (:func:`_couple_bodies`' ``z``, left in ``cpl_S``), or 0."""
    m6 = 6 * d.cpl_index.shape[0]
    for k in range(d.cpl_index.shape[0]):
        if d.body_row[d.cpl_index[k]] == idx:
            return d.cpl_S[6 * k + at + q, m6]
    return 0.0


@njit(cache=True, fastmath=False, inline="always")
def _support_power(d, v, w, out):
    """Moving supports: the reaction (the residual of the supported row, with the coupling
    force of a body off its end point there) times the prescribed velocity."""
    power = 0.0
    for e in range(d.end_index.shape[0]):
        idx = d.end_index[e]
        for k in range(d.fp.shape[0]):
            if d.end_sliding[e] and d.fp[k] == idx:
                for q in range(3):
                    f = _column_dot(d.Cp, k, out[2], q) - d.keep[k, q] + _coupling_force(d, idx, 0, q)
                    power += f * v[idx, q]
        for k in range(d.fr.shape[0]):
            if d.end_moving[e] and d.fr[k] == idx:
                for q in range(3):
                    c = _column_dot(d.Crot[q], k, out[3], q) - d.keep[2 + k, q] + _coupling_force(d, idx, 3, q)
                    power += c * w[idx, q]
    return power


@njit(cache=True, fastmath=FM, inline="always")
def rates(c, v, w, R, K, u, out, d, kin):
    """Stage rate ``(4, n, 3)`` into ``out`` (the loads at the stage time already in the
    data); returns the power of the loads and supports minus the dissipation when the
    problem computes it, else 0. ``kin`` (:data:`~.adapters.KIN_NONE`, ``KIN_COMPUTE``,
    ``KIN_FROM_ACTION``): without it the rotational increment's rate ``out[1]`` is not
    formed (the leapfrog's kicks read the accelerations ``out[2], out[3]`` only); from the
    action's values, the state must be the one :func:`action` has just made from ``u`` with
    these data (the engine's stages after the first: the rate 7.0-7.4 us against 8.0-8.4 us
    at 118 points)."""
    B, j0, u1 = d.band, d.j0, u[1]
    for j in range(v.shape[0]):
        for q in range(3):
            out[0, j, q], out[1, j, q], out[2, j, q], out[3, j, q] = v[j, q], 0.0, 0.0, 0.0
    o1, o2, o3 = out[1], out[2], out[3]
    power = 0.0
    for i in range(R.shape[0]):
        if d.wf[i] == 0.0 and d.wa[i] == 0.0:
            continue
        dth, p, Mw, nw, pi = _point_forces(d, i, c, v, w, R, K, u1, kin)
        power += pi
        js = j0[i]
        for k in range(B.shape[2]):
            j, b0, b1 = js + k, B[0, i, k], B[1, i, k]
            if kin != KIN_NONE:
                put(o1, j, axpy(b0, dth, row(o1, j)))
            put(o2, j, axpy(-b1, nw, row(o2, j)))
            put(o3, j, add(row(o3, j), sub(scale(b0, p), scale(b1, Mw))))
    power += _point_loads(d, v, w, R, out)
    power += _body_terms(d, w, R, out)
    power += _hinge_springs(d, R, w, out)
    _solve(d, w, out, R, u1)
    if d.cpl_index.shape[0]:
        _couple_bodies(d, R, w, u1, out)
    if not d.power:
        return 0.0
    return power + _support_power(d, v, w, out)


# ====================================================================== entries from Python
# The entries (from Python, and from the engine's loops and the leapfrog through their
# addresses) inline the action and the stage rate, with their fast-math flags: the named data
# are then built from ``flat, head`` only where read, instead of passed whole to a compiled
# function (an RKMK4 step at n_ctrl 21: 19.0-19.4 us against 19.6-20.3 us), and the
# default kernel sets compile in about 3 s less (20.8-25.9 s against 24.2-29.4 s).
@njit(cache=True, fastmath=FM, _nrt=False)
def call_action(u, c, v, w, R, K, c2, v2, w2, R2, K2, flat, head):
    action(u, c, v, w, R, K, c2, v2, w2, R2, K2, unpack(flat, head))


@njit(cache=True, fastmath=FM, _nrt=False)
def call_rates(c, v, w, R, K, u, out, flat, head, kin):
    return rates(c, v, w, R, K, u, out, unpack(flat, head), kin)


# ====================================================================== engine kernels
ENGINE_KERNELS = ad.engine_kernels("beam_galerkin", 5)


# ====================================================================== splitting
# data: the engine's (:meth:`.adapters.KernelSet.compiled_problem`): the flat data, the load
# table, and the entries :func:`call_rates` and :func:`call_action` as first-class functions
@njit(cache=True, inline="always")
def _accelerations(data, t, y, zero, out):
    """The accelerations ``out[2], out[3]`` at ``(t, y)`` (a zero increment, without the
    rotational increment's rate); returns the power as :func:`rates`."""
    set_loads(data[ad.LOADS], data[ad.ROWS], data[ad.VECS], data[ad.PROFILES], t)
    return data[ad.RATES](y[0], y[1], y[2], y[3], y[4], zero, out, data[ad.FLAT], data[ad.HEAD], KIN_NONE)


@njit(cache=True, inline="always")
def _kick(y, acc, h):
    """Velocities ``v, W`` of ``y`` moved by ``h`` times the accelerations ``acc[2], acc[3]``."""
    v, w = y[1], y[2]
    for j in range(v.shape[0]):
        for q in range(3):
            v[j, q] += h * acc[2, j, q]
            w[j, q] += h * acc[3, j, q]


@njit(cache=True, fastmath=FM, inline="always")
def _synchronized_power(d, y, acc, scratch):
    """Power of the loads and supports at a state whose velocities are synchronized (after
    a substep's second kick), with the rates ``acc`` of its configuration (the supports'
    reactions): the distributed and point loads, the hinges' dampers, the distributed
    couple and the moving supports. The dissipation of ``tau > 0`` is not in it (the
    splitting driver refuses damped problems)."""
    v, w, R = y[1], y[2], y[3]
    power = _point_loads(d, v, w, R, scratch) + _hinge_springs(d, R, w, scratch)
    if d.has_m:
        for i in range(R.shape[0]):
            if d.wf[i] != 0.0:
                Om = window(d.band, 0, i, d.j0, w, 0)
                power += d.wf[i] * dot(rot_T(R, i, row(d.loads, MD)), Om)
    return power + _support_power(d, v, w, acc)


@njit(cache=True, inline="always")
def split_steps(data, y, y2, gammas, h, n, t, work, tmp):
    """``n`` steps of length ``h`` from ``(t, y)`` of the symmetric composition ``gammas`` of
    kick-drift-kick (Stormer-Verlet): a kick moves ``v, W`` by the accelerations of the stage
    rates at ``(t, y)``; a drift moves the configuration by the increment ``(h v, h W, 0, 0)``
    (``Theta' = W`` at a zero increment) through the action, exactly on the group. The
    accelerations at the end of a substep serve the next one's first kick. ``y`` (the
    result) and ``y2`` (work) are states of the compiled engine. When the problem computes
    the power of its loads, ``work[0]`` gains their work, the trapezoidal rule over the
    synchronized states of the substeps. ``tmp`` ``(4, 4, n, 3)`` holds the increment,
    the rates, a zero increment and a scratch load vector. Returns the rate evaluations.

    The stage rate and the action are called through their addresses (``data``'s
    first-class functions, the entries the engine's loops call), so this kernel compiles
    without their code and runs the machine code that ``liegroup-int compile`` cached for
    them (its first call after the default sets: 7.9 s of CPU against 9.7 s linking their
    code in; a step 3.0-3.1 us against 2.9 us on the pendulum p3 n20, the unpacking of the
    named data at each call)."""
    u, acc, zero, scratch = tmp[0], tmp[1], tmp[2], tmp[3]
    u[:] = 0.0
    zero[:] = 0.0
    m, ng = y[1].shape[0], gammas.shape[0]
    a, b = y, y2
    d = unpack(data[ad.FLAT], data[ad.HEAD])
    evals, odd, p0, hg, k = 0, False, 0.0, 0.0, -1
    for _ in range(n * ng + 1):  # k = -1: the accelerations and power at the start
        if k >= 0:
            hg = gammas[k] * h
            _kick(a, acc, 0.5 * hg)
            for j in range(m):
                for q in range(3):
                    u[0, j, q], u[1, j, q] = hg * a[1][j, q], hg * a[2][j, q]
            ad._action5(data, u, a, b)
            a, b, odd = b, a, not odd
            t += hg
        _accelerations(data, t, a, zero, acc)
        evals += 1
        if k >= 0:
            _kick(a, acc, 0.5 * hg)
        if d.power:
            p1 = _synchronized_power(d, a, acc, scratch)
            if k >= 0:
                work[0] += 0.5 * hg * (p0 + p1)
            p0 = p1
        k += 1
        if k == ng:
            ad.engine_end_step(data, a)
            k = 0
    if odd:  # an odd number of drifts: the result is in the work state
        ad._copy_state5(data, a, y)
    return evals


@njit(cache=True, _nrt=False, nogil=True)
def call_split_steps(data, y, y2, gammas, h, n, t, work, tmp):
    """:func:`split_steps` on the engine's data (the named data's fields are unpacked inside:
    two arrays to unbox at a call instead of the fields). Called through the entry compiled
    for the data's function types (:func:`~liegroup_int.integrators.engine.typed_entry`): a
    one-step call takes 16 us on the pendulum p3 n20, 3.0-3.1 us a step in a long call.
    Compiled without reference counting, which the loop would otherwise do on the arrays it
    takes out of tuples. It releases the GIL, as the engine's loops do."""
    return split_steps(data, y, y2, gammas, h, n, t, work, tmp)


STATE_FIELDS = ("c", "v", "w", "R", "K")


# ====================================================================== Python side
def _end_loads(pb, loads: np.ndarray, table: LoadTable) -> dict:
    """The end fields of :class:`GalerkinData`; the supports' accelerations into ``loads``."""
    for e_i, e in enumerate(pb.ends):
        if e.translation is not None:
            s, prof = e.translation.acceleration_profile()
            table.add_or_fix(loads, ACC + 2 * e_i, s * e.translation.unit_axis, prof)
        if e.motion is not None:
            s, prof = e.motion.acceleration_profile()
            table.add_or_fix(loads, ALPHA + 2 * e_i, s * (pb.gs.R0[e.point].T @ e.motion.unit_axis), prof)
    return {"end_index": np.array([e.index for e in pb.ends], dtype=np.int64),
            "end_moving": np.array([e.motion is not None for e in pb.ends], dtype=np.int64),
            "end_sliding": np.array([e.translation is not None for e in pb.ends], dtype=np.int64)}


def _point_data(pb, loads: np.ndarray, table: LoadTable) -> dict:
    """The loaded points' fields of :class:`GalerkinData`; their loads into ``loads``."""
    pls = pb.point_loads
    for k, (_, _, ld, _) in enumerate(pls):
        table.add_or_fix(loads, POINTS + 2 * k, ld.force, ld.force_profile)
        table.add_or_fix(loads, POINTS + 2 * k + 1, ld.couple, ld.couple_profile)
    cols = [(row, point, bool(np.any(ld.force)), bool(np.any(ld.couple)), bool(ld.follower))
            for row, point, ld, _ in pls]
    arr = np.array(cols, dtype=np.int64).reshape(len(pls), 5)
    return {**{f"point_{name}": np.ascontiguousarray(arr[:, k])
               for k, name in enumerate(("row", "pt", "force", "couple", "follower"))},
            "point_arm": c64(np.array([arm for *_, arm in pls], dtype=float).reshape(len(pls), 3))}


def _joint_data(pb) -> dict:
    """The joints' and the end bodies' fields of :class:`GalerkinData` (a ball joint's
    rotational rows are zero in ``Y`` and ``Sinv``)."""
    n, nj = pb.n, len(pb.joints)
    if nj:
        cons = [pb._constraints[k] for k in ("position", "theta", "rotation")]
        Y, Sinv = np.array([c[0] for c in cons]), np.array([c[1] for c in cons])
    else:
        Y, Sinv = np.zeros((3, 0, n, 3)), np.zeros((3, 0, 0))
    return {"joint_ab": np.array([(j[0], j[1]) for j in pb.joints], dtype=np.int64).reshape(nj, 2),
            "joint_q": np.array([j[3] for j in pb.joints], dtype=float).reshape(nj, 3, 3),
            "Y": c64(Y), "Sinv": c64(Sinv), "keep": np.zeros((10, 3)), "jr": np.zeros(3 * nj),
            **_body_data(pb), **_hinge_data(pb)}


def _body_data(pb) -> dict:
    """The end bodies' fields of :class:`GalerkinData` and those of their mass coupling."""
    bs, cp, n = pb.bodies, pb._coupling, pb.n
    k = len(cp.index) if cp is not None else 0
    return {"body_row": np.array([b.row for b in bs], dtype=np.int64),
            "body_pt": np.array([b.point for b in bs], dtype=np.int64),
            "body_m": c64([b.body.mass for b in bs]), "body_c": c64(np.array([b.c for b in bs]).reshape(-1, 3)),
            "body_J": c64(np.array([b.J for b in bs]).reshape(-1, 3, 3)),
            "body_wt": c64(np.array([b.weight for b in bs]).reshape(-1, 3)),
            "cpl_index": np.array(cp.index if cp is not None else (), dtype=np.int64),
            "cpl_P": c64(cp.P if cp is not None else np.zeros((0, n, 3))),
            "cpl_G": c64(cp.G if cp is not None else np.zeros((0, 0))),
            "cpl_C": np.zeros((6 * k, 6 * k)), "cpl_S": np.zeros((6 * k, 6 * k + 2)),
            "cpl_Ph": np.zeros((6 * k if pb.hinges else 0, n, 3)),
            "cpl_Gh": np.zeros((6 * k if pb.hinges else 0,) * 2)}


def _hinge_data(pb) -> dict:
    """The hinges' fields of :class:`GalerkinData`."""
    hs, n = pb.hinges, pb.n
    Z = np.array([[h.Z[f] for f in ("theta", "rotation")] for h in hs], dtype=float).reshape(12 * len(hs), n, 3)
    return {"hinge_ab": np.array([(h.a, h.b, h.point, h.point_b) for h in hs], dtype=np.int64).reshape(len(hs), 4),
            "hinge_E": c64(np.array([h.E for h in hs], dtype=float).reshape(len(hs), 2, 3)), "hinge_Z": c64(Z),
            "hinge_C": np.zeros((2 * len(hs), 2, 3)), "hinge_S": np.zeros((2 * len(hs), 2 * len(hs) + 1)),
            "hinge_axis": c64(np.array([h.axis for h in hs], dtype=float).reshape(len(hs), 3)),
            "hinge_Q": c64(np.array([h.Q for h in hs], dtype=float).reshape(len(hs), 3, 3)),
            "hinge_kc": c64(np.array([(h.stiffness, h.damping) for h in hs], dtype=float).reshape(len(hs), 2))}


def galerkin_data(pb):
    """``(GalerkinData, LoadTable)`` of a :class:`~..galerkin.GalerkinBeamProblem`."""
    gs, n = pb.gs, pb.n
    band, j0 = basis_windows([gs.B0, gs.B1], pb.space.degree + 1)
    loads, table = np.zeros((POINTS + 2 * len(pb.point_loads), 3)), LoadTable()
    table.add_or_fix(loads, Q, (1.0, 0.0, 0.0), pb.loads.distributed_profile)
    table.add_or_fix(loads, MD, pb.m_dist, pb.loads.distributed_profile)
    masses = (pb.mass_position, pb.mass_theta) + tuple(pb.mass_rotation)
    fp = np.flatnonzero(pb.mass_position.fixed).astype(np.int64)
    fr = np.flatnonzero(pb.mass_theta.fixed).astype(np.int64)
    U = c64([mm.factor for mm in masses])
    data = GalerkinData(
        band, j0, c64(gs.w_full), c64(gs.w_axial), c64(gs.gamma0), c64(gs.K0), c64(pb.CN), c64(pb.CM),
        c64(pb.Jm), c64(pb.load_vector), U, c64(1.0 / U[:, -1]), c64(pb.mass_position.coupling),
        c64(pb.mass_theta.coupling), c64(np.array([mm.coupling for mm in pb.mass_rotation]).reshape(3, n, fr.size)),
        fp, fr, series_table(), float(TAYLOR_THRESHOLD), float(pb.tau), bool(pb.has_quadrature), bool(pb.has_q),
        bool(pb.has_m), loads, **_end_loads(pb, loads, table), **_point_data(pb, loads, table), **_joint_data(pb),
        pts=np.zeros((10, gs.w_full.shape[0])))
    return data, table


class NumbaGalerkinKernels(ad.KernelSet):
    """The compiled kernels of one :class:`~..galerkin.GalerkinBeamProblem`."""

    data_cls, fields, rate_args = GalerkinData, STATE_FIELDS, (ad.KIN_COMPUTE,)

    def __init__(self, pb):
        data, table = galerkin_data(pb)
        super().__init__(data, table, pb.n)

    def kernels(self) -> tuple:
        return call_action, call_rates, ENGINE_KERNELS
