"""A free rigid body in SE(3), translating and rotating, for robotics and multibody users.

The state is the pose ``g = [[R, x], [0, 1]]`` of the body frame at the centre of mass
(``SE3``, algebra ordered ``(rho, theta)``) and the body twist ``xi = (V, W)`` (linear and
angular velocity in body coordinates, ``R^6``): ``y in SE(3) x R^6``, stored flat
``(..., 22)``. Newton-Euler equations in the body frame, in uniform gravity ``g_vec``
(spatial):

    m (dV/dt + W x V) = m R^T g_vec,        I dW/dt + W x (I W) = 0,

and ``dg/dt = g hat(xi)``, whose left-trivialized (spatial) rate is ``Ad_g xi``: the
vector field is ``f(t, y) = (Ad_g xi, V x W + R^T g_vec, (I W x W) / I)``.

Exact invariants: the angular momentum about the centre of mass ``R I W`` and the
rotational energy; the centre of mass follows ``x0 + v0 t + g_vec t^2 / 2``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..groups import SE3, Product, Rn
from ..groups.so3 import cross
from ..integrators import GroupProblem
from .errors import ParameterError
from .rigid_body import check_inertia

SPACE = Product(SE3, Rn(6))


@dataclass(frozen=True)
class FreeBody:
    """A free rigid body in uniform gravity.

    Parameters
    ----------
    mass : float
        Mass [kg], > 0.
    inertia : (3,) array_like
        Principal moments of inertia about the centre of mass [kg m^2], positive and
        satisfying the triangle inequalities.
    gravity : (3,) array_like
        Gravitational acceleration, spatial [m/s^2].
    """

    mass: float = 1.0
    inertia: tuple = (1.0, 2.0, 3.0)
    gravity: tuple = (0.0, 0.0, -9.81)

    def __post_init__(self):
        if not self.mass > 0:
            raise ParameterError("mass", f"expected a positive mass, got {self.mass!r}")
        check_inertia(self.inertia)

    @property
    def _I(self) -> np.ndarray:
        return np.asarray(self.inertia, dtype=float)

    @property
    def _g(self) -> np.ndarray:
        return np.asarray(self.gravity, dtype=float)

    # -- state
    def state(self, R: np.ndarray, x: np.ndarray, V: np.ndarray, W: np.ndarray) -> np.ndarray:
        """Flat state ``(..., 22)`` from the attitude ``R (..., 3, 3)``, centre of mass ``x``
        and the body velocities ``V``, ``W`` ``(..., 3)``."""
        g = np.zeros(np.shape(R)[:-2] + (4, 4))
        g[..., :3, :3], g[..., :3, 3], g[..., 3, 3] = R, x, 1.0
        return SPACE.join(g, np.concatenate([V, W], axis=-1))

    def split(self, y: np.ndarray):
        """``(R, x, V, W)`` of a flat state."""
        g, xi = SPACE.split(y)
        return g[..., :3, :3], g[..., :3, 3], xi[..., :3], xi[..., 3:]

    # -- dynamics
    def vector_field(self, t: float, y: np.ndarray) -> np.ndarray:
        """``(Ad_g xi, dV/dt, dW/dt)``, shape ``(..., 12)``."""
        g, xi = SPACE.split(y)
        R = g[..., :3, :3]
        V, W = xi[..., :3], xi[..., 3:]
        I = self._I
        spatial = np.einsum("...ij,...j->...i", SE3.Ad(g), xi)
        dV = cross(V, W) + np.einsum("...ji,j->...i", R, self._g)
        dW = cross(I * W, W) / I
        return np.concatenate([spatial, dV, dW], axis=-1)

    def problem(self) -> GroupProblem:
        """The RKMK problem on ``SE(3) x R^6``."""
        return GroupProblem(SPACE, self.vector_field)

    # -- diagnostics
    def energy(self, y: np.ndarray) -> float:
        """Kinetic plus gravitational energy [J]."""
        R, x, V, W = self.split(y)
        return float(0.5 * self.mass * V @ V + 0.5 * W @ (self._I * W) - self.mass * self._g @ x)

    def momentum(self, y: np.ndarray) -> np.ndarray:
        """Linear momentum ``m R V`` (spatial), ``(3,)``."""
        R, _, V, _ = self.split(y)
        return self.mass * R @ V

    def angular_momentum(self, y: np.ndarray) -> np.ndarray:
        """Angular momentum about the centre of mass ``R I W`` (spatial), ``(3,)``."""
        R, _, _, W = self.split(y)
        return R @ (self._I * W)

    def orth_error(self, y: np.ndarray) -> float:
        R = self.split(y)[0]
        return float(np.linalg.norm(R.T @ R - np.eye(3)))

    def diagnostics(self) -> dict:
        """``position``, ``energy``, ``momentum``, ``angular_momentum``, ``orth_error``."""
        return {
            "position": lambda t, y: self.split(y)[1].copy(),
            "energy": lambda t, y: self.energy(y),
            "momentum": lambda t, y: self.momentum(y),
            "angular_momentum": lambda t, y: self.angular_momentum(y),
            "orth_error": lambda t, y: self.orth_error(y),
        }
