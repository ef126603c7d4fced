"""One explicit RKMK step as small pure functions (docs/theory.md section 2).

::

    u_r     = h * sum_l A[r, l] k_l
    y_r     = Lambda(u_r, y_n)
    k_r     = dexpinv_{u_r}(f(t_n + c_r h, y_r))
    y_{n+1} = Lambda(h * sum_r b_r k_r, y_n)
"""

from __future__ import annotations

import numpy as np

from ..tableaux import ButcherTableau
from .problem import Problem


def combine(weights: np.ndarray, K: np.ndarray, h: float, total: float | None = None) -> np.ndarray:
    """``h * sum_l weights[l] * K[l]`` for ``K`` of shape ``(s, *increment_shape)``.

    With ``total = sum(weights)`` known exactly (``c_r`` for a row of ``A``, 1 for ``b``,
    0 for error weights) the sum is formed as ``total K[0] + sum_l w_l (K[l] - K[0])``.
    Tableaux with large coefficients of both signs (Verner's 6(5): |a_ij| up to 208)
    otherwise lose ``~|w| eps |K|`` per stage to cancellation, a first-order-in-h
    global error floor near 1e-12; the differences ``K[l] - K[0]`` are O(h), so the
    cancellation error shrinks with the step.
    """
    n = weights.shape[0]
    shape = K.shape[1:]
    if total is None or n == 1:
        return (h * (weights @ K[:n].reshape(n, -1))).reshape(shape)
    d = (K[1:n] - K[0]).reshape(n - 1, -1)
    out = weights[1:] @ d
    out += total * K[0].reshape(-1)
    out *= h
    return out.reshape(shape)


def compute_stages(problem: Problem, tab: ButcherTableau, t: float, y, h: float, K: np.ndarray,
                   Q: np.ndarray | None = None, f0: np.ndarray | None = None, fsal: bool = False):
    """Fill ``K[r] = dexpinv_{u_r}(f(t + c_r h, Lambda(u_r, y)))`` for every stage ``r``,
    and ``Q[r] = q(t + c_r h, Lambda(u_r, y))`` when a ``Q`` of shape ``(stages,)`` is
    given (:meth:`Problem.quadrature_rate`).

    ``f0`` is ``f(t, y)`` when already known (the first stage of an FSAL pair, whose
    increment is zero, so ``K[0] = dexpinv_0(f) = f``): it is used instead of evaluating.
    With ``fsal`` the last stage is evaluated as ``dexpinv(u, vector_field(...))`` and
    ``(f_last, u_last, y_last)`` returned: its vector field (the next step's ``f0``), its
    increment and its state; otherwise returns ``None``.
    """
    A, c = tab.A_f, tab.c_f
    s = tab.stages
    K[0] = f0 if f0 is not None else problem.increment_rate(t, y, np.zeros_like(K[0]))
    if Q is not None:
        Q[0] = problem.quadrature_rate(t, y)
    f_last = None
    for r in range(1, s):
        u = combine(A[r, :r], K, h, c[r])
        y_r = problem.action(u, y)
        if fsal and r == s - 1:
            # a copy: a user's f may return (and later overwrite) one buffer
            f = np.array(problem.vector_field(t + c[r] * h, y_r), dtype=float)
            K[r] = problem.dexpinv(u, f)
            f_last = (f, u, y_r)
        else:
            K[r] = problem.increment_rate(t + c[r] * h, y_r, u)
        if Q is not None:
            Q[r] = problem.quadrature_rate(t + c[r] * h, y_r)
    return f_last


def rkmk_step(problem: Problem, tab: ButcherTableau, t: float, y, h: float, K: np.ndarray,
              Q: np.ndarray | None = None):
    """One RKMK step from ``(t, y)``; returns ``(y_new, u)`` with ``u`` the total increment.

    ``K`` is a work array of shape ``(stages, *increment_shape)``; on return it holds
    the stage rates, from which :func:`error_estimate` forms the embedded error. With
    ``Q`` (shape ``(stages,)``) the stage values of the problem's quadrature rate are
    filled in too; the step's quadrature is then ``h * b . Q`` (:func:`step_quadrature`).
    """
    y_new, u, _ = rkmk_step_fsal(problem, tab, t, y, h, K, Q)
    return y_new, u


def rkmk_step_fsal(problem: Problem, tab: ButcherTableau, t: float, y, h: float, K: np.ndarray,
                   Q: np.ndarray | None = None, f0: np.ndarray | None = None, fsal: bool = False):
    """:func:`rkmk_step` with first-same-as-last reuse: ``f0`` (``f(t, y)`` if known) and
    ``fsal`` as in :func:`compute_stages`. Returns ``(y_new, u, f_last)``.

    For an FSAL pair the last row of ``A`` is ``b``: the last stage state is the step's end
    state, and with ``fsal`` it is taken as such (its increment as ``u``), so that with
    ``end_step`` the identity (:attr:`Problem.fsal_reuse`) ``f_last`` is exactly
    ``f(t + h, y_new)``. (Forming ``h b . K`` again gives the same numbers up to the
    summation order of one more, zero-weighted, term.)"""
    last = compute_stages(problem, tab, t, y, h, K, Q, f0, fsal)
    if last is not None:
        f_last, u, y_last = last
        return problem.end_step(y_last), u, f_last
    u = combine(tab.b_f, K, h, 1.0)
    return problem.end_step(problem.action(u, y)), u, None


def cf_step(problem: Problem, tab, t: float, y, h: float, F: np.ndarray, Q: np.ndarray | None = None):
    """One commutator-free (or Crouch-Grossman) step (:mod:`liegroup_int.tableaux.commutator_free`).

    ``F[j] = f(t + c_j h, Y_j)`` (the vector field, no dexpinv) into ``F`` ``(s, ...)``;
    stage ``i`` starts from ``y`` and applies the action of each of its exponentials'
    increments ``h sum_j alpha_j F_j`` in turn; so does the step with the final rows.
    ``Q[i]`` receives the quadrature rate at stage ``i`` when given. Returns
    ``(y_new, u_max)``: the end state and the largest final increment (its rotation angle
    is the step's).
    """
    for i in range(tab.stages):
        y_i = y
        for row in tab.stage_rows_f[i]:
            y_i = problem.action(combine(row[:i], F, h), y_i)
        F[i] = problem.vector_field(t + tab.c_f[i] * h, y_i)
        if Q is not None:
            Q[i] = problem.quadrature_rate(t + tab.c_f[i] * h, y_i)
    y_new, u_max, angle = y, None, -1.0
    for row in tab.final_rows_f:
        u = combine(row, F, h)
        y_new = problem.action(u, y_new)
        a = problem.rotation_angle(u)
        if a > angle:
            u_max, angle = u, a
    return problem.end_step(y_new), u_max


def step_quadrature(tab: ButcherTableau, Q: np.ndarray, h: float) -> float:
    """``h sum_r b_r Q[r]``: one step's share of the quadrature."""
    return float(h * (tab.b_f @ Q))


def error_estimate(tab: ButcherTableau, K: np.ndarray, h: float) -> np.ndarray:
    """Embedded error ``h * sum_r (b_r - b_hat_r) k_r`` in the increment space."""
    return combine(tab.e_f, K, h, 0.0)


def error_norm(err: np.ndarray, scale: np.ndarray, rtol: float, atol: float) -> float:
    """RMS norm of ``err / (atol + rtol * scale)`` (Hairer-Norsett-Wanner II.4)."""
    w = err / (atol + rtol * scale)
    return float(np.sqrt(np.mean(w * w)))
