"""The cantilever set-up timed by ``benchmarks/beam_backends.py`` and ``stage_flops.py``.

The built-in ``cantilever`` at p = 4 with ``n_ctrl`` control points (primal collocation),
RKMK4, started from a smooth deformed and moving state (:func:`start_state`): from rest, with the tiny steps
large meshes need, the far field underflows to subnormal numbers during the first hundreds
of steps and subnormal arithmetic slows every backend by ~2x on x86. The step
``dt = 0.3e-6 (31 / n)^2`` (:func:`step_dt`) is below the stability limit at every size
from ``n_ctrl = 31``.
"""

from __future__ import annotations

import time

import numpy as np

from ..integrators import integrate_fixed, resolve_method
from ..scenes import load_scene
from ..scenes.beam import problem as scene_problem
from .timing import best_of

TAB = resolve_method("rkmk4")


def cantilever(n: int, backend: str = "numba", formulation: str = "primal"):
    """The built-in cantilever, p = 4, ``n_ctrl = n``, with the given stage backend, in primal
    collocation unless ``formulation`` says otherwise (the benchmarks count per collocation point)."""
    return scene_problem(load_scene("cantilever", {"space.n_ctrl": n, "space.degree": 4,
                                                   "integrator.backend": backend, "space.formulation": formulation}))


def start_state(pb):
    """Smooth deformed, moving state: ``Lambda(u, y0)`` with control values
    ``eta ~ 1e-3 s^2, theta ~ 1e-2 s^2, dv, dw ~ 1e-2 s^2`` (zero at the clamp)."""
    s = np.asarray(pb.space.curve.greville())
    u = np.zeros((4, pb.n, 3))
    u[0, :, 1], u[0, :, 2] = 5e-4 * s**3, 1e-3 * s**2
    u[1, :, 1], u[1, :, 2] = 1e-2 * s**2, 5e-3 * s**3
    u[2, :, 2] = 1e-2 * s**2
    u[3, :, 1] = 1e-2 * s**2
    return pb.action(u, pb.initial_state())


def step_dt(n: int) -> float:
    """The fixed step at ``n_ctrl = n``."""
    return 0.3e-6 * (31.0 / n) ** 2


def no_monitor(t, y, stats):
    """A per-step monitor that does nothing: keeps the driver on its generic loop."""


class NullProblem:
    """The driver's own cost: increments of the beam's shape, no work."""

    def __init__(self, n):
        self.n = n

    def action(self, u, y):
        return y

    def end_step(self, y):
        return y

    def increment_rate(self, t, y, u):
        return np.zeros((4, self.n, 3))

    def zero_increment(self, y):
        return np.zeros((4, self.n, 3))

    def rotation_angle(self, u):
        return 0.0


def time_steps(prob, y, dt: float, batch_s: float, repeats: int, monitor=None, clock=time.process_time):
    """Best seconds per RKMK4 step over ``repeats`` batches of ``N`` steps (a batch lasts
    at least ``batch_s``), after a warm-up: ``(seconds, N, end state)``."""
    est = best_of(lambda: integrate_fixed(prob, TAB, (0.0, 10 * dt), y, dt, monitor=monitor), 1,
                  clock=clock).seconds / 10
    N = max(3, int(np.ceil(batch_s / max(est, 1e-7))))
    t = best_of(lambda: integrate_fixed(prob, TAB, (0.0, N * dt), y, dt, monitor=monitor), repeats, clock=clock)
    return t.seconds / N, N, t.result[1]
