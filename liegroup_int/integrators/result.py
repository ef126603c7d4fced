"""Run statistics, results and the errors integrators raise."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class Stats:
    """Counters of one integration.

    Attributes
    ----------
    steps : int
        Accepted steps.
    rejected : int
        Rejected steps (adaptive drivers only).
    rhs_evals : int
        Evaluations of the increment rate (one per stage, rejected steps included).
    wall_time_s : float
        Wall-clock time of the integration loop.
    h_min, h_max : float
        Smallest and largest accepted step.
    quadrature : float
        ``int q(t, y) dt`` along the accepted steps for a problem with a quadrature rate
        (:meth:`Problem.quadrature_rate`: the beam's external power, so this is the work
        of its loads), formed with the step's weights ``h sum_r b_r q(t_r, y_r)``; 0 for
        other problems.
    controller : dict or None
        Memory of the adaptive controller at the last output time (``h``: the next step to
        try, ``err_prev``, ``rate``; ``None`` before an adaptive run). An adaptive run given
        stats with it continues from it, so a run resumed from a checkpoint at an output
        time takes the same steps as one that never stopped. Not part of :meth:`as_dict`.
    """

    steps: int = 0
    rejected: int = 0
    rhs_evals: int = 0
    wall_time_s: float = 0.0
    h_min: float = np.inf
    h_max: float = 0.0
    quadrature: float = 0.0
    controller: dict | None = None

    def accept(self, h: float) -> None:
        self.steps += 1
        self.h_min = min(self.h_min, h)
        self.h_max = max(self.h_max, h)

    def accept_many(self, steps: int, h_min: float, h_max: float) -> None:
        """``steps`` accepted steps at once, with the extreme sizes among them."""
        if steps > 0:
            self.steps += steps
            self.h_min = min(self.h_min, h_min)
            self.h_max = max(self.h_max, h_max)

    def as_dict(self) -> dict:
        return {
            "steps": self.steps,
            "rejected": self.rejected,
            "rhs_evals": self.rhs_evals,
            "wall_time_s": self.wall_time_s,
            "h_min": float(self.h_min) if self.steps else None,
            "h_max": float(self.h_max) if self.steps else None,
            "quadrature": float(self.quadrature),
        }


@dataclass
class Solution:
    """Result of :func:`liegroup_int.integrate`.

    Attributes
    ----------
    t : ndarray, shape (n_out,)
        Output times.
    y : list
        States at the output times (as recorded by the observer; empty if the caller
        passed an observer that keeps its own records).
    t_final : float
        Time reached.
    y_final : object
        State at ``t_final``.
    stats : Stats
    method : str
        Name of the tableau used.
    sol : DenseSolution or None
        With ``dense_output=True``: ``sol(t)``, the state at any ``t`` in ``[t0, t_final]``
        (:class:`~liegroup_int.integrators.dense.DenseSolution`).
    t_events : list of ndarray or None
        With ``events``: for each event, the times of its zeros.
    y_events : list of ndarray or None
        With ``events``: for each event, the states at its zeros (stacked along axis 0).
    status : int
        0: the run reached ``t_end``; 1: a terminal event stopped it at ``t_final``.
    """

    t: np.ndarray
    y: list
    t_final: float
    y_final: object
    stats: Stats
    method: str
    observer: object = field(default=None, repr=False)
    sol: object = field(default=None, repr=False)
    t_events: list | None = None
    y_events: list | None = None
    status: int = 0


class IntegrationError(RuntimeError):
    """An integration stopped early; ``t`` and ``step`` say where.

    Everything recorded before the failure stays in the observer.
    """

    def __init__(self, message: str, t: float, step: int):
        super().__init__(message)
        self.t = t
        self.step = step


class BlowUpError(IntegrationError):
    """The state became non-finite (or a problem-specific blow-up check fired)."""


class StepSizeError(IntegrationError):
    """The step cannot satisfy the tolerance or the rotation guard."""
