"""Observers (sinks) receive ``(t, y)`` at output times; callers choose what is kept.

An observer is any callable ``observer(t, y)``. Nothing but what an observer computes is
computed at output times, so diagnostics cost nothing unless recorded.
"""

from __future__ import annotations

import copy
from typing import Callable, Mapping

import numpy as np


class StateRecorder:
    """Keeps a copy of every observed state.

    Attributes
    ----------
    t : list of float
    y : list
    """

    def __init__(self):
        self.t: list[float] = []
        self.y: list = []

    def __call__(self, t: float, y) -> None:
        self.t.append(float(t))
        self.y.append(copy.deepcopy(y) if not isinstance(y, np.ndarray) else y.copy())


class DiagnosticsRecorder:
    """Evaluates named functions of the state at output times and keeps the values.

    Parameters
    ----------
    functions : mapping of str to callable
        ``name -> fn(t, y)`` returning a float (or an array).

    Attributes
    ----------
    t : list of float
    values : dict of str to list
    """

    def __init__(self, functions: Mapping[str, Callable]):
        self.functions = dict(functions)
        self.t: list[float] = []
        self.values: dict[str, list] = {k: [] for k in self.functions}

    def __call__(self, t: float, y) -> None:
        self.t.append(float(t))
        for k, fn in self.functions.items():
            self.values[k].append(fn(t, y))

    def as_arrays(self) -> dict[str, np.ndarray]:
        out = {"t": np.asarray(self.t)}
        out.update({k: np.asarray(v) for k, v in self.values.items()})
        return out


class Observers:
    """Calls several observers in turn."""

    def __init__(self, *observers: Callable):
        self.observers = observers

    def __call__(self, t: float, y) -> None:
        for obs in self.observers:
            obs(t, y)
