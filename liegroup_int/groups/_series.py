"""Exact rational constants used by the series forms (Bernoulli numbers, factorials)."""

from __future__ import annotations

from fractions import Fraction
from functools import lru_cache
from math import comb, factorial

import numpy as np


@lru_cache(maxsize=None)
def bernoulli_fractions(n: int) -> tuple[Fraction, ...]:
    """Bernoulli numbers ``B_0 .. B_n`` as exact fractions, with ``B_1 = -1/2``."""
    b = [Fraction(1)]
    for m in range(1, n + 1):
        b.append(-sum(comb(m + 1, k) * b[k] for k in range(m)) / (m + 1))
    return tuple(b)


@lru_cache(maxsize=None)
def _bernoulli_array(n: int) -> np.ndarray:
    arr = np.array([float(x) for x in bernoulli_fractions(n)])
    arr.setflags(write=False)
    return arr


def bernoulli_numbers(n: int) -> np.ndarray:
    """Bernoulli numbers ``B_0 .. B_n`` as floats (read-only array)."""
    return _bernoulli_array(n)


@lru_cache(maxsize=None)
def _factorial_array(n: int) -> np.ndarray:
    arr = np.array([float(factorial(k)) for k in range(n + 1)])
    arr.setflags(write=False)
    return arr


def factorials(n: int) -> np.ndarray:
    """``0!, 1!, ..., n!`` as floats (read-only array)."""
    return _factorial_array(n)
