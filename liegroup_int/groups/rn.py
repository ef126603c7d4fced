"""The additive group R^n: points and algebra elements are both ``(..., n)``."""

from __future__ import annotations

import numpy as np

from .base import LieGroup


class Rn(LieGroup):
    """Vector space R^n as an abelian Lie group (``compose = +``, ``exp = id``).

    Parameters
    ----------
    n : int
        Dimension, >= 1.
    """

    def __init__(self, n: int):
        if int(n) != n or n < 1:
            raise ValueError(f"Rn: dimension must be a positive integer, got {n!r}")
        self.n = int(n)
        self.dim = self.n
        self.point_shape = (self.n,)
        self.act_shape = (self.n,)
        self.name = f"R{self.n}"

    def __eq__(self, other):
        return isinstance(other, Rn) and other.n == self.n

    def __hash__(self):
        return hash(("Rn", self.n))

    def identity(self, batch_shape=()):
        return np.zeros(tuple(batch_shape) + (self.n,))

    def compose(self, g, h):
        return np.add(g, h)

    def inverse(self, g):
        return np.negative(g)

    def exp(self, xi):
        return np.array(xi, dtype=float, copy=True)

    def log(self, g):
        return np.array(g, dtype=float, copy=True)

    def hat(self, xi):
        """Translation generator ``[[0, xi], [0, 0]]``, ``(..., n + 1, n + 1)``."""
        xi = np.asarray(xi, dtype=float)
        out = np.zeros(xi.shape[:-1] + (self.n + 1, self.n + 1))
        out[..., : self.n, self.n] = xi
        return out

    def vee(self, m):
        return np.array(np.asarray(m, dtype=float)[..., : self.n, self.n], copy=True)

    def ad(self, xi):
        return np.zeros(np.shape(xi)[:-1] + (self.n, self.n))

    def Ad(self, g):
        return np.broadcast_to(np.eye(self.n), np.shape(g)[:-1] + (self.n, self.n)).copy()

    def act(self, g, p):
        return np.add(g, p)

    def dexp(self, xi, v):
        return np.array(v, dtype=float, copy=True)

    def dexpinv(self, xi, v):
        return np.array(v, dtype=float, copy=True)

    def retract(self, xi, g):
        return np.add(xi, g)

    def magnitude(self, g):
        return np.abs(g)
