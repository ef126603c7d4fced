"""``integrate``: a ``solve_ivp``-like entry point for ODEs on Lie groups."""

from __future__ import annotations

from typing import Callable

import numpy as np

from ..groups import LieGroup, Product, Rn
from .drivers import MAX_INCREMENT_ANGLE, integrate_adaptive, integrate_fixed
from .methods import resolve_method
from .observers import StateRecorder
from .problem import ActionProblem, GroupProblem, Problem
from .result import Solution


def integrate(
    f: "Callable | Problem",
    y0,
    t_span: tuple[float, float],
    space: LieGroup | None = None,
    method: str = "rkmk4",
    dt: float | None = None,
    rtol: float | None = None,
    atol: float | None = None,
    t_eval=None,
    observer: Callable | None = None,
    monitor: Callable | None = None,
    max_increment_angle: float = MAX_INCREMENT_ANGLE,
    coordinates: str = "exp",
) -> Solution:
    """Integrate ``dy/dt = f(t, y) y`` on a Lie group with an explicit RKMK method.

    Parameters
    ----------
    f : callable or Problem
        ``f(t, y) -> xi``, the spatial velocity in the algebra, shape ``(..., space.dim)``;
        or a ready :class:`Problem` (then ``space`` is ignored).
    y0 : ndarray or tuple of ndarrays
        Initial point; for a :class:`Product` space a tuple of factor points is joined.
    t_span : (float, float)
        ``(t0, t_end)``.
    space : LieGroup or HomogeneousSpace, optional
        Defaults to ``Rn(len(y0))`` (classical RK). A homogeneous space
        (:mod:`liegroup_int.manifolds`: ``Sphere``, ``Stiefel``, ``Isospectral``, ...) takes
        ``f(t, y)`` in its group's algebra and steps by the group's action on ``y``.
    method : str
        ``"rkmk1"`` (Lie-Euler), ``"rkmk2"``, ``"rkmk3"``, ``"rkmk4"``, ``"rkmk6"``,
        embedded pairs ``"rkmk32"``, ``"rkmk45"``, ``"rkmk65"``, or a tableau name.
    dt : float, optional
        Fixed step. Give either ``dt`` or ``rtol``/``atol`` (adaptive pairs only).
    rtol, atol : float, optional
        Tolerances of the adaptive driver (a missing one defaults to 1e-6 / 1e-9).
    t_eval : array_like, optional
        Output times; by default only the final time (and ``t0``) are recorded.
    observer : callable, optional
        ``observer(t, y)`` at output times. Default: a :class:`StateRecorder`, whose
        states are returned in ``Solution.y``.
    monitor : callable, optional
        ``monitor(t, y, stats)`` after every accepted step.
    max_increment_angle : float
        Largest rotation angle one step may carry [rad].
    coordinates : {"exp", "cayley"}
        On a homogeneous space whose group has a Cayley map (``SOn``): step with it
        instead of the exponential (:class:`ActionProblem`).

    Returns
    -------
    Solution

    Examples
    --------
    >>> import numpy as np
    >>> from liegroup_int import integrate, SO3
    >>> w = np.array([0.0, 0.0, 1.0])
    >>> sol = integrate(lambda t, R: w, np.eye(3), (0.0, np.pi), space=SO3, dt=0.01)
    >>> np.allclose(sol.y_final, SO3.exp(np.pi * w))
    True
    """
    if coordinates != "exp" and (isinstance(f, Problem) or space is None or isinstance(space, LieGroup)):
        raise ValueError("coordinates='cayley' applies to homogeneous spaces (space=M); use an ActionProblem")
    if isinstance(f, Problem):
        problem = f
    elif space is not None and not isinstance(space, LieGroup):
        # a homogeneous space (liegroup_int.manifolds); a group without a closed-form
        # dexpinv gets its Bernoulli series truncated to the method's order
        series = type(space.group).dexpinv is LieGroup.dexpinv
        problem = ActionProblem(space, f, dexpinv_order=resolve_method(method).order - 1 if series else None,
                                coordinates=coordinates)
        y0 = np.asarray(y0, dtype=float)
    else:
        if space is None:
            y0 = np.asarray(y0, dtype=float)
            space = Rn(y0.shape[-1])
        if isinstance(space, Product) and isinstance(y0, (tuple, list)):
            y0 = space.join(*y0)
        y0 = np.asarray(y0, dtype=float)
        problem = GroupProblem(space, f)
    tab = resolve_method(method)
    t0, t_end = float(t_span[0]), float(t_span[1])
    if not t_end > t0:
        raise ValueError(f"t_span must have t_end > t0, got {t_span!r}")
    recorder = observer if observer is not None else StateRecorder()
    if dt is not None:
        if rtol is not None or atol is not None:
            raise ValueError("give either dt (fixed step) or rtol/atol (adaptive), not both")
        t, y, stats = integrate_fixed(problem, tab, (t0, t_end), y0, dt, recorder, t_eval, monitor, max_increment_angle)
    elif rtol is not None or atol is not None:
        t, y, stats = integrate_adaptive(
            problem, tab, (t0, t_end), y0, rtol if rtol is not None else 1e-6, atol if atol is not None else 1e-9,
            recorder, t_eval, monitor, max_increment_angle=max_increment_angle,
        )
    else:
        raise ValueError("give a step size dt, or rtol/atol for an adaptive pair")
    if isinstance(recorder, StateRecorder):
        ts, ys = np.asarray(recorder.t), recorder.y
    else:
        ts, ys = np.asarray(getattr(recorder, "t", [])), []
    return Solution(t=ts, y=ys, t_final=t, y_final=y, stats=stats, method=tab.name, observer=recorder)
