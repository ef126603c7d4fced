"""Rigid bodies on SO(3) x R^3: the free rigid body and the heavy top.

State ``y = (R, W)`` stored flat as a point of ``Product(SO3, Rn(3))``, shape ``(..., 12)``:

* ``R`` (3x3) maps body to spatial coordinates;
* ``W`` (3,) is the **body** angular velocity, so ``dR/dt = R hat(W) = hat(R W) R``.

The vector field returns the left (spatial) increment rate of each factor:
``(omega, dW/dt)`` with ``omega = R W`` the spatial angular velocity and Euler's equations

    I dW/dt = (I W) x W + m g (Gamma x chi),   Gamma = R^T e3,

for a body of principal inertia ``I`` (about the fixed point), mass ``m``, centre of
mass at body vector ``chi`` from the fixed point, and gravity ``-g e3``. The free rigid
body is ``m = 0``. All operations are batched over leading axes (many bodies at once).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..groups import SO3, Product, Rn
from ..groups.so3 import cross
from ..integrators import GroupProblem
from .errors import ParameterError

SPACE = Product(SO3, Rn(3))
E3 = np.array([0.0, 0.0, 1.0])


def check_inertia(inertia) -> None:
    """Raise :class:`ParameterError` unless ``inertia`` holds three positive principal
    moments satisfying the triangle inequalities of a physical body."""
    I = np.asarray(inertia, dtype=float)
    if I.shape != (3,) or not np.all(I > 0):
        raise ParameterError("inertia", f"expected three positive principal moments, got {inertia!r}")
    a, b, c = I
    if a > b + c or b > a + c or c > a + b:
        raise ParameterError("inertia", f"{inertia!r} violates the triangle inequality of a rigid body")


@dataclass(frozen=True)
class RigidBody:
    """A rigid body with a fixed point, optionally in uniform gravity.

    Parameters
    ----------
    inertia : (3,) array_like
        Principal moments of inertia about the fixed point [kg m^2], all > 0, satisfying
        the triangle inequalities of a physical body.
    mass : float
        Mass [kg], >= 0 (0: free rigid body, gravity has no effect).
    com : (3,) array_like
        Centre of mass in body coordinates, relative to the fixed point [m].
    gravity : float
        Gravitational acceleration along ``-e3`` [m/s^2].
    """

    inertia: tuple = (1.0, 2.0, 3.0)
    mass: float = 0.0
    com: tuple = (0.0, 0.0, 0.0)
    gravity: float = 9.81
    space: Product = field(default=SPACE, init=False, repr=False)

    def __post_init__(self):
        check_inertia(self.inertia)
        if not self.mass >= 0:
            raise ParameterError("mass", f"expected >= 0, got {self.mass!r}")
        if np.asarray(self.com, dtype=float).shape != (3,):
            raise ParameterError("com", f"expected 3 numbers, got {self.com!r}")

    # -- state helpers
    def state(self, R: np.ndarray, W: np.ndarray) -> np.ndarray:
        """Flat state ``(..., 12)`` from ``R (..., 3, 3)`` and body ``W (..., 3)``."""
        return SPACE.join(R, W)

    def split(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(R, W)`` views of a flat state."""
        return SPACE.split(y)

    @property
    def _I(self) -> np.ndarray:
        return np.asarray(self.inertia, dtype=float)

    @property
    def _mgchi(self) -> np.ndarray:
        return self.mass * self.gravity * np.asarray(self.com, dtype=float)

    # -- dynamics
    def vector_field(self, t: float, y: np.ndarray) -> np.ndarray:
        """``(R W, dW/dt)``, shape ``(..., 6)``."""
        R, W = SPACE.split(y)
        I = self._I
        torque = cross(I * W, W)
        if self.mass > 0:
            gamma = R[..., 2, :]  # R^T e3
            torque = torque + cross(gamma, self._mgchi)
        omega = np.einsum("...ij,...j->...i", R, W)
        return np.concatenate((omega, torque / I), axis=-1)

    def problem(self, compiled: bool = True) -> GroupProblem:
        """The RKMK problem on ``SO3 x R3`` (a :class:`RigidBodyProblem`); ``compiled=False``:
        NumPy only (no numba import, for short runs)."""
        return RigidBodyProblem(self, compiled)

    # -- diagnostics
    def energy(self, y: np.ndarray) -> np.ndarray:
        """Kinetic plus gravitational energy [J], shape ``(...)``."""
        R, W = SPACE.split(y)
        e = 0.5 * np.einsum("...i,...i->...", W, self._I * W)
        if self.mass > 0:
            e = e + np.einsum("...i,i->...", R[..., 2, :], self._mgchi)
        return e

    def spatial_momentum(self, y: np.ndarray) -> np.ndarray:
        """Spatial angular momentum ``R I W`` about the fixed point, ``(..., 3)``."""
        R, W = SPACE.split(y)
        return np.einsum("...ij,...j->...i", R, self._I * W)

    def casimir(self, y: np.ndarray) -> np.ndarray:
        """Conserved momentum invariant, shape ``(...)``.

        Free body: ``|I W|^2`` (Casimir of the Lie-Poisson bracket). Heavy top: the
        vertical angular momentum ``(R I W) . e3`` (conserved since gravity is vertical).
        """
        if self.mass > 0:
            return self.spatial_momentum(y)[..., 2]
        R, W = SPACE.split(y)
        m = self._I * W
        return np.einsum("...i,...i->...", m, m)

    def orth_error(self, y: np.ndarray) -> np.ndarray:
        """``|R^T R - I|`` (Frobenius), shape ``(...)``."""
        R, _ = SPACE.split(y)
        E = np.swapaxes(R, -1, -2) @ R - np.eye(3)
        return np.sqrt(np.einsum("...ij,...ij->...", E, E))

    def diagnostics(self) -> dict:
        """Named diagnostics for recorders: ``energy``, ``casimir``, ``orth_error``."""
        return {
            "energy": lambda t, y: float(self.energy(y)),
            "casimir": lambda t, y: float(self.casimir(y)),
            "orth_error": lambda t, y: float(self.orth_error(y)),
        }


class RigidBodyProblem(GroupProblem):
    """``GroupProblem(SO3 x R3, body.vector_field)`` with compiled kernels.

    :meth:`compiled_kernels` hands the compiled engine the body's vector field
    (:mod:`.rigid_body_numba`), so that the drivers run all the steps between two output
    times in one compiled call when no per-step monitor is given.
    """

    def __init__(self, body: RigidBody, compiled: bool = True):
        super().__init__(SPACE, body.vector_field, compiled)
        self.body = body

    def _plain(self) -> bool:
        """The problem is the body's own dynamics: no subclass of this class or of
        :class:`RigidBody` overriding them, ``f`` and ``space`` as built."""
        cls = type(self.body)
        return (type(self) is RigidBodyProblem and self.space == SPACE and self.f == self.body.vector_field
                and all(getattr(cls, k) is getattr(RigidBody, k) for k in ("vector_field", "_I", "_mgchi")))

    def compiled_kernels(self):
        """The engine's kernels, or ``None`` (generic path) when they would not reproduce
        this problem (:meth:`_plain`)."""
        if not (self._compiled is not None and self._plain()):
            return None
        from .rigid_body_numba import compiled_problem

        return compiled_problem(self.body, SPACE)

    def split_steps(self, y: np.ndarray, h: float, gammas: np.ndarray, n: int, t: float = 0.0) -> np.ndarray:
        """``n`` steps of length ``h`` of the symmetric composition ``gammas`` of the body's
        Strang splitting (:mod:`.rigid_body_splitting`: symplectic), from ``y`` ``(..., 12)``;
        a new array (autonomous: ``t`` unused)."""
        if not self._plain():
            raise ValueError("splitting methods integrate the rigid body's own dynamics; this problem overrides "
                             "them (use an RKMK method)")
        from .rigid_body_splitting import advance

        out = np.array(y, dtype=float)
        I, mgchi = self.body._I, self.body._mgchi
        for b in out.reshape(-1, 12):
            R, W = b[:9].reshape(3, 3).copy(), b[9:].copy()
            advance(R, W, I, mgchi, self.body.mass > 0, np.asarray(gammas, dtype=float), float(h), int(n))
            b[:9], b[9:] = R.ravel(), W
        return out


def axisymmetric_free_rotation(I1: float, I3: float, R0: np.ndarray, W0: np.ndarray, t: np.ndarray):
    """Closed-form motion of a torque-free body with ``I = (I1, I1, I3)``.

    ``R(t) = exp(t hat(L / I1)) R0 exp(t nu hat(e3))`` with the spatial momentum
    ``L = R0 I W0`` and ``nu = (I1 - I3) W0[2] / I1``; then ``W = R^T L / I1 + nu e3``.

    Returns
    -------
    R : (..., 3, 3), W : (..., 3)
        For every entry of ``t``.
    """
    t = np.asarray(t, dtype=float)
    I = np.array([I1, I1, I3])
    L = R0 @ (I * W0)
    nu = (I1 - I3) * W0[2] / I1
    R = SO3.exp(t[..., None] * (L / I1)) @ R0 @ SO3.exp(t[..., None] * (nu * E3))
    W = np.einsum("...ji,j->...i", R, L) / I1 + nu * E3
    return R, W
