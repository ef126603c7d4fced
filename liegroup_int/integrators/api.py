"""``integrate``: a ``solve_ivp``-like entry point for ODEs on Lie groups."""

from __future__ import annotations

from typing import Callable

import numpy as np

from ..groups import LieGroup, Product, Rn
from ..tableaux.composition import COMPOSITIONS
from ..tableaux.continuous import continuous_extension
from .drivers import MAX_INCREMENT_ANGLE, integrate_adaptive, integrate_fixed
from .events import DenseRun, event_specs
from .methods import is_commutator_free, resolve_method
from .observers import StateRecorder
from .problem import ActionProblem, GroupProblem, Problem
from .result import Solution, Stats
from .splitting import integrate_composition


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
    dense_output: bool = False,
    events=None,
    dense_order: int | None = None,
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
        embedded pairs ``"rkmk32"``, ``"rkmk45"``, ``"rkmk65"``, or a tableau name; or a
        symplectic splitting composition, ``"strang"``, ``"yoshida4"``, ``"yoshida6"``
        (:data:`~liegroup_int.tableaux.composition.COMPOSITIONS`), for a problem with exactly
        integrable flows (``RigidBody(...).problem()``: the free body and the heavy top), fixed
        ``dt`` only, output times on the step grid.
    dt : float, optional
        Fixed step. Give either ``dt`` or ``rtol``/``atol`` (adaptive pairs only).
    rtol, atol : float, optional
        Tolerances of the adaptive driver (a missing one defaults to 1e-6 / 1e-9).
    t_eval : array_like, optional
        Sorted output times in ``[t0, t_end]``; ``Solution.t`` holds ``t0``, these and the
        final time (by default only ``t0`` and the final time). Their states come from the
        dense output (below), so they do not shorten the steps: the step sequence is that of
        the run without ``t_eval``, in the compiled engine (a ``numba.njit`` field, or a
        problem with compiled kernels, and no ``monitor``) as in the Python loop. The
        commutator-free methods land on them instead.
    observer : callable, optional
        ``observer(t, y)`` at output times. Default: a :class:`StateRecorder`, whose
        states are returned in ``Solution.y``.
    dense_output : bool
        Keep every step's interpolant: ``Solution.sol(t)`` is then the state at any ``t``
        in ``[t0, t_final]``, ``Lambda(Theta(theta), y_n)`` with ``Theta`` from the
        tableau's continuous weights (:mod:`liegroup_int.integrators.dense`; order
        ``dense_order``), a point of the group or space to round-off.
    events : callable or list of callables, optional
        ``g(t, y) -> float`` with scipy's optional attributes ``terminal`` (stop at the
        first, or at the ``terminal``-th, occurrence) and ``direction`` (``+1``: rising
        zeros only, ``-1``: falling, ``0``: both). Zeros are located on the dense output by
        Brent's method to ``4 eps`` (:mod:`liegroup_int.integrators.events`) and returned in
        ``Solution.t_events`` / ``Solution.y_events``. With the compiled engine the steps run
        compiled: a ``numba.njit`` ``g`` is evaluated in the compiled loop after every step,
        which hands back to Python only the steps over which an event changes sign; a
        Python ``g`` gets every step.
    dense_order : int, optional
        Order ``q`` of the continuous extension (local error ``O(h^(q+1))``), in
        ``[1, p]``. Default: ``p`` for the embedded pairs (rkmk32, rkmk45, rkmk65: values
        between the steps as accurate as at the steps, for 0, 2 and 4 bootstrapped stages per
        interpolated step), ``p - 1`` for the others (rkmk4: 0 extra stages, rkmk6: 2)
        (:func:`~liegroup_int.tableaux.continuous.default_order`). ``p - 1`` is the cheaper
        choice of scipy's RK45 and DOP853 (rkmk45: 0 extra stages, rkmk65: 1). Bootstrapped
        stages count in ``stats.rhs_evals``.
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
        ``t``, ``y`` at the output times; ``sol`` (with ``dense_output``), ``t_events``,
        ``y_events`` (with ``events``) and ``status`` (0: reached ``t_end``, 1: a terminal
        event) as in ``scipy.integrate.solve_ivp``.

    Examples
    --------
    >>> import numpy as np
    >>> from liegroup_int import integrate, SO3
    >>> w = np.array([0.0, 0.0, 1.0])
    >>> sol = integrate(lambda t, R: w, np.eye(3), (0.0, np.pi), space=SO3, dt=0.01)
    >>> np.allclose(sol.y_final, SO3.exp(np.pi * w))
    True
    """
    if isinstance(method, str) and method in COMPOSITIONS:
        return _integrate_split(f, y0, t_span, COMPOSITIONS[method], dt, rtol, atol, t_eval, observer,
                                dense_output or events is not None or monitor is not None)
    problem, y0 = _problem(f, y0, space, method, coordinates)
    tab = resolve_method(method)
    t0, t_end = float(t_span[0]), float(t_span[1])
    if not t_end > t0:
        raise ValueError(f"t_span must have t_end > t0, got {t_span!r}")
    if dt is None and rtol is None and atol is None:
        raise ValueError("give a step size dt, or rtol/atol for an adaptive pair")
    if dt is not None and (rtol is not None or atol is not None):
        raise ValueError("give either dt (fixed step) or rtol/atol (adaptive), not both")
    recorder = observer if observer is not None else StateRecorder()
    specs = event_specs(events)
    run = None
    if dense_output or specs or (t_eval is not None and not is_commutator_free(tab)):
        if is_commutator_free(tab):
            raise ValueError(f"method {tab.name!r}: dense output and events need an RKMK method")
        run = DenseRun(problem, continuous_extension(tab, dense_order), (t0, t_end), y0, t_eval, recorder,
                       dense_output, specs, Stats())
    kw = dict(monitor=monitor, max_increment_angle=max_increment_angle, on_step=run,
              stats=run.stats if run is not None else None)
    obs, t_out = (None, None) if run is not None else (recorder, t_eval)
    if dt is not None:
        t, y, stats = integrate_fixed(problem, tab, (t0, t_end), y0, dt, obs, t_out, **kw)
    else:
        t, y, stats = integrate_adaptive(problem, tab, (t0, t_end), y0, rtol if rtol is not None else 1e-6,
                                         atol if atol is not None else 1e-9, obs, t_out, **kw)
    return _solution(recorder, run, t, y, stats, tab.name)


def _integrate_split(f, y0, t_span, comp, dt, rtol, atol, t_eval, observer, extras: bool) -> Solution:
    """``integrate`` with a splitting composition (:mod:`.splitting`)."""
    if not isinstance(f, Problem):
        raise ValueError(f"method {comp.name!r} is a splitting method: pass a problem with exactly integrable flows "
                         "(e.g. RigidBody(...).problem()), not a vector field")
    if rtol is not None or atol is not None or extras:
        raise ValueError(f"method {comp.name!r}: fixed steps only (dt), without rtol/atol, dense output, events or "
                         "a monitor")
    recorder = observer if observer is not None else StateRecorder()
    t, y, stats = integrate_composition(f, comp, t_span, y0, dt, recorder, t_eval)
    return _solution(recorder, None, t, y, stats, comp.name)


def _problem(f, y0, space, method, coordinates):
    """The :class:`Problem` and initial state ``integrate`` runs."""
    if coordinates != "exp" and (isinstance(f, Problem) or space is None or isinstance(space, LieGroup)):
        raise ValueError("coordinates='cayley' applies to homogeneous spaces (space=M); use an ActionProblem")
    if isinstance(f, Problem):
        return f, y0
    if space is not None and not isinstance(space, LieGroup):
        # a homogeneous space (liegroup_int.manifolds); a group without a closed-form
        # dexpinv gets its Bernoulli series truncated to the method's order
        series = type(space.group).dexpinv is LieGroup.dexpinv
        return (ActionProblem(space, f, dexpinv_order=resolve_method(method).order - 1 if series else None,
                              coordinates=coordinates), np.asarray(y0, dtype=float))
    if space is None:
        y0 = np.asarray(y0, dtype=float)
        space = Rn(y0.shape[-1])
    if isinstance(space, Product) and isinstance(y0, (tuple, list)):
        y0 = space.join(*y0)
    return GroupProblem(space, f), np.asarray(y0, dtype=float)


def _solution(recorder, run, t, y, stats, name) -> Solution:
    sol = run.finish(t, y) if run is not None else None
    if isinstance(recorder, StateRecorder):
        ts, ys = np.asarray(recorder.t), recorder.y
    else:
        ts, ys = np.asarray(getattr(recorder, "t", [])), []
    t_events, y_events = run.events.arrays() if run is not None and run.events is not None else (None, None)
    status = 1 if run is not None and run.stopped else 0
    return Solution(t=ts, y=ys, t_final=t, y_final=y, stats=stats, method=name, observer=recorder, sol=sol,
                    t_events=t_events, y_events=y_events, status=status)
