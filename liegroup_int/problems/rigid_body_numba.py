"""Compiled (numba) vector field of the rigid body, for the compiled engine
(:meth:`RigidBodyProblem.compiled_kernels`).

The generic path spends ~100 us of NumPy call overhead per RKMK stage on 3-vectors, which
for a single body is almost all of its cost. Here the body supplies only its vector field
(:func:`field_kernel`, the arithmetic of
:meth:`~liegroup_int.problems.rigid_body.RigidBody.vector_field`: ``omega = R W``,
``dW = ((I W) x W [+ Gamma x m g chi]) / I`` with ``Gamma = R[2, :]``); the action,
dexpinv, rotation angle and error scale are the compiled kernels of the group on ``(SO3 x
R3)^N`` for a batch of ``N`` bodies (the per-factor SO(3) kernels of
:mod:`liegroup_int.groups.kernels_numba` for the action and dexpinv, inlined into the
stage; :mod:`liegroup_int.integrators.compiled_group` for the angle and scale), and the
loops are the engine's (:mod:`liegroup_int.integrators.engine`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..groups.kernels_numba import dexpinv_so3, retract_so3
from ..integrators.compiled_group import group_angle, group_data, group_scale
from ..integrators.engine import CompiledProblem, EngineKernels

# layout of the parameter array ``prm``: I(3), m g chi (3), heavy (mass > 0)
_P_I, _P_MGCHI, _P_HEAVY = 0, 3, 6
_N_PRM = 7


@njit(cache=True, fastmath=False, inline="always")
def field_kernel(data, t, y, out):
    """``out = f(t, y)`` for ``N`` bodies: ``y`` flat ``(N, 12)`` (``R`` row by row, then
    ``W``), ``out`` flat ``(N, 6)`` (``R W``, ``dW/dt``). Returns 0 (no quadrature)."""
    prm = data[5]
    I0, I1, I2 = prm[_P_I], prm[_P_I + 1], prm[_P_I + 2]
    heavy = prm[_P_HEAVY] != 0.0
    c0, c1, c2 = prm[_P_MGCHI], prm[_P_MGCHI + 1], prm[_P_MGCHI + 2]
    for j in range(y.shape[0] // 12):
        p, a = 12 * j, 6 * j
        w0, w1, w2 = y[p + 9], y[p + 10], y[p + 11]
        a0, a1, a2 = I0 * w0, I1 * w1, I2 * w2
        tq0 = a1 * w2 - a2 * w1
        tq1 = a2 * w0 - a0 * w2
        tq2 = a0 * w1 - a1 * w0
        if heavy:
            g0, g1, g2 = y[p + 6], y[p + 7], y[p + 8]
            tq0 = tq0 + (g1 * c2 - g2 * c1)
            tq1 = tq1 + (g2 * c0 - g0 * c2)
            tq2 = tq2 + (g0 * c1 - g1 * c0)
        out[a] = y[p] * w0 + y[p + 1] * w1 + y[p + 2] * w2
        out[a + 1] = y[p + 3] * w0 + y[p + 4] * w1 + y[p + 5] * w2
        out[a + 2] = y[p + 6] * w0 + y[p + 7] * w1 + y[p + 8] * w2
        out[a + 3] = tq0 / I0
        out[a + 4] = tq1 / I1
        out[a + 5] = tq2 / I2
    return 0.0


@njit(cache=True, fastmath=False, inline="always")
def action_kernel(data, u, y, out):
    """``out = exp(u) y`` on ``(SO3 x R3)^N``: the group's kernels for this layout, inlined
    (the generic factor-table loop, :func:`~..integrators.compiled_group.group_action`, is
    called out of line)."""
    ser, thr = data[1], data[2]
    for j in range(y.shape[0] // 12):
        p, a = 12 * j, 6 * j
        retract_so3(ser, thr, u, a, y, p, out)
        for k in range(3):
            out[p + 9 + k] = y[p + 9 + k] + u[a + 3 + k]


@njit(cache=True, fastmath=False, inline="always")
def dexpinv_kernel(data, u, w, out):
    """``out = dexpinv_u(w)`` on ``(SO3 x R3)^N`` (``w`` may be ``out``)."""
    ser, thr = data[1], data[2]
    for j in range(u.shape[0] // 6):
        a = 6 * j
        dexpinv_so3(ser, thr, u, w, out, a)
        for k in range(3, 6):
            out[a + k] = w[a + k]


@njit(cache=True, fastmath=False, inline="always")
def rate_kernel(data, t, y, u, out):
    """``out = dexpinv_u f(t, y)``."""
    field_kernel(data, t, y, out)
    dexpinv_kernel(data, u, out, out)
    return 0.0


#: The rigid body's kernels for the compiled engine.
ENGINE_KERNELS = EngineKernels("rigid_body", rate_kernel, action_kernel, group_angle, group_scale,
                               field=field_kernel, dexpinv=dexpinv_kernel)


def parameters(body) -> np.ndarray:
    """The ``prm`` array of :func:`field_kernel` for a :class:`RigidBody`."""
    prm = np.zeros(_N_PRM)
    prm[_P_I:_P_I + 3] = body._I
    prm[_P_MGCHI:_P_MGCHI + 3] = body._mgchi
    prm[_P_HEAVY] = 1.0 if body.mass > 0 else 0.0
    return prm


def compiled_problem(body, space) -> CompiledProblem:
    """The engine's view of ``body``'s problem on ``space = SO3 x R3``, for states of shape
    ``(..., 12)`` (a batch is ``N`` bodies one after the other)."""
    shapes = {}

    def pack(y):
        y = np.asarray(y, dtype=float)
        if y.ndim == 0 or y.shape[-1] != 12:
            raise ValueError(f"rigid body: state must have shape (..., 12), got {y.shape}")
        shapes["last"] = y.shape
        return np.ascontiguousarray(y).reshape(-1)

    def unpack(flat):
        return flat.reshape(shapes["last"])

    return CompiledProblem(ENGINE_KERNELS, group_data(space, parameters(body)), lambda flat: flat.size // 2, pack, unpack)
