"""Engine kernels of ODEs on the SO(n) homogeneous spaces (numba): ``Stiefel(n, k)``
(``Lambda(Q, Y) = Q Y``) and ``Isospectral(n)`` (``Lambda(Q, L) = Q L Q^T``).

A user's ``numba.njit`` ``f(t, y) -> xi`` (``xi`` of length ``n (n - 1) / 2``, the
coordinates of :class:`~liegroup_int.groups.SOn`) then runs in the compiled engine, as on
the sphere (:mod:`.compiled_group`). The mathematics is that of ``SOn``:

* ``exp``: scaling and squaring of the degree-16 Taylor polynomial (the scaled matrix has
  max-row-sum norm <= 1/2, truncation below 1e-19), then one Newton-Schulz step, as
  ``SOn.exp`` ends (the generic path diagonalizes ``i hat(xi)`` instead: both are exact to
  round-off);
* ``dexpinv``: the Bernoulli series ``sum_{k<=K} B_k ad^k / k!`` with matrix commutators:
  K = 40 terms (equal to ``SOn.dexpinv``'s closed form to round-off while ``|ad_u| < 2``,
  far above a step's increments), or ``SOn.dexpinv_series`` truncated to the method's
  order (``ActionProblem(dexpinv_order=K)``, what ``integrate(..., space=M)`` sets);
* the rotation angle: the spectral norm of ``hat(u)`` (``SOn.rotation_angle``).

The kernels write into the data's work arrays (plain loops: the matrices are small), so a
stage allocates nothing (the once-per-step angle check's eigenvalue call does).

Data ``(ii, jj, coef, n, dim, point_shape, f, events, event_state, A, T, S, E, W)``: the basis indices
(``hat(xi)[jj, ii] = xi``, ``hat(xi)[ii, jj] = -xi``), the series coefficients, sizes, the
point shape (what the user's ``f`` sees), ``f`` itself (a first-class function value,
:func:`~.compiled_group.user_problem`), the event slots and ``n x n`` work arrays.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .compiled_group import unit_scale, user_field, user_problem, user_watch
from .engine import CompiledProblem, EngineKernels

#: Terms of the dexpinv series without a truncation order (the base class's 40).
SERIES_TERMS = 40
_TAYLOR_DEGREE = 16


@njit(cache=True)
def _hat(x, ii, jj, A):
    A[:, :] = 0.0
    for k in range(ii.shape[0]):
        A[jj[k], ii[k]] = x[k]
        A[ii[k], jj[k]] = -x[k]


@njit(cache=True)
def _vee(M, ii, jj, out):
    for k in range(ii.shape[0]):
        out[k] = 0.5 * (M[jj[k], ii[k]] - M[ii[k], jj[k]])


@njit(cache=True)
def _matmul_into(X, Y, out):
    """``out = X Y`` for small square matrices, without temporaries."""
    n = X.shape[0]
    for i in range(n):
        for j in range(n):
            acc = 0.0
            for k in range(n):
                acc += X[i, k] * Y[k, j]
            out[i, j] = acc


@njit(cache=True)
def son_exp(A, E, W):
    """``E = exp(A)`` for a skew ``A``, overwriting ``A`` (``W`` a work array like ``A``);
    no temporaries."""
    n = A.shape[0]
    norm = 0.0
    for i in range(n):
        r = 0.0
        for j in range(n):
            r += abs(A[i, j])
        norm = max(norm, r)
    s = 0
    while norm > 0.5:
        norm *= 0.5
        s += 1
    scale = 0.5 ** s
    for i in range(n):
        for j in range(n):
            A[i, j] *= scale
            E[i, j] = 1.0 if i == j else 0.0
    for k in range(_TAYLOR_DEGREE, 0, -1):  # Horner: E <- I + A E / k
        _matmul_into(A, E, W)
        for i in range(n):
            for j in range(n):
                E[i, j] = W[i, j] / k + (1.0 if i == j else 0.0)
    for _ in range(s):
        _matmul_into(E, E, W)
        E[:, :] = W
    # one Newton-Schulz step: E <- E (3 I - E^T E) / 2 (A is free again: its work space)
    for i in range(n):
        for j in range(n):
            acc = 0.0
            for k in range(n):
                acc += E[k, i] * E[k, j]
            A[i, j] = (3.0 if i == j else 0.0) - acc
    _matmul_into(E, A, W)
    for i in range(n):
        for j in range(n):
            E[i, j] = 0.5 * W[i, j]


@njit(cache=True)
def son_dexpinv(data, u, w, out):
    """``out = dexpinv_u(w)`` (``w`` may be ``out``)."""
    ii, jj, coef, A, T, S = data[0], data[1], data[2], data[9], data[10], data[11]
    W = data[13]
    n = A.shape[0]
    _hat(u, ii, jj, A)
    _hat(w, ii, jj, T)
    for i in range(n):
        for j in range(n):
            S[i, j] = coef[0] * T[i, j]
    for k in range(1, coef.shape[0]):
        for i in range(n):  # W = [A, T]
            for j in range(n):
                acc = 0.0
                for m in range(n):
                    acc += A[i, m] * T[m, j] - T[i, m] * A[m, j]
                W[i, j] = acc
        c = coef[k]
        for i in range(n):
            for j in range(n):
                T[i, j] = W[i, j]
                if c != 0.0:
                    S[i, j] += c * W[i, j]
    _vee(S, ii, jj, out)


@njit(cache=True)
def son_angle(data, u):
    """Spectral norm of ``hat(u)``: the largest rotation angle of ``exp(u)``."""
    ii, jj, A, T = data[0], data[1], data[9], data[10]
    _hat(u, ii, jj, A)
    n = A.shape[0]
    for i in range(n):  # T = A^T A
        for j in range(n):
            acc = 0.0
            for m in range(n):
                acc += A[m, i] * A[m, j]
            T[i, j] = acc
    lam = np.linalg.eigvalsh(T)
    return np.sqrt(max(lam[-1], 0.0))


@njit(cache=True)
def stiefel_action(data, u, y, out):
    """``out = exp(u) Y`` (Stiefel: ``Y`` of shape ``(n, k)``)."""
    ii, jj, n, A, E, W = data[0], data[1], data[3], data[9], data[12], data[13]
    _hat(u, ii, jj, A)
    son_exp(A, E, W)
    k = y.shape[0] // n
    for i in range(n):
        for j in range(k):
            acc = 0.0
            for m in range(n):
                acc += E[i, m] * y[m * k + j]
            out[i * k + j] = acc


@njit(cache=True)
def isospectral_action(data, u, y, out):
    """``out = Q L Q^T`` with ``Q = exp(u)`` (Isospectral: ``L`` of shape ``(n, n)``)."""
    ii, jj, n, A, E, W = data[0], data[1], data[3], data[9], data[12], data[13]
    _hat(u, ii, jj, A)
    son_exp(A, E, W)
    for i in range(n):  # W = E L
        for j in range(n):
            acc = 0.0
            for m in range(n):
                acc += E[i, m] * y[m * n + j]
            W[i, j] = acc
    for i in range(n):  # out = W E^T
        for j in range(n):
            acc = 0.0
            for m in range(n):
                acc += W[i, m] * E[j, m]
            out[i * n + j] = acc


@njit(cache=True)
def _user_rate_son(data, t, y, u, out):
    """``out = dexpinv_u f(t, y)``."""
    user_field(data, t, y, out)
    son_dexpinv(data, u, out, out)
    return 0.0


def _son_kernels(name: str, action) -> EngineKernels:
    return EngineKernels(name, _user_rate_son, action, son_angle, unit_scale, field=user_field, dexpinv=son_dexpinv,
                         watch=user_watch)


STIEFEL_KERNELS = _son_kernels("user_stiefel", stiefel_action)
ISOSPECTRAL_KERNELS = _son_kernels("user_isospectral", isospectral_action)


def son_data(group, order: int | None = None) -> tuple[tuple, tuple]:
    """The kernels' data for ``SOn(n)``, the dexpinv series to ``order`` (``None``:
    :data:`SERIES_TERMS`): the leading entries and the ``n x n`` work arrays (which follow
    the point shape and the user's ``f``, module docstring)."""
    from ..groups._series import bernoulli_numbers, factorials

    terms = SERIES_TERMS if order is None else int(order)
    bern, fact = bernoulli_numbers(terms), factorials(terms)
    coef = np.array([bern[k] / fact[k] for k in range(terms + 1)])
    n = int(group.n)
    work = tuple(np.zeros((n, n)) for _ in range(5))
    return (np.ascontiguousarray(group._i, dtype=np.int64), np.ascontiguousarray(group._j, dtype=np.int64), coef,
            n, int(group.dim)), work


def son_space_kernels(problem, order: int | None = None) -> CompiledProblem | None:
    """The engine's view of an ``ActionProblem`` with a compiled ``f`` on one point of
    ``Stiefel(n, k)`` or ``Isospectral(n)`` (dexpinv series to ``order``, ``None``: the
    group's 40 terms); ``None`` for other spaces."""
    from ..manifolds import Isospectral, Stiefel

    space = problem.space
    if type(space) is Stiefel:
        kernels = STIEFEL_KERNELS
    elif type(space) is Isospectral:
        kernels = ISOSPECTRAL_KERNELS
    else:
        return None
    if space.group.n == 2:
        return None  # SO(2): the generic path (its exp is closed-form there)
    head, work = son_data(space.group, order)
    return user_problem(kernels, head, problem, int(space.group.dim), work)
