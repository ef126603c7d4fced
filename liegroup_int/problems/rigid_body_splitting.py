"""Symplectic splitting of the rigid body and the heavy top (compiled kernels).

With body momentum ``M = I W``, ``H = sum_i M_i^2 / (2 I_i) + m g (R^T e3) . chi`` splits into
four exactly integrable flows (McLachlan 1993, Touma & Wisdom 1994, Reich 1994):

* the potential ``V``: ``R`` fixed, ``M <- M + tau (Gamma x m g chi)`` with
  ``Gamma = R^T e3`` (a kick);
* each kinetic term ``M_i^2 / (2 I_i)``: a turn about body axis ``i`` by
  ``phi = tau W_i``, ``R <- R exp(phi hat(e_i))``, ``M <- exp(-phi hat(e_i)) M``.

:func:`strang` composes them symmetrically, ``V(h/2) T1(h/2) T2(h/2) T3(h) T2(h/2)
T1(h/2) V(h/2)``: a symmetric, symplectic (Lie-Poisson) method of order 2 that keeps the
vertical angular momentum ``(R M) . e3`` (every flow does) and ``R`` orthogonal to
round-off. :func:`advance` runs ``n`` steps of a composition of it
(:class:`~liegroup_int.tableaux.composition.Composition`).
"""

from __future__ import annotations

import math

from numba import njit


@njit(cache=True, inline="always")
def _kick(R, W, I, mgchi, tau):
    """The potential's flow: ``W <- W + tau (Gamma x m g chi) / I``."""
    g0, g1, g2 = R[2, 0], R[2, 1], R[2, 2]
    W[0] += tau * (g1 * mgchi[2] - g2 * mgchi[1]) / I[0]
    W[1] += tau * (g2 * mgchi[0] - g0 * mgchi[2]) / I[1]
    W[2] += tau * (g0 * mgchi[1] - g1 * mgchi[0]) / I[2]


@njit(cache=True, inline="always")
def _turn(R, W, I, axis, tau):
    """The flow of ``M_axis^2 / (2 I_axis)``: a turn about the body axis by ``tau W_axis``."""
    phi = tau * W[axis]
    c, s = math.cos(phi), math.sin(phi)
    j, k = (axis + 1) % 3, (axis + 2) % 3
    for r in range(3):
        a, b = R[r, j], R[r, k]
        R[r, j] = c * a + s * b
        R[r, k] = c * b - s * a
    mj, mk = I[j] * W[j], I[k] * W[k]
    W[j] = (c * mj + s * mk) / I[j]
    W[k] = (c * mk - s * mj) / I[k]


@njit(cache=True)
def strang(R, W, I, mgchi, heavy, h):
    """One symmetric second-order step of length ``h`` in place."""
    if heavy:
        _kick(R, W, I, mgchi, 0.5 * h)
    _turn(R, W, I, 0, 0.5 * h)
    _turn(R, W, I, 1, 0.5 * h)
    _turn(R, W, I, 2, h)
    _turn(R, W, I, 1, 0.5 * h)
    _turn(R, W, I, 0, 0.5 * h)
    if heavy:
        _kick(R, W, I, mgchi, 0.5 * h)


@njit(cache=True)
def advance(R, W, I, mgchi, heavy, gammas, h, n):
    """``n`` steps of the composition ``gammas`` of :func:`strang`, in place."""
    for _ in range(n):
        for g in gammas:
            strang(R, W, I, mgchi, heavy, g * h)
