"""Best-of timing for the benchmark scripts.

:func:`best_of` calls a function once untimed (numba compilation, caches), then times
``repeats`` batches and returns the best time per call. A call shorter than ``min_time``
is repeated within a batch until the batch lasts at least ``min_time`` seconds, so short
calls are not dominated by the clock's resolution. The clock is process CPU time by
default (``time.process_time``: less disturbed by other processes on a shared machine
than wall time); pass ``clock=time.perf_counter`` for wall time.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any, NamedTuple


class Timing(NamedTuple):
    """Best seconds per call over the batches, calls per batch, and the last result."""

    seconds: float
    calls: int
    result: Any


def best_of(fn: Callable[[], Any], repeats: int = 3, min_time: float = 0.0,
            clock: Callable[[], float] = time.process_time) -> Timing:
    """Best time per call of ``fn()`` over ``repeats`` batches, after one untimed call
    (see the module docstring)."""
    if repeats < 1:
        raise ValueError(f"best_of: repeats must be >= 1, got {repeats}")
    result = fn()
    calls = 1
    if min_time > 0:
        t0 = clock()
        result = fn()
        calls = max(1, math.ceil(min_time / max(clock() - t0, 1e-9)))
    best = math.inf
    for _ in range(repeats):
        t0 = clock()
        for _ in range(calls):
            result = fn()
        best = min(best, (clock() - t0) / calls)
    return Timing(best, calls, result)


def cpu(fn: Callable[[], Any], clock: Callable[[], float] = time.process_time) -> tuple[Any, float]:
    """``(fn(), seconds)`` of one call (no warm-up, no repeats)."""
    t0 = clock()
    result = fn()
    return result, clock() - t0
