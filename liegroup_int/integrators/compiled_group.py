"""Compiled fixed-step RKMK for a user's ``numba.njit`` vector field on a built-in group.

``integrate(f, y0, ..., space=G)`` with ``f`` a numba-compiled function ``f(t, y) -> xi``
(``xi`` a float64 array of shape ``(G.dim,)``) and ``G`` built from ``Rn``, ``SO3``, ``SE3``,
``Product`` and ``Power``: :meth:`GroupProblem.compiled_stepper` returns a
:class:`CompiledGroupStepper`, and :func:`~liegroup_int.integrators.drivers.integrate_fixed`
hands it all the steps between two output times. Each step is the generic one
(:func:`~liegroup_int.integrators.rkmk.rkmk_step`: the same cancellation-safe stage
combinations, the groups' compiled ``exp``/``dexpinv`` of
:mod:`liegroup_int.groups.kernels_numba`, the finiteness and rotation-angle checks), with
``f`` called from compiled code. Single points only (no batch axes).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..groups.kernels_numba import dexpinv_flat, retract_flat, rotation_angle_flat
from .combine_numba import combine_into
from .problem import Advance

ADVANCE_OK, ADVANCE_NON_FINITE, ADVANCE_ANGLE = 0, 1, 2


def is_compiled_function(f) -> bool:
    """Whether ``f`` is a numba-compiled function (a CPU dispatcher)."""
    try:
        from numba.core.registry import CPUDispatcher
    except ImportError:  # pragma: no cover - numba is a core dependency
        return False
    return isinstance(f, CPUDispatcher)


@njit(cache=False)
def advance_kernel(f, shape, ft, ser, thr, A, b, cc, y, t_start, t_stop, dt, n_steps, max_angle):
    """Up to ``n_steps`` fixed RKMK steps of the flat point ``y`` (read, not written); the
    grid and the checks of ``integrate_fixed``. ``f`` receives the point reshaped to
    ``shape``. Returns ``(y, steps, status, t, t_fail, h_min, h_max, angle)`` as the
    compiled steppers of the plugins do (:class:`~liegroup_int.integrators.problem.Advance`).
    """
    s, size = b.shape[0], y.shape[0]
    dim = ft[ft.shape[0] - 1, 2] + ft[ft.shape[0] - 1, 3]
    K = np.empty((s, dim))
    u = np.empty(dim)
    ys = np.empty(size)
    y0 = y.copy()
    y1 = np.empty(size)
    t, h_min, h_max = t_start, np.inf, 0.0
    for i in range(n_steps):
        t_next = t_stop if i == n_steps - 1 else t_start + (i + 1) * dt
        h = t_next - t
        K[0, :] = f(t, y0.reshape(shape))
        for r in range(1, s):
            combine_into(A[r], r, cc[r], K, h, u)
            retract_flat(ft, ser, thr, u, y0, ys)
            dexpinv_flat(ft, ser, thr, u, f(t + cc[r] * h, ys.reshape(shape)), K[r])
        combine_into(b, s, 1.0, K, h, u)
        for k in range(dim):
            if not math.isfinite(u[k]):
                return y0, i, ADVANCE_NON_FINITE, t, t_next, h_min, h_max, np.nan
        ang = rotation_angle_flat(ft, u)
        if ang > max_angle:
            return y0, i, ADVANCE_ANGLE, t, t_next, h_min, h_max, ang
        retract_flat(ft, ser, thr, u, y0, y1)
        y0, y1 = y1, y0
        t = t_next
        h_min, h_max = min(h_min, h), max(h_max, h)
    return y0, n_steps, ADVANCE_OK, t, np.nan, h_min, h_max, 0.0


class CompiledGroupStepper:
    """Fixed-step loop of a :class:`GroupProblem` whose ``f`` is numba-compiled.

    Parameters
    ----------
    problem : GroupProblem
        With compiled group kernels (``problem._compiled``) and a compiled ``f``.
    tab : ButcherTableau
    """

    def __init__(self, problem, tab):
        self.f = problem.f
        self.cg = problem._compiled
        self.shape = tuple(int(k) for k in problem.space.point_shape)
        self.A = np.ascontiguousarray(tab.A_f, dtype=float)
        self.b = np.ascontiguousarray(tab.b_f, dtype=float)
        self.c = np.ascontiguousarray(tab.c_f, dtype=float)

    def advance(self, t_start: float, y, t_stop: float, dt: float, n_steps: int, max_angle: float) -> Advance:
        """See :meth:`liegroup_int.integrators.Problem.compiled_stepper`."""
        y = np.asarray(y, dtype=float)
        if y.shape != self.shape:
            raise ValueError(f"a numba-compiled f runs on one point of shape {self.shape}, got {y.shape}; "
                             "use a plain Python f for batches")
        out = advance_kernel(self.f, self.shape, self.cg.ft, self.cg.ser, self.cg.thr, self.A, self.b, self.c,
                             np.ascontiguousarray(y).reshape(-1), float(t_start), float(t_stop), float(dt),
                             int(n_steps), float(max_angle))
        yf, steps, status, t, t_fail, h_min, h_max, ang = out
        status = {ADVANCE_OK: "ok", ADVANCE_NON_FINITE: "non-finite", ADVANCE_ANGLE: "angle"}[status]
        return Advance(yf.reshape(self.shape), float(t), int(steps), float(h_min), float(h_max), status,
                       float(t_fail), float(ang))
