"""Events located on the dense output, and the per-step wiring of ``integrate``'s
``t_eval`` / ``dense_output`` / ``events`` (scipy's ``solve_ivp`` conventions).

An event is a function ``g(t, y) -> float`` with optional attributes ``terminal`` (bool,
or the number of occurrences after which the run stops) and ``direction`` (``> 0``: only
crossings from negative to positive; ``< 0``: the reverse; ``0``: both). After every
accepted step ``g`` is evaluated at the step's end; a sign change selected by ``direction``
(scipy's rule: ``g_old <= 0 <= g_new`` is upward, ``g_old >= 0 >= g_new`` downward) is
located by Brent's method on ``t -> g(t, y_dense(t))`` over the step, to
``|dt| <= 4 eps (1 + |t|)`` (scipy's ``xtol = rtol = 4 eps``). The event's time is then
that of the interpolant's root: its error is the dense output's error divided by ``|dg/dt|``.
"""

from __future__ import annotations

import math

from typing import Callable, NamedTuple

import numpy as np

from ..tableaux.continuous import ContinuousExtension
from .dense import DenseSolution, StepInterpolant
from .problem import Problem

EPS = np.finfo(float).eps


class EventSpec(NamedTuple):
    """One event function with scipy's attributes: ``terminal`` as a count (0: never stops)."""

    fn: Callable
    terminal: int
    direction: float


def event_specs(events) -> list[EventSpec]:
    """The :class:`EventSpec` of each event (one callable or a sequence of them)."""
    if events is None:
        return []
    fns = [events] if callable(events) else list(events)
    specs = []
    for fn in fns:
        if not callable(fn):
            raise TypeError(f"events: expected callables g(t, y), got {fn!r}")
        terminal = getattr(fn, "terminal", False)
        count = int(terminal) if not isinstance(terminal, bool) else int(terminal)
        if count < 0:
            raise ValueError(f"event {fn!r}: terminal must be a bool or a count >= 0, got {terminal!r}")
        specs.append(EventSpec(fn, count, float(getattr(fn, "direction", 0.0))))
    return specs


def value(fn: Callable, t: float, y) -> float:
    """``g(t, y)`` as a float; one line naming the result when it is not a number."""
    v = fn(t, y)
    try:
        return float(v)
    except (TypeError, ValueError):
        raise ValueError(f"event g(t, y) must return a number, got {type(v).__name__} of shape {np.shape(v)}") from None


def triggered(g_old: float, g_new: float, direction: float) -> bool:
    """Whether a step from ``g_old`` to ``g_new`` crosses zero in ``direction`` (scipy's rule)."""
    up = g_old <= 0 <= g_new
    down = g_old >= 0 >= g_new
    return (up and direction > 0) or (down and direction < 0) or ((up or down) and direction == 0)


def locate(fn: Callable, interp: Callable, t_old: float, t_new: float) -> float:
    """The root of ``t -> fn(t, interp(t))`` in ``[t_old, t_new]`` (a bracketed sign change),
    to ``xtol = rtol = 4 eps``. (SciPy is imported here, by the runs that have events.)"""
    from scipy.optimize import brentq

    return float(brentq(lambda t: float(fn(t, interp(t))), t_old, t_new, xtol=4 * EPS, rtol=4 * EPS))


class EventTracker:
    """Sign changes of each event over every step; records ``t_events`` and ``y_events``."""

    def __init__(self, specs: list[EventSpec], t0: float, y0):
        self.specs = specs
        self.g = [value(s.fn, t0, y0) for s in specs]
        self.t_events: list[list[float]] = [[] for _ in specs]
        self.y_events: list[list] = [[] for _ in specs]
        self.counts = [0] * len(specs)

    def step(self, dense: Callable, t_old: float, t_new: float, y_new) -> float | None:
        """Records the events of the step; returns the time of a terminal one, else ``None``.
        ``dense()`` returns the step's interpolant (built only when an event is found)."""
        g_new = [value(s.fn, t_new, y_new) for s in self.specs]
        hits = [i for i, s in enumerate(self.specs) if triggered(self.g[i], g_new[i], s.direction)]
        self.g = g_new
        if not hits:
            return None
        interp = dense()
        found = sorted((locate(self.specs[i].fn, interp, t_old, t_new), i) for i in hits)
        for t, i in found:
            self.t_events[i].append(t)
            self.y_events[i].append(interp(t))
            self.counts[i] += 1
            if self.specs[i].terminal and self.counts[i] >= self.specs[i].terminal:
                return t
        return None

    def arrays(self) -> tuple[list[np.ndarray], list[np.ndarray]]:
        """``(t_events, y_events)`` as scipy returns them: one array per event."""
        ys = [(np.array(y) if all(isinstance(v, np.ndarray) for v in y) else list(y)) if y else np.empty((0,))
              for y in self.y_events]
        return [np.array(t, dtype=float) for t in self.t_events], ys


def output_times(t_span: tuple[float, float], t_eval) -> np.ndarray:
    """The output times after ``t0`` (``t_eval`` must be sorted and inside ``t_span``)."""
    t0, t_end = float(t_span[0]), float(t_span[1])
    t = np.asarray(t_eval if t_eval is not None else [], dtype=float).ravel()
    if np.any(np.diff(t) < 0) or (t.size and (t[0] < t0 or t[-1] > t_end)):
        raise ValueError(f"t_eval must be sorted and inside [{t0}, {t_end}]")
    return t[t > t0]


class DenseRun:
    """The drivers' ``on_step`` hook behind ``integrate(t_eval=..., dense_output=...,
    events=...)``: per accepted step, it builds the step's interpolant, looks for events,
    and passes the states at the output times inside the step to ``observer``. Returns
    ``(t, y)`` of a terminal event (the drivers stop there), else ``None``.

    The output times do not shorten steps; ``observer`` sees ``t0`` first.
    """

    def __init__(self, problem: Problem, ext: ContinuousExtension, t_span: tuple[float, float], y0, t_eval,
                 observer, keep: bool, specs: list[EventSpec], stats=None):
        t0 = float(t_span[0])
        self.stats = stats
        self.problem, self.ext, self.observer = problem, ext, observer
        self.t_eval = output_times(t_span, t_eval)
        self.i_eval = 0
        self.stopped = False
        self.pieces: list[StepInterpolant] | None = [] if keep else None
        self.events = EventTracker(specs, t0, y0) if specs else None
        self.t0, self.y0 = t0, y0
        self.last_observed = t0
        self.watched = False  # the compiled engine checks the events' signs itself (attach)
        if observer is not None:
            observer(t0, y0)

    def __call__(self, t_old: float, y_old, t_new: float, y_new, K: np.ndarray):
        built: list[StepInterpolant] = []

        def dense() -> StepInterpolant:  # the step's interpolant, built once if needed
            if not built:
                built.append(StepInterpolant(self.problem, self.ext, t_old, y_old, t_new, y_new, K, self.stats))
            return built[0]

        if self.pieces is not None:
            self.pieces.append(dense())
        if self.watched:  # steps were skipped: the signs to compare are those at this step's start
            self.events.g = [value(s.fn, t_old, y_old) for s in self.events.specs]
        stop = self.events.step(dense, t_old, t_new, y_new) if self.events is not None else None
        t_hi = t_new if stop is None else stop
        while self.i_eval < self.t_eval.size and self.t_eval[self.i_eval] <= t_hi:
            self._observe(self.t_eval[self.i_eval], dense()(self.t_eval[self.i_eval]))
            self.i_eval += 1
        if stop is None:
            return None
        self.stopped = True
        return stop, dense()(stop)

    def attach(self, stepper) -> None:
        """Let the compiled ``stepper`` watch the events' signs (numba-compiled ``g`` on a
        problem whose kernels can), so that it hands over only the steps over which one
        changes sign besides those :meth:`next_stop` asks for."""
        if self.events is not None:
            self.watched = stepper.watch(self.events.specs, self.t0, self.y0)

    def next_stop(self, t: float) -> float:
        """The first step after ``t`` that must be seen ends at or after this time (the
        compiled engine hands over only that step): ``t`` (every step) while the
        interpolants are kept or events are tracked here, else the next output time
        (``inf`` past the last)."""
        if self.pieces is not None or (self.events is not None and not self.watched):
            return t
        return float(self.t_eval[self.i_eval]) if self.i_eval < self.t_eval.size else math.inf

    def _observe(self, t: float, y) -> None:
        if self.observer is not None:
            self.observer(float(t), y)
        self.last_observed = float(t)

    def finish(self, t: float, y) -> DenseSolution | None:
        """Observes the final state (unless it was the last output) and returns the dense
        solution over ``[t0, t]`` when it was kept."""
        if self.last_observed != t:
            self._observe(t, y)
        if self.pieces is None:
            return None
        sol = DenseSolution(self.pieces, self.t0, self.y0)
        sol.t_max = float(t)
        return sol
