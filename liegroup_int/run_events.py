"""Scene events (``[[events]]``) during a run: crossings of a recorded quantity.

The run's loop (compiled engine) only stops at output times. At each one the
:class:`EventWatcher` evaluates every event's ``quantity - value``; a sign change since the
previous output (in the event's direction) is then located exactly: the interval is run
again from the previous output's state with the same method and steps through
:func:`~liegroup_int.integrate` with ``events``, whose roots are found by Brent's method on
the step's dense output (continuous extension of the RKMK step). A terminal event raises
:class:`TerminalEvent` before the output row past it is written; the runner then records
the state at the event and stops there.
"""

from __future__ import annotations

import copy
from typing import Callable

import numpy as np

from .integrators import integrate
from .integrators.methods import is_commutator_free, is_splitting
from .scenes import SceneError
from .scenes.scene import EventSpec, Scene


class TerminalEvent(Exception):
    """A terminal event happened at ``t`` (state ``y``)."""

    def __init__(self, name: str, t: float, y):
        super().__init__(f"event {name!r} at t = {t:.9g}")
        self.name, self.t, self.y = name, t, y


def event_function(scene: Scene, spec: EventSpec, diagnostics: dict, columns: dict) -> Callable:
    """``g(t, y) = quantity - value`` of a history column of a recorded quantity;
    one-line :class:`SceneError` for a column that the run does not record."""
    for q, fn in diagnostics.items():
        names = columns.get(q, [q])
        if spec.quantity in names:
            k = names.index(spec.quantity)
            if len(names) == 1:
                return lambda t, y: float(np.ravel(fn(t, y))[0]) - spec.value
            return lambda t, y: float(np.ravel(fn(t, y))[k]) - spec.value
    known = [c for q in diagnostics for c in columns.get(q, [q])]
    raise SceneError(f"{scene.source}: event {spec.name!r}: key 'quantity' = {spec.quantity!r} is not a recorded "
                     f"column; recorded: {', '.join(known)} (add its quantity to output.quantities)")


def _crosses(g0: float, g1: float, direction: int) -> bool:
    if direction >= 0 and g0 < 0.0 <= g1:
        return True
    return direction <= 0 and g0 > 0.0 >= g1


class EventWatcher:
    """Wraps the run's output observer (module docstring); ``found`` lists the events as
    ``{"name", "t", "terminal"}``."""

    def __init__(self, scene: Scene, sim, tab, dt, observer: Callable):
        if scene.events and (is_commutator_free(tab) or is_splitting(tab)):
            raise SceneError(f"{scene.source}: key 'events': locating events needs an RKMK method (dense output), "
                             f"not {tab.name!r}")
        columns = sim.info.get("columns") or {}
        self.events = [(e, event_function(scene, e, sim.diagnostics, columns)) for e in scene.events]
        self.scene, self.problem, self.tab, self.dt, self.observer = scene, sim.problem, tab, dt, observer
        self.found: list[dict] = []
        self._prev = None

    def __call__(self, t: float, y) -> None:
        if self.events:
            now = [g(t, y) for _, g in self.events]
            if self._prev is not None:
                self._check(self._prev, (t, y, now))
            self._prev = (t, copy.deepcopy(y), now)
        self.observer(t, y)

    def _check(self, prev, cur) -> None:
        crossing = [(e, g) for (e, g), a, b in zip(self.events, prev[2], cur[2]) if _crosses(a, b, e.direction)]
        if not crossing:
            return
        terminal = any(e.terminal for e, _ in crossing)
        funcs = []
        for e, g in crossing:
            f = lambda t, y, g=g: g(t, y)  # noqa: E731
            f.direction, f.terminal = e.direction, e.terminal
            funcs.append(f)
        spec = self.scene.integrator
        kw = {"dt": self.dt} if self.dt is not None else {"rtol": spec.rtol or 1e-6, "atol": spec.atol or 1e-9}
        sol = integrate(self.problem, copy.deepcopy(prev[1]), (prev[0], cur[0]), method=self.tab.name,
                        events=funcs, **kw)
        hits = sorted(((float(te), e) for (e, _), ts in zip(crossing, sol.t_events) for te in ts), key=lambda x: x[0])
        for te, e in hits:
            self.found.append({"name": e.name, "t": te, "terminal": e.terminal})
            if e.terminal:
                raise TerminalEvent(e.name, te, sol.y_final)
        if terminal:  # the refined run found no root where the outputs bracket one: stop at the output
            self.found.append({"name": crossing[0][0].name, "t": float(cur[0]), "terminal": True})
            raise TerminalEvent(crossing[0][0].name, float(cur[0]), cur[1])
