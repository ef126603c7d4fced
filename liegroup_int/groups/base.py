"""Abstract Lie group: a small minimum API per group, a derived API written once.

Conventions (docs/theory.md, section "Conventions")
---------------------------------------------------
* Points are plain ndarrays with leading batch axes; ``point_shape`` gives the trailing
  shape of one point (``(3, 3)`` for SO(3), ``(n,)`` for R^n, ``(P,)`` for products).
* Algebra elements are ndarrays of shape ``(..., dim)``.
* Increments act from the left: ``Lambda(xi, g) = exp(xi) * g``.
* ``dexp`` is the left-trivialized derivative of exp,
  ``d/dt exp(xi(t)) = dexp(xi, xi') * exp(xi(t))`` (right-multiplied by ``exp(xi)``,
  i.e. read as the spatial velocity), so ``dexp_xi = sum_k ad_xi^k / (k+1)!`` and
  ``dexpinv_xi = sum_k B_k ad_xi^k / k!`` with ``B_1 = -1/2``.
"""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np

from ._series import bernoulli_numbers, factorials


class LieGroup(ABC):
    """A matrix or vector Lie group acting on itself from the left.

    Subclasses implement the *minimum API* (``identity``, ``compose``, ``inverse``,
    ``exp``, ``log``, ``hat``, ``vee``, ``ad``, ``Ad``, ``act``) and may override
    ``dexp``/``dexpinv`` with closed forms and ``normalize`` where points satisfy
    constraints; everything else is derived here once.

    Attributes
    ----------
    dim : int
        Dimension of the Lie algebra (length of the last axis of algebra elements).
    point_shape : tuple of int
        Trailing shape of one group element.
    act_shape : tuple of int
        Trailing shape of the points :meth:`act` transforms.
    """

    dim: int
    point_shape: tuple[int, ...]
    act_shape: tuple[int, ...]
    name: str

    # ------------------------------------------------------------------ minimum API
    @abstractmethod
    def identity(self, batch_shape: tuple[int, ...] = ()) -> np.ndarray:
        """Identity element, shape ``batch_shape + point_shape``."""

    @abstractmethod
    def compose(self, g: np.ndarray, h: np.ndarray) -> np.ndarray:
        """Group product ``g * h``, broadcasting over batch axes."""

    @abstractmethod
    def inverse(self, g: np.ndarray) -> np.ndarray:
        """Group inverse ``g^-1``."""

    @abstractmethod
    def exp(self, xi: np.ndarray) -> np.ndarray:
        """Exponential map, ``(..., dim) -> (..., *point_shape)``."""

    @abstractmethod
    def log(self, g: np.ndarray) -> np.ndarray:
        """Logarithm (principal branch), ``(..., *point_shape) -> (..., dim)``."""

    @abstractmethod
    def hat(self, xi: np.ndarray) -> np.ndarray:
        """The algebra element as a matrix of the group's matrix representation,
        ``(..., dim) -> (..., m, m)``, so that ``hat([xi, eta]) = [hat(xi), hat(eta)]``."""

    @abstractmethod
    def vee(self, m: np.ndarray) -> np.ndarray:
        """Inverse of :meth:`hat`, ``(..., m, m) -> (..., dim)``."""

    @abstractmethod
    def ad(self, xi: np.ndarray) -> np.ndarray:
        """Matrix of ``ad_xi = [xi, .]``, shape ``(..., dim, dim)``."""

    @abstractmethod
    def Ad(self, g: np.ndarray) -> np.ndarray:
        """Matrix of the adjoint representation ``Ad_g``, shape ``(..., dim, dim)``."""

    @abstractmethod
    def act(self, g: np.ndarray, p: np.ndarray) -> np.ndarray:
        """Action of ``g`` on a point ``p`` of the space the group transforms,
        ``(..., *act_shape) -> (..., *act_shape)``."""

    # ------------------------------------------------------------------ derived API
    def bracket(self, xi: np.ndarray, eta: np.ndarray) -> np.ndarray:
        """Lie bracket ``[xi, eta] = ad_xi(eta)``, shape ``(..., dim)``."""
        return np.einsum("...ij,...j->...i", self.ad(xi), eta)

    def dexp(self, xi: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Left-trivialized derivative of exp applied to ``v``, shape ``(..., dim)``.

        Generic fallback: the series ``sum_k ad_xi^k v / (k+1)!`` to 30 terms; groups
        override it with closed forms.
        """
        return self.dexp_series(xi, v, 30)

    def dexpinv(self, xi: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Inverse of :meth:`dexp`, shape ``(..., dim)``; generic fallback by series."""
        return self.dexpinv_series(xi, v, 40)

    def dexp_series(self, xi: np.ndarray, v: np.ndarray, order: int) -> np.ndarray:
        """Truncated series ``sum_{k=0}^{order} ad_xi^k v / (k+1)!``."""
        fact = factorials(order + 1)
        ad = self.ad(xi)
        term = np.array(v, dtype=float, copy=True)
        out = term.copy()
        for k in range(1, order + 1):
            term = np.einsum("...ij,...j->...i", ad, term)
            out = out + term / fact[k + 1]
        return out

    def dexpinv_series(self, xi: np.ndarray, v: np.ndarray, order: int) -> np.ndarray:
        """Truncated Bernoulli series ``sum_{k=0}^{order} B_k ad_xi^k v / k!``.

        Uses ``B_1 = -1/2`` (left-trivialized convention). Converges for
        ``|xi| < 2 pi`` on SO(3) and SE(3).
        """
        bern = bernoulli_numbers(order)
        fact = factorials(order)
        ad = self.ad(xi)
        term = np.array(v, dtype=float, copy=True)
        out = term.copy()
        for k in range(1, order + 1):
            term = np.einsum("...ij,...j->...i", ad, term)
            if bern[k] != 0.0:
                out = out + (bern[k] / fact[k]) * term
        return out

    def between(self, g: np.ndarray, h: np.ndarray) -> np.ndarray:
        """``g^-1 * h``."""
        return self.compose(self.inverse(g), h)

    def retract(self, xi: np.ndarray, g: np.ndarray) -> np.ndarray:
        """Left action of an algebra increment: ``exp(xi) * g`` (docs/theory.md, section "Conventions")."""
        return self.compose(self.exp(xi), g)

    def magnitude(self, g: np.ndarray) -> np.ndarray:
        """Per-component size of ``g`` used to scale error norms, shape ``(..., dim)``.

        Rotational components are angles and get scale 1; vector-space components
        override this with ``|g|``.
        """
        batch = np.shape(g)[: np.ndim(g) - len(self.point_shape)]
        return np.ones(batch + (self.dim,))

    def normalize(self, g: np.ndarray) -> np.ndarray:
        """A point pulled back onto the group after round-off drift, same shape as ``g``.

        Default: a copy (points without constraints). Rotations take one Newton-Schulz
        step ``R (3 I - R^T R) / 2`` toward the nearest rotation: for a drift ``e`` in
        ``R^T R = I + e`` the result has ``O(e^2)`` drift (quadratic), so one step per
        integration step keeps rotations orthogonal to round-off for ever.
        """
        return np.array(g, dtype=float, copy=True)

    def sample(self, rng: np.random.Generator, batch_shape: tuple[int, ...] = (), scale: float = 1.0) -> np.ndarray:
        """Random points ``exp(scale * xi)`` with standard normal ``xi``, shape
        ``batch_shape + point_shape`` (for tests and examples)."""
        return self.exp(scale * rng.standard_normal(tuple(batch_shape) + (self.dim,)))

    def rotation_angle(self, xi: np.ndarray) -> np.ndarray:
        """Largest rotation angle contained in the algebra element ``xi``, shape ``(...)``.

        Zero for groups without rotations; used to keep RKMK increments away from the
        ``2 pi`` pole of ``dexpinv``.
        """
        return np.zeros(np.shape(xi)[:-1])

    def __repr__(self) -> str:
        return self.name
