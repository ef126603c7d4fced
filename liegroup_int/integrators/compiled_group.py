"""Engine kernels of problems on the built-in groups (numba).

``Rn``, ``SO3``, ``SE3``, ``Product`` and ``Power`` have compiled single-point kernels
(:mod:`liegroup_int.groups.kernels_numba`) working on a factor table. The kernels here
adapt them to the engine's contract (:mod:`.engine`) with ``data = (ft, ser, thr, ...)``:
the action ``exp(u) y``, ``dexpinv``, the rotation angle and the error scale of any point
of the table. A problem on a group then supplies only its vector field:

* a user's ``numba.njit`` function ``f(t, y) -> xi`` (:func:`group_problem_kernels`,
  what ``integrate(f, y0, ..., space=G)`` runs when ``f`` is compiled), called from
  compiled code on the point reshaped to ``G.point_shape``;
* a plugin's own field kernel (the rigid body, on a power of ``SO3 x R3`` for a batch of
  bodies).
"""

from __future__ import annotations

import math
import types

import numpy as np
from numba import njit

from ..groups import SE3, SO3, Product
from ..groups.kernels_numba import (
    CompiledGroup,
    _coef_AB,
    _cross,
    _exp_rot,
    dexpinv_flat,
    magnitude_flat,
    retract_flat,
    rotation_angle_flat,
    se3_exp_parts,
)
from .engine import CompiledProblem, EngineKernels


def is_compiled_function(f) -> bool:
    """Whether ``f`` is a numba-compiled function (a CPU dispatcher)."""
    try:
        from numba.core.registry import CPUDispatcher
    except ImportError:  # pragma: no cover - numba is a core dependency
        return False
    return isinstance(f, CPUDispatcher)


@njit(cache=True, inline="always")
def group_action(data, u, y, out):
    """``out = exp(u) y``, point by point."""
    ft, ser, thr, ps, dim = data[0], data[1], data[2], data[3], data[4]
    for j in range(y.shape[0] // ps):
        retract_flat(ft, ser, thr, u, y, out, j * ps, j * dim)


@njit(cache=True, inline="always")
def group_dexpinv(data, u, w, out):
    """``out = dexpinv_u(w)``, point by point (``w`` may be ``out``)."""
    ft, ser, thr, dim = data[0], data[1], data[2], data[4]
    for j in range(u.shape[0] // dim):
        dexpinv_flat(ft, ser, thr, u, w, out, j * dim)


@njit(cache=True, inline="always")
def group_angle(data, u):
    """Largest rotation angle of ``u`` over all points (NaN wins)."""
    ft, dim = data[0], data[4]
    best = 0.0
    for j in range(u.shape[0] // dim):
        a = rotation_angle_flat(ft, u, j * dim)
        if a != a:
            return a
        if a > best:
            best = a
    return best


@njit(cache=True, inline="always")
def group_scale(data, y, out):
    """Error scale of each point of ``y`` (``LieGroup.magnitude``)."""
    ft, ps, dim = data[0], data[3], data[4]
    for j in range(y.shape[0] // ps):
        magnitude_flat(ft, y, out, j * ps, j * dim)


def group_data(space, *extra) -> tuple:
    """``(ft, ser, thr, point_size, dim, *extra)`` for the group kernels on ``space`` (one
    point's factor table; states hold any number of points one after the other)."""
    cg = CompiledGroup.of(space)
    if cg is None:
        raise ValueError(f"{space!r} has no compiled kernels")
    return (cg.ft, cg.ser, cg.thr, int(np.prod(space.point_shape)), int(space.dim)) + tuple(extra)


@njit(cache=True, inline="always")
def sphere_action(data, u, y, out):
    """``out = exp(u) y`` for points of the unit sphere (``Sphere``, SO(3) acting)."""
    ser, thr = data[1], data[2]
    for j in range(y.shape[0] // 3):
        a = 3 * j
        x0, x1, x2 = u[a], u[a + 1], u[a + 2]
        cA, cB = _coef_AB(math.sqrt(x0 * x0 + x1 * x1 + x2 * x2), ser, thr)
        e = _exp_rot(cA, cB, x0, x1, x2)
        y0, y1, y2 = y[a], y[a + 1], y[a + 2]
        out[a] = e[0] * y0 + e[1] * y1 + e[2] * y2
        out[a + 1] = e[3] * y0 + e[4] * y1 + e[5] * y2
        out[a + 2] = e[6] * y0 + e[7] * y1 + e[8] * y2


@njit(cache=True, inline="always")
def tangent_sphere_action(data, u, y, out):
    """``(q, w) <- (R q, R w + r x R q)`` with ``(R, r) = exp(u)`` of SE(3), ``u = (rho,
    theta)``, ``r = J_l(theta) rho`` (``TangentSphere`` and its powers: 6 numbers per link)."""
    ser, thr = data[1], data[2]
    for j in range(y.shape[0] // 6):
        a = 6 * j
        e, t0, t1, t2 = se3_exp_parts(u, a, ser, thr)
        q0, q1, q2 = y[a], y[a + 1], y[a + 2]
        w0, w1, w2 = y[a + 3], y[a + 4], y[a + 5]
        Q0, Q1, Q2 = e[0] * q0 + e[1] * q1 + e[2] * q2, e[3] * q0 + e[4] * q1 + e[5] * q2, e[6] * q0 + e[7] * q1 + e[8] * q2
        k0, k1, k2 = _cross(t0, t1, t2, Q0, Q1, Q2)
        out[a], out[a + 1], out[a + 2] = Q0, Q1, Q2
        out[a + 3] = e[0] * w0 + e[1] * w1 + e[2] * w2 + k0
        out[a + 4] = e[3] * w0 + e[4] * w1 + e[5] * w2 + k1
        out[a + 5] = e[6] * w0 + e[7] * w1 + e[8] * w2 + k2


@njit(cache=True, inline="always")
def unit_scale(data, y, out):
    """Error scale 1 on every increment component (``Problem.increment_scale``'s default)."""
    for k in range(out.shape[0]):
        out[k] = 1.0


# ---------------------------------------------------------------- a user's njit f
USER_F = None  # bound to the user's function in each compiled copy (see _user_kernels)


def _user_field(data, t, y, out):
    """``out = f(t, y)`` with the point reshaped to the group's point shape."""
    w = USER_F(t, y.reshape(data[5]))
    if w.ndim != 1 or w.shape[0] != out.shape[0]:
        raise ValueError("f(t, y) must return a float array of shape (space.dim,)")
    for k in range(out.shape[0]):
        out[k] = w[k]
    return 0.0


def _user_rate(data, t, y, u, out):
    """``out = dexpinv_u f(t, y)``."""
    _user_field(data, t, y, out)  # the compiled copy bound next to this one (_user_kernels)
    dexpinv_flat(data[0], data[1], data[2], u, out, out, 0)
    return 0.0


_USER_KERNELS: dict = {}


def _user_kernels(f, action=group_action, scale=group_scale, name: str = "user") -> EngineKernels:
    """Engine kernels calling the compiled ``f`` with the given action and error scale
    (built once per function and action; not cached on disk: numba cannot key a cache on a
    user's function)."""
    kern = _USER_KERNELS.get((f, name))
    if kern is None:
        ns = dict(globals(), USER_F=f)
        made = {}
        for fn in (_user_field, _user_rate):  # _user_rate calls the compiled _user_field
            copy = types.FunctionType(fn.__code__, ns, fn.__name__)
            made[fn.__name__] = ns[fn.__name__] = njit(cache=False)(copy)
        kern = EngineKernels(name, made["_user_rate"], action, group_angle, scale,
                             field=made["_user_field"], dexpinv=group_dexpinv, cache=False)
        _USER_KERNELS[(f, name)] = kern
    return kern


def sphere_kernels(problem) -> CompiledProblem:
    """The engine's view of an ODE on ``Sphere()`` (SO(3) acting) with a numba-compiled ``f``,
    on one point, with the group's compiled exp and dexpinv."""
    return _space_kernels(problem, SO3, sphere_action, "user_sphere")


def tangent_sphere_kernels(problem) -> CompiledProblem:
    """The engine's view of an ODE on ``TangentSphere()`` or a power of it (SE(3) per link)
    with a numba-compiled ``f``, on one point."""
    factors = getattr(problem.space, "factors", (problem.space,))
    group = SE3 if len(factors) == 1 else Product(*[SE3] * len(factors))
    return _space_kernels(problem, group, tangent_sphere_action, "user_ts2")


def _space_kernels(problem, group, action, name) -> CompiledProblem:
    space = problem.space
    dim = int(group.dim)
    return CompiledProblem(_user_kernels(problem.f, action, unit_scale, name), group_data(group, space.point_shape),
                           lambda n: dim, single_point_pack(space.point_shape),
                           lambda flat: flat.reshape(space.point_shape))


def single_point_pack(shape):
    """``pack(y)`` of a user's compiled ``f``: one point of ``shape`` as a flat contiguous
    vector; a batch is refused in one line (the compiled ``f`` sees single points)."""
    shape = tuple(int(k) for k in shape)
    size = int(np.prod(shape))

    def pack(y):
        y = np.asarray(y, dtype=float)
        if y.shape != shape:
            raise ValueError(f"a numba-compiled f runs on one point of shape {shape}, got {y.shape}; "
                             "use a plain Python f for batches")
        return np.ascontiguousarray(y).reshape(size)

    return pack


def group_problem_kernels(problem) -> CompiledProblem:
    """The engine's view of a :class:`~liegroup_int.integrators.problem.GroupProblem`
    whose ``f`` is numba-compiled: single points of ``problem.space`` only."""
    shape = tuple(int(k) for k in problem.space.point_shape)
    dim = int(problem.space.dim)
    return CompiledProblem(_user_kernels(problem.f), group_data(problem.space, shape), lambda n: dim,
                           single_point_pack(shape), lambda flat: flat.reshape(shape))
