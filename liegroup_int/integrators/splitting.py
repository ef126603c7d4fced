"""The time loop of splitting methods: symmetric compositions of a problem's own
symmetric second-order splitting (:class:`~liegroup_int.tableaux.composition.Composition`).

A problem that has a symmetric second-order splitting offers ``split_steps(y, h, gammas, n,
t)``: ``n`` steps of length ``h`` from time ``t`` of the composition with coefficients
``gammas`` (a compiled loop in the plugin: the rigid body's exact flows,
:meth:`~liegroup_int.problems.rigid_body.RigidBodyProblem.split_steps`; the Galerkin beam's
kick-drift-kick, :meth:`~liegroup_int.problems.beam.galerkin.GalerkinBeamProblem.split_steps`).
A problem with ``has_quadrature`` also takes ``quadrature=`` (a ``(1,)`` array that gains
the integral of :meth:`~liegroup_int.integrators.problem.Problem.quadrature_rate` over the
steps), which this driver adds to :attr:`Stats.quadrature`, as the RKMK drivers do.
This driver lands on the output times with whole steps: every output time must be a
multiple of ``dt`` from ``t0`` (splitting methods have no continuous extension here), or
with ``fit=True`` an output interval that is not is covered by the fewest equal steps no
longer than ``dt`` (scene runs: a ``t_end`` off the step grid).
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
    return all(np.isfinite(a).all() for a in arrays)  # the method: 1.4 us a call less than np.all


def step_counts(t0: float, t_out: np.ndarray, dt: float, fit: bool = False) -> np.ndarray:
    """Whole steps from ``t0`` to each output time; ValueError naming the first time that
    is not on the step grid, or with ``fit`` the step counts of the intervals that are not
    rounded up (each interval then takes equal steps, :func:`_segments`)."""
    k = (t_out - t0) / dt
    n = np.rint(k).astype(np.int64)
    off = np.flatnonzero(np.abs(k - n) > GRID_TOL * np.maximum(1.0, np.abs(k)))
    if off.size and fit:
        edges = np.concatenate(([t0], t_out))
        per = np.ceil(np.diff(edges) / dt * (1.0 - GRID_TOL)).astype(np.int64)
        return np.cumsum(np.maximum(per, 0))
    if off.size:
        raise ValueError(f"splitting methods land on output times with whole steps: t = {float(t_out[off[0]])!r} is "
                         f"{k[off[0]]:.6g} steps of dt = {dt!r} from t0 (choose dt dividing the output spacing)")
    return n


def integrate_composition(problem, comp: Composition, t_span: tuple[float, float], y0, dt: float,
                          observer=None, t_out=None, stats: Stats | None = None,
                          fit: bool = False) -> tuple[float, np.ndarray, Stats]:
    """Run ``comp`` with step ``dt`` from ``y0`` over ``t_span``; ``observer(t, y)`` at
    ``t0``, at each output time (default: ``t_end``); returns ``(t, y, stats)``.
    ``stats`` continues given counters (a resumed run); ``fit`` lets an output interval
    off the step grid take equal shorter steps (module docstring)."""
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
    counts = step_counts(t0, t_out, dt, fit)
    stats = stats if stats is not None else Stats()
    steps0, evals0, wall0 = stats.steps, stats.rhs_evals, stats.wall_time_s
    quad = np.zeros(1) if getattr(problem, "has_quadrature", False) else None  # the work of the loads
    y, done, t_done, clock = (y0 if hasattr(y0, "arrays") else np.asarray(y0, dtype=float)), 0, t0, \
        time.perf_counter()
    if observer is not None:
        observer(t0, y)
    for t, n in zip(t_out, counts):
        if n > done:
            h = (float(t) - t_done) / int(n - done)
            h = dt if abs(h - dt) <= GRID_TOL * dt else h  # on the grid: the step itself
            if quad is None:
                y = problem.split_steps(y, h, comp.gammas_f, int(n - done), t=t_done)
            else:
                quad[0] = 0.0
                y = problem.split_steps(y, h, comp.gammas_f, int(n - done), t=t_done, quadrature=quad)
                stats.quadrature += float(quad[0])
            if not _finite(y):
                raise BlowUpError(f"non-finite state before t = {t:g}", float(t), steps0 + int(n))
            stats.h_min = min(stats.h_min, h)
            stats.h_max = max(stats.h_max, h)
            done, t_done = int(n), float(t)
            stats.steps, stats.rhs_evals = steps0 + done, evals0 + done * comp.stages
            stats.wall_time_s = wall0 + time.perf_counter() - clock
        if observer is not None and t > t0:
            observer(float(t), y)
    return float(t_out[-1]), y, stats
