"""The RKMK plugin contract (docs/theory.md section 2, homogeneous-space form).

A problem supplies

* a linear space of increments (ndarrays of a fixed shape, combined linearly),
* an action ``Lambda(u, y_n) -> y``,
* ``dexpinv_u(w)``, and
* a vector field ``f(t, y)`` with values in the increment space.

One explicit RKMK stage then needs ``k_r = dexpinv_{u_r}(f(t_r, Lambda(u_r, y_n)))``,
which :meth:`Problem.increment_rate` returns. Problems whose ``dexpinv`` is best fused
with the vector field (the beam: pointwise dexpinv before the collocation solve)
override :meth:`increment_rate` directly. On R^n, ``Lambda(u, y) = y + u`` and
``dexpinv = id``, so RKMK is classical RK.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Callable

import numpy as np

from ..groups import LieGroup


class Problem(ABC):
    """Abstract RKMK problem. States ``y`` may be any object; increments are ndarrays."""

    @abstractmethod
    def action(self, u: np.ndarray, y):
        """``Lambda(u, y)``: the state reached from ``y`` by the increment ``u``."""

    @abstractmethod
    def dexpinv(self, u: np.ndarray, w: np.ndarray) -> np.ndarray:
        """``dexpinv_u(w)`` in the increment space."""

    @abstractmethod
    def vector_field(self, t: float, y) -> np.ndarray:
        """``f(t, y)``, an element of the increment space."""

    @abstractmethod
    def zero_increment(self, y) -> np.ndarray:
        """The zero increment at ``y`` (fixes the increment shape)."""

    def increment_rate(self, t: float, y, u: np.ndarray) -> np.ndarray:
        """``dexpinv_u(f(t, y))`` where ``y = Lambda(u, y_n)``."""
        return self.dexpinv(u, self.vector_field(t, y))

    def end_step(self, y):
        """Called on the state that ends an accepted step (not on stage states); returns
        the state to continue from. Default: unchanged. Problems may remove round-off
        drift here (the beam re-orthonormalizes its rotations)."""
        return y

    def increment_scale(self, y) -> np.ndarray:
        """Typical size of each increment component at ``y``, for error norms.

        Defaults to ones (increments measured in absolute terms).
        """
        return np.ones_like(self.zero_increment(y))

    def rotation_angle(self, u: np.ndarray) -> float:
        """Largest rotation angle carried by the increment ``u`` (0 if none)."""
        return 0.0

    def compiled_kernels(self):
        """Optional compiled kernels for the engine
        (:class:`~liegroup_int.integrators.engine.CompiledProblem`), or ``None``.

        With them, and no per-step monitor, the drivers run all the steps between two
        output times in one call of the compiled engine
        (:mod:`liegroup_int.integrators.engine`), which must give the same steps as
        :meth:`increment_rate`, :meth:`action`, :meth:`end_step`, :meth:`increment_scale`
        and :meth:`rotation_angle` to round-off. Default: ``None`` (the generic path).
        """
        return None

    #: Whether :meth:`quadrature_rate` is defined (the drivers then integrate it).
    has_quadrature: bool = False

    @property
    def fsal_reuse(self) -> bool:
        """Whether the generic drivers may reuse the last stage's vector field of an FSAL
        pair as the next step's first stage: true when :meth:`end_step` is the identity
        (the step then ends exactly in that stage's state) and ``increment_rate(t, y, 0)``
        is ``vector_field(t, y)`` (``dexpinv_0`` is the identity)."""
        return type(self).end_step is Problem.end_step

    def quadrature_rate(self, t: float, y) -> float:
        """An optional scalar ``q(t, y)`` whose time integral the drivers accumulate in
        :attr:`Stats.quadrature` with each step's weights, ``h sum_r b_r q(t_r, y_r)``
        over the stage states (so to the method's order). The beam returns the power of
        its external loads, making the quadrature their work for the energy balance.
        Only called when :attr:`has_quadrature` is true."""
        raise NotImplementedError

    def is_finite(self, y) -> bool:
        """Whether the state holds only finite numbers."""
        return bool(np.all(np.isfinite(y)))


class GroupProblem(Problem):
    """An ODE ``dy/dt = f(t, y) y`` on a Lie group, with left increments.

    Parameters
    ----------
    space : LieGroup
        The group ``y`` lives on (``Rn``, ``SO3``, ``SE3``, ``Product``, ``Power``).
    f : callable
        ``f(t, y) -> xi`` with ``xi`` of shape ``(..., space.dim)``: the *spatial*
        (right-trivialized) velocity, ``dy/dt = hat(xi) y`` for matrix groups, and
        ``dy/dt = xi`` on R^n.
    compiled : bool
        Use the groups' compiled (numba) single-point kernels and, for a ``numba.njit``
        ``f``, the compiled engine. ``False`` keeps to NumPy and never imports numba: for
        runs too short to repay numba's start-up (about 0.8 s per process).
    """

    def __init__(self, space: LieGroup, f: Callable[[float, np.ndarray], np.ndarray], compiled: bool = True):
        if not isinstance(space, LieGroup):
            raise TypeError(f"GroupProblem: space must be a LieGroup, got {space!r}")
        self.space = space
        self.f = f
        #: compiled single-point kernels of the built-in groups (None: NumPy only)
        self._compiled = None
        if compiled:
            from ..groups.kernels_numba import CompiledGroup

            self._compiled = CompiledGroup.of(space)
        self._ndim = len(space.point_shape)

    def _single(self, y) -> bool:
        """One point, no batch axes, and compiled kernels for the space."""
        return self._compiled is not None and np.ndim(y) == self._ndim

    def action(self, u, y):
        if self._single(y):
            return self._compiled.retract(u, np.asarray(y, dtype=float))
        return self.space.retract(u, y)

    def dexpinv(self, u, w):
        if self._compiled is not None and np.ndim(u) == 1:
            return self._compiled.dexpinv(u, w)
        return self.space.dexpinv(u, w)

    def increment_rate(self, t, y, u):
        w = np.asarray(self.f(t, y), dtype=float)
        if self._compiled is not None and u.ndim == 1 and w.shape == u.shape:
            return self._compiled.dexpinv(u, w)
        return self.space.dexpinv(u, w)

    def vector_field(self, t, y):
        return np.asarray(self.f(t, y), dtype=float)

    def zero_increment(self, y):
        k = self._ndim
        return np.zeros(np.shape(y)[: np.ndim(y) - k] + (self.space.dim,))

    def increment_scale(self, y):
        if self._single(y):
            return self._compiled.magnitude(np.asarray(y, dtype=float))
        return self.space.magnitude(y)

    def rotation_angle(self, u):
        if self._compiled is not None and np.ndim(u) == 1:
            return self._compiled.rotation_angle(u)
        return float(np.max(self.space.rotation_angle(u), initial=0.0))

    def compiled_kernels(self):
        """The engine's kernels for a ``numba.njit`` ``f`` on a space with compiled group
        kernels (:func:`~.compiled_group.group_problem_kernels`; single points), else
        ``None``. Subclasses that change the step (their own ``action``, ``dexpinv``,
        ``increment_rate``, ``end_step`` or ``vector_field``) keep the generic loop."""
        from .compiled_group import group_problem_kernels, is_compiled_function

        own = ("action", "dexpinv", "increment_rate", "end_step", "vector_field", "increment_scale",
               "rotation_angle")
        if (self._compiled is None or not is_compiled_function(self.f)
                or any(getattr(type(self), m) is not getattr(GroupProblem, m) for m in own)):
            return None
        return group_problem_kernels(self)


class ActionProblem(Problem):
    """An ODE on a homogeneous space, ``dy/dt = f(t, y) . y`` (Munthe-Kaas's RKMK on
    manifolds): ``y`` on ``space`` (a :class:`~liegroup_int.manifolds.HomogeneousSpace`),
    ``f(t, y)`` in the algebra of ``space.group``, increments ``u`` in that algebra, and
    the step ``y_{n+1} = Lambda(exp(u), y_n)``.

    Parameters
    ----------
    space : HomogeneousSpace
    f : callable
        ``f(t, y) -> xi``, shape ``(..., space.group.dim)``: the infinitesimal generator
        whose action moves ``y`` (``dy/dt = d/ds Lambda(exp(s xi), y)`` at ``s = 0``).
    dexpinv_order : int, optional
        Truncate the Bernoulli series of ``dexpinv`` after ``ad_u^k`` with ``k`` this
        order (Munthe-Kaas: a method of order ``q`` needs ``k <= q - 1``, since
        ``u = O(h)``). ``None``: the group's own ``dexpinv`` (closed form, or its series
        to convergence).
    coordinates : {"exp", "cayley"}
        The map from the algebra to the group: the exponential, or the Cayley map
        (groups with ``cay`` and ``dcayinv``, e.g. ``SOn``: no transcendental functions,
        and a closed-form inverse derivative instead of a series; same order).
    """

    def __init__(self, space, f: Callable[[float, np.ndarray], np.ndarray], dexpinv_order: int | None = None,
                 coordinates: str = "exp"):
        from ..manifolds import HomogeneousSpace

        if not isinstance(space, HomogeneousSpace):
            raise TypeError(f"ActionProblem: space must be a HomogeneousSpace, got {space!r}")
        if dexpinv_order is not None and int(dexpinv_order) < 0:
            raise ValueError(f"dexpinv_order: expected an integer >= 0, got {dexpinv_order!r}")
        if coordinates not in ("exp", "cayley"):
            raise ValueError(f"coordinates: expected 'exp' or 'cayley', got {coordinates!r}")
        if coordinates == "cayley" and not hasattr(space.group, "cay"):
            raise ValueError(f"coordinates='cayley': the group {space.group.name} has no Cayley map (SOn has)")
        self.space, self.f = space, f
        self.dexpinv_order = None if dexpinv_order is None else int(dexpinv_order)
        self.coordinates = coordinates
        self._ndim = len(space.point_shape)

    def action(self, u, y):
        if self.coordinates == "cayley":
            return self.space.act(self.space.group.cay(u), y)
        return self.space.retract(u, y)

    def dexpinv(self, u, w):
        if self.coordinates == "cayley":
            return self.space.group.dcayinv(u, w)
        if self.dexpinv_order is not None:
            return self.space.group.dexpinv_series(u, w, self.dexpinv_order)
        return self.space.dexpinv(u, w)

    def increment_rate(self, t, y, u):
        return self.dexpinv(u, np.asarray(self.f(t, y), dtype=float))

    def compiled_kernels(self):
        """The compiled engine's kernels for a ``numba.njit`` ``f`` on ``Sphere()``,
        ``TangentSphere()`` or a power of it, ``Stiefel`` or ``Isospectral`` (single
        points, exp coordinates; :data:`~.compiled_spaces.SPACE_KERNELS`; the SO(n)
        spaces with their truncated dexpinv series too), else ``None`` (the generic loop).
        Imported here so that problems that never compile never import numba."""
        from .compiled_group import is_compiled_function
        from .compiled_spaces import space_kernels

        if self.coordinates != "exp" or not is_compiled_function(self.f):
            return None
        return space_kernels(self, self.dexpinv_order)

    def vector_field(self, t, y):
        return np.asarray(self.f(t, y), dtype=float)

    def zero_increment(self, y):
        return np.zeros(np.shape(y)[: np.ndim(y) - self._ndim] + (self.space.group.dim,))

    def rotation_angle(self, u):
        return float(np.max(self.space.rotation_angle(u), initial=0.0))
