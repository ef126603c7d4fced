"""Homogeneous spaces: a manifold M, a group G of ours, and an action Lambda: G x M -> M.

RKMK on M (Munthe-Kaas 1999): ``dy/dt = f(t, y) . y`` with ``f: R x M -> g`` the algebra of
G, stepped by ``y_{n+1} = Lambda(exp(u), y_n)`` with ``u`` from the RK stages and
``dexpinv`` of G. Points are plain arrays with leading batch axes, like the groups'.

A space implements the *minimum API* (``act``, ``constraint``, ``project``, ``sample``) and
gets the rest (``retract``, ``dexpinv``, ``rotation_angle``) once, here.
"""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np

from ..groups.base import LieGroup


class HomogeneousSpace(ABC):
    """A manifold acted on by a Lie group (from the left).

    Attributes
    ----------
    group : LieGroup
        The acting group; increments live in its algebra, ``(..., group.dim)``.
    point_shape : tuple of int
        Trailing shape of one point of M.
    name : str
    """

    group: LieGroup
    point_shape: tuple[int, ...]
    name: str

    # ------------------------------------------------------------------ minimum API
    @abstractmethod
    def act(self, g: np.ndarray, p: np.ndarray) -> np.ndarray:
        """``Lambda(g, p)``: group elements ``(..., *group.point_shape)`` on points
        ``(..., *point_shape)``, broadcasting over batch axes."""

    @abstractmethod
    def constraint(self, p: np.ndarray) -> np.ndarray:
        """How far ``p`` is off the manifold, ``(...)`` (0 on it): what the action keeps."""

    @abstractmethod
    def project(self, p: np.ndarray) -> np.ndarray:
        """The nearest point of M (or a retraction onto it), ``(..., *point_shape)``."""

    @abstractmethod
    def sample(self, rng: np.random.Generator, batch_shape: tuple[int, ...] = ()) -> np.ndarray:
        """Random points of M, ``batch_shape + point_shape``."""

    # ------------------------------------------------------------------ derived API
    def retract(self, xi: np.ndarray, p: np.ndarray) -> np.ndarray:
        """``Lambda(exp(xi), p)``: an algebra increment ``(..., group.dim)`` applied to ``p``."""
        return self.act(self.group.exp(xi), p)

    def dexpinv(self, xi: np.ndarray, v: np.ndarray) -> np.ndarray:
        """The acting group's ``dexpinv``."""
        return self.group.dexpinv(xi, v)

    def rotation_angle(self, xi: np.ndarray) -> np.ndarray:
        """Rotation angle of an increment (the group's), ``(...)``."""
        return self.group.rotation_angle(xi)

    def magnitude(self, p: np.ndarray) -> np.ndarray:
        """``|p|`` entry by entry, flattened per point (error scales of adaptive steps)."""
        p = np.asarray(p, dtype=float)
        k = len(self.point_shape)
        return np.abs(p).reshape(p.shape[: p.ndim - k] + (-1,))

    def __repr__(self) -> str:
        return self.name
