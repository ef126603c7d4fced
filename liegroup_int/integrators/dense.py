"""Dense output of RKMK steps on Lie groups and homogeneous spaces.

Within one step from ``(t_n, y_n)`` the exact solution is ``y(t_n + tau) = Lambda(u(tau), y_n)``
with ``u`` solving the ODE in the algebra ``u' = dexpinv_u(f(t_n + tau, Lambda(u, y_n)))``,
``u(0) = 0``. An RKMK step is a classical RK step for that ODE, its stage rates ``k_i`` are
that ODE's stage derivatives, so a continuous extension of the tableau
(:mod:`liegroup_int.tableaux.continuous`, weights ``b_i(theta)`` of order ``q``) carries
over unchanged:

    y(t_n + theta h) ~ Lambda(Theta(theta), y_n),    Theta(theta) = h sum_i b_i(theta) k_i,

a point of the group (the action of an algebra element) at every ``theta``, with local error
``O(h^(q+1))``, ``Theta(0) = 0`` and ``Theta(1)`` the step's increment (continuous across
steps). By default ``q = p`` for the embedded pairs (rkmk32 3, rkmk45 5 with two
bootstrapped stages, rkmk65 6 with four) and ``q = p - 1`` for the others (rkmk4 3, rkmk6 5
with two); bootstrapped stages are evaluated only when the step is interpolated. Between
steps of a method of order ``p`` the interpolated values carry a global error
``O(h^p) + O(h^(q+1))``.
"""

from __future__ import annotations

import numpy as np

from ..tableaux.continuous import ContinuousExtension
from .problem import Problem
from .rkmk import combine


def bootstrap_rates(problem: Problem, ext: ContinuousExtension, t: float, y, h: float, K: np.ndarray) -> np.ndarray:
    """The step's stage rates ``K`` ``(s, ...)`` extended by the rates of the extension's
    bootstrapped stages ``(s + e, ...)``, each ``dexpinv_u(f(t + c h, Lambda(u, y)))`` with
    ``u = h sum_l A[r, l] k_l``."""
    if ext.extra == 0:
        return K
    out = np.concatenate([K, np.zeros((ext.extra,) + K.shape[1:])])
    for r in range(ext.stages, len(ext.c)):
        u = combine(ext.A_f[r, :r], out, h, ext.c_f[r])
        out[r] = problem.increment_rate(t + ext.c_f[r] * h, problem.action(u, y), u)
    return out


def increment_at(ext: ContinuousExtension, K: np.ndarray, h: float, theta: float) -> np.ndarray:
    """``Theta(theta) = h sum_i b_i(theta) k_i`` for the extended rates ``K`` (``sum_i
    b_i(theta) = theta`` exactly, so it is formed as :func:`~.rkmk.combine` does)."""
    return combine(ext.weights(theta), K, h, theta)


class StepInterpolant:
    """The dense output of one accepted step, ``t -> Lambda(Theta((t - t_old) / h), y_old)``.

    Holds copies of the step's start state and stage rates; bootstrapped stages are
    evaluated on the first call (and counted in ``stats.rhs_evals`` when ``stats`` is given).
    At ``t_new`` it returns the step's end state itself.
    """

    def __init__(self, problem: Problem, ext: ContinuousExtension, t_old: float, y_old, t_new: float, y_new,
                 K: np.ndarray, stats=None):
        self.problem, self.ext, self.stats = problem, ext, stats
        self.t_old, self.t_new = float(t_old), float(t_new)
        self.y_old, self.y_new = _copy(y_old), _copy(y_new)
        self._K = K.copy()
        self._ready = ext.extra == 0

    def __call__(self, t: float):
        if t == self.t_new:
            return _copy(self.y_new)
        if t == self.t_old:
            return _copy(self.y_old)
        h = self.t_new - self.t_old
        if not self._ready:
            self._K = bootstrap_rates(self.problem, self.ext, self.t_old, self.y_old, h, self._K)
            self._ready = True
            if self.stats is not None:
                self.stats.rhs_evals += self.ext.extra
        return self.problem.action(increment_at(self.ext, self._K, h, (t - self.t_old) / h), self.y_old)


def _copy(y):
    return y.copy() if isinstance(y, np.ndarray) else y


class DenseSolution:
    """The piecewise dense output of a run (scipy's ``OdeSolution``): ``sol(t)`` is the state
    at ``t`` in ``[t_min, t_max]``, a point on the group; for an array of times, the points
    stacked along a new first axis (a list for states that are not arrays).

    Attributes
    ----------
    ts : ndarray
        Step boundaries ``t_0 < t_1 < ... < t_N``.
    interpolants : list of StepInterpolant
    """

    def __init__(self, interpolants: list[StepInterpolant], t0: float, y0):
        self.interpolants = interpolants
        self.ts = np.array([t0] + [p.t_new for p in interpolants])
        self.t_min, self.t_max = float(self.ts[0]), float(self.ts[-1])
        self._y0 = _copy(y0)

    def _one(self, t: float):
        if not self.t_min <= t <= self.t_max:
            raise ValueError(f"sol(t): t={t!r} outside the integrated interval [{self.t_min}, {self.t_max}]")
        if not self.interpolants:
            return _copy(self._y0)
        i = min(max(int(np.searchsorted(self.ts, t, side="left")) - 1, 0), len(self.interpolants) - 1)
        return self.interpolants[i](t)

    def __call__(self, t):
        if np.ndim(t) == 0:
            return self._one(float(t))
        ys = [self._one(float(s)) for s in np.asarray(t, dtype=float)]
        return np.stack(ys) if all(isinstance(y, np.ndarray) for y in ys) else ys
