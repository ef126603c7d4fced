"""Truncated power series in ``h`` with matrix coefficients, ``(P + 1, n, n)``: the
arithmetic behind the order checks of :mod:`.lie_order` and :mod:`.composition`."""

from __future__ import annotations

import numpy as np


def series_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Product of two matrix series, truncated at the common order."""
    out = np.zeros_like(a)
    for k in range(a.shape[0]):
        for j in range(k + 1):
            out[k] += a[j] @ b[k - j]
    return out


def series_scalar_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Product of two scalar series ``(P + 1,)``."""
    return np.array([sum(a[j] * b[k - j] for j in range(k + 1)) for k in range(a.shape[0])])


def series_exp(e: np.ndarray) -> np.ndarray:
    """``exp`` of a matrix series without constant term."""
    out, term = np.zeros_like(e), np.zeros_like(e)
    out[0] = term[0] = np.eye(e.shape[1])
    for m in range(1, e.shape[0]):
        term = series_mul(term, e) / m
        out += term
    return out
