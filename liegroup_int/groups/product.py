"""Direct products of groups, with points and algebra elements stored flat.

A point of ``Product(G1, G2, ...)`` is one ndarray ``(..., P)`` holding the flattened
points of the factors one after another (``P = sum of prod(Gi.point_shape)``); an algebra
element is ``(..., D)`` with ``D = sum of Gi.dim``. ``split``/``join`` convert between
the flat form and the factors' natural shapes. ``Power(G, N)`` is the product of ``N``
copies of one group, evaluated in a single batched call of ``G``'s operations.
"""

from __future__ import annotations

from math import prod

import numpy as np

from .base import LieGroup


def _block_diag(blocks: list[np.ndarray]) -> np.ndarray:
    batch = np.broadcast_shapes(*(b.shape[:-2] for b in blocks))
    n = sum(b.shape[-1] for b in blocks)
    out = np.zeros(batch + (n, n))
    i = 0
    for b in blocks:
        k = b.shape[-1]
        out[..., i : i + k, i : i + k] = b
        i += k
    return out


class Product(LieGroup):
    """Direct product ``G1 x G2 x ...`` acting componentwise.

    Parameters
    ----------
    *factors : LieGroup
        The factor groups, at least one.
    """

    def __init__(self, *factors: LieGroup):
        if not factors or not all(isinstance(f, LieGroup) for f in factors):
            raise ValueError("Product: needs one or more LieGroup factors")
        self.factors = tuple(factors)
        sizes = [prod(f.point_shape) for f in factors]
        self._p_off = np.concatenate(([0], np.cumsum(sizes))).astype(int)
        self._a_off = np.concatenate(([0], np.cumsum([f.dim for f in factors]))).astype(int)
        self._x_off = np.concatenate(([0], np.cumsum([prod(f.act_shape) for f in factors]))).astype(int)
        self.dim = int(self._a_off[-1])
        self.point_shape = (int(self._p_off[-1]),)
        self.act_shape = (int(self._x_off[-1]),)
        self.name = " x ".join(f.name for f in factors)

    def __eq__(self, other):
        return isinstance(other, Product) and other.factors == self.factors

    def __hash__(self):
        return hash(("Product",) + self.factors)

    # -- flat <-> factors
    def split(self, g: np.ndarray) -> tuple[np.ndarray, ...]:
        """Views of the factors of a flat point, each ``(..., *Gi.point_shape)``."""
        g = np.asarray(g)
        return tuple(
            g[..., self._p_off[i] : self._p_off[i + 1]].reshape(g.shape[:-1] + f.point_shape)
            for i, f in enumerate(self.factors)
        )

    def join(self, *parts: np.ndarray) -> np.ndarray:
        """Flat point from factor points (inverse of :meth:`split`)."""
        if len(parts) != len(self.factors):
            raise ValueError(f"{self.name}: expected {len(self.factors)} parts, got {len(parts)}")
        flat = []
        for f, p in zip(self.factors, parts):
            p = np.asarray(p, dtype=float)
            n = len(f.point_shape)
            if p.shape[p.ndim - n :] != f.point_shape:
                raise ValueError(f"{self.name}: factor {f.name} needs trailing shape {f.point_shape}, got {p.shape}")
            flat.append(p.reshape(p.shape[: p.ndim - n] + (-1,)))
        batch = np.broadcast_shapes(*(x.shape[:-1] for x in flat))
        return np.concatenate([np.broadcast_to(x, batch + x.shape[-1:]) for x in flat], axis=-1)

    def split_algebra(self, xi: np.ndarray) -> tuple[np.ndarray, ...]:
        """Views of the factors' algebra components, each ``(..., Gi.dim)``."""
        return tuple(xi[..., self._a_off[i] : self._a_off[i + 1]] for i in range(len(self.factors)))

    def _map_points(self, fn, *points):
        parts = [self.split(p) for p in points]
        return self.join(*(fn(f, *(p[i] for p in parts)) for i, f in enumerate(self.factors)))

    def _map_algebra(self, fn, *xis):
        parts = [self.split_algebra(np.asarray(x, dtype=float)) for x in xis]
        return np.concatenate([fn(f, *(p[i] for p in parts)) for i, f in enumerate(self.factors)], axis=-1)

    # -- minimum API
    def identity(self, batch_shape=()):
        return self.join(*(f.identity(batch_shape) for f in self.factors))

    def compose(self, g, h):
        return self._map_points(lambda f, a, b: f.compose(a, b), g, h)

    def inverse(self, g):
        return self._map_points(lambda f, a: f.inverse(a), g)

    def exp(self, xi):
        return self.join(*(f.exp(x) for f, x in zip(self.factors, self.split_algebra(np.asarray(xi, dtype=float)))))

    def log(self, g):
        return np.concatenate([f.log(p) for f, p in zip(self.factors, self.split(g))], axis=-1)

    def ad(self, xi):
        return _block_diag([f.ad(x) for f, x in zip(self.factors, self.split_algebra(np.asarray(xi, dtype=float)))])

    def Ad(self, g):
        return _block_diag([f.Ad(p) for f, p in zip(self.factors, self.split(g))])

    def hat(self, xi):
        """Block diagonal of the factors' matrices."""
        return _block_diag([f.hat(x) for f, x in zip(self.factors, self.split_algebra(np.asarray(xi, dtype=float)))])

    def vee(self, m):
        m = np.asarray(m, dtype=float)
        parts, i = [], 0
        for f in self.factors:
            k = f.hat(np.zeros(f.dim)).shape[-1]
            parts.append(f.vee(m[..., i : i + k, i : i + k]))
            i += k
        return np.concatenate(parts, axis=-1)

    def act(self, g, p):
        """Componentwise action on the flat concatenation ``(..., act_shape)`` of one point
        per factor (each flattened from ``Gi.act_shape``)."""
        p = np.asarray(p, dtype=float)
        out = []
        for i, (f, gi) in enumerate(zip(self.factors, self.split(g))):
            pi = p[..., self._x_off[i] : self._x_off[i + 1]].reshape(p.shape[:-1] + f.act_shape)
            r = np.asarray(f.act(gi, pi))
            out.append(r.reshape(r.shape[: r.ndim - len(f.act_shape)] + (-1,)))
        batch = np.broadcast_shapes(*(x.shape[:-1] for x in out))
        return np.concatenate([np.broadcast_to(x, batch + x.shape[-1:]) for x in out], axis=-1)

    def normalize(self, g):
        return self._map_points(lambda f, a: f.normalize(a), g)

    # -- closed forms componentwise
    def dexp(self, xi, v):
        return self._map_algebra(lambda f, a, b: f.dexp(a, b), xi, v)

    def dexpinv(self, xi, v):
        return self._map_algebra(lambda f, a, b: f.dexpinv(a, b), xi, v)

    def retract(self, xi, g):
        xs = self.split_algebra(np.asarray(xi, dtype=float))
        return self.join(*(f.retract(x, p) for f, x, p in zip(self.factors, xs, self.split(g))))

    def magnitude(self, g):
        return np.concatenate([f.magnitude(p) for f, p in zip(self.factors, self.split(g))], axis=-1)

    def rotation_angle(self, xi):
        xs = self.split_algebra(np.asarray(xi, dtype=float))
        return np.max(np.stack([f.rotation_angle(x) for f, x in zip(self.factors, xs)], axis=-1), axis=-1)


class Power(LieGroup):
    """``N`` copies of one group, ``G^N``, evaluated as one batched call of ``G``.

    Points are ``(..., N * prod(G.point_shape))`` and algebra elements ``(..., N * G.dim)``
    (flat, like :class:`Product`); ``split`` gives ``(..., N, *G.point_shape)``.
    """

    def __init__(self, group: LieGroup, n: int):
        if not isinstance(group, LieGroup) or int(n) != n or n < 1:
            raise ValueError(f"Power: needs a LieGroup and a positive count, got {group!r}, {n!r}")
        self.group, self.n = group, int(n)
        self._psize = prod(group.point_shape)
        self.dim = self.n * group.dim
        self.point_shape = (self.n * self._psize,)
        self.act_shape = (self.n,) + tuple(group.act_shape)
        self.name = f"{group.name}^{self.n}"

    def __eq__(self, other):
        return isinstance(other, Power) and (other.group, other.n) == (self.group, self.n)

    def __hash__(self):
        return hash(("Power", self.group, self.n))

    def split(self, g):
        g = np.asarray(g)
        return g.reshape(g.shape[:-1] + (self.n,) + self.group.point_shape)

    def join(self, g):
        g = np.asarray(g, dtype=float)
        k = len(self.group.point_shape)
        return g.reshape(g.shape[: g.ndim - k - 1] + (-1,))

    def split_algebra(self, xi):
        xi = np.asarray(xi, dtype=float)
        return xi.reshape(xi.shape[:-1] + (self.n, self.group.dim))

    def _flat_algebra(self, x):
        return x.reshape(x.shape[:-2] + (-1,))

    def identity(self, batch_shape=()):
        return self.join(self.group.identity(tuple(batch_shape) + (self.n,)))

    def compose(self, g, h):
        return self.join(self.group.compose(self.split(g), self.split(h)))

    def inverse(self, g):
        return self.join(self.group.inverse(self.split(g)))

    def exp(self, xi):
        return self.join(self.group.exp(self.split_algebra(xi)))

    def log(self, g):
        return self._flat_algebra(self.group.log(self.split(g)))

    def _block(self, m):
        d = self.group.dim
        out = np.zeros(m.shape[:-3] + (self.dim, self.dim))
        for i in range(self.n):
            out[..., i * d : (i + 1) * d, i * d : (i + 1) * d] = m[..., i, :, :]
        return out

    def ad(self, xi):
        return self._block(self.group.ad(self.split_algebra(xi)))

    def Ad(self, g):
        return self._block(self.group.Ad(self.split(g)))

    def act(self, g, p):
        """Copy ``i`` acts on ``p[..., i, :]`` (``act_shape = (N, *G.act_shape)``)."""
        return self.group.act(self.split(g), p)

    def hat(self, xi):
        """Block diagonal of the copies' matrices."""
        m = self.group.hat(self.split_algebra(xi))
        k = m.shape[-1]
        out = np.zeros(m.shape[:-3] + (self.n * k, self.n * k))
        for i in range(self.n):
            out[..., i * k : (i + 1) * k, i * k : (i + 1) * k] = m[..., i, :, :]
        return out

    def vee(self, m):
        m = np.asarray(m, dtype=float)
        k = m.shape[-1] // self.n
        blocks = np.stack([m[..., i * k : (i + 1) * k, i * k : (i + 1) * k] for i in range(self.n)], axis=-3)
        return self._flat_algebra(self.group.vee(blocks))

    def normalize(self, g):
        return self.join(self.group.normalize(self.split(g)))

    def dexp(self, xi, v):
        return self._flat_algebra(self.group.dexp(self.split_algebra(xi), self.split_algebra(v)))

    def dexpinv(self, xi, v):
        return self._flat_algebra(self.group.dexpinv(self.split_algebra(xi), self.split_algebra(v)))

    def retract(self, xi, g):
        return self.join(self.group.retract(self.split_algebra(xi), self.split(g)))

    def magnitude(self, g):
        return self._flat_algebra(self.group.magnitude(self.split(g)))

    def rotation_angle(self, xi):
        return np.max(self.group.rotation_angle(self.split_algebra(xi)), axis=-1)
