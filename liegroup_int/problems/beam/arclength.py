"""Arc-length continuation of the Galerkin beam's static equilibria: paths through limit
points (snap-through), where load stepping (:func:`~.statics.solve_static`) stops.

The unknowns are the free increments ``x`` of :mod:`.statics` and the load factor
``lambda``; the residual ``r(x, lambda) = f(x) + lambda q(x)`` is the same as the static
solver's (``q = dr / d lambda``, the loads, state-dependent for follower loads). Each step
(Riks 1979, Crisfield 1981):

* predictor along the tangent ``t = -K^-1 q`` (``K = dr / dx``), of length ``ds`` in the
  norm ``|(dx, psi dlambda)|`` with ``|dx|`` the weighted norm ``|(eta / L, Theta)|``, in
  the direction that continues the previous step;
* corrector: Newton on ``r = 0`` constrained to the hyperplane normal to the predictor
  (``w . dx + psi^2 dlambda_p dlambda = 0``): two solves with one factor, ``a = -K^-1 r``
  and ``b = -K^-1 q``, and ``dx = a + dlambda b``.

The load factor may fall along the path: its largest value before a fall is the limit load.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .galerkin import GalerkinBeamProblem
from .statics import _System, _check


@dataclass
class ArcLengthPath:
    """Outcome of :func:`arc_length_path`.

    Attributes
    ----------
    load_factors : list of float
        The load factor at each converged point of the path (the reference, 0, first).
    tips : list of ndarray
        The tip ``(3,)`` at each point.
    iterations : list of int
        Corrector iterations of each step.
    states : list
        The states at the points.
    converged : bool
        Every step converged (else the path ends at the last converged point).
    limit : float or None
        The limit load factor: the peak of the parabola through the largest sampled load
        factor before the first fall and its two neighbours (against the arc length), or
        None when the load factor has not fallen.
    """

    load_factors: list = field(default_factory=list)
    tips: list = field(default_factory=list)
    iterations: list = field(default_factory=list)
    states: list = field(default_factory=list)
    converged: bool = True
    limit: float | None = None


def _peak(lams: list, ds: float) -> float:
    """The peak of the parabola through the last three load factors, ``ds`` apart in arc
    length (the middle one the largest)."""
    a, b, c = lams[-3:]
    curv = a - 2.0 * b + c
    return b - (c - a) ** 2 / (8.0 * curv) if curv < 0.0 else b


def _weights(system: _System) -> np.ndarray:
    """Weights of the increment norm ``|(eta / L, Theta)|``, per free unknown."""
    return np.where(system.dofs.field == 0, 1.0 / system.dofs.length**2, 1.0)


def _load(system: _System, y) -> np.ndarray:
    """``q = dr / d lambda`` at ``y`` (the residual is affine in the load factor)."""
    return system.residual(y, 1.0) - system.residual(y, 0.0)


def _factor(system: _System, y, lam: float, r):
    """The sparse LU of the tangent at ``(y, lam)``, or None where it is singular (a step
    that lands on a singular tangent fails as one whose corrector does not converge)."""
    import scipy.sparse.linalg

    try:
        return scipy.sparse.linalg.splu(system.tangent(y, lam, r))
    except RuntimeError:
        return None


def _step(system: _System, y, lam: float, ds: float, psi: float, prev, tol: float, scale: float, max_iter: int):
    """One predictor-corrector step: ``(y, lambda, iterations, predictor)`` or None."""
    W = _weights(system)
    r, q = system.residual(y, lam), _load(system, y)
    lu = _factor(system, y, lam, r)
    if lu is None:
        return None
    t = -lu.solve(q)
    dlam = ds / np.sqrt(float(t @ (W * t)) + psi**2)
    if prev is not None and float(t @ (W * prev[0])) + psi**2 * prev[1] < 0.0:
        dlam = -dlam  # continue along the path, not back
    dx_p = dlam * t
    y, lam = system.move(y, dx_p), lam + dlam
    for it in range(1, max_iter + 1):
        r = system.residual(y, lam)
        if system.dofs.norm(r) <= tol * scale:
            return y, lam, it - 1, (dx_p, dlam)
        q = _load(system, y)
        lu = _factor(system, y, lam, r)
        if lu is None:
            return None
        a, b = -lu.solve(r), -lu.solve(q)
        dl = -float(dx_p @ (W * a)) / (float(dx_p @ (W * b)) + psi**2 * dlam)
        y, lam = system.move(y, a + dl * b), lam + dl
    return None


def arc_length_path(problem: GalerkinBeamProblem, *, steps: int, ds: float, t: float = 0.0, psi: float = 1.0,
                    tol: float = 1e-8, max_iter: int = 25, lam_max: float = np.inf,
                    until_limit: bool = False) -> ArcLengthPath:
    """Follow the static equilibria of ``problem`` under its loads at time ``t`` times a
    load factor, from the reference, for ``steps`` arc-length steps of length ``ds`` (norm
    ``|(eta / L, Theta, psi lambda)|``), until the load factor passes ``lam_max``, or, with
    ``until_limit``, until it first falls (the limit point passed).

    ``tol``: the residual norm relative to the full load's, as :func:`~.statics.solve_static`.
    A step whose corrector does not converge ends the path (``converged`` False).
    """
    _check(problem, 1, tol, max_iter)
    if not (steps >= 1 and ds > 0 and psi > 0):
        raise ValueError(f"arc length: expected steps >= 1, ds > 0 and psi > 0, got {steps!r}, {ds!r}, {psi!r}")
    system = _System(problem, t)
    y = problem.initial_state().copy()
    y.v[:] = 0.0
    y.w[:] = 0.0
    scale = system.dofs.norm(_load(system, y)) or 1.0
    path = ArcLengthPath([0.0], [problem.tip(y)], [], [y])
    lam, prev = 0.0, None
    for _ in range(steps):
        out = _step(system, y, lam, ds, psi, prev, tol, scale, max_iter)
        if out is None:
            path.converged = False
            break
        y, lam, its, prev = out
        path.load_factors.append(lam)
        path.tips.append(problem.tip(y))
        path.iterations.append(its)
        path.states.append(y)
        if path.limit is None and len(path.load_factors) > 2 and lam < path.load_factors[-2]:
            path.limit = _peak(path.load_factors, ds)
            if until_limit:
                break
        if lam > lam_max:
            break
    return path
