"""RATTLE for the N-fold pendulum (:mod:`.n_pendulum`), compiled: constant mass matrix in the
link directions ``q_j``, constraints ``|q_j| = 1`` (Hairer, Lubich & Wanner, VII.1)."""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def _constrained_positions(q, qa, Cinv, hh, lam, qn):
    """``qn = qa - hh C^-1 (lam q)`` per link (the position update with multipliers ``lam``)."""
    N = q.shape[0]
    for j in range(N):
        for d in range(3):
            s = 0.0
            for k in range(N):
                s += Cinv[j, k] * lam[k] * q[k, d]
            qn[j, d] = qa[j, d] - hh * s


@njit(cache=True)
def rattle_step(q, v, Cinv, acc, k):
    """One RATTLE step of size ``k`` in place: ``q`` ``(N, 3)`` unit directions, ``v`` their
    velocities (``q_j . v_j = 0``), constant mass matrix ``C`` (its inverse ``Cinv``) and
    constant accelerations ``acc = C^-1 F``. The position multipliers solve ``|q_j| = 1``
    by Newton's method (quadratic convergence: stops at 4 ulp or after 30 iterations),
    the velocity ones ``q_j . v_j = 0`` exactly (a linear system). Returns ``False`` if
    Newton did not converge."""
    N = q.shape[0]
    hh = 0.5 * k * k
    qa = q + k * v + hh * acc
    lam = np.zeros(N)
    qn = np.empty_like(q)
    J = np.empty((N, N))
    r = np.empty(N)
    ok = False
    for _ in range(30):
        _constrained_positions(q, qa, Cinv, hh, lam, qn)
        worst = 0.0
        for j in range(N):
            r[j] = qn[j, 0] ** 2 + qn[j, 1] ** 2 + qn[j, 2] ** 2 - 1.0
            worst = max(worst, abs(r[j]))
        if worst <= 8.9e-16:
            ok = True
            break
        for j in range(N):
            for m in range(N):
                J[j, m] = -2.0 * hh * Cinv[j, m] * (qn[j, 0] * q[m, 0] + qn[j, 1] * q[m, 1] + qn[j, 2] * q[m, 2])
        lam -= np.linalg.solve(J, r)
    b = (qn - q) / k + 0.5 * k * acc
    A = np.empty((N, N))
    rhs = np.empty(N)
    for j in range(N):
        rhs[j] = qn[j, 0] * b[j, 0] + qn[j, 1] * b[j, 1] + qn[j, 2] * b[j, 2]
        for m in range(N):
            A[j, m] = 0.5 * k * Cinv[j, m] * (qn[j, 0] * qn[m, 0] + qn[j, 1] * qn[m, 1] + qn[j, 2] * qn[m, 2])
    mu = np.linalg.solve(A, rhs)
    _constrained_positions(qn, b, Cinv, 0.5 * k, mu, v)
    q[:, :] = qn
    return ok


@njit(cache=True)
def rattle_steps(q, v, Cinv, acc, gammas, h, n):
    """``n`` steps of length ``h`` of the composition ``gammas`` of :func:`rattle_step`, in
    place; ``False`` as soon as a step's Newton iteration does not converge."""
    for _ in range(n):
        for g in gammas:
            if not rattle_step(q, v, Cinv, acc, g * h):
                return False
    return True
