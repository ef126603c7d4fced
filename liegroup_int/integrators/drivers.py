"""Fixed-step and adaptive drivers around :func:`rkmk_step`.

Both drivers are plain functions of ``(problem, tableau, t_span, y0, ...)``; they call
the observer at ``t0``, at every output time and at the final time, and an optional
``monitor(t, y, stats)`` after every accepted step (progress bars, checkpoints).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..tableaux import ButcherTableau
from .controller import DEFAULT_CONTROLLER, PIController, h_accepted, h_rejected, rotation_cap, rotation_rate
from .problem import Problem
from .methods import is_commutator_free
from .result import BlowUpError, Stats, StepSizeError
from .rkmk import cf_step, error_estimate, error_norm, rkmk_step_fsal, step_quadrature

#: Default bound on the rotation angle of one step's increment [rad]. The closed-form
#: dexpinv of SO(3) has its pole at 2 pi; 1 rad keeps every stage far from it.
MAX_INCREMENT_ANGLE = 1.0


def _output_times(t0: float, t_end: float, t_out) -> np.ndarray:
    if t_out is None:
        return np.array([t_end])
    t_out = np.asarray(t_out, dtype=float).ravel()
    if np.any(np.diff(t_out) < 0) or (t_out.size and (t_out[0] < t0 or t_out[-1] > t_end)):
        raise ValueError(f"output times must be sorted and inside [{t0}, {t_end}]")
    t_out = t_out[t_out > t0]
    if t_out.size == 0 or t_out[-1] < t_end:
        t_out = np.append(t_out, t_end)
    return t_out


def _workspace(problem: Problem, tab: ButcherTableau, y0) -> np.ndarray:
    z = problem.zero_increment(y0)
    return np.zeros((tab.stages,) + z.shape)


def _fsal(problem: Problem, tab: ButcherTableau) -> bool:
    """Reuse the last stage of an FSAL pair as the next first stage (generic loops)."""
    return bool(tab.fsal and getattr(problem, "fsal_reuse", False))


def _quadrature_workspace(problem: Problem, tab: ButcherTableau) -> np.ndarray | None:
    """Stage values of the problem's quadrature rate, or ``None`` if it has none."""
    return np.zeros(tab.stages) if getattr(problem, "has_quadrature", False) else None


def _blow_up(t: float, step: int) -> BlowUpError:
    return BlowUpError(f"non-finite state at t={t:.6g} (step {step}); the step is beyond the stability limit", t, step)


def _too_large(angle: float, max_angle: float, t: float, step: int) -> StepSizeError:
    return StepSizeError(f"rotation increment {angle:.3g} rad at t={t:.6g} exceeds {max_angle:.3g} rad; reduce dt",
                         t, step)


def _check_finite(u: np.ndarray, t: float, step: int) -> None:
    if not np.all(np.isfinite(u)):
        raise _blow_up(t, step)


def stepper_for(problem, tab: ButcherTableau, monitor=None):
    """The compiled engine's loops (:class:`~.engine.CompiledStepper`) for ``problem`` and
    ``tab``, or ``None``: the problem has no compiled kernels (:meth:`Problem.compiled_kernels`;
    duck-typed problems have none), or a per-step ``monitor`` needs the generic loop. The
    engine (hence numba) is imported only when there are kernels to run."""
    hook = getattr(problem, "compiled_kernels", None)
    cp = hook() if (hook is not None and monitor is None) else None
    if cp is None:
        return None
    from .engine import CompiledStepper

    return CompiledStepper(cp, tab)


def _advance_compiled(stepper, t: float, y, stop: float, dt: float, n: int, max_increment_angle: float,
                      stats: Stats, memory=None, i_first: int = 0, t_return: float = np.inf):
    """Steps ``i_first .. n - 1`` of the grid from ``t`` to ``stop`` in one call of the
    compiled engine (up to the first that ends at or after ``t_return``); counts and errors
    as in the step loop of :func:`integrate_fixed`. Returns the engine's :class:`Advance`."""
    res = stepper.advance(t, y, stop, dt, n, max_increment_angle, i_first, t_return, memory)
    stats.accept_many(res.steps, res.h_min, res.h_max)
    stats.quadrature += res.quadrature
    stats.rhs_evals += res.rhs_evals
    if res.status == "non-finite":
        raise _blow_up(res.t_fail, stats.steps + 1)
    if res.status == "angle":
        raise _too_large(res.angle, max_increment_angle, res.t_fail, stats.steps + 1)
    return res


def _next_stop(on_step, t: float) -> float:
    """Where the compiled engine must hand a step to ``on_step`` next: the first step that
    ends at or after this time (``on_step.next_stop(t)``; without it, every step)."""
    nxt = getattr(on_step, "next_stop", None)
    return t if nxt is None else float(nxt(t))


def _attach(stepper, on_step) -> None:
    """Let ``on_step`` hand its events to the compiled ``stepper`` (``on_step.attach``)."""
    attach = getattr(on_step, "attach", None)
    if stepper is not None and attach is not None:
        attach(stepper)


def _hand_over(problem: Problem, on_step, res):
    """``on_step`` of the last step of a compiled call; its ``(t, y)`` to stop at, or ``None``."""
    last = res.last
    y_prev = last.y
    K = last.K.reshape((last.K.shape[0],) + np.shape(problem.zero_increment(y_prev)))
    return on_step(last.t, y_prev, res.t, res.y, K)


def integrate_fixed(
    problem: Problem,
    tab: ButcherTableau,
    t_span: tuple[float, float],
    y0,
    dt: float,
    observer: Callable | None = None,
    t_out=None,
    monitor: Callable | None = None,
    max_increment_angle: float = MAX_INCREMENT_ANGLE,
    stats: Stats | None = None,
    on_step: Callable | None = None,
):
    """Integrate with constant step ``dt`` (shortened only to land on output times).

    Parameters
    ----------
    problem : Problem
    tab : ButcherTableau
    t_span : (float, float)
        ``(t0, t_end)`` with ``t_end > t0``.
    y0 : state
    dt : float
        Step size, ``0 < dt``.
    observer : callable, optional
        ``observer(t, y)`` called at ``t0`` and at every output time.
    t_out : array_like, optional
        Output times in ``(t0, t_end]``; ``t_end`` is always one.
    monitor : callable, optional
        ``monitor(t, y, stats)`` after every step. Without one, the compiled engine
        takes all the steps between two output times in one call when the problem has
        compiled kernels (:meth:`Problem.compiled_kernels`).
    max_increment_angle : float
        A step whose rotational increment exceeds this angle raises
        :class:`StepSizeError` (dt too large for the rotation rate).
    stats : Stats, optional
        Counters to continue (resumed runs); a new one otherwise.
    on_step : callable, optional
        ``on_step(t_old, y_old, t_new, y_new, K) -> None or (t, y)`` after every accepted
        RKMK step, with ``K`` the step's stage rates (dense output and events,
        :class:`~.events.DenseRun`); returning ``(t, y)`` ends the run there (a terminal
        event). The compiled engine hands it the steps it asks for (``on_step.next_stop(t)``:
        the first step that ends at or after that time; without the method, every step).

    Returns
    -------
    (t_end, y_end, stats)
    """
    t0, t_end = float(t_span[0]), float(t_span[1])
    if not dt > 0:
        raise ValueError(f"dt must be positive, got {dt!r}")
    stops = _output_times(t0, t_end, t_out)
    stats = stats if stats is not None else Stats()
    cf = is_commutator_free(tab)  # several exponentials per stage, no dexpinv
    if cf and on_step is not None:
        raise ValueError(f"method {tab.name!r}: dense output and events need an RKMK method")
    stepper = stepper_for(problem, tab, monitor) if not cf else None
    steps = _GenericSteps(problem, tab, y0, stats, monitor, on_step) if stepper is None else None
    memory = stepper.memory(y0) if stepper is not None else None
    _attach(stepper, on_step)
    t, y = t0, y0
    if observer is not None:
        observer(t, y)
    start = time.perf_counter()
    for stop in stops:
        # steps of dt from the last stop; the last one lands exactly on ``stop``
        n = max(1, int(np.ceil((stop - t) / dt - 1e-9)))
        if stepper is not None and on_step is not None:
            t, y, stopped = _compiled_steps(stepper, problem, t, y, stop, dt, n, max_increment_angle, stats, memory,
                                            on_step)
            if stopped:
                break
        elif stepper is not None:
            res = _advance_compiled(stepper, t, y, stop, dt, n, max_increment_angle, stats, memory)
            t, y = res.t, res.y
        else:
            t, y, stopped = _fixed_steps(steps, t, y, stop, dt, n, max_increment_angle)
            if stopped:
                break
        if observer is not None:
            observer(t, y)
    stats.wall_time_s += time.perf_counter() - start
    return t, y, stats


def _compiled_steps(stepper, problem: Problem, t: float, y, stop: float, dt: float, n: int, max_angle: float,
                    stats: Stats, memory, on_step):
    """:func:`_fixed_steps` through the compiled engine: the grid's steps in calls that end
    where ``on_step`` needs the next step (:func:`_next_stop`). ``(t, y, stopped)``."""
    t_start, i = t, 0
    while i < n:
        res = _advance_compiled(stepper, t_start, y, stop, dt, n, max_angle, stats, memory, i,
                                _next_stop(on_step, t))
        i += res.steps
        hit = _hand_over(problem, on_step, res)
        if hit is not None:
            return hit[0], hit[1], True
        t, y = res.t, res.y
    return t, y, False


class _GenericSteps:
    """The drivers' generic (Python) step: work arrays, FSAL reuse and the book-keeping of
    an accepted step (counters, quadrature, ``monitor``, ``on_step``)."""

    def __init__(self, problem: Problem, tab: ButcherTableau, y0, stats: Stats, monitor, on_step):
        self.problem, self.tab, self.stats = problem, tab, stats
        self.monitor, self.on_step = monitor, on_step
        self.cf = is_commutator_free(tab)
        self.K = _workspace(problem, tab, y0)
        self.Q = _quadrature_workspace(problem, tab)
        self.fsal = _fsal(problem, tab)
        self.f0 = None  # f(t, y) of the current state, once known (FSAL pairs; kept over rejections)

    def attempt(self, t: float, y, h: float):
        """One step of size ``h`` from ``(t, y)``: ``(y_new, u, f_last)``; stage rates in ``K``."""
        if self.cf:
            y_new, u = cf_step(self.problem, self.tab, t, y, h, self.K, self.Q)
            f_last = None
        else:
            y_new, u, f_last = rkmk_step_fsal(self.problem, self.tab, t, y, h, self.K, self.Q, self.f0, self.fsal)
        self.stats.rhs_evals += self.tab.stages - (self.f0 is not None)
        if self.fsal and self.f0 is None:
            self.f0 = self.K[0].copy()  # f(t, y): reused by retries of this step
        return y_new, u, f_last

    def accept(self, t_old: float, y_old, t: float, y, h: float, f_last):
        """Book-keeping of an accepted step; ``on_step``'s ``(t, y)`` to stop at, or ``None``."""
        self.f0 = f_last
        self.stats.accept(h)
        if self.Q is not None:
            self.stats.quadrature += step_quadrature(self.tab, self.Q, h)
        if self.monitor is not None:
            self.monitor(t, y, self.stats)
        return self.on_step(t_old, y_old, t, y, self.K) if self.on_step is not None else None


def _fixed_steps(steps: _GenericSteps, t: float, y, stop: float, dt: float, n: int, max_angle: float):
    """``n`` steps of :func:`integrate_fixed`'s grid from ``(t, y)`` to ``stop``:
    ``(t, y, stopped)``, ``stopped`` when ``on_step`` ended the run at ``(t, y)``."""
    t_start = t
    for i in range(n):
        t_next = stop if i == n - 1 else t_start + (i + 1) * dt
        h = t_next - t
        y_new, u, f_last = steps.attempt(t, y, h)
        _check_finite(u, t_next, steps.stats.steps + 1)
        angle = steps.problem.rotation_angle(u)
        if angle > max_angle:
            raise _too_large(angle, max_angle, t_next, steps.stats.steps + 1)
        hit = steps.accept(t, y, t_next, y_new, h, f_last)
        if hit is not None:
            return hit[0], hit[1], True
        t, y = t_next, y_new
    return t, y, False


def initial_step(problem: Problem, tab: ButcherTableau, t0: float, y0, t_end: float, rtol: float, atol: float) -> float:
    """Starting step size (Hairer-Norsett-Wanner I, II.4, algorithm of eq. 4.14)."""
    order = min(tab.order, tab.order_hat if tab.order_hat is not None else tab.order)
    z = problem.zero_increment(y0)
    scale = atol + rtol * problem.increment_scale(y0)
    f0 = problem.increment_rate(t0, y0, z)
    d0 = float(np.sqrt(np.mean((problem.increment_scale(y0) / scale) ** 2)))
    d1 = float(np.sqrt(np.mean((f0 / scale) ** 2)))
    h0 = 1e-6 if (d0 < 1e-5 or d1 < 1e-5) else 0.01 * d0 / d1
    h0 = min(h0, t_end - t0)
    y1 = problem.action(h0 * f0, y0)
    f1 = problem.increment_rate(t0 + h0, y1, h0 * f0)
    d2 = float(np.sqrt(np.mean(((f1 - f0) / scale) ** 2))) / h0
    if max(d1, d2) <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / (order + 1))
    return min(100 * h0, h1, t_end - t0)


def integrate_adaptive(
    problem: Problem,
    tab: ButcherTableau,
    t_span: tuple[float, float],
    y0,
    rtol: float = 1e-6,
    atol: float = 1e-9,
    observer: Callable | None = None,
    t_out=None,
    monitor: Callable | None = None,
    h0: float | None = None,
    h_max: float = np.inf,
    max_steps: int = 10_000_000,
    max_increment_angle: float = MAX_INCREMENT_ANGLE,
    controller: PIController = DEFAULT_CONTROLLER,
    stats: Stats | None = None,
    on_step: Callable | None = None,
):
    """Integrate with an embedded pair and PI step-size control.

    The local error ``h sum (b - b_hat) k`` is measured in the increment space with
    the RMS norm of ``err / (atol + rtol * scale)``. The step size follows
    ``controller`` (:class:`~.controller.PIController`: ``h_new = h * safety *
    err^(-0.7/k) * err_prev^(0.4/k)`` with ``k = min(order, order_hat) + 1`` by default,
    Hairer-Wanner II, IV.2). Steps whose rotational increment exceeds
    ``max_increment_angle`` are rejected too (they would approach the 2 pi pole of
    dexpinv). Output times are hit exactly by shortening steps.

    Without a ``monitor``, the compiled engine runs all the attempts between two output
    times in one call when the problem has compiled kernels
    (:meth:`Problem.compiled_kernels`), with the same arithmetic, controller and limits.

    ``on_step(t_old, y_old, t_new, y_new, K)`` is called after every accepted step as in
    :func:`integrate_fixed` (returning ``(t, y)`` ends the run there; the compiled engine
    hands it the steps it asks for, and lands on the final time only).

    Returns
    -------
    (t_end, y_end, stats)
    """
    if getattr(tab, "b_hat_f", None) is None:
        raise ValueError(f"method {tab.name!r} has no embedded pair; give a fixed dt instead of rtol/atol")
    if not (rtol > 0 and atol > 0):
        raise ValueError(f"rtol and atol must be positive, got rtol={rtol!r}, atol={atol!r}")
    t0, t_end = float(t_span[0]), float(t_span[1])
    stops = _output_times(t0, t_end, t_out)
    stats = stats if stats is not None else Stats()
    stepper = stepper_for(problem, tab, monitor)
    steps = _GenericSteps(problem, tab, y0, stats, monitor, on_step) if stepper is None else None
    run = _AdaptiveRun(rtol, atol, h_max, max_steps, max_increment_angle, controller.gains(tab),
                       _initial_control(problem, tab, (t0, t_end), y0, rtol, atol, h0, h_max, controller, stats),
                       stepper.memory(y0) if stepper is not None else None)
    stats.controller = run.ctl.memory()
    _attach(stepper, on_step)
    t, y = t0, y0
    if observer is not None:
        observer(t, y)
    start = time.perf_counter()
    for stop in stops:
        if stepper is not None and on_step is not None:  # calls that end where on_step needs a step
            t, y, stopped = run.compiled_dense(stepper, problem, t, y, stop, stats, on_step)
            if stopped:
                break
        elif stepper is not None:  # every attempt up to ``stop`` in one compiled call
            res = run.compiled(stepper, t, y, stop, stats)
            t, y = res.t, res.y
        else:
            t, y, stopped = run.generic(steps, t, y, stop)
            if stopped:
                break
        stats.controller = run.ctl.memory()  # kept at every output time (resumed runs)
        if observer is not None:
            observer(t, y)
    stats.wall_time_s += time.perf_counter() - start
    return t, y, stats


@dataclass
class _Control:
    """The adaptive controller's memory: the next step to try, the last error norm and the
    rotation rate (0 until the rotation guard rejects a step: controller.rotation_rate)."""

    h: float
    err_prev: float
    rate: float

    def memory(self) -> dict:
        return {"h": float(self.h), "err_prev": float(self.err_prev), "rate": float(self.rate)}


def _initial_control(problem, tab, t_span, y0, rtol, atol, h0, h_max, controller, stats) -> _Control:
    """A continued run's controller as it was at its last output (``stats.controller``), or
    a new one from ``h0`` or :func:`initial_step`."""
    memory = stats.controller
    if memory is not None and h0 is None:
        return _Control(min(memory["h"], h_max), memory["err_prev"], memory["rate"])
    h = h0 if h0 is not None else initial_step(problem, tab, t_span[0], y0, t_span[1], rtol, atol)
    return _Control(min(h, h_max), controller.err_floor, 0.0)


@dataclass
class _AdaptiveRun:
    """The limits and controller of one adaptive run; attempts up to one output time."""

    rtol: float
    atol: float
    h_max: float
    max_steps: int
    max_angle: float
    gains: tuple
    ctl: _Control
    memory: object = None  # the compiled engine's FSAL memory

    def compiled_dense(self, stepper, problem: Problem, t: float, y, t_land: float, stats: Stats, on_step):
        """Attempts from ``(t, y)`` to ``t_land`` in compiled calls that end where ``on_step``
        needs the next step (:func:`_next_stop`), landing on ``t_land`` only. ``(t, y,
        stopped)``."""
        while True:
            res = self.compiled(stepper, t, y, min(_next_stop(on_step, t), t_land), stats, t_land)
            hit = _hand_over(problem, on_step, res)
            if hit is not None:
                return hit[0], hit[1], True
            t, y = res.t, res.y
            if t == t_land:
                return t, y, False

    def compiled(self, stepper, t: float, y, stop: float, stats: Stats, t_land: float | None = None):
        """Every attempt from ``(t, y)`` up to the first accepted step that ends at or after
        ``stop`` (landing on ``t_land``, default ``stop``) in one call of the compiled engine;
        returns the engine's :class:`AdaptiveAdvance`."""
        c = self.ctl
        res = stepper.advance_to(t, y, stop, c.h, c.err_prev, c.rate, self.rtol, self.atol, self.h_max,
                                 self.max_steps - stats.steps, self.max_angle, self.gains, t_land, self.memory)
        stats.accept_many(res.steps, res.h_min, res.h_max)
        stats.quadrature += res.quadrature
        stats.rejected += res.rejected
        stats.rhs_evals += res.rhs_evals
        c.h, c.err_prev, c.rate = res.h, res.err_prev, res.rate
        if res.status == "max-steps":
            raise StepSizeError(f"reached max_steps={self.max_steps} at t={res.t:.6g}", res.t, stats.steps)
        if res.status == "underflow":
            raise StepSizeError(f"step size underflow (h={c.h:.3g}) at t={res.t:.6g}", res.t, stats.steps)
        return res

    def generic(self, steps: _GenericSteps, t: float, y, stop: float):
        """Attempts from ``(t, y)`` until a step lands on ``stop``: ``(t, y, stopped)``,
        ``stopped`` when ``on_step`` ended the run at ``(t, y)``."""
        c, stats = self.ctl, steps.stats
        while True:
            if stats.steps >= self.max_steps:
                raise StepSizeError(f"reached max_steps={self.max_steps} at t={t:.6g}", t, stats.steps)
            land = t + c.h >= stop - 1e-12 * max(1.0, abs(stop))
            h_try = stop - t if land else c.h
            y_new, u, f_last = steps.attempt(t, y, h_try)
            err, angle = self._measure(steps, y, y_new, u, h_try)
            c.rate = rotation_rate(angle, h_try, self.max_angle, c.rate)
            if err <= 1.0 and angle <= self.max_angle:
                t_new = stop if land else t + h_try
                c.h, c.err_prev = h_accepted(err, c.err_prev, h_try, self.h_max, self.gains)
                c.h = rotation_cap(c.h, c.rate, self.max_angle, self.gains)
                hit = steps.accept(t, y, t_new, y_new, h_try, f_last)
                if hit is not None:
                    return hit[0], hit[1], True
                t, y = t_new, y_new
                if land:
                    return t, y, False
            else:
                stats.rejected += 1
                c.h = rotation_cap(h_rejected(err, angle, h_try, self.max_angle, self.gains), c.rate,
                                   self.max_angle, self.gains)
                if c.h < 1e-14 * max(1.0, abs(t)):
                    raise StepSizeError(f"step size underflow (h={c.h:.3g}) at t={t:.6g}", t, stats.steps)

    def _measure(self, steps: _GenericSteps, y, y_new, u, h: float) -> tuple[float, float]:
        """``(err, angle)`` of an attempt: the embedded error norm (``inf`` if not finite)
        and the rotation angle of its increment."""
        p = steps.problem
        err = error_norm(error_estimate(steps.tab, steps.K, h),
                         np.maximum(p.increment_scale(y), p.increment_scale(y_new)), self.rtol, self.atol)
        return (err if np.isfinite(err) else np.inf), p.rotation_angle(u)
