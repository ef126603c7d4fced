"""Built-in homogeneous spaces: spheres, Stiefel manifolds, isospectral matrices, R^n, and
their products."""

from __future__ import annotations

import numpy as np

from ..groups import SE3, SO3, Product, Rn, SOn
from .base import HomogeneousSpace


class Sphere(HomogeneousSpace):
    """The unit sphere S^2 in R^3 with SO(3) acting by rotation, ``Lambda(R, p) = R p``.

    Points ``(..., 3)``; a director, a magnetization, a pendulum link. ``f(t, p)`` returns
    an angular velocity ``(..., 3)`` (any ``w`` with ``dp/dt = w x p``).
    """

    def __init__(self, dim: int = 2):
        if dim != 2:
            raise ValueError(f"Sphere: only S^2 (dim = 2) is built in, got dim = {dim}")
        self.group = SO3
        self.point_shape = (3,)
        self.name = "S2"

    def act(self, g, p):
        return np.einsum("...ij,...j->...i", g, p)

    def constraint(self, p):
        return np.abs(np.linalg.norm(p, axis=-1) - 1.0)

    def project(self, p):
        p = np.asarray(p, dtype=float)
        return p / np.linalg.norm(p, axis=-1, keepdims=True)

    def sample(self, rng, batch_shape=()):
        return self.project(rng.standard_normal(tuple(batch_shape) + (3,)))


class TangentSphere(HomogeneousSpace):
    """The tangent bundle TS^2 = {(q, w): |q| = 1, q . w = 0}, points ``(..., 6)`` =
    ``(q, w)``, with SE(3) acting as in Celledoni, Cokaj, Leone, Murari & Owren (2022):
    ``(R, r) . (q, w) = (R q, R w + r x R q)`` (a group action: it composes like SE(3)'s
    product, and keeps both constraints).

    A link of a spherical pendulum: ``q`` its direction, ``w`` its angular velocity. The
    generator ``xi = (rho, theta)`` (SE(3)'s ordering) moves ``(q, w)`` at
    ``(theta x q, theta x w + rho x q)``; ``theta = w`` and ``rho x q = w'`` give any motion.
    """

    def __init__(self):
        self.group = SE3
        self.point_shape = (6,)
        self.name = "TS2"

    def act(self, g, p):
        g, p = np.asarray(g, dtype=float), np.asarray(p, dtype=float)
        R, r = g[..., :3, :3], g[..., :3, 3]
        q = np.einsum("...ij,...j->...i", R, p[..., :3])
        w = np.einsum("...ij,...j->...i", R, p[..., 3:]) + np.cross(r, q)
        return np.concatenate([q, w], axis=-1)

    def constraint(self, p):
        p = np.asarray(p, dtype=float)
        q, w = p[..., :3], p[..., 3:]
        return np.maximum(np.abs(np.linalg.norm(q, axis=-1) - 1.0), np.abs(np.sum(q * w, axis=-1)))

    def project(self, p):
        p = np.asarray(p, dtype=float)
        q = p[..., :3] / np.linalg.norm(p[..., :3], axis=-1, keepdims=True)
        w = p[..., 3:] - np.sum(p[..., 3:] * q, axis=-1, keepdims=True) * q
        return np.concatenate([q, w], axis=-1)

    def sample(self, rng, batch_shape=()):
        return self.project(rng.standard_normal(tuple(batch_shape) + (6,)))


class Stiefel(HomogeneousSpace):
    """The Stiefel manifold V_k(R^n) of orthonormal k-frames, ``Y^T Y = I_k``, points
    ``(..., n, k)``, with SO(n) acting from the left, ``Lambda(Q, Y) = Q Y``."""

    def __init__(self, n: int, k: int):
        n, k = int(n), int(k)
        if not 1 <= k <= n or n < 2:
            raise ValueError(f"Stiefel: need 1 <= k <= n and n >= 2, got n = {n}, k = {k}")
        self.n, self.k = n, k
        self.group = SOn(n)
        self.point_shape = (n, k)
        self.name = f"V_{k}(R^{n})"

    def act(self, g, p):
        return np.matmul(g, p)

    def constraint(self, p):
        p = np.asarray(p, dtype=float)
        return np.linalg.norm(np.swapaxes(p, -1, -2) @ p - np.eye(self.k), axis=(-2, -1))

    def project(self, p):
        """The polar factor ``U V^T`` of ``p = U S V^T`` (nearest frame in Frobenius norm)."""
        u, _, vt = np.linalg.svd(np.asarray(p, dtype=float), full_matrices=False)
        return u @ vt

    def sample(self, rng, batch_shape=()):
        return self.project(rng.standard_normal(tuple(batch_shape) + (self.n, self.k)))


class Isospectral(HomogeneousSpace):
    """Symmetric n x n matrices with SO(n) acting by conjugation, ``Lambda(Q, L) = Q L Q^T``:
    the action keeps the spectrum (isospectral flows, ``L' = [B(L), L]`` with ``B`` skew,
    e.g. the Toda lattice: ``f(t, L) = vee(B(L))``). Points ``(..., n, n)``."""

    def __init__(self, n: int):
        n = int(n)
        if n < 2:
            raise ValueError(f"Isospectral: n must be >= 2, got {n}")
        self.n = n
        self.group = SOn(n)
        self.point_shape = (n, n)
        self.name = f"Isospectral({n})"

    def act(self, g, p):
        return g @ p @ np.swapaxes(g, -1, -2)

    def constraint(self, p):
        p = np.asarray(p, dtype=float)
        return np.linalg.norm(p - np.swapaxes(p, -1, -2), axis=(-2, -1))

    def project(self, p):
        p = np.asarray(p, dtype=float)
        return 0.5 * (p + np.swapaxes(p, -1, -2))

    def sample(self, rng, batch_shape=()):
        return self.project(rng.standard_normal(tuple(batch_shape) + (self.n, self.n)))


class RnSpace(HomogeneousSpace):
    """R^n under translations, ``Lambda(x, p) = x + p``: classical RK as the special case."""

    def __init__(self, n: int):
        self.n = int(n)
        self.group = Rn(self.n)
        self.point_shape = (self.n,)
        self.name = f"R{self.n}"

    def act(self, g, p):
        return np.asarray(g, dtype=float) + np.asarray(p, dtype=float)

    def constraint(self, p):
        return np.zeros(np.shape(p)[:-1])

    def project(self, p):
        return np.asarray(p, dtype=float)

    def sample(self, rng, batch_shape=()):
        return rng.standard_normal(tuple(batch_shape) + (self.n,))


class ProductSpace(HomogeneousSpace):
    """``M_1 x ... x M_m`` with ``G_1 x ... x G_m`` acting factor by factor.

    Points are flat, ``(..., P)`` with ``P`` the sum of the factors' point sizes
    (:meth:`split`, :meth:`join`); increments are the product group's flat algebra.
    """

    def __init__(self, *factors: HomogeneousSpace):
        if not factors or not all(isinstance(f, HomogeneousSpace) for f in factors):
            raise ValueError("ProductSpace needs one or more HomogeneousSpace factors")
        self.factors = tuple(factors)
        self.group = Product(*[f.group for f in factors])
        self._sizes = [int(np.prod(f.point_shape)) for f in factors]
        self._offsets = np.concatenate([[0], np.cumsum(self._sizes)]).astype(int)
        self.point_shape = (int(self._offsets[-1]),)
        self.name = " x ".join(f.name for f in factors)

    @classmethod
    def power(cls, space: HomogeneousSpace, m: int) -> "ProductSpace":
        """``M^m``."""
        return cls(*([space] * int(m)))

    def split(self, p):
        """The factors' points, each ``(..., *factor.point_shape)``."""
        p = np.asarray(p, dtype=float)
        o = self._offsets
        return [p[..., o[i]:o[i + 1]].reshape(p.shape[:-1] + f.point_shape) for i, f in enumerate(self.factors)]

    def join(self, *parts):
        """Flat points from the factors' points."""
        flat = [np.asarray(q, dtype=float).reshape(np.shape(q)[: np.ndim(q) - len(f.point_shape)] + (-1,))
                for q, f in zip(parts, self.factors)]
        batch = np.broadcast_shapes(*[q.shape[:-1] for q in flat])
        return np.concatenate([np.broadcast_to(q, batch + q.shape[-1:]) for q in flat], axis=-1)

    def act(self, g, p):
        gs = self.group.split(g)
        return self.join(*[f.act(gi, pi) for f, gi, pi in zip(self.factors, gs, self.split(p))])

    def retract(self, xi, p):
        xs = self.group.split_algebra(xi)
        return self.join(*[f.retract(x, q) for f, x, q in zip(self.factors, xs, self.split(p))])

    def constraint(self, p):
        return np.max(np.stack([f.constraint(q) for f, q in zip(self.factors, self.split(p))], axis=-1), axis=-1)

    def project(self, p):
        return self.join(*[f.project(q) for f, q in zip(self.factors, self.split(p))])

    def sample(self, rng, batch_shape=()):
        return self.join(*[f.sample(rng, batch_shape) for f in self.factors])
