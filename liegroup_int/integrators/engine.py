"""The compiled RKMK engine: fixed-step and adaptive loops for every plugin (numba).

A problem that wants its steps compiled hands the engine a :class:`CompiledProblem`
(:meth:`Problem.compiled_kernels`): its state as one float64 vector (or, with
``new_state``/``copy_state`` kernels, any fixed tuple of arrays), its increments as a flat
float64 vector, a tuple of constant data, and a few ``numba.njit`` kernels
(:class:`EngineKernels`)::

    rate(data, t, y, u, out) -> q       out = dexpinv_u f(t, y); q: quadrature rate (or 0)
    action(data, u, y, out)             out = Lambda(u, y)
    angle(data, u) -> float             largest rotation angle carried by u
    scale(data, y, out)                 increment scale at y (error norm)
    end_step(data, y)                   optional, in place (re-orthonormalization)
    field(data, t, y, out) -> q         optional, f(t, y) alone (FSAL pairs)
    dexpinv(data, u, w, out)            optional, with field (FSAL pairs)
    new_state(data, y) -> y'            optional, an uninitialized state like y
    copy_state(data, src, dst)          optional, dst <- src
    increment_view(data, u) -> view     optional, the kernels' shape of a flat increment
    increment_views(data, K) -> view    optional, the same for rows K (k, m)

Everything else lives here, once: the stages and their cancellation-safe combinations
(:func:`~liegroup_int.integrators.combine_numba.combine_into`), FSAL reuse, the
finiteness and rotation-angle checks, landing on output times, the embedded error norm
and the :class:`~.controller.PIController` (compiled from the same functions the Python
driver calls). The arithmetic is that of :func:`~liegroup_int.integrators.rkmk.rkmk_step`
and of the drivers, so the compiled and generic paths agree to round-off.

How the kernels get into the loops. The loop functions below are written once, as plain
Python calling the global names ``RATE``, ``ACTION``, ... . :func:`engine_for` builds a
copy of each with those names bound to a plugin's kernels (a new function object over the
same code, with its own globals) and compiles it: numba inlines calls to the kernels, as
for a closure over other ``@njit`` functions. Unlike a closure (whose captured
dispatchers pickle differently in every process), the copies can be cached on disk:
each is named after the plugin and a hash of the package's and the kernels' source files,
so numba keeps one cache entry per plugin and any change to the code they call compiles
anew. A plugin may instead hand a large kernel to the loops as a first-class function
value in its data (:class:`FunctionValue`, typed by :attr:`CompiledProblem.functions`):
the loops then call it through its address and compile without its code.
"""

from __future__ import annotations

import hashlib
import inspect
import math
import types
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np
from numba import njit
from numba.core import types as nbtypes
from numba.experimental import function_type as _function_type  # noqa: F401  (types a FunctionValue argument)

from . import controller as _controller
from .combine_numba import combine_into as _combine

ADVANCE_OK, ADVANCE_NON_FINITE, ADVANCE_ANGLE = 0, 1, 2
ADAPTIVE_OK, ADAPTIVE_MAX_STEPS, ADAPTIVE_UNDERFLOW = 0, 1, 2
_FIXED_STATUS = {ADVANCE_OK: "ok", ADVANCE_NON_FINITE: "non-finite", ADVANCE_ANGLE: "angle"}
_ADAPTIVE_STATUS = {ADAPTIVE_OK: "ok", ADAPTIVE_MAX_STEPS: "max-steps", ADAPTIVE_UNDERFLOW: "underflow"}

_h_accepted = njit(cache=True)(_controller.h_accepted)
_h_rejected = njit(cache=True)(_controller.h_rejected)
_rotation_rate = njit(cache=True)(_controller.rotation_rate)
_rotation_cap = njit(cache=True)(_controller.rotation_cap)


@njit(cache=True)
def no_end_step(data, y):
    """End step of problems without one."""


@njit(cache=True)
def no_field(data, t, y, out):
    """Placeholder of problems without a separate vector field (never called)."""
    return 0.0


@njit(cache=True)
def no_watch(data, t, y):
    """Watch kernel of problems without compiled events (never stops a loop)."""
    return False


@njit(cache=True)
def no_dexpinv(data, u, w, out):
    """Placeholder of problems without a separate dexpinv (never called)."""


@njit(cache=True)
def flat_new_state(data, y):
    """An uninitialized state like the flat vector ``y``."""
    return np.empty_like(y)


@njit(cache=True, inline="always")
def copy_flat(src, dst):
    """``dst[:] = src`` for 1-D arrays of equal length, as a loop: a slice assignment compiles
    numba's shape check and its error-message formatting into every loop that inlines it."""
    for j in range(dst.shape[0]):
        dst[j] = src[j]


@njit(cache=True)
def flat_copy_state(data, src, dst):
    """``dst[:] = src`` for flat states."""
    copy_flat(src, dst)


@njit(cache=True, inline="always")
def flat_view(data, x):
    """Increments as the kernels see them: flat (the default)."""
    return x



@dataclass(frozen=True)
class Advance:
    """What the compiled engine's fixed-step loop reports back
    (:meth:`CompiledStepper.advance`).

    Attributes
    ----------
    y : state
        State after the accepted steps.
    t : float
        Its time.
    steps : int
        Accepted steps.
    h_min, h_max : float
        Smallest and largest accepted step (``inf``, ``0`` if none).
    status : {"ok", "non-finite", "angle"}
        ``"ok"``: all requested steps taken. Otherwise the next step failed the driver's
        checks: a non-finite increment, or a rotation increment above the bound.
    t_fail : float
        Time at which the failed step would have ended (NaN if none).
    angle : float
        Rotation angle of the failed step's increment (``"angle"`` only).
    quadrature : float
        ``sum h b . q`` of the accepted steps (``Problem.quadrature_rate``), 0 if none.
    rhs_evals : int
        Vector-field evaluations made (the failed step's included).
    last : object
        The last accepted step: ``last.t``, ``last.y`` (its start time and state) and
        ``last.K`` (its stage rates, flat rows), for dense output.
    """

    y: object
    t: float
    steps: int
    h_min: float
    h_max: float
    status: str
    t_fail: float
    angle: float
    quadrature: float = 0.0
    rhs_evals: int = 0
    last: object = None



@dataclass(frozen=True)
class AdaptiveAdvance:
    """What the compiled engine's adaptive loop reports back
    (:meth:`CompiledStepper.advance_to`).

    Attributes
    ----------
    y : state
        State after the accepted steps.
    t : float
        Its time (``status == "ok"``: the landing time, or the end of the first step past
        the stop).
    h : float
        Next step to try (after the last accepted or rejected step); for
        ``"underflow"`` the step that fell below the bound.
    err_prev : float
        Controller memory (error norm of the last accepted step, at least 1e-4).
    steps, rejected, attempts : int
        Accepted steps, rejected steps, and all steps tried (each costs one
        evaluation per stage).
    h_min, h_max : float
        Smallest and largest accepted step (``inf``, ``0`` if none).
    status : {"ok", "max-steps", "underflow"}
        ``"ok"``: reached the stop. ``"max-steps"``: the step budget ran out before
        the next attempt. ``"underflow"``: a rejection shrank the step below
        ``1e-14 max(1, |t|)``.
    quadrature : float
        ``sum h b . q`` of the accepted steps (``Problem.quadrature_rate``), 0 if none.
    rhs_evals : int
        Vector-field evaluations made.
    rate : float
        Controller memory: the rotation rate once the guard has rejected a step, else 0
        (:func:`~liegroup_int.integrators.controller.rotation_rate`).
    last : object
        The last accepted step, as in :class:`Advance`.
    """

    y: object
    t: float
    h: float
    err_prev: float
    steps: int
    rejected: int
    attempts: int
    h_min: float
    h_max: float
    status: str
    quadrature: float = 0.0
    rhs_evals: int = 0
    rate: float = 0.0
    last: object = None


@dataclass(frozen=True)
class EngineKernels:
    """The compiled kernels of one plugin (see the module docstring for their contract).

    Parameters
    ----------
    name : str
        Short plugin name (part of the compiled functions' names).
    rate, action, angle, scale : numba dispatcher
    end_step, field, dexpinv, new_state, copy_state : numba dispatcher or None
        ``None``: no end step; no FSAL reuse; flat float64 vector states.
    increment_view, increment_views : numba dispatcher or None
        ``view(data, u)`` and ``views(data, K)``: the kernels' shape of a flat increment
        ``(m,)`` and of rows of increments ``(k, m)`` (views, made once per call); ``None``:
        flat.
    watch : numba dispatcher or None
        ``watch(data, t, y) -> bool`` after every accepted step: ``True`` ends the call
        there (an event function changed sign, :meth:`CompiledStepper.watch`); ``None``:
        never.
    staged_rate : numba dispatcher or None
        ``staged_rate(data, t, y, u, out)``, the stage rate where ``y`` is the state that
        ``action`` has just made from the same increment ``u`` with the same data (every
        stage after the first): it may reuse what the action computed and left in the data;
        ``None``: ``rate``.
    cache : bool
        Whether the engine's loops for these kernels are cached on disk (``False`` for
        kernels that call a user's function).
    """

    name: str
    rate: Callable
    action: Callable
    angle: Callable
    scale: Callable
    end_step: Callable | None = None
    field: Callable | None = None
    dexpinv: Callable | None = None
    new_state: Callable | None = None
    copy_state: Callable | None = None
    increment_view: Callable | None = None
    increment_views: Callable | None = None
    watch: Callable | None = None
    staged_rate: Callable | None = None
    cache: bool = True

    @property
    def fsal(self) -> bool:
        """Whether FSAL pairs may reuse the last stage: a separate ``field`` and
        ``dexpinv``, and no end step (the step then ends in the last stage's state)."""
        return self.field is not None and self.dexpinv is not None and self.end_step is None


@dataclass(frozen=True)
class CompiledProblem:
    """What a problem hands to the engine (:meth:`Problem.compiled_kernels`).

    Parameters
    ----------
    kernels : EngineKernels
    data : tuple
        Constant data passed to every kernel (arrays may be work space of the kernels;
        one ``CompiledProblem`` is not shared between threads).
    increment_size : callable
        ``increment_size(packed) -> int``: length of the flat increment vector for a
        packed state (batches of points may vary in size).
    pack : callable
        ``pack(y)``: the engine's form of the state (C-contiguous float64 arrays: a copy
        or a view, the engine never writes it).
    unpack : callable
        ``unpack(packed) -> y``: the state from the engine's form (arrays the engine
        returns are new; they may be kept).
    functions : tuple of (int, numba.types.FunctionType)
        Entries of ``data`` that are compiled functions passed as first-class function
        values of the given type (a user's vector field): the loops are compiled once per
        function type, cached on disk, and call the function through its address, so a
        new function costs only its own compilation.
    with_events : callable or None
        ``with_events(cp, specs, t0, y0) -> CompiledProblem or None``: ``cp`` with the event
        functions ``specs`` (:class:`~.events.EventSpec`) in its data, watched by the
        kernels' ``watch`` from ``(t0, y0)``; ``None`` when they cannot be compiled.
    """

    kernels: EngineKernels
    data: tuple
    increment_size: Callable[[object], int]
    pack: Callable
    unpack: Callable
    functions: tuple = ()
    with_events: Callable | None = None


# ====================================================================== the loops
# Written once; ``engine_for`` compiles a copy per plugin with RATE, STAGED_RATE, ACTION,
# ANGLE, SCALE, END_STEP, FIELD, DEXPINV, NEW_STATE and COPY_STATE bound to its kernels.
RATE = ACTION = ANGLE = SCALE = END_STEP = FIELD = DEXPINV = NEW_STATE = COPY_STATE = INC_VIEW = INC_VIEWS = WATCH = None
STAGED_RATE = None


def _stage_rate(data, t, y, u, out, staged):
    """The stage rate at ``(t, y)`` with increment ``u``; ``staged``: right after the action
    that made ``y`` from ``u`` (:attr:`EngineKernels.staged_rate`)."""
    if staged:
        return STAGED_RATE(data, t, y, u, out)
    return RATE(data, t, y, u, out)


def _rate_only(data, t, y, u, out, staged):
    """:func:`_stage_rate` of kernels without a staged rate: ``RATE`` at one call site, so
    the loops compile the plugin's rate once."""
    return RATE(data, t, y, u, out)


def _step(data, A, b, cc, fsal, y0, t, h, K, Kv, u, uv, zv, ys, y1, F, Fv, i0, have_f0, q0, qs):
    """One RKMK step of size ``h`` from ``(t, y0)`` (``y0`` not written): stage rates into
    ``K``, total increment into ``u``, end state into ``y1``. ``Kv``, ``uv``, ``zv``
    (zeros) and ``Fv`` are the kernels' views of ``K``, ``u``, zeros and ``F``.

    With ``have_f0``, ``F[i0]`` is ``f(t, y0)`` and ``q0`` its quadrature rate (FSAL); with
    ``fsal`` the last stage's vector field goes to ``F[1 - i0]`` and the step ends in the
    last stage's state (as :func:`~liegroup_int.integrators.rkmk.rkmk_step_fsal`).

    Returns ``(quadrature, evaluations, q_last)``.
    """
    s = b.shape[0]
    evals = 0
    for r in range(s):
        if r == 0 and have_f0:
            copy_flat(F[i0], K[0])
            qs[0] = q0
            continue
        if r > 0:
            _combine(A[r], r, cc[r], K, h, u)
            ACTION(data, uv, y0, ys)
        if fsal and r == s - 1:
            f1 = Fv[1 - i0]
            qs[r] = FIELD(data, t + cc[r] * h, ys, f1)
            DEXPINV(data, uv, f1, Kv[r])
        else:  # one call site: a plugin's rate is compiled into the loop once
            qs[r] = _stage_rate(data, t + cc[r] * h, ys if r > 0 else y0, uv if r > 0 else zv, Kv[r], r > 0)
        evals += 1
    if fsal:
        COPY_STATE(data, ys, y1)
    else:
        _combine(b, s, 1.0, K, h, u)
        ACTION(data, uv, y0, y1)
        END_STEP(data, y1)
    q = 0.0
    for r in range(s):
        q += b[r] * qs[r]
    return h * q, evals, qs[s - 1]


def _workspace(data, s, m, y):
    """Work arrays of one call: stage rates ``K (s, m)``, increment, zeros, stage quadrature
    rates, and three states (a copy of ``y``, the stage state, the next state)."""
    y0 = NEW_STATE(data, y)
    COPY_STATE(data, y, y0)
    return np.empty((s, m)), np.empty(m), np.zeros(m), np.zeros(s), y0, NEW_STATE(data, y), NEW_STATE(data, y)


def _carry(c, i0, have_f0, q0):
    """Keep the FSAL memory in ``c``: which row of ``F`` holds ``f(t, y)``, whether it is
    known, and its quadrature rate (the next call continues from it)."""
    c[0], c[1], c[2] = float(i0), 1.0 if have_f0 else 0.0, q0


def _finite(x):
    for j in range(x.shape[0]):
        if not math.isfinite(x[j]):
            return False
    return True


def _advance_fixed(data, m, A, b, cc, fsal, y, t_start, t_stop, dt, i_first, n_steps, t_return, max_angle, F, c):
    """Steps ``i_first .. n_steps - 1`` of the grid of
    :func:`~liegroup_int.integrators.drivers.integrate_fixed` from ``y`` at its time (step
    ``i`` ends at ``t_start + (i + 1) dt``, the last at ``t_stop``), stopping before the
    first step whose increment is not finite or rotates by more than ``max_angle``, or after
    the first step that ends at or after ``t_return`` or after which ``WATCH`` is true (an
    event's sign change). ``F (2, m)`` and ``c (3,)`` carry the
    FSAL memory from call to call (:func:`_carry`; ``c`` zero: none).

    Returns ``(y, steps, status, t, t_fail, h_min, h_max, angle, quadrature, evals, y_prev, K,
    t_prev)``: the last step's start state, stage rates and start time (dense output).
    """
    s = b.shape[0]
    K, u, zero, qs, y0, ys, y1 = _workspace(data, s, m, y)
    Kv, uv, zv, Fv = INC_VIEWS(data, K), INC_VIEW(data, u), INC_VIEW(data, zero), INC_VIEWS(data, F)
    i0, have_f0, q0 = int(c[0]), c[1] != 0.0, c[2]
    t = t_start + i_first * dt if i_first > 0 else t_start
    h_min, h_max, quad, evals, t_prev = np.inf, 0.0, 0.0, 0, t
    for i in range(i_first, n_steps):
        t_next = t_stop if i == n_steps - 1 else t_start + (i + 1) * dt
        h = t_next - t
        q, ev, q_last = _step(data, A, b, cc, fsal, y0, t, h, K, Kv, u, uv, zv, ys, y1, F, Fv, i0, have_f0, q0, qs)
        evals += ev
        if not _finite(u):
            _carry(c, i0, have_f0, q0)
            return y0, i - i_first, ADVANCE_NON_FINITE, t, t_next, h_min, h_max, np.nan, quad, evals, y1, K, t_prev
        ang = ANGLE(data, uv)
        if ang > max_angle:
            _carry(c, i0, have_f0, q0)
            return y0, i - i_first, ADVANCE_ANGLE, t, t_next, h_min, h_max, ang, quad, evals, y1, K, t_prev
        y0, y1 = y1, y0
        if fsal:
            i0, have_f0, q0 = 1 - i0, True, q_last
        t_prev, t = t, t_next
        h_min, h_max = min(h_min, h), max(h_max, h)
        quad += q
        if WATCH(data, t, y0) or t >= t_return:
            _carry(c, i0, have_f0, q0)
            return y0, i + 1 - i_first, ADVANCE_OK, t, np.nan, h_min, h_max, 0.0, quad, evals, y1, K, t_prev
    _carry(c, i0, have_f0, q0)
    return y0, n_steps - i_first, ADVANCE_OK, t, np.nan, h_min, h_max, 0.0, quad, evals, y1, K, t_prev


def _error_norm(err, s0, s1, rtol, atol):
    """RMS of ``err / (atol + rtol max(s0, s1))`` (NaN in a scale propagates, as
    ``np.maximum``): :func:`~liegroup_int.integrators.rkmk.error_norm`."""
    acc = 0.0
    for j in range(err.shape[0]):
        a, c = s0[j], s1[j]
        sc = a if (a >= c or a != a) else c
        wv = err[j] / (atol + rtol * sc)
        acc += wv * wv
    return math.sqrt(acc / err.shape[0])


def _advance_adaptive(data, m, A, b, cc, e, fsal, y, t, stop, t_land, h, err_prev, rate, rtol, atol, h_max,
                      max_steps_left, max_angle, g, F, c):
    """Accepted and rejected embedded steps from ``(t, y)`` until the first accepted step
    that ends at or after ``stop`` (or after which ``WATCH`` is true): the loop body of
    :func:`~liegroup_int.integrators.drivers.integrate_adaptive`, controller gains ``g``
    (:meth:`PIController.gains`) and memory ``err_prev``, ``rate``
    (:func:`~.controller.rotation_rate`). Steps are shortened to land on ``t_land`` only
    (``stop``: every output time is landed on; the final time: outputs come from the dense
    output). ``F`` and ``c`` carry the FSAL memory as in :func:`_advance_fixed`.

    Returns ``(y, t, h, err_prev, rate, steps, rejected, attempts, h_min, h_max, status,
    quadrature, evals, y_prev, K, t_prev)``: the last accepted step's start state, stage
    rates and start time.
    """
    s = b.shape[0]
    K, u, zero, qs, y0, ys, y1 = _workspace(data, s, m, y)
    Kv, uv, zv, Fv = INC_VIEWS(data, K), INC_VIEW(data, u), INC_VIEW(data, zero), INC_VIEWS(data, F)
    err_v = np.empty(m)
    sc0 = np.empty(m)
    sc1 = np.empty(m)
    i0, have_f0, q0 = int(c[0]), c[1] != 0.0, c[2]
    steps, rejected, attempts, evals, quad, t_prev = 0, 0, 0, 0, 0.0, t
    h_min_acc, h_max_acc = np.inf, 0.0
    land_tol = 1e-12 * max(1.0, abs(t_land))
    SCALE(data, y0, sc0)
    while True:
        if steps >= max_steps_left:
            _carry(c, i0, have_f0, q0)
            return (y0, t, h, err_prev, rate, steps, rejected, attempts, h_min_acc, h_max_acc, ADAPTIVE_MAX_STEPS,
                    quad, evals, y1, K, t_prev)
        land = t + h >= t_land - land_tol
        h_try = t_land - t if land else h
        q, ev, q_last = _step(data, A, b, cc, fsal, y0, t, h_try, K, Kv, u, uv, zv, ys, y1, F, Fv, i0, have_f0, q0,
                              qs)
        evals += ev
        attempts += 1
        _combine(e, s, 0.0, K, h_try, err_v)
        SCALE(data, y1, sc1)
        err = _error_norm(err_v, sc0, sc1, rtol, atol)
        ang = ANGLE(data, uv)
        if not math.isfinite(err):
            err = np.inf
        rate = _rotation_rate(ang, h_try, max_angle, rate)
        if err <= 1.0 and ang <= max_angle:
            t_prev, t = t, (t_land if land else t + h_try)
            y0, y1 = y1, y0
            sc0, sc1 = sc1, sc0
            if fsal:
                i0, have_f0, q0 = 1 - i0, True, q_last
            steps += 1
            quad += q
            h_min_acc = h_try if h_try < h_min_acc else h_min_acc
            h_max_acc = h_try if h_try > h_max_acc else h_max_acc
            h, err_prev = _h_accepted(err, err_prev, h_try, h_max, g)
            h = _rotation_cap(h, rate, max_angle, g)
            if WATCH(data, t, y0) or land or t >= stop:
                _carry(c, i0, have_f0, q0)
                return (y0, t, h, err_prev, rate, steps, rejected, attempts, h_min_acc, h_max_acc, ADAPTIVE_OK,
                        quad, evals, y1, K, t_prev)
        else:
            rejected += 1
            if fsal and not have_f0:  # K[0] = f(t, y0): the retry starts from it
                copy_flat(K[0], F[i0])
                have_f0, q0 = True, qs[0]
            h = _rotation_cap(_h_rejected(err, ang, h_try, max_angle, g), rate, max_angle, g)
            if h < 1e-14 * max(1.0, abs(t)):
                _carry(c, i0, have_f0, q0)
                return (y0, t, h, err_prev, rate, steps, rejected, attempts, h_min_acc, h_max_acc,
                        ADAPTIVE_UNDERFLOW, quad, evals, y1, K, t_prev)


# ====================================================================== specialization
_TEMPLATES = (("_step", _step), ("_advance_fixed", _advance_fixed), ("_advance_adaptive", _advance_adaptive))
_HELPERS = (("_finite", _finite), ("_error_norm", _error_norm), ("_workspace", _workspace), ("_carry", _carry))


@dataclass(frozen=True)
class Engine:
    """The compiled loops of one set of kernels (:func:`engine_for`)."""

    kernels: EngineKernels
    advance_fixed: Callable
    advance_adaptive: Callable


_ENGINES: dict[EngineKernels, Engine] = {}


def _source_hash(kernels: EngineKernels) -> str:
    """Hash of every source file the compiled loops may depend on: the kernels' own files
    and all of the ``liegroup_int`` package (numba's cache watches only the file of the
    function it caches, here this one, so an edit to a callee elsewhere, e.g. a group
    kernel the plugin's kernels call, must change the copies' names to be compiled anew)."""
    files = {p for p in Path(__file__).resolve().parents[1].rglob("*.py")}
    for k in (kernels.rate, kernels.action, kernels.angle, kernels.scale, kernels.end_step, kernels.field,
              kernels.dexpinv, kernels.new_state, kernels.copy_state, kernels.increment_view,
              kernels.increment_views, kernels.watch, kernels.staged_rate):
        if k is not None:
            files.add(Path(inspect.getfile(getattr(k, "py_func", k))).resolve())
    h = hashlib.sha1()
    for path in sorted(files):
        h.update(path.read_bytes())
    return h.hexdigest()[:12]


def engine_for(kernels: EngineKernels) -> Engine:
    """The engine's loops compiled with ``kernels`` (built once per process per kernels)."""
    eng = _ENGINES.get(kernels)
    if eng is not None:
        return eng
    ns = dict(globals())
    ns.update(RATE=kernels.rate, ACTION=kernels.action, ANGLE=kernels.angle, SCALE=kernels.scale,
              END_STEP=kernels.end_step or no_end_step, FIELD=kernels.field or no_field,
              DEXPINV=kernels.dexpinv or no_dexpinv, NEW_STATE=kernels.new_state or flat_new_state,
              COPY_STATE=kernels.copy_state or flat_copy_state, INC_VIEW=kernels.increment_view or flat_view,
              INC_VIEWS=kernels.increment_views or flat_view, WATCH=kernels.watch or no_watch,
              STAGED_RATE=kernels.staged_rate or kernels.rate)
    tag = f"{kernels.name}_{_source_hash(kernels)}" if kernels.cache else kernels.name
    stage_rate = ("_stage_rate", _stage_rate if kernels.staged_rate is not None else _rate_only)
    for name, fn in (stage_rate,) + _HELPERS + _TEMPLATES:
        copy = types.FunctionType(fn.__code__, ns, name, fn.__defaults__)
        copy.__qualname__ = f"{tag}.{name}"
        copy.__doc__ = fn.__doc__
        # the step and the helpers are inlined into the two loops (numba IR inlining)
        loop = name in ("_advance_fixed", "_advance_adaptive")
        # the loops release the GIL: a caller's other threads run while they integrate
        ns[name] = njit(cache=kernels.cache, inline="never", nogil=True)(copy) if loop else \
            njit(cache=kernels.cache, inline="always")(copy)
    eng = Engine(kernels, ns["_advance_fixed"], ns["_advance_adaptive"])
    _ENGINES[kernels] = eng
    return eng


class FunctionValue(nbtypes.WrapperAddressProtocol):
    """A compiled function ``fn`` as a first-class function value of type ``ftype`` (a
    ``numba.types.FunctionType``) whose address is looked up once. Given the dispatcher
    itself, numba looks its compiled wrapper up again at every call of a loop (about 40 us
    a function, more than a one-step call's whole work). Numba's wrapper address protocol
    (``__wrapper_address__``, ``signature``); the address is not pickled.

    The overload is looked up by its argument types first, as a call from Python does:
    numba keys its disk cache by the signature it compiles for, and asked for the full
    signature (with the return type) it would miss the entry that a call from Python, or
    ``liegroup-int compile``, wrote, and compile the kernel again."""

    def __init__(self, fn, ftype):
        self.fn, self.ftype, self._address = fn, ftype, None

    def __wrapper_address__(self) -> int:
        if self._address is None:
            from numba.experimental.function_type import _get_wrapper_address

            sig = self.ftype.signature
            overloads = getattr(self.fn, "overloads", None)
            if overloads is not None and tuple(sig.args) not in overloads:
                self.fn.compile(tuple(sig.args))  # loads the entry a call from Python cached
            self._address = _get_wrapper_address(self.fn, sig)
        return self._address

    def signature(self):
        return self.ftype.signature

    def __getstate__(self):
        return {"fn": self.fn, "ftype": self.ftype, "_address": None}


def typed_entry(loop, args: tuple, functions: dict) -> Callable:
    """The entry point of the numba dispatcher ``loop`` compiled for ``args`` with the
    entries ``functions`` of ``args[0]`` (index -> ``FunctionType``) typed as first-class
    functions (compiled, or loaded from the disk cache, once per signature)."""
    import warnings

    from numba import typeof
    from numba.core import types as nt
    from numba.core.errors import NumbaExperimentalFeatureWarning

    data = nt.Tuple([functions.get(i) or typeof(x) for i, x in enumerate(args[0])])
    sig = (data,) + tuple(typeof(a) for a in args[1:])
    with warnings.catch_warnings():  # first-class function types are "experimental" in numba
        warnings.simplefilter("ignore", NumbaExperimentalFeatureWarning)
        loop.compile(sig)
    return loop.overloads[sig].entry_point


# ====================================================================== Python side
class CompiledStepper:
    """Fixed-step and adaptive loops of one problem and tableau through the engine:
    the objects :func:`~liegroup_int.integrators.drivers.integrate_fixed` and
    :func:`~liegroup_int.integrators.drivers.integrate_adaptive` hand all steps between
    two output times.

    Parameters
    ----------
    cp : CompiledProblem
    tab : ButcherTableau
        Explicit tableau; :meth:`advance_to` needs an embedded pair.
    """

    def __init__(self, cp: CompiledProblem, tab):
        self.cp = cp
        self.engine = engine_for(cp.kernels)
        self.stages = int(tab.stages)
        self.tab = tab
        self.fsal = bool(tab.fsal and cp.kernels.fsal)
        self.A = np.ascontiguousarray(tab.A_f, dtype=float)
        self.b = np.ascontiguousarray(tab.b_f, dtype=float)
        self.c = np.ascontiguousarray(tab.c_f, dtype=float)
        self.e = None if tab.e_f is None else np.ascontiguousarray(tab.e_f, dtype=float)
        self._entries: dict[str, Callable] = {}

    def _loop(self, name: str, args: tuple) -> Callable:
        """The engine loop ``name`` for ``args``: the dispatcher itself, or, when the data
        carry first-class functions, the entry point compiled for their function types
        (a plain call would specialize the loop on each function)."""
        loop = getattr(self.engine, name)
        if not self.cp.functions:
            return loop
        entry = self._entries.get(name)
        if entry is None:
            entry = self._entries[name] = typed_entry(loop, args, dict(self.cp.functions))
        return entry

    def watch(self, specs, t0: float, y0) -> bool:
        """Watch the events ``specs`` in the compiled loops from ``(t0, y0)``: a call then also
        ends after a step over which one of them changes sign. ``False`` (nothing changes)
        when the problem's kernels cannot (a Python ``g``, or kernels without ``watch``)."""
        hook = self.cp.with_events
        cp = hook(self.cp, specs, t0, y0) if hook is not None else None
        if cp is None:
            return False
        self.cp = cp
        self._entries.clear()
        return True

    def memory(self, y) -> FsalMemory:
        """A new FSAL memory for runs from states like ``y`` (empty: the first call evaluates
        ``f(t, y)``)."""
        return FsalMemory(np.empty((2, self.cp.increment_size(self.cp.pack(y)))), np.zeros(3))

    def advance(self, t_start: float, y, t_stop: float, dt: float, n_steps: int, max_angle: float,
                i_first: int = 0, t_return: float = math.inf, memory: FsalMemory | None = None) -> Advance:
        """Steps ``i_first .. n_steps - 1`` of the driver's grid (step ``i`` ends at
        ``t_start + (i + 1) dt``, the last one at ``t_stop``) from ``y`` at the end of step
        ``i_first - 1`` (at ``t_start`` if 0), stopping after the first step that ends at or
        after ``t_return``; ``y`` is not modified. ``memory`` (:meth:`memory`) carries FSAL
        reuse from one call to the next; without it each call starts afresh. See
        :class:`Advance`."""
        cp = self.cp
        args = self._fixed_args(t_start, y, t_stop, dt, n_steps, max_angle, i_first, t_return, memory)
        out = self._loop("advance_fixed", args)(*args)
        yf, steps, status, t, t_fail, h_min, h_max, ang, quad, evals, y_prev, K, t_prev = out
        return Advance(cp.unpack(yf), float(t), int(steps), float(h_min), float(h_max), _FIXED_STATUS[status],
                       float(t_fail), float(ang), float(quad), int(evals), _LastStep(cp, y_prev, K, t_prev))

    def _fixed_args(self, t_start, y, t_stop, dt, n_steps, max_angle, i_first, t_return, memory) -> tuple:
        cp, flat = self.cp, self.cp.pack(y)
        mem = memory if memory is not None else self.memory(y)
        return (cp.data, cp.increment_size(flat), self.A, self.b, self.c, self.fsal, flat, float(t_start),
                float(t_stop), float(dt), int(i_first), int(n_steps), float(t_return), float(max_angle), mem.F, mem.c)

    def compile_fixed(self, y) -> None:
        """Compile (or load from the disk cache) the fixed-step loop for states like ``y``
        without running it. When the data carry first-class functions, only their types
        are needed: the loop compiles while the functions compile elsewhere (``liegroup-int
        compile`` does both side by side)."""
        from numba import typeof

        args = self._fixed_args(0.0, y, 1.0, 1.0, 1, math.inf, 0, math.inf, None)
        if self.cp.functions:
            self._loop("advance_fixed", args)
        else:
            self.engine.advance_fixed.compile(tuple(typeof(a) for a in args))

    def advance_to(self, t, y, stop, h, err_prev, rate, rtol, atol, h_max, max_steps_left, max_angle,
                   gains, t_land: float | None = None, memory: FsalMemory | None = None) -> AdaptiveAdvance:
        """Accepted and rejected steps from ``(t, y)`` until the first accepted step that
        ends at or after ``stop``; steps are shortened to land on ``t_land`` only (default
        ``stop``); ``y`` is not modified; ``gains`` from
        :meth:`~.controller.PIController.gains`; ``memory`` as in :meth:`advance`. See
        :class:`AdaptiveAdvance`."""
        if self.e is None:
            raise ValueError(f"method {self.tab.name!r} has no embedded pair")
        cp, flat = self.cp, self.cp.pack(y)
        mem = memory if memory is not None else self.memory(y)
        args = (cp.data, cp.increment_size(flat), self.A, self.b, self.c, self.e, self.fsal, flat, float(t),
                float(stop), float(stop if t_land is None else t_land), float(h), float(err_prev), float(rate),
                float(rtol), float(atol), float(h_max), int(max_steps_left), float(max_angle),
                np.asarray(gains, dtype=float), mem.F, mem.c)
        out = self._loop("advance_adaptive", args)(*args)
        yf, t, h, err_prev, rate, steps, rejected, attempts, h_min, h_max_acc, status, quad, evals = out[:13]
        return AdaptiveAdvance(cp.unpack(yf), float(t), float(h), float(err_prev), int(steps), int(rejected),
                               int(attempts), float(h_min), float(h_max_acc), _ADAPTIVE_STATUS[status], float(quad),
                               int(evals), float(rate), _LastStep(cp, *out[13:]))


@dataclass(frozen=True)
class FsalMemory:
    """The compiled loops' FSAL memory from one call to the next: two vector fields ``F (2,
    m)`` and ``c = (row of F holding f(t, y), whether it is known, its quadrature rate)``."""

    F: np.ndarray
    c: np.ndarray


class _LastStep:
    """The last accepted step of a call, as the engine returned it: its start time, start
    state and stage rates, converted on request (dense output, events)."""

    def __init__(self, cp: CompiledProblem, y_prev, K: np.ndarray, t_prev: float):
        self._cp, self._y, self.K, self.t = cp, y_prev, K, float(t_prev)

    @property
    def y(self):
        return self._cp.unpack(self._y)
