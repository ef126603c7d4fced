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
from .engine import CompiledProblem, EngineKernels, FunctionValue


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
#: Where the data of a user's field hold the point shape it sees (``data[SHAPE]``), the
#: function itself (``data[FIELD]``, a first-class function value of :func:`field_type`),
#: the event functions (``data[EVENTS]``, a tuple of first-class values of :func:`event_type`)
#: and their state (``data[EVSTATE]``, ``(3, k)``: last value, direction, watched or not).
SHAPE, FIELD, EVENTS, EVSTATE = 5, 6, 7, 8


def field_type(point_ndim: int):
    """The first-class function type of a user's field on points of ``point_ndim``
    dimensions: ``f(t: float64, y: float64[C-contiguous, point_ndim]) -> float64[::1]``."""
    from numba.core import types as nt

    return nt.FunctionType(nt.Array(nt.float64, 1, "C")(nt.float64, nt.Array(nt.float64, point_ndim, "C")))


def event_type(point_ndim: int):
    """The first-class function type of an event ``g(t: float64, y) -> float64`` on points
    of ``point_ndim`` dimensions."""
    from numba.core import types as nt

    return nt.FunctionType(nt.float64(nt.float64, nt.Array(nt.float64, point_ndim, "C")))


_DIM_ERROR = "f(t, y) must return a float array of shape (space.dim,)"


def field_function(f, point_ndim: int):
    """``f`` as the engine calls it: ``f`` itself when it returns a C-contiguous float64
    vector for a point of ``point_ndim`` dimensions, else a small compiled adapter that
    copies its 1-D result into one (a result that is not 1-D is refused in one line)."""
    from numba.core import types as nt

    ftype = field_type(point_ndim)
    args = tuple(ftype.signature.args)
    f.compile(args)
    res = f.overloads[args].signature.return_type
    if res == ftype.signature.return_type:
        return f
    if not (isinstance(res, nt.Array) and res.ndim == 1 and isinstance(res.dtype, (nt.Float, nt.Integer))):
        raise ValueError(f"{_DIM_ERROR}, got {res}")

    @njit(cache=False)
    def adapted(t, y):
        w = f(t, y)
        out = np.empty(w.shape[0])
        for k in range(w.shape[0]):
            out[k] = w[k]
        return out

    return adapted


def event_function(g, point_ndim: int):
    """``g`` as the engine calls it: ``g`` itself when it returns a float64, else an adapter
    converting its scalar result (a result that is not a number is refused in one line)."""
    from numba.core import types as nt

    args = tuple(event_type(point_ndim).signature.args)
    g.compile(args)
    res = g.overloads[args].signature.return_type
    if res == nt.float64:
        return g
    if not isinstance(res, (nt.Float, nt.Integer, nt.Boolean)):
        raise ValueError(f"event g(t, y) must return a number, got {res}")

    @njit(cache=False)
    def adapted(t, y):
        return float(g(t, y))

    return adapted


@njit(cache=True)
def no_event(t, y):
    """The event slot of a run without compiled events (never evaluated)."""
    return 1.0


@njit(cache=True)
def user_watch(data, t, y):
    """After an accepted step: each watched event ``g`` at ``(t, y)``; ``True`` if one crossed
    zero since the last step in its direction (scipy's rule, as
    :func:`~.events.triggered`). The values are kept for the next step."""
    gs, st = data[EVENTS], data[EVSTATE]
    hit = False
    for i in range(st.shape[1]):
        if st[2, i] == 0.0:
            continue
        g, old, d = gs[i](t, y.reshape(data[SHAPE])), st[0, i], st[1, i]
        up, down = old <= 0.0 <= g, old >= 0.0 >= g
        if (up and d > 0) or (down and d < 0) or ((up or down) and d == 0):
            hit = True
        st[0, i] = g
    return hit


@njit(cache=True)
def user_field(data, t, y, out):
    """``out = f(t, y)`` with the point reshaped to the group's point shape."""
    w = data[FIELD](t, y.reshape(data[SHAPE]))
    if w.shape[0] != out.shape[0]:
        raise ValueError(_DIM_ERROR)
    for k in range(out.shape[0]):
        out[k] = w[k]
    return 0.0


@njit(cache=True)
def _user_rate(data, t, y, u, out):
    """``out = dexpinv_u f(t, y)``."""
    user_field(data, t, y, out)
    group_dexpinv(data, u, out, out)
    return 0.0


def user_problem(kernels: EngineKernels, data: tuple, problem, dim: int, extra: tuple = ()) -> CompiledProblem:
    """The engine's view of a user's compiled ``f`` on one point of ``problem.space``: the
    kernels' ``data`` (:data:`SHAPE` entries), the point shape, ``f`` as a first-class
    function value, the event slots (none watched), then ``extra``."""
    from numba.core import types as nt

    shape = tuple(int(k) for k in problem.space.point_shape)
    ft, et = field_type(len(shape)), event_type(len(shape))
    data = data + (shape, FunctionValue(field_function(problem.f, len(shape)), ft), (FunctionValue(no_event, et),),
                   np.zeros((3, 1))) + tuple(extra)
    functions = ((FIELD, ft), (EVENTS, nt.UniTuple(et, 1)))
    return CompiledProblem(kernels, data, lambda n: dim, single_point_pack(shape), lambda flat: flat.reshape(shape),
                           functions=functions, with_events=_with_events)


def _with_events(cp: CompiledProblem, specs, t0: float, y0) -> CompiledProblem | None:
    """``cp`` watching the events ``specs`` (:class:`~.events.EventSpec`) from ``(t0, y0)``,
    or ``None`` when one of them is not numba-compiled (the drivers then hand every step
    to Python)."""
    import dataclasses

    from numba.core import types as nt

    if not specs or not all(is_compiled_function(s.fn) for s in specs):
        return None
    ndim = len(cp.data[SHAPE])
    gs = tuple(FunctionValue(event_function(s.fn, ndim), event_type(ndim)) for s in specs)
    state = np.array([[float(s.fn(t0, y0)) for s in specs], [s.direction for s in specs], [1.0] * len(specs)])
    data = cp.data[:EVENTS] + (gs, state) + cp.data[EVSTATE + 1:]
    functions = dict(cp.functions)
    functions[EVENTS] = nt.UniTuple(event_type(ndim), len(gs))
    return dataclasses.replace(cp, data=data, functions=tuple(functions.items()))


def _user_kernels(name: str, action, scale) -> EngineKernels:
    """Engine kernels calling a user's ``f`` from the data with ``action`` and ``scale``: one
    set per kind of space, whatever the function (cached on disk)."""
    return EngineKernels(name, _user_rate, action, group_angle, scale, field=user_field, dexpinv=group_dexpinv,
                         watch=user_watch)


USER_KERNELS = _user_kernels("user", group_action, group_scale)
SPHERE_KERNELS = _user_kernels("user_sphere", sphere_action, unit_scale)
TANGENT_SPHERE_KERNELS = _user_kernels("user_ts2", tangent_sphere_action, unit_scale)


def sphere_kernels(problem) -> CompiledProblem:
    """The engine's view of an ODE on ``Sphere()`` (SO(3) acting) with a numba-compiled ``f``,
    on one point, with the group's compiled exp and dexpinv."""
    return user_problem(SPHERE_KERNELS, group_data(SO3), problem, int(SO3.dim))


def tangent_sphere_kernels(problem) -> CompiledProblem:
    """The engine's view of an ODE on ``TangentSphere()`` or a power of it (SE(3) per link)
    with a numba-compiled ``f``, on one point."""
    factors = getattr(problem.space, "factors", (problem.space,))
    group = SE3 if len(factors) == 1 else Product(*[SE3] * len(factors))
    return user_problem(TANGENT_SPHERE_KERNELS, group_data(group), problem, int(group.dim))


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
    return user_problem(USER_KERNELS, group_data(problem.space), problem, int(problem.space.dim))
