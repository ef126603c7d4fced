"""Compiled twin of :func:`liegroup_int.integrators.rkmk.combine` for fused step loops
(numba). Problems with a compiled stepper (beams, rigid bodies) call it from their kernels."""

from __future__ import annotations

from numba import njit


@njit(cache=True, fastmath=False, inline="always")
def combine_into(wts, m, total, Kf, h, out):
    """``out = h sum_{l < m} wts[l] Kf[l]`` in the cancellation-safe form of
    :func:`liegroup_int.integrators.rkmk.combine` (``total = sum(wts[:m])``):
    ``h (sum_{l >= 1} wts[l] (Kf[l] - Kf[0]) + total Kf[0])``; ``m = 1``: ``h (wts[0] Kf[0])``.
    ``Kf`` is a ``(stages, size)`` view of the stage rates, ``out`` of shape ``(size,)``."""
    if m == 1:
        w0 = wts[0]
        for j in range(out.shape[0]):
            out[j] = h * (w0 * Kf[0, j])
        return
    for j in range(out.shape[0]):
        k0 = Kf[0, j]
        acc = wts[1] * (Kf[1, j] - k0)
        for l in range(2, m):
            acc += wts[l] * (Kf[l, j] - k0)
        acc += total * k0
        out[j] = acc * h
