"""Compiled (numba) kernels of the beam plugin: ``BeamProblem(..., backend="numba")``.

Same mathematics as the NumPy path of :mod:`.problem` and :mod:`.kinematics`, fused into
one loop over the collocation points per call:

* :func:`action_kernel` (primal; :func:`action_mixed` for the mixed formulation): ``theta, theta_s, theta_ss`` at the collocation points from the
  control values (banded ``N0, N1, N2``), ``R <- exp(hat(theta)) R``, the curvature update
  (eqs. 52-53 of method.md section 1: ``K' = K + R^T J_r theta_s`` and its s-derivative,
  with ``B1 = B'/t`` and ``C1 = C'/t``), ``c, v, w`` plus their increments.
* :func:`rates_into`: ``c_s, c_ss, v_c, w_c, theta_c`` (banded matvecs), strains
  (plus ``tau`` times their rates with Kelvin-Voigt damping), resultants, balance
  residuals, enhanced-collocation terms at Neumann ends, ``dexpinv``, Dirichlet rows set
  to zero, all into a row-contiguous ``(n, 12)`` right-hand side whose forward (``L``)
  sweep runs in the same loop; then the backward (``U``) sweep writes the ``(4, n, 3)``
  rate (:func:`rates_into_mixed` for the mixed formulation).
* :func:`rotation_angle_kernel`: ``max |N0 u_theta|`` (the driver calls it every step).
* ``engine_*``: the kernels the compiled engine (:mod:`liegroup_int.integrators.engine`)
  runs its fixed-step and adaptive loops with (:data:`ENGINE_KERNELS`,
  :meth:`NumbaBeamKernels.compiled_problem`): stage rate with the loads' time profiles
  evaluated per stage time by :func:`profile_value`, action, Newton-Schulz end step,
  rotation angle, error scale; the state as the tuple ``(c, v, w, R, K, K_s)``.

SO(3) coefficients use the branch logic of :mod:`liegroup_int.groups.so3_coefficients`:
the 12-term Horner polynomial in ``theta**2`` with the same float coefficients
(``TAYLOR`` tables, passed in at run time, not frozen into the cached machine code) below
``TAYLOR_THRESHOLD`` (1 rad), the same closed forms at and above it.

Banded storage. ``N0, N1, N2`` are stored as ``(3, n, W)`` row windows with one start
column ``j0[i]`` per row: ``W`` is the widest row support of the union of their non-zero
patterns (``p + 1`` at the Greville points: 5 multiply-adds per row and field at p = 4),
windows kept inside ``[0, n)``; the construction checks that the windows hold every
non-zero entry.

``M_c`` solve. ``M_c = N0`` is the collocation matrix of the (rational) B-spline basis at
the Greville abscissae: totally positive (Karlin; for NURBS ``diag(1/W(u_i)) N diag(w_j)``
with positive weights stays totally positive), so Gaussian elimination *without*
pivoting exists, produces non-negative ``L`` and ``U`` and is backward stable because
``|L||U| = |L U| = M_c`` (de Boor & Pinkus, Linear Algebra Appl. 17, 1977). It is
factored once, in band form without fill-in; the factorization is checked (positive
pivots, non-negative factors up to round-off, small residual against the dense matrix)
and the dense inverse is used instead if a check fails. The solve costs
``12 n (lower + upper + 1)`` multiply-adds, linear in ``n``. A precomputed dense inverse
(``12 n^2``) is available too (``solver="dense"``); ``solver="auto"`` uses it only for
``n <= DENSE_MAX_N`` (0: measured, the banded solve is never slower, see the constant).
Checked against LAPACK ``gbtrf/gbtrs`` (partial pivoting) for p = 2..8, n up to 2001, on
straight, arch (NURBS) and helix geometries: factors non-negative, solutions equal to
2e-15 relative.

Data passing. A numba call costs ~0.12 us per array argument on top of ~0.3 us, so all
constant data (section constants, loads, series tables, reference strains/curvatures,
band matrices, LU factors, end data) live in one float array ``sf`` and one int array
``si`` with the offsets of :class:`NumbaBeamKernels` (``_H_*`` header slots). The end
force and couple (already multiplied by their time profiles) sit in ``sf`` too; the
Python wrapper rewrites them once per distinct stage time when a profile is not constant.

State arrays must be float64; C-contiguous arrays use the fast compiled specialization.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ...groups.kernels_numba import normalize_rotations as _newton_schulz
from ...groups.so3_coefficients import TAYLOR, TAYLOR_THRESHOLD
from ...integrators.engine import CompiledProblem, EngineKernels

#: Largest ``n_ctrl`` for which ``solver="auto"`` uses the dense inverse of ``M_c``.
#: Measured (cantilever p = 4, whole stage-rate kernel, best of 30 x 500 calls):
#: n = 5: banded 1.29 us / dense 1.47 us; 8: 1.56 / 1.51; 12: 1.81 / 2.08;
#: 16: 2.08 / 2.48; 31: 3.16 / 5.32; 61: 5.31 / 31.2; 121: 14.2 / 105.
#: The dense inverse never wins by more than timing noise, so ``auto`` is banded; the
#: dense inverse remains the fallback when the no-pivot factorization fails its checks.
DENSE_MAX_N = 0

_SERIES_KEYS = ("A", "B", "C", "D", "B1", "C1")
_IA, _IB, _IC, _ID, _IB1, _IC1 = range(6)

# ---- layout of the int array ``si`` (header) -----------------------------------------
_H_N, _H_W, _H_L, _H_U, _H_DENSE, _H_NE = 0, 1, 2, 3, 4, 5
_H_PRM, _H_SER, _H_GEO, _H_BAND, _H_LU, _H_MINV, _H_ENDF, _H_ENDI, _H_J0, _H_NT = range(6, 16)
_H_FORM = 16  # formulation: FORM_PRIMAL or FORM_MIXED
_H_QUAD = 17  # offset of the quadrature weights (n) in sf
_H_NJ, _H_JF, _H_JI = 18, 19, 20  # rigid joints: count, offsets of their float and int rows
_HEADER = 21
FORM_PRIMAL, FORM_MIXED = 0, 1
#: Columns of the stage work array ``x``: 12 right-hand sides, then (mixed only) the
#: resultant values n, m (6, solved in place into their control values), R^T c_s (3),
#: N (3), M (3) per point, and 6 scratch columns for the dense fallback solve.
_X_NM, _X_RC, _X_N, _X_M, _X_TMP, X_COLS = 12, 18, 21, 24, 27, 33
# (everything that may change outside this file - series length and coefficients, the
# threshold - is run-time data: numba's cache only watches this file)
# ---- layout of the parameter block ``prm`` inside ``sf`` -----------------------------
# distributed force q (3), gravity g (3) (the force per length at point i is q + mu_i g),
# distributed couple m_dist (3), has_q, has_m, threshold, tau (Kelvin-Voigt), power (1:
# compute the external power per stage, BeamProblem.quadrature_rate)
_P_Q, _P_G, _P_M, _P_HASQ, _P_HASM, _P_THR, _P_TAU, _P_POW = 0, 3, 6, 9, 10, 11, 12, 13
_N_PRM = 14
# ---- per-point block ``geo`` (n, _GEO): Gamma0 (3), K0 (3), K0_s (3), then the section at
# the point (one section per patch of a frame): CN (3), CM (3), Jm (3), mu
_G_CN, _G_CM, _G_JM, _G_MU, _GEO = 9, 12, 15, 18, 19
# per end: ints (index, fix_position, fix_rotation, force_neumann, moment_neumann, follower,
# prescribed rotation, prescribed displacement), floats (normal, factor, force(3) or the
# prescribed angular acceleration, couple(3), prescribed acceleration(3))
_NEI, _NEF = 8, 11
# per joint: ints (row a, row b), floats (factor_a, factor_b, force(3), couple(3))
_NJI, _NJF = 2, 8


# ====================================================================== scalar helpers
#: LLVM fast-math flags of the per-point kernels (action, stage rates and their scalar
#: helpers): only ``contract`` (a * b + c may become one FMA, rounded once); no
#: reassociation, no assumptions about NaN or infinities, so results differ from the NumPy
#: backend by round-off only. Time arithmetic, load profiles, combinations and the end
#: step keep plain IEEE operations (they must match the Python driver exactly).
_FM = {"contract"}


@njit(cache=True, fastmath=_FM, inline="always")
def _n_terms(t2, m):
    """Series terms needed below 1e-20 relative truncation: 5 for t < 0.05 rad, 7 for
    t < 0.25 rad (largest dropped term ~t^(2k) / (2k + 1)!), all ``m`` otherwise."""
    if t2 < 2.5e-3:
        return min(5, m)
    if t2 < 6.25e-2:
        return min(7, m)
    return m


@njit(cache=True, fastmath=_FM, inline="always")
def _horner(ser, k, t2):
    m = _n_terms(t2, ser.shape[1])
    out = ser[k, m - 1]
    for j in range(m - 2, -1, -1):
        out = out * t2 + ser[k, j]
    return out


@njit(cache=True, fastmath=_FM, inline="always")
def _coef_ABCB1C1(t, ser, thr):
    """``(A, B, C, B1, C1)`` at the angle ``t`` (series below ``thr``, closed form above).

    The five Horner recurrences run in one loop (independent chains, same arithmetic
    per chain as :func:`_horner`), which hides their latency.
    """
    if t < thr:
        t2 = t * t
        m = _n_terms(t2, ser.shape[1])
        a, b, c, b1, c1 = ser[_IA, m - 1], ser[_IB, m - 1], ser[_IC, m - 1], ser[_IB1, m - 1], ser[_IC1, m - 1]
        for j in range(m - 2, -1, -1):
            a = a * t2 + ser[_IA, j]
            b = b * t2 + ser[_IB, j]
            c = c * t2 + ser[_IC, j]
            b1 = b1 * t2 + ser[_IB1, j]
            c1 = c1 * t2 + ser[_IC1, j]
        return a, b, c, b1, c1
    s, co = math.sin(t), math.cos(t)
    sh = math.sin(0.5 * t) / t
    return (s / t, 2.0 * sh * sh, (t - s) / t ** 3.0,
            (t * s + 2.0 * co - 2.0) / t ** 4.0, (3.0 * s - 2.0 * t - t * co) / t ** 5.0)


@njit(cache=True, fastmath=_FM, inline="always")
def _coef_ABC(t, ser, thr):
    """``(A, B, C)`` at the angle ``t`` (what the mixed action needs; same branches)."""
    if t < thr:
        t2 = t * t
        m = _n_terms(t2, ser.shape[1])
        a, b, c = ser[_IA, m - 1], ser[_IB, m - 1], ser[_IC, m - 1]
        for j in range(m - 2, -1, -1):
            a = a * t2 + ser[_IA, j]
            b = b * t2 + ser[_IB, j]
            c = c * t2 + ser[_IC, j]
        return a, b, c
    s = math.sin(t)
    sh = math.sin(0.5 * t) / t
    return s / t, 2.0 * sh * sh, (t - s) / t ** 3.0


@njit(cache=True, fastmath=_FM, inline="always")
def _coef_D(t, ser, thr):
    """``D = (1 - (t/2) cot(t/2)) / t^2`` (dexpinv), same branches."""
    if t < thr:
        return _horner(ser, _ID, t * t)
    return (1.0 - 0.5 * t / math.tan(0.5 * t)) / t ** 2.0


@njit(cache=True, fastmath=_FM, inline="always")
def _cross(a0, a1, a2, b0, b1, b2):
    return a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0


# ====================================================================== data views
@njit(cache=True, fastmath=False, inline="always")
def _views(sf, si):
    n, W = si[_H_N], si[_H_W]
    nlu = si[_H_L] + si[_H_U] + 1
    ne = si[_H_NE]
    prm = sf[si[_H_PRM]:si[_H_PRM] + _N_PRM]
    nt = si[_H_NT]
    ser = sf[si[_H_SER]:si[_H_SER] + 6 * nt].reshape((6, nt))
    geo = sf[si[_H_GEO]:si[_H_GEO] + _GEO * n].reshape((n, _GEO))
    band = sf[si[_H_BAND]:si[_H_BAND] + 3 * n * W].reshape((3, n, W))
    lu = sf[si[_H_LU]:si[_H_LU] + n * nlu].reshape((n, nlu))
    nm = n if si[_H_DENSE] != 0 else 0
    minv = sf[si[_H_MINV]:si[_H_MINV] + nm * nm].reshape((nm, nm))
    endf = sf[si[_H_ENDF]:si[_H_ENDF] + _NEF * ne].reshape((ne, _NEF))
    endi = si[si[_H_ENDI]:si[_H_ENDI] + _NEI * ne].reshape((ne, _NEI))
    j0 = si[si[_H_J0]:si[_H_J0] + n]
    return prm, ser, geo, band, lu, minv, endf, endi, j0


@njit(cache=True, fastmath=False, inline="always")
def _quad_view(sf, si):
    """Collocation quadrature weights ``(n,)`` (``BeamProblem.quad``)."""
    return sf[si[_H_QUAD]:si[_H_QUAD] + si[_H_N]]


# ====================================================================== M_c solve
@njit(cache=True, fastmath=False)
def band_lu_nopivot(ab, lower, upper):
    """In-place banded LU without pivoting of ``ab[i, lower + j - i] = M[i, j]``.

    Afterwards the strictly lower part holds the multipliers of the unit lower factor
    ``L`` and the rest ``U``. No fill-in (no row exchanges). Returns the smallest pivot.
    (:func:`_factor_mc` then replaces the diagonal by the reciprocal pivots.)
    """
    n = ab.shape[0]
    pmin = np.inf
    for k in range(n):
        piv = ab[k, lower]
        if abs(piv) < pmin:
            pmin = abs(piv)
        for i in range(k + 1, min(n, k + lower + 1)):
            m = ab[i, lower + k - i] / piv
            ab[i, lower + k - i] = m
            for j in range(k + 1, min(n, k + upper + 1)):
                ab[i, lower + j - i] -= m * ab[k, lower + j - k]
    return pmin


@njit(cache=True, fastmath=False, inline="always")
def _forward_row(x, i, lu, lower):
    """Row ``i`` of the unit-lower sweep ``x <- L^-1 x`` (rows ``< i`` already done)."""
    for j in range(max(0, i - lower), i):
        m = lu[i, lower + j - i]
        if m != 0.0:
            for q in range(12):
                x[i, q] -= m * x[j, q]


@njit(cache=True, fastmath=False, inline="always")
def _finish_solve(x, lu, lower, upper, minv, dense, forward_done, out):
    """``out[f, :, d] = M_c^-1 x[:, 3 f + d]``; ``x`` ``(n, 12)`` is overwritten.

    Banded: forward sweep (unless ``forward_done``), then the backward sweep with ``U``
    (diagonal stored as reciprocal), scattering each finished row into ``out``.
    Dense: ``out = M_c^-1 x`` with the precomputed inverse.
    """
    n = x.shape[0]
    if dense:
        for i in range(n):
            for q in range(12):
                acc = 0.0
                for j in range(n):
                    acc += minv[i, j] * x[j, q]
                out[q // 3, i, q % 3] = acc
        return
    if not forward_done:
        for i in range(1, n):
            _forward_row(x, i, lu, lower)
    for i in range(n - 1, -1, -1):
        for j in range(i + 1, min(n, i + upper + 1)):
            m = lu[i, lower + j - i]
            if m != 0.0:
                for q in range(12):
                    x[i, q] -= m * x[j, q]
        r = lu[i, lower]
        for q in range(12):
            x[i, q] *= r
        for f in range(4):
            out[f, i, 0] = x[i, 3 * f]
            out[f, i, 1] = x[i, 3 * f + 1]
            out[f, i, 2] = x[i, 3 * f + 2]


@njit(cache=True, fastmath=False, inline="always")
def _forward_row_cols(x, i, lu, lower, q0, q1):
    """Row ``i`` of the unit-lower sweep on columns ``q0:q1`` of ``x``."""
    for j in range(max(0, i - lower), i):
        m = lu[i, lower + j - i]
        if m != 0.0:
            for q in range(q0, q1):
                x[i, q] -= m * x[j, q]


@njit(cache=True, fastmath=False)
def _solve_cols(x, lu, lower, upper, minv, dense, forward_done, q0, q1, tmp):
    """``x[:, q0:q1] <- M_c^-1 x[:, q0:q1]`` in place (banded sweeps, or the dense
    inverse through the scratch columns starting at ``tmp``)."""
    n = x.shape[0]
    if dense:
        for i in range(n):
            for q in range(q0, q1):
                acc = 0.0
                for j in range(n):
                    acc += minv[i, j] * x[j, q]
                x[i, tmp + q - q0] = acc
        for i in range(n):
            for q in range(q0, q1):
                x[i, q] = x[i, tmp + q - q0]
        return
    if not forward_done:
        for i in range(1, n):
            _forward_row_cols(x, i, lu, lower, q0, q1)
    for i in range(n - 1, -1, -1):
        for j in range(i + 1, min(n, i + upper + 1)):
            m = lu[i, lower + j - i]
            if m != 0.0:
                for q in range(q0, q1):
                    x[i, q] -= m * x[j, q]
        r = lu[i, lower]
        for q in range(q0, q1):
            x[i, q] *= r


@njit(cache=True, fastmath=False)
def solve_kernel(x, sf, si):
    """``M_c^-1`` on an increment-shaped array ``x`` ``(4, n, 3)``, in place."""
    prm, ser, geo, band, lu, minv, endf, endi, j0 = _views(sf, si)
    n = x.shape[1]
    ws = np.empty((n, 12))
    for i in range(n):
        for f in range(4):
            for d in range(3):
                ws[i, 3 * f + d] = x[f, i, d]
    _finish_solve(ws, lu, si[_H_L], si[_H_U], minv, si[_H_DENSE] != 0, False, x)


# ====================================================================== action
@njit(cache=True, fastmath=_FM, inline="always")
def _translate_point(u, c, v, w, c2, v2, w2, i):
    """``c, v, w`` of control point ``i`` plus their increments."""
    for d in range(3):
        c2[i, d] = c[i, d] + u[0, i, d]
        v2[i, d] = v[i, d] + u[2, i, d]
        w2[i, d] = w[i, d] + u[3, i, d]


@njit(cache=True, fastmath=_FM, inline="always")
def _rotate_point(R, R2, i, cA, cB, t0, t1, t2):
    """``R2[i] = exp(hat(theta)) R[i]`` with ``exp(hat(theta)) = I + A X + B X X``."""
    xx, yy, zz = t0, t1, t2
    e00 = 1.0 + cB * (-zz * zz - yy * yy)
    e11 = 1.0 + cB * (-zz * zz - xx * xx)
    e22 = 1.0 + cB * (-yy * yy - xx * xx)
    e01 = cA * -zz + cB * (xx * yy)
    e10 = cA * zz + cB * (xx * yy)
    e02 = cA * yy + cB * (xx * zz)
    e20 = cA * -yy + cB * (xx * zz)
    e12 = cA * -xx + cB * (yy * zz)
    e21 = cA * xx + cB * (yy * zz)
    r00, r01, r02 = R[i, 0, 0], R[i, 0, 1], R[i, 0, 2]
    r10, r11, r12 = R[i, 1, 0], R[i, 1, 1], R[i, 1, 2]
    r20, r21, r22 = R[i, 2, 0], R[i, 2, 1], R[i, 2, 2]
    R2[i, 0, 0] = e00 * r00 + e01 * r10 + e02 * r20
    R2[i, 0, 1] = e00 * r01 + e01 * r11 + e02 * r21
    R2[i, 0, 2] = e00 * r02 + e01 * r12 + e02 * r22
    R2[i, 1, 0] = e10 * r00 + e11 * r10 + e12 * r20
    R2[i, 1, 1] = e10 * r01 + e11 * r11 + e12 * r21
    R2[i, 1, 2] = e10 * r02 + e11 * r12 + e12 * r22
    R2[i, 2, 0] = e20 * r00 + e21 * r10 + e22 * r20
    R2[i, 2, 1] = e20 * r01 + e21 * r11 + e22 * r21
    R2[i, 2, 2] = e20 * r02 + e21 * r12 + e22 * r22


@njit(cache=True, fastmath=_FM)
def action_kernel(u, c, v, w, R, K, Ks, c2, v2, w2, R2, K2, Ks2, sf, si):
    """``Lambda(u, y)`` into the preallocated ``c2, v2, w2, R2, K2, Ks2``: with the
    curvature derivative update (eq. 53), which the primal balance laws read; the mixed
    formulation takes :func:`action_mixed`.

    Each formulation has its own kernels (no run-time branch between them), so that a run
    compiles only the one it uses."""
    prm, ser, geo, band, lu, minv, endf, endi, j0 = _views(sf, si)
    n, W = c.shape[0], band.shape[2]
    thr = prm[_P_THR]
    for i in range(n):
        _translate_point(u, c, v, w, c2, v2, w2, i)
        # theta and its s-derivatives at the collocation point
        t0 = t1 = t2 = s0 = s1 = s2 = q0 = q1 = q2 = 0.0
        js = j0[i]
        for k in range(W):
            j = js + k
            b0, b1, b2 = band[0, i, k], band[1, i, k], band[2, i, k]
            x0, x1, x2 = u[1, j, 0], u[1, j, 1], u[1, j, 2]
            t0 += b0 * x0
            t1 += b0 * x1
            t2 += b0 * x2
            s0 += b1 * x0
            s1 += b1 * x1
            s2 += b1 * x2
            q0 += b2 * x0
            q1 += b2 * x1
            q2 += b2 * x2
        ang = math.sqrt(t0 * t0 + t1 * t1 + t2 * t2)
        cA, cB, cC, cB1, cC1 = _coef_ABCB1C1(ang, ser, thr)
        _rotate_point(R, R2, i, cA, cB, t0, t1, t2)
        r00, r01, r02 = R[i, 0, 0], R[i, 0, 1], R[i, 0, 2]
        r10, r11, r12 = R[i, 1, 0], R[i, 1, 1], R[i, 1, 2]
        r20, r21, r22 = R[i, 2, 0], R[i, 2, 1], R[i, 2, 2]
        # g = J_r(theta) theta_s and g_s = d/ds g (kinematics.jr_and_derivative)
        tt = t0 * s0 + t1 * s1 + t2 * s2
        tg0, tg1, tg2 = _cross(t0, t1, t2, s0, s1, s2)
        ttg0, ttg1, ttg2 = _cross(t0, t1, t2, tg0, tg1, tg2)
        ts0, ts1, ts2 = _cross(t0, t1, t2, q0, q1, q2)
        a0, a1, a2 = _cross(s0, s1, s2, tg0, tg1, tg2)
        b0_, b1_, b2_ = _cross(t0, t1, t2, ts0, ts1, ts2)
        g0 = s0 - cB * tg0 + cC * ttg0
        g1 = s1 - cB * tg1 + cC * ttg1
        g2 = s2 - cB * tg2 + cC * ttg2
        h0 = q0 - cB1 * tt * tg0 - cB * ts0 + cC1 * tt * ttg0 + cC * (a0 + b0_)
        h1 = q1 - cB1 * tt * tg1 - cB * ts1 + cC1 * tt * ttg1 + cC * (a1 + b1_)
        h2 = q2 - cB1 * tt * tg2 - cB * ts2 + cC1 * tt * ttg2 + cC * (a2 + b2_)
        # x = R^T g, x_s = R^T g_s (old R); K' = K + x, K_s' = K_s - K x x + x_s
        x0 = r00 * g0 + r10 * g1 + r20 * g2
        x1 = r01 * g0 + r11 * g1 + r21 * g2
        x2 = r02 * g0 + r12 * g1 + r22 * g2
        y0 = r00 * h0 + r10 * h1 + r20 * h2
        y1 = r01 * h0 + r11 * h1 + r21 * h2
        y2 = r02 * h0 + r12 * h1 + r22 * h2
        k0, k1, k2 = K[i, 0], K[i, 1], K[i, 2]
        kx0, kx1, kx2 = _cross(k0, k1, k2, x0, x1, x2)
        K2[i, 0] = k0 + x0
        K2[i, 1] = k1 + x1
        K2[i, 2] = k2 + x2
        Ks2[i, 0] = Ks[i, 0] - kx0 + y0
        Ks2[i, 1] = Ks[i, 1] - kx1 + y1
        Ks2[i, 2] = Ks[i, 2] - kx2 + y2


@njit(cache=True, fastmath=_FM)
def action_mixed(u, c, v, w, R, K, Ks, c2, v2, w2, R2, K2, Ks2, sf, si):
    """The action without the curvature derivative (the mixed balance laws do not read
    ``K_s``, which is carried unchanged): no ``theta_ss``, ``B1``, ``C1``."""
    prm, ser, geo, band, lu, minv, endf, endi, j0 = _views(sf, si)
    n, W = c.shape[0], band.shape[2]
    thr = prm[_P_THR]
    for i in range(n):
        _translate_point(u, c, v, w, c2, v2, w2, i)
        t0 = t1 = t2 = s0 = s1 = s2 = 0.0
        js = j0[i]
        for k in range(W):
            j = js + k
            b0, b1 = band[0, i, k], band[1, i, k]
            x0, x1, x2 = u[1, j, 0], u[1, j, 1], u[1, j, 2]
            t0 += b0 * x0
            t1 += b0 * x1
            t2 += b0 * x2
            s0 += b1 * x0
            s1 += b1 * x1
            s2 += b1 * x2
        cA, cB, cC = _coef_ABC(math.sqrt(t0 * t0 + t1 * t1 + t2 * t2), ser, thr)
        _rotate_point(R, R2, i, cA, cB, t0, t1, t2)
        # K' = K + R^T J_r(theta) theta_s (old R)
        tg0, tg1, tg2 = _cross(t0, t1, t2, s0, s1, s2)
        ttg0, ttg1, ttg2 = _cross(t0, t1, t2, tg0, tg1, tg2)
        g0 = s0 - cB * tg0 + cC * ttg0
        g1 = s1 - cB * tg1 + cC * ttg1
        g2 = s2 - cB * tg2 + cC * ttg2
        K2[i, 0] = K[i, 0] + (R[i, 0, 0] * g0 + R[i, 1, 0] * g1 + R[i, 2, 0] * g2)
        K2[i, 1] = K[i, 1] + (R[i, 0, 1] * g0 + R[i, 1, 1] * g1 + R[i, 2, 1] * g2)
        K2[i, 2] = K[i, 2] + (R[i, 0, 2] * g0 + R[i, 1, 2] * g1 + R[i, 2, 2] * g2)
        Ks2[i, 0], Ks2[i, 1], Ks2[i, 2] = Ks[i, 0], Ks[i, 1], Ks[i, 2]


# ====================================================================== stage rates
@njit(cache=True, fastmath=False, inline="always")
def _joint_views(sf, si):
    nj = si[_H_NJ]
    jf = sf[si[_H_JF]:si[_H_JF] + _NJF * nj].reshape((nj, _NJF))
    ji = si[si[_H_JI]:si[_H_JI] + _NJI * nj].reshape((nj, _NJI))
    return jf, ji


@njit(cache=True, fastmath=_FM, inline="always")
def _spatial(R, i, c, x0, x1, x2):
    """Row ``c`` of ``R[i] (x0, x1, x2)``."""
    return R[i, c, 0] * x0 + R[i, c, 1] * x1 + R[i, c, 2] * x2


@njit(cache=True, fastmath=_FM, inline="always")
def _inertia(R, i, J0, J1, J2, c, d):
    """Entry ``(c, d)`` of the spatial inertia ``R[i] diag(J) R[i]^T``."""
    return R[i, c, 0] * J0 * R[i, d, 0] + R[i, c, 1] * J1 * R[i, d, 1] + R[i, c, 2] * J2 * R[i, d, 2]


@njit(cache=True, fastmath=_FM)
def joint_rows(x, v, w, R, sf, si, power):
    """Rigid joints (``BeamProblem._joint_rows``, docs/theory.md section 13): the rows
    ``a, b`` of each joint get one common rate, from their own rows in ``x`` (before any
    solve) and the joint's balance residuals ``r_n = n_b - n_a + F``, ``r_m = m_b - m_a + C``
    (material ``N, M`` read from ``x[:, _X_N]`` and ``x[:, _X_M]``). Returns the power of
    the joint loads. Scalars only: nothing is allocated."""
    geo = sf[si[_H_GEO]:si[_H_GEO] + _GEO * si[_H_N]].reshape((si[_H_N], _GEO))
    jf, ji = _joint_views(sf, si)
    pwr = 0.0
    for k in range(ji.shape[0]):
        a, b = ji[k, 0], ji[k, 1]
        fac = jf[k, 0] + jf[k, 1]
        Na0, Na1, Na2 = x[a, _X_N], x[a, _X_N + 1], x[a, _X_N + 2]
        Nb0, Nb1, Nb2 = x[b, _X_N], x[b, _X_N + 1], x[b, _X_N + 2]
        Ma0, Ma1, Ma2 = x[a, _X_M], x[a, _X_M + 1], x[a, _X_M + 2]
        Mb0, Mb1, Mb2 = x[b, _X_M], x[b, _X_M + 1], x[b, _X_M + 2]
        rn0 = _spatial(R, b, 0, Nb0, Nb1, Nb2) - _spatial(R, a, 0, Na0, Na1, Na2) + jf[k, 2]
        rn1 = _spatial(R, b, 1, Nb0, Nb1, Nb2) - _spatial(R, a, 1, Na0, Na1, Na2) + jf[k, 3]
        rn2 = _spatial(R, b, 2, Nb0, Nb1, Nb2) - _spatial(R, a, 2, Na0, Na1, Na2) + jf[k, 4]
        rm0 = _spatial(R, b, 0, Mb0, Mb1, Mb2) - _spatial(R, a, 0, Ma0, Ma1, Ma2) + jf[k, 5]
        rm1 = _spatial(R, b, 1, Mb0, Mb1, Mb2) - _spatial(R, a, 1, Ma0, Ma1, Ma2) + jf[k, 6]
        rm2 = _spatial(R, b, 2, Mb0, Mb1, Mb2) - _spatial(R, a, 2, Ma0, Ma1, Ma2) + jf[k, 7]
        if power:
            pwr += (jf[k, 2] * v[a, 0] + jf[k, 3] * v[a, 1] + jf[k, 4] * v[a, 2]
                    + jf[k, 5] * w[a, 0] + jf[k, 6] * w[a, 1] + jf[k, 7] * w[a, 2])
        # spatial inertias R diag(J) R^T of both sections (symmetric), and the torque sum
        Ja0, Ja1, Ja2 = geo[a, _G_JM], geo[a, _G_JM + 1], geo[a, _G_JM + 2]
        Jb0, Jb1, Jb2 = geo[b, _G_JM], geo[b, _G_JM + 1], geo[b, _G_JM + 2]
        a00, a01, a02 = _inertia(R, a, Ja0, Ja1, Ja2, 0, 0), _inertia(R, a, Ja0, Ja1, Ja2, 0, 1), _inertia(R, a, Ja0, Ja1, Ja2, 0, 2)
        a11, a12, a22 = _inertia(R, a, Ja0, Ja1, Ja2, 1, 1), _inertia(R, a, Ja0, Ja1, Ja2, 1, 2), _inertia(R, a, Ja0, Ja1, Ja2, 2, 2)
        b00, b01, b02 = _inertia(R, b, Jb0, Jb1, Jb2, 0, 0), _inertia(R, b, Jb0, Jb1, Jb2, 0, 1), _inertia(R, b, Jb0, Jb1, Jb2, 0, 2)
        b11, b12, b22 = _inertia(R, b, Jb0, Jb1, Jb2, 1, 1), _inertia(R, b, Jb0, Jb1, Jb2, 1, 2), _inertia(R, b, Jb0, Jb1, Jb2, 2, 2)
        xa0, xa1, xa2 = x[a, 9], x[a, 10], x[a, 11]
        xb0, xb1, xb2 = x[b, 9], x[b, 10], x[b, 11]
        t0 = a00 * xa0 + a01 * xa1 + a02 * xa2 + b00 * xb0 + b01 * xb1 + b02 * xb2 + fac * rm0
        t1 = a01 * xa0 + a11 * xa1 + a12 * xa2 + b01 * xb0 + b11 * xb1 + b12 * xb2 + fac * rm1
        t2 = a02 * xa0 + a12 * xa1 + a22 * xa2 + b02 * xb0 + b12 * xb1 + b22 * xb2 + fac * rm2
        s00, s01, s02, s11, s12, s22 = a00 + b00, a01 + b01, a02 + b02, a11 + b11, a12 + b12, a22 + b22
        # symmetric 3x3 solve by cofactors
        c00, c01, c02 = s11 * s22 - s12 * s12, s02 * s12 - s01 * s22, s01 * s12 - s02 * s11
        c11, c12, c22 = s00 * s22 - s02 * s02, s01 * s02 - s00 * s12, s00 * s11 - s01 * s01
        det = s00 * c00 + s01 * c01 + s02 * c02
        al0 = (c00 * t0 + c01 * t1 + c02 * t2) / det
        al1 = (c01 * t0 + c11 * t1 + c12 * t2) / det
        al2 = (c02 * t0 + c12 * t1 + c22 * t2) / det
        mu_a, mu_b = geo[a, _G_MU], geo[b, _G_MU]
        for d in range(3):
            x[a, d] = x[b, d] = 0.5 * (x[a, d] + x[b, d])
            x[a, 3 + d] = x[b, 3 + d] = 0.5 * (x[a, 3 + d] + x[b, 3 + d])
        rn = (rn0, rn1, rn2)
        for d in range(3):
            x[a, 6 + d] = x[b, 6 + d] = (mu_a * x[a, 6 + d] + mu_b * x[b, 6 + d] + fac * rn[d]) / (mu_a + mu_b)
        x[a, 9], x[a, 10], x[a, 11] = al0, al1, al2
        x[b, 9], x[b, 10], x[b, 11] = al0, al1, al2
    return pwr


@njit(cache=True, fastmath=_FM)
def rates_into(c, v, w, R, K, Ks, u, sf, si, fixp, fixr, x, out, pw):
    """Stage rate ``k = M_c^-1 rhs`` of the primal formulation into ``out`` ``(4, n, 3)``
    (``problem._rates`` + ``_solve``); the mixed formulation takes :func:`rates_into_mixed`.

    ``u`` is the stage increment (its rotational component gives ``theta_c`` for
    ``dexpinv``; zeros for the plain vector field), ``fixp, fixr`` come from
    :func:`dirichlet_rows`, ``x`` is an ``(n, 12)`` work array (overwritten with the
    right-hand sides). When the problem has loads that work or viscous damping, ``pw[0]``
    receives the power (``quadrature_rate``).

    The per-point tail (loads, enhanced collocation, ``dexpinv``, rows) is written out here
    and again in :func:`rates_into_mixed`: as one shared inline helper (3-tuples of scalars)
    it cost 13 % of the fused primal step (cantilever p = 4, n_ctrl = 31: 23.2 against
    20.5 us per step) and 10 % of the mixed one.
    """
    prm, ser, geo, band, lu, minv, endf, endi, j0 = _views(sf, si)
    n, W, ne = c.shape[0], band.shape[2], endf.shape[0]
    lower, dense = si[_H_L], si[_H_DENSE] != 0
    # x: right-hand sides, row i = (v, w, n_s/mu, tq) rows of point i; Dirichlet rows
    # (prescribed zero rates, method.md section 3) are zero per row and field
    qdx, qdy, qdz = prm[_P_Q], prm[_P_Q + 1], prm[_P_Q + 2]  # distributed force, and gravity
    gx, gy, gz = prm[_P_G], prm[_P_G + 1], prm[_P_G + 2]
    mx, my, mz = prm[_P_M], prm[_P_M + 1], prm[_P_M + 2]
    has_q, has_m = prm[_P_HASQ] != 0.0, prm[_P_HASM] != 0.0
    thr = prm[_P_THR]
    tau = prm[_P_TAU]
    power = prm[_P_POW] != 0.0
    quad = _quad_view(sf, si)
    power_sum = 0.0
    nj = si[_H_NJ]  # rigid joints: their rows are combined before the solve
    for i in range(n):
        CN0, CN1, CN2 = geo[i, _G_CN], geo[i, _G_CN + 1], geo[i, _G_CN + 2]  # the section at point i
        CM0, CM1, CM2 = geo[i, _G_CM], geo[i, _G_CM + 1], geo[i, _G_CM + 2]
        J0, J1, J2 = geo[i, _G_JM], geo[i, _G_JM + 1], geo[i, _G_JM + 2]
        mu = geo[i, _G_MU]
        qx, qy, qz = qdx + mu * gx, qdy + mu * gy, qdz + mu * gz
        cs0 = cs1 = cs2 = css0 = css1 = css2 = 0.0
        vc0 = vc1 = vc2 = wc0 = wc1 = wc2 = th0 = th1 = th2 = 0.0
        js = j0[i]
        for k in range(W):
            j = js + k
            b0, b1, b2 = band[0, i, k], band[1, i, k], band[2, i, k]
            x0, x1, x2 = c[j, 0], c[j, 1], c[j, 2]
            cs0 += b1 * x0
            cs1 += b1 * x1
            cs2 += b1 * x2
            css0 += b2 * x0
            css1 += b2 * x1
            css2 += b2 * x2
            vc0 += b0 * v[j, 0]
            vc1 += b0 * v[j, 1]
            vc2 += b0 * v[j, 2]
            wc0 += b0 * w[j, 0]
            wc1 += b0 * w[j, 1]
            wc2 += b0 * w[j, 2]
            th0 += b0 * u[1, j, 0]
            th1 += b0 * u[1, j, 1]
            th2 += b0 * u[1, j, 2]
        r00, r01, r02 = R[i, 0, 0], R[i, 0, 1], R[i, 0, 2]
        r10, r11, r12 = R[i, 1, 0], R[i, 1, 1], R[i, 1, 2]
        r20, r21, r22 = R[i, 2, 0], R[i, 2, 1], R[i, 2, 2]
        k0, k1, k2 = K[i, 0], K[i, 1], K[i, 2]
        # strains (kinematics.strains)
        rc0 = r00 * cs0 + r10 * cs1 + r20 * cs2
        rc1 = r01 * cs0 + r11 * cs1 + r21 * cs2
        rc2 = r02 * cs0 + r12 * cs1 + r22 * cs2
        ga0, ga1, ga2 = rc0 - geo[i, 0], rc1 - geo[i, 1], rc2 - geo[i, 2]
        kr0, kr1, kr2 = _cross(k0, k1, k2, rc0, rc1, rc2)
        gs0 = (r00 * css0 + r10 * css1 + r20 * css2) - kr0
        gs1 = (r01 * css0 + r11 * css1 + r21 * css2) - kr1
        gs2 = (r02 * css0 + r12 * css1 + r22 * css2) - kr2
        km0, km1, km2 = k0 - geo[i, 3], k1 - geo[i, 4], k2 - geo[i, 5]
        kms0, kms1, kms2 = Ks[i, 0] - geo[i, 6], Ks[i, 1] - geo[i, 7], Ks[i, 2] - geo[i, 8]
        if tau != 0.0:  # Kelvin-Voigt (problem._add_strain_rates): strains + tau * rates
            vs0 = vs1 = vs2 = vss0 = vss1 = vss2 = 0.0
            ws0 = ws1 = ws2 = wss0 = wss1 = wss2 = 0.0
            for k in range(W):
                j = js + k
                b1, b2 = band[1, i, k], band[2, i, k]
                vs0 += b1 * v[j, 0]
                vs1 += b1 * v[j, 1]
                vs2 += b1 * v[j, 2]
                vss0 += b2 * v[j, 0]
                vss1 += b2 * v[j, 1]
                vss2 += b2 * v[j, 2]
                ws0 += b1 * w[j, 0]
                ws1 += b1 * w[j, 1]
                ws2 += b1 * w[j, 2]
                wss0 += b2 * w[j, 0]
                wss1 += b2 * w[j, 1]
                wss2 += b2 * w[j, 2]
            # dGamma/dt = R^T (v_s - w x c_s)
            h0, h1, h2 = _cross(wc0, wc1, wc2, cs0, cs1, cs2)
            h0, h1, h2 = vs0 - h0, vs1 - h1, vs2 - h2
            gd0 = r00 * h0 + r10 * h1 + r20 * h2
            gd1 = r01 * h0 + r11 * h1 + r21 * h2
            gd2 = r02 * h0 + r12 * h1 + r22 * h2
            # d/ds dGamma/dt = R^T (v_ss - w_s x c_s - w x c_ss) - K x dGamma/dt
            h0, h1, h2 = _cross(ws0, ws1, ws2, cs0, cs1, cs2)
            g0, g1, g2 = _cross(wc0, wc1, wc2, css0, css1, css2)
            h0, h1, h2 = vss0 - h0 - g0, vss1 - h1 - g1, vss2 - h2 - g2
            g0, g1, g2 = _cross(k0, k1, k2, gd0, gd1, gd2)
            gds0 = r00 * h0 + r10 * h1 + r20 * h2 - g0
            gds1 = r01 * h0 + r11 * h1 + r21 * h2 - g1
            gds2 = r02 * h0 + r12 * h1 + r22 * h2 - g2
            # dK/dt = R^T w_s, d/ds dK/dt = R^T w_ss - K x dK/dt
            kd0 = r00 * ws0 + r10 * ws1 + r20 * ws2
            kd1 = r01 * ws0 + r11 * ws1 + r21 * ws2
            kd2 = r02 * ws0 + r12 * ws1 + r22 * ws2
            if power:  # viscous dissipation tau (dGamma . C_N dGamma + dK . C_M dK), per length
                power_sum -= quad[i] * tau * (CN0 * gd0 * gd0 + CN1 * gd1 * gd1 + CN2 * gd2 * gd2
                                              + CM0 * kd0 * kd0 + CM1 * kd1 * kd1 + CM2 * kd2 * kd2)
            g0, g1, g2 = _cross(k0, k1, k2, kd0, kd1, kd2)
            kds0 = r00 * wss0 + r10 * wss1 + r20 * wss2 - g0
            kds1 = r01 * wss0 + r11 * wss1 + r21 * wss2 - g1
            kds2 = r02 * wss0 + r12 * wss1 + r22 * wss2 - g2
            ga0, ga1, ga2 = ga0 + tau * gd0, ga1 + tau * gd1, ga2 + tau * gd2
            gs0, gs1, gs2 = gs0 + tau * gds0, gs1 + tau * gds1, gs2 + tau * gds2
            km0, km1, km2 = km0 + tau * kd0, km1 + tau * kd1, km2 + tau * kd2
            kms0, kms1, kms2 = kms0 + tau * kds0, kms1 + tau * kds1, kms2 + tau * kds2
        # resultants (material frame)
        N0_, N1_, N2_ = CN0 * ga0, CN1 * ga1, CN2 * ga2
        M0_, M1_, M2_ = CM0 * km0, CM1 * km1, CM2 * km2
        if nj > 0:
            x[i, _X_N], x[i, _X_N + 1], x[i, _X_N + 2] = N0_, N1_, N2_
            x[i, _X_M], x[i, _X_M + 1], x[i, _X_M + 2] = M0_, M1_, M2_
        # n_s = R (K x N + CN Gamma_s)
        a0, a1, a2 = _cross(k0, k1, k2, N0_, N1_, N2_)
        a0 += CN0 * gs0
        a1 += CN1 * gs1
        a2 += CN2 * gs2
        ns0 = r00 * a0 + r01 * a1 + r02 * a2
        ns1 = r10 * a0 + r11 * a1 + r12 * a2
        ns2 = r20 * a0 + r21 * a1 + r22 * a2
        # tq = -Om x (J Om) + K x M + CM KM_s + (R^T c_s) x N
        om0 = r00 * wc0 + r10 * wc1 + r20 * wc2
        om1 = r01 * wc0 + r11 * wc1 + r21 * wc2
        om2 = r02 * wc0 + r12 * wc1 + r22 * wc2
        p0, p1, p2 = _cross(om0, om1, om2, J0 * om0, J1 * om1, J2 * om2)
        e0, e1, e2 = _cross(k0, k1, k2, M0_, M1_, M2_)
        f0, f1, f2 = _cross(rc0, rc1, rc2, N0_, N1_, N2_)
        tq0 = -p0 + e0 + CM0 * kms0 + f0
        tq1 = -p1 + e1 + CM1 * kms1 + f1
        tq2 = -p2 + e2 + CM2 * kms2 + f2
        if has_q:
            ns0 += qx
            ns1 += qy
            ns2 += qz
        if has_m:
            tq0 += r00 * mx + r10 * my + r20 * mz
            tq1 += r01 * mx + r11 * my + r21 * mz
            tq2 += r02 * mx + r12 * my + r22 * mz
        if power and (has_q or has_m):  # int (q . v + m_d . omega) ds by the collocation quadrature
            power_sum += quad[i] * (qx * vc0 + qy * vc1 + qz * vc2 + mx * wc0 + my * wc1 + mz * wc2)
        # enhanced collocation at Neumann ends
        moving = -1
        sliding = -1
        for e in range(ne):
            if endi[e, 0] != i:
                continue
            nrm, fac = endf[e, 0], endf[e, 1]
            if endi[e, 7] != 0:  # a translating support: prescribed acceleration in endf[e, 8:11]
                sliding = e
                if power:  # the support's force nrm n on the end's velocity
                    power_sum += nrm * ((r00 * N0_ + r01 * N1_ + r02 * N2_) * vc0 + (r10 * N0_ + r11 * N1_ + r12 * N2_) * vc1
                                        + (r20 * N0_ + r21 * N1_ + r22 * N2_) * vc2)
            if endi[e, 6] != 0:  # a moving support: prescribed angular acceleration in endf[e, 2:5]
                moving = e
                if power:  # the support's couple nrm m on the end's angular velocity
                    power_sum += nrm * ((r00 * M0_ + r01 * M1_ + r02 * M2_) * wc0 + (r10 * M0_ + r11 * M1_ + r12 * M2_) * wc1
                                        + (r20 * M0_ + r21 * M1_ + r22 * M2_) * wc2)
                continue
            lf0, lf1, lf2, m0, m1, m2 = endf[e, 2], endf[e, 3], endf[e, 4], endf[e, 5], endf[e, 6], endf[e, 7]
            if endi[e, 5] != 0:  # follower loads: material components, turned by R
                lf0, lf1, lf2 = (r00 * lf0 + r01 * lf1 + r02 * lf2, r10 * lf0 + r11 * lf1 + r12 * lf2,
                                 r20 * lf0 + r21 * lf1 + r22 * lf2)
                m0, m1, m2 = r00 * m0 + r01 * m1 + r02 * m2, r10 * m0 + r11 * m1 + r12 * m2, r20 * m0 + r21 * m1 + r22 * m2
            if power:  # end loads (zero where absent) on the end velocities
                power_sum += lf0 * vc0 + lf1 * vc1 + lf2 * vc2 + m0 * wc0 + m1 * wc1 + m2 * wc2
            if endi[e, 3] != 0:
                rn0 = r00 * N0_ + r01 * N1_ + r02 * N2_
                rn1 = r10 * N0_ + r11 * N1_ + r12 * N2_
                rn2 = r20 * N0_ + r21 * N1_ + r22 * N2_
                ns0 += fac * (lf0 - nrm * rn0)
                ns1 += fac * (lf1 - nrm * rn1)
                ns2 += fac * (lf2 - nrm * rn2)
            if endi[e, 4] != 0:
                mc0 = r00 * m0 + r10 * m1 + r20 * m2
                mc1 = r01 * m0 + r11 * m1 + r21 * m2
                mc2 = r02 * m0 + r12 * m1 + r22 * m2
                tq0 += fac * (mc0 - nrm * M0_)
                tq1 += fac * (mc1 - nrm * M1_)
                tq2 += fac * (mc2 - nrm * M2_)
        # right-hand sides (Dirichlet rows: zero)
        ang = math.sqrt(th0 * th0 + th1 * th1 + th2 * th2)
        cD = _coef_D(ang, ser, thr)
        xv0, xv1, xv2 = _cross(th0, th1, th2, wc0, wc1, wc2)
        xx0, xx1, xx2 = _cross(th0, th1, th2, xv0, xv1, xv2)
        z0, z1, z2 = tq0 / J0, tq1 / J1, tq2 / J2
        if fixp[i]:
            x[i, 0] = x[i, 1] = x[i, 2] = x[i, 6] = x[i, 7] = x[i, 8] = 0.0
        else:
            x[i, 0], x[i, 1], x[i, 2] = vc0, vc1, vc2
            x[i, 6], x[i, 7], x[i, 8] = ns0 / mu, ns1 / mu, ns2 / mu
            if sliding >= 0:
                x[i, 6], x[i, 7], x[i, 8] = endf[sliding, 8], endf[sliding, 9], endf[sliding, 10]
        if fixr[i]:
            x[i, 3] = x[i, 4] = x[i, 5] = x[i, 9] = x[i, 10] = x[i, 11] = 0.0
        else:
            x[i, 3] = wc0 - 0.5 * xv0 + cD * xx0
            x[i, 4] = wc1 - 0.5 * xv1 + cD * xx1
            x[i, 5] = wc2 - 0.5 * xv2 + cD * xx2
            x[i, 9] = r00 * z0 + r01 * z1 + r02 * z2
            x[i, 10] = r10 * z0 + r11 * z1 + r12 * z2
            x[i, 11] = r20 * z0 + r21 * z1 + r22 * z2
            if moving >= 0:
                x[i, 9], x[i, 10], x[i, 11] = endf[moving, 2], endf[moving, 3], endf[moving, 4]
        if not dense and nj == 0:  # forward sweep of the banded solve, fused (rows < i are final)
            _forward_row(x, i, lu, lower)
    if nj > 0:
        power_sum += joint_rows(x, v, w, R, sf, si, power)
    _finish_solve(x, lu, lower, si[_H_U], minv, dense, nj == 0, out)
    pw[0] = power_sum


@njit(cache=True, fastmath=_FM)
def rates_into_mixed(c, v, w, R, K, u, sf, si, fixp, fixr, x, out, pw):
    """Stage rate of the mixed formulation (``BeamProblem._rates`` with
    ``formulation="mixed"``) into ``out`` ``(4, n, 3)``; ``x`` is the ``(n, X_COLS)``
    work array.

    Pass 1, per point: ``R^T c_s``, strains (plus ``tau`` times their rates), material
    resultants ``N, M`` and spatial ``n = R N, m = R M``, whose forward sweep through
    ``M_c`` runs in the same loop; then the backward sweep gives the resultant control
    values. Pass 2, per point: their s-derivatives ``N1 n_hat, N1 m_hat``, the balance
    laws, enhanced collocation at Neumann ends, ``dexpinv``, Dirichlet rows, and the
    forward sweep of the final solve.
    """
    prm, ser, geo, band, lu, minv, endf, endi, j0 = _views(sf, si)
    n, W, ne = c.shape[0], band.shape[2], endf.shape[0]
    lower, upper, dense = si[_H_L], si[_H_U], si[_H_DENSE] != 0
    qdx, qdy, qdz = prm[_P_Q], prm[_P_Q + 1], prm[_P_Q + 2]  # distributed force, and gravity
    gx, gy, gz = prm[_P_G], prm[_P_G + 1], prm[_P_G + 2]
    mx, my, mz = prm[_P_M], prm[_P_M + 1], prm[_P_M + 2]
    has_q, has_m = prm[_P_HASQ] != 0.0, prm[_P_HASM] != 0.0
    thr = prm[_P_THR]
    tau = prm[_P_TAU]
    power = prm[_P_POW] != 0.0
    quad = _quad_view(sf, si)
    power_sum = 0.0
    nj = si[_H_NJ]  # rigid joints: their rows are combined before the solve
    # ---- pass 1: pointwise constitutive resultants
    for i in range(n):
        CN0, CN1, CN2 = geo[i, _G_CN], geo[i, _G_CN + 1], geo[i, _G_CN + 2]  # the section at point i
        CM0, CM1, CM2 = geo[i, _G_CM], geo[i, _G_CM + 1], geo[i, _G_CM + 2]
        J0, J1, J2 = geo[i, _G_JM], geo[i, _G_JM + 1], geo[i, _G_JM + 2]
        mu = geo[i, _G_MU]
        qx, qy, qz = qdx + mu * gx, qdy + mu * gy, qdz + mu * gz
        cs0 = cs1 = cs2 = 0.0
        js = j0[i]
        for k in range(W):
            j = js + k
            b1 = band[1, i, k]
            cs0 += b1 * c[j, 0]
            cs1 += b1 * c[j, 1]
            cs2 += b1 * c[j, 2]
        r00, r01, r02 = R[i, 0, 0], R[i, 0, 1], R[i, 0, 2]
        r10, r11, r12 = R[i, 1, 0], R[i, 1, 1], R[i, 1, 2]
        r20, r21, r22 = R[i, 2, 0], R[i, 2, 1], R[i, 2, 2]
        rc0 = r00 * cs0 + r10 * cs1 + r20 * cs2
        rc1 = r01 * cs0 + r11 * cs1 + r21 * cs2
        rc2 = r02 * cs0 + r12 * cs1 + r22 * cs2
        ga0, ga1, ga2 = rc0 - geo[i, 0], rc1 - geo[i, 1], rc2 - geo[i, 2]
        km0, km1, km2 = K[i, 0] - geo[i, 3], K[i, 1] - geo[i, 4], K[i, 2] - geo[i, 5]
        if tau != 0.0:  # Kelvin-Voigt (kinematics.strain_rates): strains + tau * rates
            vs0 = vs1 = vs2 = ws0 = ws1 = ws2 = wc0 = wc1 = wc2 = 0.0
            for k in range(W):
                j = js + k
                b0, b1 = band[0, i, k], band[1, i, k]
                vs0 += b1 * v[j, 0]
                vs1 += b1 * v[j, 1]
                vs2 += b1 * v[j, 2]
                ws0 += b1 * w[j, 0]
                ws1 += b1 * w[j, 1]
                ws2 += b1 * w[j, 2]
                wc0 += b0 * w[j, 0]
                wc1 += b0 * w[j, 1]
                wc2 += b0 * w[j, 2]
            h0, h1, h2 = _cross(wc0, wc1, wc2, cs0, cs1, cs2)
            h0, h1, h2 = vs0 - h0, vs1 - h1, vs2 - h2
            gd0 = r00 * h0 + r10 * h1 + r20 * h2
            gd1 = r01 * h0 + r11 * h1 + r21 * h2
            gd2 = r02 * h0 + r12 * h1 + r22 * h2
            kd0 = r00 * ws0 + r10 * ws1 + r20 * ws2
            kd1 = r01 * ws0 + r11 * ws1 + r21 * ws2
            kd2 = r02 * ws0 + r12 * ws1 + r22 * ws2
            ga0 += tau * gd0
            ga1 += tau * gd1
            ga2 += tau * gd2
            km0 += tau * kd0
            km1 += tau * kd1
            km2 += tau * kd2
            if power:  # viscous dissipation tau (dGamma . C_N dGamma + dK . C_M dK), per length
                power_sum -= quad[i] * tau * (CN0 * gd0 * gd0 + CN1 * gd1 * gd1 + CN2 * gd2 * gd2
                                              + CM0 * kd0 * kd0 + CM1 * kd1 * kd1 + CM2 * kd2 * kd2)
        N0_, N1_, N2_ = CN0 * ga0, CN1 * ga1, CN2 * ga2
        M0_, M1_, M2_ = CM0 * km0, CM1 * km1, CM2 * km2
        x[i, _X_NM] = r00 * N0_ + r01 * N1_ + r02 * N2_
        x[i, _X_NM + 1] = r10 * N0_ + r11 * N1_ + r12 * N2_
        x[i, _X_NM + 2] = r20 * N0_ + r21 * N1_ + r22 * N2_
        x[i, _X_NM + 3] = r00 * M0_ + r01 * M1_ + r02 * M2_
        x[i, _X_NM + 4] = r10 * M0_ + r11 * M1_ + r12 * M2_
        x[i, _X_NM + 5] = r20 * M0_ + r21 * M1_ + r22 * M2_
        x[i, _X_RC], x[i, _X_RC + 1], x[i, _X_RC + 2] = rc0, rc1, rc2
        x[i, _X_N], x[i, _X_N + 1], x[i, _X_N + 2] = N0_, N1_, N2_
        x[i, _X_M], x[i, _X_M + 1], x[i, _X_M + 2] = M0_, M1_, M2_
        if not dense:
            _forward_row_cols(x, i, lu, lower, _X_NM, _X_NM + 6)
    _solve_cols(x, lu, lower, upper, minv, dense, True, _X_NM, _X_NM + 6, _X_TMP)
    # ---- pass 2: balance laws with the spline derivatives of the resultants
    for i in range(n):
        CN0, CN1, CN2 = geo[i, _G_CN], geo[i, _G_CN + 1], geo[i, _G_CN + 2]  # the section at point i
        CM0, CM1, CM2 = geo[i, _G_CM], geo[i, _G_CM + 1], geo[i, _G_CM + 2]
        J0, J1, J2 = geo[i, _G_JM], geo[i, _G_JM + 1], geo[i, _G_JM + 2]
        mu = geo[i, _G_MU]
        qx, qy, qz = qdx + mu * gx, qdy + mu * gy, qdz + mu * gz
        vc0 = vc1 = vc2 = wc0 = wc1 = wc2 = th0 = th1 = th2 = 0.0
        ns0 = ns1 = ns2 = ms0 = ms1 = ms2 = 0.0
        js = j0[i]
        for k in range(W):
            j = js + k
            b0, b1 = band[0, i, k], band[1, i, k]
            vc0 += b0 * v[j, 0]
            vc1 += b0 * v[j, 1]
            vc2 += b0 * v[j, 2]
            wc0 += b0 * w[j, 0]
            wc1 += b0 * w[j, 1]
            wc2 += b0 * w[j, 2]
            th0 += b0 * u[1, j, 0]
            th1 += b0 * u[1, j, 1]
            th2 += b0 * u[1, j, 2]
            ns0 += b1 * x[j, _X_NM]
            ns1 += b1 * x[j, _X_NM + 1]
            ns2 += b1 * x[j, _X_NM + 2]
            ms0 += b1 * x[j, _X_NM + 3]
            ms1 += b1 * x[j, _X_NM + 4]
            ms2 += b1 * x[j, _X_NM + 5]
        r00, r01, r02 = R[i, 0, 0], R[i, 0, 1], R[i, 0, 2]
        r10, r11, r12 = R[i, 1, 0], R[i, 1, 1], R[i, 1, 2]
        r20, r21, r22 = R[i, 2, 0], R[i, 2, 1], R[i, 2, 2]
        rc0, rc1, rc2 = x[i, _X_RC], x[i, _X_RC + 1], x[i, _X_RC + 2]
        N0_, N1_, N2_ = x[i, _X_N], x[i, _X_N + 1], x[i, _X_N + 2]
        M0_, M1_, M2_ = x[i, _X_M], x[i, _X_M + 1], x[i, _X_M + 2]
        # tq = R^T m_s - Om x (J Om) + (R^T c_s) x N
        om0 = r00 * wc0 + r10 * wc1 + r20 * wc2
        om1 = r01 * wc0 + r11 * wc1 + r21 * wc2
        om2 = r02 * wc0 + r12 * wc1 + r22 * wc2
        p0, p1, p2 = _cross(om0, om1, om2, J0 * om0, J1 * om1, J2 * om2)
        f0, f1, f2 = _cross(rc0, rc1, rc2, N0_, N1_, N2_)
        tq0 = (r00 * ms0 + r10 * ms1 + r20 * ms2) - p0 + f0
        tq1 = (r01 * ms0 + r11 * ms1 + r21 * ms2) - p1 + f1
        tq2 = (r02 * ms0 + r12 * ms1 + r22 * ms2) - p2 + f2
        if has_q:
            ns0 += qx
            ns1 += qy
            ns2 += qz
        if has_m:
            tq0 += r00 * mx + r10 * my + r20 * mz
            tq1 += r01 * mx + r11 * my + r21 * mz
            tq2 += r02 * mx + r12 * my + r22 * mz
        if power and (has_q or has_m):  # int (q . v + m_d . omega) ds by the collocation quadrature
            power_sum += quad[i] * (qx * vc0 + qy * vc1 + qz * vc2 + mx * wc0 + my * wc1 + mz * wc2)
        moving = -1
        sliding = -1
        for e in range(ne):  # enhanced collocation at Neumann ends
            if endi[e, 0] != i:
                continue
            nrm, fac = endf[e, 0], endf[e, 1]
            if endi[e, 7] != 0:  # a translating support: prescribed acceleration in endf[e, 8:11]
                sliding = e
                if power:  # the support's force nrm n on the end's velocity
                    power_sum += nrm * ((r00 * N0_ + r01 * N1_ + r02 * N2_) * vc0 + (r10 * N0_ + r11 * N1_ + r12 * N2_) * vc1
                                        + (r20 * N0_ + r21 * N1_ + r22 * N2_) * vc2)
            if endi[e, 6] != 0:  # a moving support: prescribed angular acceleration in endf[e, 2:5]
                moving = e
                if power:  # the support's couple nrm m on the end's angular velocity
                    power_sum += nrm * ((r00 * M0_ + r01 * M1_ + r02 * M2_) * wc0 + (r10 * M0_ + r11 * M1_ + r12 * M2_) * wc1
                                        + (r20 * M0_ + r21 * M1_ + r22 * M2_) * wc2)
                continue
            lf0, lf1, lf2, m0, m1, m2 = endf[e, 2], endf[e, 3], endf[e, 4], endf[e, 5], endf[e, 6], endf[e, 7]
            if endi[e, 5] != 0:  # follower loads: material components, turned by R
                lf0, lf1, lf2 = (r00 * lf0 + r01 * lf1 + r02 * lf2, r10 * lf0 + r11 * lf1 + r12 * lf2,
                                 r20 * lf0 + r21 * lf1 + r22 * lf2)
                m0, m1, m2 = r00 * m0 + r01 * m1 + r02 * m2, r10 * m0 + r11 * m1 + r12 * m2, r20 * m0 + r21 * m1 + r22 * m2
            if power:  # end loads (zero where absent) on the end velocities
                power_sum += lf0 * vc0 + lf1 * vc1 + lf2 * vc2 + m0 * wc0 + m1 * wc1 + m2 * wc2
            if endi[e, 3] != 0:
                rn0 = r00 * N0_ + r01 * N1_ + r02 * N2_
                rn1 = r10 * N0_ + r11 * N1_ + r12 * N2_
                rn2 = r20 * N0_ + r21 * N1_ + r22 * N2_
                ns0 += fac * (lf0 - nrm * rn0)
                ns1 += fac * (lf1 - nrm * rn1)
                ns2 += fac * (lf2 - nrm * rn2)
            if endi[e, 4] != 0:
                tq0 += fac * ((r00 * m0 + r10 * m1 + r20 * m2) - nrm * M0_)
                tq1 += fac * ((r01 * m0 + r11 * m1 + r21 * m2) - nrm * M1_)
                tq2 += fac * ((r02 * m0 + r12 * m1 + r22 * m2) - nrm * M2_)
        ang = math.sqrt(th0 * th0 + th1 * th1 + th2 * th2)
        cD = _coef_D(ang, ser, thr)
        xv0, xv1, xv2 = _cross(th0, th1, th2, wc0, wc1, wc2)
        xx0, xx1, xx2 = _cross(th0, th1, th2, xv0, xv1, xv2)
        z0, z1, z2 = tq0 / J0, tq1 / J1, tq2 / J2
        if fixp[i]:
            x[i, 0] = x[i, 1] = x[i, 2] = x[i, 6] = x[i, 7] = x[i, 8] = 0.0
        else:
            x[i, 0], x[i, 1], x[i, 2] = vc0, vc1, vc2
            x[i, 6], x[i, 7], x[i, 8] = ns0 / mu, ns1 / mu, ns2 / mu
            if sliding >= 0:
                x[i, 6], x[i, 7], x[i, 8] = endf[sliding, 8], endf[sliding, 9], endf[sliding, 10]
        if fixr[i]:
            x[i, 3] = x[i, 4] = x[i, 5] = x[i, 9] = x[i, 10] = x[i, 11] = 0.0
        else:
            x[i, 3] = wc0 - 0.5 * xv0 + cD * xx0
            x[i, 4] = wc1 - 0.5 * xv1 + cD * xx1
            x[i, 5] = wc2 - 0.5 * xv2 + cD * xx2
            x[i, 9] = r00 * z0 + r01 * z1 + r02 * z2
            x[i, 10] = r10 * z0 + r11 * z1 + r12 * z2
            x[i, 11] = r20 * z0 + r21 * z1 + r22 * z2
            if moving >= 0:
                x[i, 9], x[i, 10], x[i, 11] = endf[moving, 2], endf[moving, 3], endf[moving, 4]
        if not dense and nj == 0:
            _forward_row(x, i, lu, lower)
    if nj > 0:
        power_sum += joint_rows(x, v, w, R, sf, si, power)
    _finish_solve(x, lu, lower, upper, minv, dense, nj == 0, out)
    pw[0] = power_sum


@njit(cache=True, fastmath=False)
def rotation_angle_kernel(u, sf, si):
    """``max_i |(N0 u[1])_i|``."""
    prm, ser, geo, band, lu, minv, endf, endi, j0 = _views(sf, si)
    n, W = u.shape[1], band.shape[2]
    best = 0.0
    for i in range(n):
        t0 = t1 = t2 = 0.0
        js = j0[i]
        for k in range(W):
            b0 = band[0, i, k]
            t0 += b0 * u[1, js + k, 0]
            t1 += b0 * u[1, js + k, 1]
            t2 += b0 * u[1, js + k, 2]
        a = math.sqrt(t0 * t0 + t1 * t1 + t2 * t2)
        if a > best or a != a:  # propagate NaN like np.max
            best = a
            if a != a:
                return a
    return best


# ====================================================================== time profiles of loads
# Load-profile encoding (one row per time-dependent load, see :func:`profile_row`):
# kind code, t_on, t_off, ramp, number of table points m, table times (m), factors (m).
_PROFILE_KINDS = {"constant": 0, "step": 1, "ramp": 2, "smooth": 3, "table": 4, "raised_cosine": 5, "sine": 6}
_PR_KIND, _PR_ON, _PR_OFF, _PR_RAMP, _PR_M, _PR_TABLE = 0, 1, 2, 3, 4, 5


@njit(cache=True, fastmath=False)
def _interp(t, row):
    """``np.interp(t, tt, ff)`` for the (non-decreasing) table of a profile row, with
    NumPy's branch logic: ends held constant, the last node ``<= t`` starts the segment,
    exact hits return the node value."""
    m = int(row[_PR_M])
    tt, ff = row[_PR_TABLE:_PR_TABLE + m], row[_PR_TABLE + m:_PR_TABLE + 2 * m]
    if t > tt[m - 1]:
        return ff[m - 1]
    if t < tt[0]:
        return ff[0]
    j = 0
    while j + 1 < m and t >= tt[j + 1]:
        j += 1
    if j == m - 1 or tt[j] == t:
        return ff[j]
    slope = (ff[j + 1] - ff[j]) / (tt[j + 1] - tt[j])
    out = slope * (t - tt[j]) + ff[j]
    if out != out:  # NaN one way: NumPy tries the other end of the segment
        out = slope * (t - tt[j + 1]) + ff[j + 1]
        if out != out and ff[j] == ff[j + 1]:
            out = ff[j]
    return out


@njit(cache=True, fastmath=False)
def profile_value(row, t):
    """:meth:`liegroup_int.problems.beam.model.Profile.__call__` on an encoded row."""
    kind = int(row[_PR_KIND])
    if kind == 0:
        return 1.0
    if kind == 4:
        return _interp(t, row)
    if t < row[_PR_ON] or t >= row[_PR_OFF]:
        return 0.0
    if kind == 1:
        return 1.0
    if kind == 6:
        return math.sin(2.0 * math.pi * (t - row[_PR_ON]) / row[_PR_RAMP])
    if kind == 5:
        y = (t - row[_PR_ON]) / row[_PR_RAMP]
        return 1.0 - math.cos(2.0 * math.pi * y) if y < 1.0 else 0.0
    x = min(1.0, (t - row[_PR_ON]) / row[_PR_RAMP])
    if kind == 2:
        return x
    s = math.sin(0.5 * math.pi * x)
    return s * s


@njit(cache=True, fastmath=False)
def _set_loads(sf, lpos, lvec, lprof, t):
    """Time-dependent loads at ``t`` into ``sf``: ``sf[lpos[k]:+3] = lvec[k] * profile_k(t)``
    (what :meth:`NumbaBeamKernels._set_loads` does in Python)."""
    for k in range(lpos.shape[0]):
        f = profile_value(lprof[k], t)
        for d in range(3):
            sf[lpos[k] + d] = lvec[k, d] * f


@njit(cache=True, fastmath=False)
def _all_finite(x):
    for j in range(x.shape[0]):
        if not math.isfinite(x[j]):
            return False
    return True


# ====================================================================== engine kernels
# The beam's kernels for the compiled engine (liegroup_int.integrators.engine): the state
# as the tuple (c, v, w, R, K, K_s), increments flat (12 n) seen as (4, n, 3), and
# ``data = (sf, si, fixp, fixr, x, lpos, lvec, lprof, pw)`` (:meth:`NumbaBeamKernels.compiled_problem`).
@njit(cache=True, fastmath=False, inline="always")
def engine_rate(data, t, y, u, out):
    """Stage rate at ``(t, y)`` with increment ``u`` into ``out`` (loads at ``t``); returns
    the external power (0 unless the problem computes it)."""
    sf, si, fixp, fixr, x, lpos, lvec, lprof, pw = data
    _set_loads(sf, lpos, lvec, lprof, t)
    c, v, w, R, K, Ks = y
    rates_into(c, v, w, R, K, Ks, u, sf, si, fixp, fixr, x, out, pw)
    return pw[0]


@njit(cache=True, fastmath=False, inline="always")
def engine_rate_mixed(data, t, y, u, out):
    """:func:`engine_rate` of the mixed formulation."""
    sf, si, fixp, fixr, x, lpos, lvec, lprof, pw = data
    _set_loads(sf, lpos, lvec, lprof, t)
    c, v, w, R, K, Ks = y
    rates_into_mixed(c, v, w, R, K, u, sf, si, fixp, fixr, x, out, pw)
    return pw[0]


@njit(cache=True, fastmath=False, inline="always")
def engine_action(data, u, y0, y1):
    """``y1 = Lambda(u, y0)``."""
    sf, si = data[0], data[1]
    c0, v0, w0, R0, K0, Ks0 = y0
    c1, v1, w1, R1, K1, Ks1 = y1
    action_kernel(u, c0, v0, w0, R0, K0, Ks0, c1, v1, w1, R1, K1, Ks1, sf, si)


@njit(cache=True, fastmath=False, inline="always")
def engine_action_mixed(data, u, y0, y1):
    """:func:`engine_action` of the mixed formulation."""
    sf, si = data[0], data[1]
    c0, v0, w0, R0, K0, Ks0 = y0
    c1, v1, w1, R1, K1, Ks1 = y1
    action_mixed(u, c0, v0, w0, R0, K0, Ks0, c1, v1, w1, R1, K1, Ks1, sf, si)


@njit(cache=True, fastmath=False, inline="always")
def engine_end_step(data, y):
    """Newton-Schulz step on the rotations of ``y``, in place (``BeamProblem.end_step``)."""
    _newton_schulz(y[3])


@njit(cache=True, fastmath=False, inline="always")
def engine_angle(data, u):
    """Largest rotation at the collocation points of the increment ``u``."""
    return rotation_angle_kernel(u, data[0], data[1])


@njit(cache=True, fastmath=False, inline="always")
def engine_scale(data, y, out):
    """``BeamProblem.increment_scale``: ``|c|`` on the position component, ones elsewhere."""
    c = y[0]
    n = c.shape[0]
    for i in range(n):
        for d in range(3):
            out[3 * i + d] = abs(c[i, d])
    for j in range(3 * n, out.shape[0]):
        out[j] = 1.0


@njit(cache=True, fastmath=False, inline="always")
def engine_increment_view(data, u):
    """The flat increment ``(12 n,)`` as ``(4, n, 3)``."""
    return u.reshape((4, data[1][_H_N], 3))


@njit(cache=True, fastmath=False, inline="always")
def engine_increment_views(data, K):
    """Rows of flat increments ``(k, 12 n)`` as ``(k, 4, n, 3)``."""
    return K.reshape((K.shape[0], 4, data[1][_H_N], 3))


@njit(cache=True, fastmath=False, inline="always")
def engine_new_state(data, y):
    """Uninitialized arrays like those of ``y``."""
    return (np.empty_like(y[0]), np.empty_like(y[1]), np.empty_like(y[2]), np.empty_like(y[3]),
            np.empty_like(y[4]), np.empty_like(y[5]))


@njit(cache=True, fastmath=False, inline="always")
def engine_copy_state(data, src, dst):
    """``dst <- src`` array by array."""
    dst[0][:] = src[0]
    dst[1][:] = src[1]
    dst[2][:] = src[2]
    dst[3][:] = src[3]
    dst[4][:] = src[4]
    dst[5][:] = src[5]


# ====================================================================== Python side
def _band_layout(mats, n):
    """Row windows of the union non-zero pattern of ``mats``: ``(bands, j0)``.

    ``W`` is the widest row support (``p + 1`` for B-splines at the Greville points);
    ``j0[i]`` is the first non-zero column of row ``i``, moved left where needed so that
    ``j0[i] + W <= n``.
    """
    nz = np.zeros((n, n), dtype=bool)
    for m in mats:
        nz |= m != 0.0
    has = nz.any(axis=1)
    first = np.where(has, nz.argmax(axis=1), 0)
    last = np.where(has, n - 1 - nz[:, ::-1].argmax(axis=1), 0)
    W = int(max(1, np.max(last - first + 1)))
    j0 = np.minimum(first, n - W).astype(np.int64)
    rows = np.arange(n)[:, None]
    cols = j0[:, None] + np.arange(W)[None, :]
    bands = np.zeros((len(mats), n, W))
    for k, m in enumerate(mats):
        bands[k] = m[rows, cols]
        if np.count_nonzero(bands[k]) != np.count_nonzero(m):  # pragma: no cover - by construction
            raise AssertionError("band extraction lost non-zero entries")
    return bands, j0


@njit(cache=True, fastmath=False)
def band_lu_residual(ab, mb, lower, upper):
    """``max |L U - M|`` over the band (``L U`` has the band of ``M``), from the factors in
    ``ab`` (before the pivots are inverted) and ``mb`` = ``M`` in the same band layout."""
    n = ab.shape[0]
    worst = 0.0
    for i in range(n):
        for j in range(max(0, i - lower), min(n, i + upper + 1)):
            acc = 0.0
            for k in range(max(0, i - lower, j - upper), min(i, j) + 1):
                lik = 1.0 if k == i else ab[i, lower + k - i]
                acc += lik * ab[k, lower + j - k]
            worst = max(worst, abs(acc - mb[i, lower + j - i]))
    return worst


def _factor_mc(N0, lower, upper):
    """Banded LU without pivoting of ``M_c``; ``None`` if a stability check fails.

    Cost ``O(n (l + u)^2)``; the checks work on the band too.
    """
    n = N0.shape[0]
    mb = np.zeros((n, lower + upper + 1))
    for d in range(-lower, upper + 1):  # diagonal j - i = d
        i = np.arange(max(0, -d), min(n, n - d))
        mb[i, lower + d] = N0[i, i + d]
    if np.count_nonzero(mb) != np.count_nonzero(N0):  # pragma: no cover - band widths are exact
        return None
    ab = mb.copy()
    pmin = band_lu_nopivot(ab, lower, upper)
    scale = float(np.max(np.abs(N0)))
    if not (np.all(np.isfinite(ab)) and pmin > 1e-8 * scale):
        return None
    # totally positive M_c: L and U are non-negative (up to round-off)
    if np.min(ab) < -1e-12 * max(1.0, float(np.max(np.abs(ab)))):
        return None
    # backward error of the factorization against |M_c|
    if band_lu_residual(ab, mb, lower, upper) > 1e-13 * scale * (lower + upper + 1):
        return None
    ab[:, lower] = 1.0 / ab[:, lower]  # the solve multiplies by the reciprocal pivots
    return ab


class NumbaBeamKernels:
    """Constant data and thin wrappers of the compiled kernels for one :class:`BeamProblem`.

    Parameters
    ----------
    pb : BeamProblem
        The problem (its NumPy-side set-up is read once).
    solver : {"auto", "banded", "dense"}
        ``M_c`` solve: banded LU without pivoting (``12 n (l + u + 1)`` per stage), the
        dense inverse (``12 n^2``), or ``auto`` (dense only for ``n <= DENSE_MAX_N``).
    """

    def __init__(self, pb, solver: str = "auto"):
        if solver not in ("auto", "banded", "dense"):
            raise ValueError(f"solver must be 'auto', 'banded' or 'dense', got {solver!r}")
        self.pb = pb
        n = pb.n
        self.n = n
        lower, upper = pb.space.bandwidths
        N0 = np.asarray(pb.N0, dtype=float)
        ab = None
        if solver != "dense":
            ab = _factor_mc(N0, lower, upper)
        dense = solver == "dense" or ab is None or (solver == "auto" and n <= DENSE_MAX_N)
        self.solver = "dense" if dense else "banded"
        if ab is None:
            ab = np.zeros((n, lower + upper + 1))
        minv = np.linalg.inv(N0) if dense else np.zeros(0)
        bands, j0 = _band_layout([N0, np.asarray(pb.N1, float), np.asarray(pb.N2, float)], n)
        self.bandwidth = bands.shape[2]

        prm = np.zeros(_N_PRM)
        prm[_P_Q:_P_Q + 3] = pb.loads.distributed_force
        prm[_P_G:_P_G + 3] = pb.loads.gravity
        prm[_P_M:_P_M + 3] = pb.m_dist
        prm[_P_HASQ] = float(pb.has_q)
        prm[_P_HASM] = float(pb.has_m)
        prm[_P_THR] = float(TAYLOR_THRESHOLD)
        prm[_P_TAU] = float(pb.tau)
        prm[_P_POW] = float(pb.has_quadrature)
        ser = np.array([[float(x) for x in TAYLOR[k]] for k in _SERIES_KEYS])
        if pb.curved:
            geo = np.concatenate([pb.gamma0, pb.K0, pb.K0_s], axis=1)
        else:  # the NumPy path does not subtract K0, K0_s (zero up to round-off) here
            geo = np.concatenate([pb.gamma0, np.zeros((n, 6))], axis=1)
        section = [np.broadcast_to(np.asarray(a, dtype=float), (n, k)) for a, k in
                   ((pb.CN, 3), (pb.CM, 3), (pb.Jm, 3), (np.reshape(pb.mu, (-1, 1)), 1))]
        geo = np.concatenate([geo, *section], axis=1)

        ends = pb.ends
        ne = len(ends)
        endi = np.zeros((ne, _NEI), dtype=np.int64)
        endf = np.zeros((ne, _NEF))
        profiles = []  # (block, row, first column, base vector, profile) of non-constant loads
        for k, e in enumerate(ends):
            endi[k] = (e.index, e.fix_position, e.fix_rotation, e.force_neumann, e.moment_neumann, e.load.follower,
                       e.motion is not None, e.translation is not None)
            endf[k, 0], endf[k, 1] = e.normal, e.factor
            if e.translation is not None:  # prescribed acceleration, per stage time
                scale, prof = e.translation.acceleration_profile()
                a = scale * e.translation.unit_axis
                endf[k, 8:11] = a * prof(0.0)
                profiles.append(("endf", k, 8, a, prof))
            if e.motion is not None:  # prescribed angular acceleration, per stage time
                scale, prof = e.motion.acceleration_profile()
                a = scale * e.motion.unit_axis
                endf[k, 2:5] = a * prof(0.0)
                profiles.append(("endf", k, 2, a, prof))
            ld = e.load
            for col, vec, prof, on in ((2, ld.force, ld.force_profile, e.force_neumann),
                                       (5, ld.couple, ld.couple_profile, e.moment_neumann)):
                vec = np.asarray(vec, dtype=float)
                if not (on and np.any(vec)):
                    continue
                if prof.is_constant:
                    endf[k, col:col + 3] = vec * prof(0.0)
                else:
                    profiles.append(("endf", k, col, vec, prof))

        nj = len(pb.joints)
        jointi = np.zeros((nj, _NJI), dtype=np.int64)
        jointf = np.zeros((nj, _NJF))
        for k, j in enumerate(pb.joints):
            jointi[k] = (j.a, j.b)
            jointf[k, 0], jointf[k, 1] = j.factor_a, j.factor_b
            if j.load is None:
                continue
            for col, vec, prof in ((2, j.load.force, j.load.force_profile), (5, j.load.couple, j.load.couple_profile)):
                vec = np.asarray(vec, dtype=float)
                if not np.any(vec):
                    continue
                if prof.is_constant:
                    jointf[k, col:col + 3] = vec * prof(0.0)
                else:
                    profiles.append(("jointf", k, col, vec, prof))

        blocks = [("prm", prm), ("ser", ser), ("geo", geo), ("band", bands), ("lu", ab),
                  ("minv", minv), ("endf", endf), ("quad", np.asarray(pb.quad, dtype=float)), ("jointf", jointf)]
        offs, pos = {}, 0
        for name, arr in blocks:
            offs[name] = pos
            pos += arr.size
        sf = np.empty(pos)
        for name, arr in blocks:
            sf[offs[name]:offs[name] + arr.size] = np.ascontiguousarray(arr, dtype=float).ravel()
        si = np.zeros(_HEADER + endi.size + n + jointi.size, dtype=np.int64)
        si[_H_N], si[_H_W], si[_H_L], si[_H_U] = n, bands.shape[2], lower, upper
        si[_H_DENSE], si[_H_NE] = int(dense), ne
        si[_H_PRM], si[_H_SER], si[_H_GEO], si[_H_BAND] = offs["prm"], offs["ser"], offs["geo"], offs["band"]
        si[_H_LU], si[_H_MINV], si[_H_ENDF] = offs["lu"], offs["minv"], offs["endf"]
        si[_H_ENDI], si[_H_J0] = _HEADER, _HEADER + endi.size
        si[_H_NT] = ser.shape[1]
        si[_H_FORM] = FORM_MIXED if pb.mixed else FORM_PRIMAL
        si[_H_QUAD] = offs["quad"]
        si[_HEADER:_HEADER + endi.size] = endi.ravel()
        si[_HEADER + endi.size:_HEADER + endi.size + n] = j0
        si[_H_NJ], si[_H_JF], si[_H_JI] = nj, offs["jointf"], _HEADER + endi.size + n
        si[_HEADER + endi.size + n:] = jointi.ravel()
        self.sf, self.si = sf, si
        # positions in ``sf`` (not views: they would not survive pickling)
        width = {"endf": _NEF, "jointf": _NJF}
        self._profiles = [(offs[blk] + k * width[blk] + col, vec, prof) for blk, k, col, vec, prof in profiles]
        dprof = pb.loads.distributed_profile
        if not dprof.is_constant:  # distributed loads with a time profile
            self._profiles += [(offs["prm"] + _P_Q, np.asarray(pb.loads.distributed_force, float), dprof),
                               (offs["prm"] + _P_G, np.asarray(pb.loads.gravity, float), dprof),
                               (offs["prm"] + _P_M, np.asarray(pb.m_dist, float), dprof)]
        self._t_loads = None
        self._zero = np.zeros((4, n, 3))
        self.mixed = bool(pb.mixed)
        # work arrays of the wrappers' rate calls (Dirichlet masks, right-hand sides, power)
        self._fixp, self._fixr = dirichlet_rows(pb)
        self._x = np.empty((n, X_COLS if self.mixed or nj else _X_NM))
        self._pw = np.zeros(1)

    # ------------------------------------------------------------------ wrappers
    def _set_loads(self, t: float) -> None:
        """End loads times their profiles at ``t`` (once per distinct stage time)."""
        if t == self._t_loads:
            return
        sf = self.sf
        for a, vec, prof in self._profiles:
            sf[a:a + 3] = vec * prof(t)
        self._t_loads = t

    def action(self, u, y, state_cls):
        n, e = self.n, np.empty
        c, v, w, K, Ks, R = e((n, 3)), e((n, 3)), e((n, 3)), e((n, 3)), e((n, 3)), e((n, 3, 3))
        act = action_mixed if self.mixed else action_kernel
        act(_c(u), *_c_state(y), c, v, w, R, K, Ks, self.sf, self.si)
        return state_cls(c, v, w, R, K, Ks)

    def increment_rate(self, t, y, u):
        if self._profiles:
            self._set_loads(t)
        out = np.empty((4, self.n, 3))
        c, v, w, R, K, Ks = _c_state(y)
        sf, si, fixp, fixr, x, pw = self.sf, self.si, self._fixp, self._fixr, self._x, self._pw
        if self.mixed:
            rates_into_mixed(c, v, w, R, K, _c(u), sf, si, fixp, fixr, x, out, pw)
        else:
            rates_into(c, v, w, R, K, Ks, _c(u), sf, si, fixp, fixr, x, out, pw)
        return out

    def vector_field(self, t, y):
        return self.increment_rate(t, y, self._zero)

    def rotation_angle(self, u) -> float:
        return float(rotation_angle_kernel(_c(u), self.sf, self.si))

    def solve(self, x):
        """``M_c^-1`` on an increment-shaped array ``(4, n, 3)`` (copy)."""
        x = np.array(x, dtype=float, copy=True)
        solve_kernel(x, self.sf, self.si)
        return x

    def compiled_problem(self, state_cls):
        """What the compiled engine needs (:class:`~liegroup_int.integrators.engine.CompiledProblem`),
        or ``None`` when a load profile cannot be evaluated inside compiled code (the
        generic path then calls it in Python).

        The data hold a private copy of ``sf`` (the stage loads are written into it, so the
        wrappers' load cache stays valid) and the stage work arrays."""
        rows = [profile_row(prof) for _, _, prof in self._profiles]
        if any(r is None for r in rows):
            return None
        k = len(rows)
        width = max((r.size for r in rows), default=_PR_TABLE)
        lpos = np.array([a for a, _, _ in self._profiles], dtype=np.int64).reshape(k)
        lvec = np.array([vec for _, vec, _ in self._profiles], dtype=float).reshape(k, 3)
        lprof = np.zeros((k, width))
        for j, r in enumerate(rows):
            lprof[j, :r.size] = r
        sf, si, n = self.sf.copy(), self.si, self.n
        fixp, fixr = self._fixp.copy(), self._fixr.copy()
        x = np.empty((n, X_COLS if si[_H_FORM] == FORM_MIXED or si[_H_NJ] else _X_NM))
        data = (sf, si, fixp, fixr, x, lpos, lvec, lprof, np.zeros(1))

        def pack(y):
            return tuple(np.ascontiguousarray(a, dtype=float) for a in (y.c, y.v, y.w, y.R, y.K, y.K_s))

        def unpack(arrays):
            return state_cls(*arrays)

        kernels = ENGINE_KERNELS_MIXED if self.mixed else ENGINE_KERNELS
        return CompiledProblem(kernels, data, lambda packed: 12 * n, pack, unpack)


def _engine_kernels(name, rate, action):
    return EngineKernels(name, rate, action, engine_angle, engine_scale,
                         end_step=engine_end_step, new_state=engine_new_state,
                         copy_state=engine_copy_state, increment_view=engine_increment_view,
                         increment_views=engine_increment_views)


#: The beam's kernels for the compiled engine, one set per formulation (a run compiles
#: the loops of its own formulation only).
ENGINE_KERNELS = _engine_kernels("beam", engine_rate, engine_action)
ENGINE_KERNELS_MIXED = _engine_kernels("beam_mixed", engine_rate_mixed, engine_action_mixed)


def dirichlet_rows(pb) -> tuple[np.ndarray, np.ndarray]:
    """Boolean ``(n,)`` masks ``(fixp, fixr)`` of the rows whose position (and velocity) and
    rotation (and angular velocity) rates are prescribed: the position and rotation columns
    of ``BeamProblem._fix_rows`` (method.md section 3; a moving support's rotation rows are
    not masked, the kernels set them)."""
    mask = pb._fix_rows
    return np.ascontiguousarray(mask[:, 0]), np.ascontiguousarray(mask[:, 1])


def _c(a):
    """``a`` as a C-contiguous float64 array: the only layout the kernels are compiled for
    (another layout would compile a second specialization of every kernel it reaches)."""
    return np.ascontiguousarray(a, dtype=np.float64)


def _c_state(y):
    return _c(y.c), _c(y.v), _c(y.w), _c(y.R), _c(y.K), _c(y.K_s)


def profile_row(prof) -> np.ndarray | None:
    """Encode a :class:`~liegroup_int.problems.beam.model.Profile` for :func:`profile_value`.

    Returns ``None`` for anything the compiled evaluation does not reproduce: objects
    other than a ``Profile`` (a subclass may override ``__call__``), unknown kinds, and
    tables whose times are not finite and non-decreasing (``np.interp`` assumes sorted
    nodes; the driver then keeps the generic path, which calls the profile in Python).
    """
    from .model import Profile

    if type(prof) is not Profile or prof.kind not in _PROFILE_KINDS:
        return None
    table = np.asarray(prof.table, dtype=float).reshape(-1, 2) if prof.kind == "table" else np.zeros((0, 2))
    tt, ff = table[:, 0], table[:, 1]
    if prof.kind == "table" and not (np.all(np.isfinite(tt)) and np.all(np.diff(tt) >= 0)):
        return None
    head = [_PROFILE_KINDS[prof.kind], prof.t_on, prof.t_off, prof.ramp, len(tt)]
    return np.concatenate([np.asarray(head, dtype=float), tt, ff])
