"""The time loop of splitting methods: symmetric compositions of a problem's own
symmetric second-order splitting (:class:`~liegroup_int.tableaux.composition.Composition`).

A problem that has a symmetric second-order splitting offers ``split_steps(y, h, gammas, n,
t)``: ``n`` steps of length ``h`` from time ``t`` of the composition with coefficients
``gammas`` (a compiled loop in the plugin: the rigid body's exact flows,
:meth:`~liegroup_int.problems.rigid_body.RigidBodyProblem.split_steps`; the Galerkin beam's
kick-drift-kick, :meth:`~liegroup_int.problems.beam.galerkin.GalerkinBeamProblem.split_steps`).
This driver lands on the output times with whole steps: every output time must be a
multiple of ``dt`` from ``t0`` (splitting methods have no continuous extension here).
"""

from __future__ import annotations

import time

import numpy as np

from ..tableaux.composition import Composition
from .result import BlowUpError, Stats

#: How far an output time may sit from a whole number of steps, in steps.
GRID_TOL = 1e-9


def _finite(y) -> bool:
    """Every value of a state finite (an array, or a state with ``arrays()``)."""
    arrays = y.arrays().values() if hasattr(y, "arrays") else (y,)
    return all(np.all(np.isfinite(a)) for a in arrays)


def step_counts(t0: float, t_out: np.ndarray, dt: float) -> np.ndarray:
    """Whole steps from ``t0`` to each output time; ValueError naming the first time that
    is not on the step grid."""
    k = (t_out - t0) / dt
    n = np.rint(k).astype(np.int64)
    off = np.flatnonzero(np.abs(k - n) > GRID_TOL * np.maximum(1.0, np.abs(k)))
    if off.size:
        raise ValueError(f"splitting methods land on output times with whole steps: t = {float(t_out[off[0]])!r} is "
                         f"{k[off[0]]:.6g} steps of dt = {dt!r} from t0 (choose dt dividing the output spacing)")
    return n


def integrate_composition(problem, comp: Composition, t_span: tuple[float, float], y0, dt: float,
                          observer=None, t_out=None) -> tuple[float, np.ndarray, Stats]:
    """Run ``comp`` with step ``dt`` from ``y0`` over ``t_span``; ``observer(t, y)`` at
    ``t0``, at each output time (default: ``t_end``); returns ``(t, y, stats)``."""
    split = getattr(problem, "split_steps", None)
    if split is None:
        raise ValueError(f"method {comp.name!r} is a splitting method: it needs a problem with exactly integrable "
                         "flows (split_steps), such as RigidBody.problem(); use an RKMK method here")
    if not (dt is not None and dt > 0):
        raise ValueError(f"method {comp.name!r}: give a fixed step dt > 0 (splitting methods are not adaptive)")
    t0, t_end = float(t_span[0]), float(t_span[1])
    t_out = np.array([t_end]) if t_out is None else np.asarray(t_out, dtype=float).ravel()
    if np.any(np.diff(t_out) < 0) or t_out[0] < t0 or t_out[-1] > t_end:
        raise ValueError(f"output times must be sorted and inside [{t0}, {t_end}]")
    if t_out[-1] < t_end:
        t_out = np.append(t_out, t_end)
    counts = step_counts(t0, t_out, dt)
    stats, y, done, clock = Stats(), (y0 if hasattr(y0, "arrays") else np.asarray(y0, dtype=float)), 0, \
        time.perf_counter()
    if observer is not None:
        observer(t0, y)
    for t, n in zip(t_out, counts):
        if n > done:
            y = problem.split_steps(y, dt, comp.gammas_f, int(n - done), t=t0 + done * dt)
            if not _finite(y):
                raise BlowUpError(f"non-finite state before t = {t:g}", float(t), int(n))
            done = int(n)
        if observer is not None and t > t0:
            observer(float(t), y)
    stats.steps, stats.rhs_evals = done, done * comp.stages
    stats.h_min = stats.h_max = dt
    stats.wall_time_s = time.perf_counter() - clock
    return float(t_out[-1]), y, stats
