"""Compiled (numba) fixed-step RKMK loop of the rigid body: ``RigidBodyProblem.compiled_stepper``.

The generic path spends ~100 us of NumPy call overhead per RKMK stage on 3-vectors
(``Product(SO3, Rn(3))`` splits, joins, ``einsum``, ``cross``, coefficient tables), which
for a single body is almost all of its cost. :func:`advance_kernel` runs many fixed steps
of a batch of ``N`` bodies in one compiled call, with the arithmetic of the generic path:

* the vector field of :meth:`~liegroup_int.problems.rigid_body.RigidBody.vector_field`
  (``omega = R W``, ``dW = ((I W) x W [+ Gamma x m g chi]) / I`` with ``Gamma = R[2, :]``),
* ``dexpinv`` of :func:`~liegroup_int.groups.so3.dexpinv_so3` on the rotation part
  (``v - xi x v / 2 + D xi x (xi x v)``) and the identity on the ``R^3`` part,
* the action ``R <- exp(hat(xi)) R`` (Rodrigues, ``I + A X + B X^2``) and ``W <- u_W + W``,
* the SO(3) coefficients ``A, B, D`` with the branches of
  :mod:`liegroup_int.groups.so3_coefficients`: the full 12-term Horner polynomial in
  ``theta**2`` below ``TAYLOR_THRESHOLD`` (1 rad) and the same closed forms at and above
  it (series tables and threshold are run-time data, not frozen into the cached code),
* the stage combinations in the cancellation-safe ``total`` form of
  :func:`liegroup_int.integrators.rkmk.combine`,
* the step grid and checks of :func:`liegroup_int.integrators.drivers.integrate_fixed`:
  step ``i`` ends at ``t_start + (i + 1) dt`` (the last one at ``t_stop``); after a step
  the increments of all bodies must be finite, and their largest rotation angle must not
  exceed ``max_angle``, otherwise the loop stops before that step.

The rigid body has no ``end_step`` (no re-orthonormalization), so neither has the loop.
Only IEEE operations (no fast-math), so results differ from the NumPy path by the order
of a few sums (BLAS/einsum) only, i.e. by round-off.

Bodies are independent, so each step runs body by body (all stages of one body, then the
next body); the checks are taken over all bodies after the step, as the generic driver
does on the batched increment.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..groups.so3_coefficients import TAYLOR, TAYLOR_THRESHOLD
from ..integrators.combine_numba import combine_into as _combine
from ..integrators.problem import Advance

ADVANCE_OK, ADVANCE_NON_FINITE, ADVANCE_ANGLE = 0, 1, 2
_STATUS = {ADVANCE_OK: "ok", ADVANCE_NON_FINITE: "non-finite", ADVANCE_ANGLE: "angle"}

# rows of the series table ``ser``
_SA, _SB, _SD = 0, 1, 2
# layout of the parameter array ``prm``: I(3), m g chi (3), heavy (mass > 0), threshold
_P_I, _P_MGCHI, _P_HEAVY, _P_THR = 0, 3, 6, 7
_N_PRM = 8


@njit(cache=True, fastmath=False, inline="always")
def _horner(ser, k, t2):
    """All terms of row ``k``, as ``so3_coefficients._horner`` / ``coefficients``."""
    m = ser.shape[1]
    out = ser[k, m - 1]
    for j in range(m - 2, -1, -1):
        out = out * t2 + ser[k, j]
    return out


@njit(cache=True, fastmath=False)
def _action(u, y0, out, ser, thr):
    """``out = Lambda(u, y0)``: ``R <- exp(hat(u_R)) R``, ``W <- u_W + W`` (flat 12)."""
    x0, x1, x2 = u[0], u[1], u[2]
    th = math.sqrt(x0 * x0 + x1 * x1 + x2 * x2)
    if th >= thr:
        a = math.sin(th) / th
        sh = math.sin(0.5 * th) / th
        b = 2.0 * (sh * sh)
    else:
        t2 = th * th
        a = _horner(ser, _SA, t2)
        b = _horner(ser, _SB, t2)
    # X = hat(x) and X @ X (row-by-column sums in index order, zeros included)
    X00, X01, X02 = 0.0, -x2, x1
    X10, X11, X12 = x2, 0.0, -x0
    X20, X21, X22 = -x1, x0, 0.0
    Q00 = X00 * X00 + X01 * X10 + X02 * X20
    Q01 = X00 * X01 + X01 * X11 + X02 * X21
    Q02 = X00 * X02 + X01 * X12 + X02 * X22
    Q10 = X10 * X00 + X11 * X10 + X12 * X20
    Q11 = X10 * X01 + X11 * X11 + X12 * X21
    Q12 = X10 * X02 + X11 * X12 + X12 * X22
    Q20 = X20 * X00 + X21 * X10 + X22 * X20
    Q21 = X20 * X01 + X21 * X11 + X22 * X21
    Q22 = X20 * X02 + X21 * X12 + X22 * X22
    # E = (I + a X) + b X^2
    E00 = (1.0 + a * X00) + b * Q00
    E01 = (0.0 + a * X01) + b * Q01
    E02 = (0.0 + a * X02) + b * Q02
    E10 = (0.0 + a * X10) + b * Q10
    E11 = (1.0 + a * X11) + b * Q11
    E12 = (0.0 + a * X12) + b * Q12
    E20 = (0.0 + a * X20) + b * Q20
    E21 = (0.0 + a * X21) + b * Q21
    E22 = (1.0 + a * X22) + b * Q22
    for k in range(3):
        r0, r1, r2 = y0[k], y0[3 + k], y0[6 + k]
        out[k] = E00 * r0 + E01 * r1 + E02 * r2
        out[3 + k] = E10 * r0 + E11 * r1 + E12 * r2
        out[6 + k] = E20 * r0 + E21 * r1 + E22 * r2
    out[9] = u[3] + y0[9]
    out[10] = u[4] + y0[10]
    out[11] = u[5] + y0[11]


@njit(cache=True, fastmath=False)
def _rate(y, u, prm, ser, out):
    """``out = dexpinv_u(f(y))`` (flat 6): the body's vector field, then SO(3) dexpinv on
    the rotation part and the identity on the angular-velocity part."""
    w0, w1, w2 = y[9], y[10], y[11]
    I0, I1, I2 = prm[_P_I], prm[_P_I + 1], prm[_P_I + 2]
    a0, a1, a2 = I0 * w0, I1 * w1, I2 * w2
    tq0 = a1 * w2 - a2 * w1
    tq1 = a2 * w0 - a0 * w2
    tq2 = a0 * w1 - a1 * w0
    if prm[_P_HEAVY] != 0.0:
        g0, g1, g2 = y[6], y[7], y[8]
        c0, c1, c2 = prm[_P_MGCHI], prm[_P_MGCHI + 1], prm[_P_MGCHI + 2]
        tq0 = tq0 + (g1 * c2 - g2 * c1)
        tq1 = tq1 + (g2 * c0 - g0 * c2)
        tq2 = tq2 + (g0 * c1 - g1 * c0)
    v0 = y[0] * w0 + y[1] * w1 + y[2] * w2
    v1 = y[3] * w0 + y[4] * w1 + y[5] * w2
    v2 = y[6] * w0 + y[7] * w1 + y[8] * w2
    # dexpinv_so3(xi, v) = (v - 0.5 xi x v) + D xi x (xi x v)
    x0, x1, x2 = u[0], u[1], u[2]
    th = math.sqrt(x0 * x0 + x1 * x1 + x2 * x2)
    if th < prm[_P_THR]:
        d = _horner(ser, _SD, th * th)
    else:
        d = (1.0 - 0.5 * th / math.tan(0.5 * th)) / (th * th)
    xv0 = x1 * v2 - x2 * v1
    xv1 = x2 * v0 - x0 * v2
    xv2 = x0 * v1 - x1 * v0
    out[0] = (v0 - 0.5 * xv0) + d * (x1 * xv2 - x2 * xv1)
    out[1] = (v1 - 0.5 * xv1) + d * (x2 * xv0 - x0 * xv2)
    out[2] = (v2 - 0.5 * xv2) + d * (x0 * xv1 - x1 * xv0)
    out[3] = tq0 / I0
    out[4] = tq1 / I1
    out[5] = tq2 / I2


@njit(cache=True, fastmath=False)
def advance_kernel(y, prm, ser, A, b, cc, t_start, t_stop, dt, n_steps, max_angle):
    """Up to ``n_steps`` fixed RKMK steps of ``N`` bodies ``y (N, 12)`` (read, not written).

    Returns
    -------
    (y, steps, status, t, t_fail, h_min, h_max, angle)
        The state after the ``steps`` accepted steps (a new array) and its time ``t``;
        ``status`` is :data:`ADVANCE_OK` or the failure of the next step
        (:data:`ADVANCE_NON_FINITE`, :data:`ADVANCE_ANGLE`), which would have ended at
        ``t_fail`` with the largest rotation ``angle``; ``h_min, h_max`` over the
        accepted steps (``inf, 0`` if none).
    """
    n, s = y.shape[0], b.shape[0]
    thr = prm[_P_THR]
    K = np.empty((s, 6))
    zero = np.zeros(6)
    us = np.empty(6)
    ys = np.empty(12)
    U = np.empty((n, 6))
    y0 = y.copy()
    y1 = np.empty_like(y0)
    t, h_min, h_max = t_start, np.inf, 0.0
    for i in range(n_steps):
        t_next = t_stop if i == n_steps - 1 else t_start + (i + 1) * dt
        h = t_next - t
        for j in range(n):
            yj = y0[j]
            _rate(yj, zero, prm, ser, K[0])
            for r in range(1, s):
                _combine(A[r], r, cc[r], K, h, us)
                _action(us, yj, ys, ser, thr)
                _rate(ys, us, prm, ser, K[r])
            _combine(b, s, 1.0, K, h, U[j])
            _action(U[j], yj, y1[j], ser, thr)
        finite = True
        for j in range(n):
            for k in range(6):
                if not math.isfinite(U[j, k]):
                    finite = False
        if not finite:
            return y0, i, ADVANCE_NON_FINITE, t, t_next, h_min, h_max, np.nan
        ang = 0.0
        for j in range(n):
            ang = max(ang, math.sqrt(U[j, 0] * U[j, 0] + U[j, 1] * U[j, 1] + U[j, 2] * U[j, 2]))
        if ang > max_angle:
            return y0, i, ADVANCE_ANGLE, t, t_next, h_min, h_max, ang
        y0, y1 = y1, y0
        t = t_next
        h_min, h_max = min(h_min, h), max(h_max, h)
    return y0, n_steps, ADVANCE_OK, t, np.nan, h_min, h_max, 0.0


def parameters(body) -> np.ndarray:
    """The ``prm`` array of :func:`advance_kernel` for a :class:`RigidBody`."""
    prm = np.zeros(_N_PRM)
    prm[_P_I:_P_I + 3] = body._I
    prm[_P_MGCHI:_P_MGCHI + 3] = body._mgchi
    prm[_P_HEAVY] = 1.0 if body.mass > 0 else 0.0
    prm[_P_THR] = TAYLOR_THRESHOLD
    return prm


def series_table() -> np.ndarray:
    """Rows ``A, B, D`` of the SO(3) Taylor tables, ``(3, N_TERMS)`` (the floats of the NumPy path)."""
    return np.array([[float(c) for c in TAYLOR[k]] for k in ("A", "B", "D")])


class FusedRigidBodyStepper:
    """Fixed-step RKMK for one rigid body (any batch of states) and one tableau, many
    steps per compiled call (:func:`advance_kernel`); the contract of
    :meth:`liegroup_int.integrators.problem.Problem.compiled_stepper`.

    Parameters
    ----------
    body : RigidBody
    tab : ButcherTableau
        Explicit tableau (``A_f, b_f, c_f``).
    """

    def __init__(self, body, tab):
        self.stages = int(tab.stages)
        self.prm = parameters(body)
        self.ser = series_table()
        self.A = np.ascontiguousarray(tab.A_f, dtype=float)
        self.b = np.ascontiguousarray(tab.b_f, dtype=float)
        self.c = np.ascontiguousarray(tab.c_f, dtype=float)

    def advance(self, t_start: float, y, t_stop: float, dt: float, n_steps: int, max_angle: float):
        """Up to ``n_steps`` steps from ``(t_start, y)`` on the driver's grid.

        ``y`` has shape ``(..., 12)`` (not modified); the returned state has its shape.

        Returns
        -------
        liegroup_int.integrators.problem.Advance
        """
        y = np.asarray(y, dtype=float)
        if y.ndim == 0 or y.shape[-1] != 12:
            raise ValueError(f"rigid body: state must have shape (..., 12), got {y.shape}")
        flat = np.ascontiguousarray(y.reshape(-1, 12))
        out = advance_kernel(flat, self.prm, self.ser, self.A, self.b, self.c, float(t_start), float(t_stop),
                             float(dt), int(n_steps), float(max_angle))
        yn, steps, status, t, t_fail, h_min, h_max, ang = out
        return Advance(yn.reshape(y.shape), float(t), int(steps), float(h_min), float(h_max), _STATUS[status],
                       float(t_fail), float(ang))
