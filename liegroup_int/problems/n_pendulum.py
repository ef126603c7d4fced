"""The N-fold 3D pendulum on (TS^2)^N, with SE(3)^N acting (Celledoni, Cokaj, Leone, Murari &
Owren, "Lie group integrators for mechanical systems", Int. J. Comput. Math. 2022).

Point masses ``m_i`` on massless links of lengths ``L_i``, ``x_i = sum_{k<=i} L_k q_k`` with
unit directions ``q_k``, a fixed pivot, gravity ``-g e3``. With ``M_jk = sum_{i >= max(j,k)}
m_i`` the kinetic energy is ``T = 1/2 sum_jk C_jk q'_j . q'_k``, ``C_jk = M_jk L_j L_k`` (a
constant mass matrix in the directions), and the potential ``U = g sum_j M_jj L_j q_j . e3``.

Two ways to integrate it, through :func:`~liegroup_int.integrate`:

* RKMK (any tableau) on ``(TS^2)^N``: the constrained Euler-Lagrange equations, crossed with
  ``q_j`` to remove the multipliers, are linear in the angular accelerations,

      sum_k C_jk [(q_j . q_k) I - q_k q_j^T] w'_k = sum_k C_jk |w_k|^2 q_j x q_k - g M_jj L_j q_j x e3,

  (``q_j . w'_j = 0`` closes the system), and the generator on link ``j`` is ``(rho_j,
  theta_j) = (q_j x w'_j, w_j)`` (``TangentSphere``);
* the symplectic splitting methods (``method="strang"``, ``"yoshida4"``, ``"yoshida6"``):
  RATTLE (Hairer, Lubich & Wanner, VII.1) for the constant mass matrix ``C`` and the
  constraints ``|q_j| = 1``, symmetric and second order, composed to order 4 and 6
  (:meth:`NPendulumProblem.split_steps`, compiled in :mod:`.n_pendulum_rattle`). The constraints hold to round-off at every step
  (the position multipliers by Newton's method, the velocity ones by a linear solve), and
  the energy error stays bounded over long runs.
"""

from __future__ import annotations

import numpy as np

from ..integrators.problem import ActionProblem
from ..manifolds import ProductSpace, TangentSphere

#: Gravity [m/s^2].
G = 9.81


class NPendulum:
    """An N-fold 3D pendulum: ``masses`` and ``lengths`` (``(n,)`` positive; default ones),
    gravity ``g``. States are points of ``space = TangentSphere()^n``, flat ``(6 n,)``: per
    link its direction ``q`` and angular velocity ``w`` (``q . w = 0``, ``q' = w x q``)."""

    def __init__(self, n: int, masses=None, lengths=None, g: float = G):
        m = np.ones(n) if masses is None else np.asarray(masses, float)
        L = np.ones(n) if lengths is None else np.asarray(lengths, float)
        if n < 1 or m.shape != (n,) or L.shape != (n,) or np.any(m <= 0) or np.any(L <= 0):
            raise ValueError(f"masses and lengths: expected {n} positive values each, got {m.tolist()} and "
                             f"{L.tolist()}")
        self.n, self.m, self.L, self.g = int(n), m, L, float(g)
        self.M = np.array([[m[max(j, k):].sum() for k in range(n)] for j in range(n)])
        self.C = self.M * np.outer(L, L)
        self.space = ProductSpace.power(TangentSphere(), n)
        e3 = np.array([0.0, 0.0, 1.0])
        self.force = -self.g * (np.diag(self.M) * L)[:, None] * e3  # -grad U, (n, 3)

    def split(self, y) -> tuple[np.ndarray, np.ndarray]:
        """``(q, w)``, each ``(n, 3)``."""
        Y = np.asarray(y, dtype=float).reshape(self.n, 6)
        return Y[:, :3], Y[:, 3:]

    def state(self, q, w) -> np.ndarray:
        """The flat state of directions ``q`` and angular velocities ``w`` ``(n, 3)``,
        projected onto the space (unit ``q``, ``w`` perpendicular to it)."""
        q, w = np.asarray(q, float).reshape(self.n, 3), np.asarray(w, float).reshape(self.n, 3)
        return self.space.project(np.concatenate([q, w], axis=1).ravel())

    def initial_state(self) -> np.ndarray:
        """Links along a helix-like zig-zag with some angular velocity (the examples' start)."""
        ang = np.linspace(0.4, 1.4, self.n)
        q0 = np.stack([np.sin(ang) * np.cos(2 * ang), np.sin(ang) * np.sin(2 * ang), -np.cos(ang)], axis=1)
        w0 = np.stack([np.cross(q0[j], [0.3, -0.2, 0.5]) + 0.1 * j * q0[j] for j in range(self.n)])
        return self.state(q0, w0)

    def angular_accelerations(self, q: np.ndarray, w: np.ndarray) -> np.ndarray:
        """``w'`` ``(n, 3)`` from the crossed Euler-Lagrange equations (module docstring)."""
        n, C = self.n, self.C
        A = np.zeros((3 * n, 3 * n))
        b = np.zeros(3 * n)
        for j in range(n):
            for k in range(n):
                A[3 * j:3 * j + 3, 3 * k:3 * k + 3] = C[j, k] * ((q[j] @ q[k]) * np.eye(3) - np.outer(q[k], q[j]))
                b[3 * j:3 * j + 3] += C[j, k] * (w[k] @ w[k]) * np.cross(q[j], q[k])
            A[3 * j:3 * j + 3, 3 * j:3 * j + 3] += np.outer(q[j], q[j])  # q_j . w'_j = 0
            b[3 * j:3 * j + 3] += np.cross(q[j], self.force[j])
        return np.linalg.solve(A, b).reshape(n, 3)

    def generator(self, t: float, y) -> np.ndarray:
        """The RKMK vector field: ``(q_j x w'_j, w_j)`` per link, flat ``(6 n,)``."""
        q, w = self.split(y)
        return np.concatenate([np.cross(q, self.angular_accelerations(q, w)), w], axis=1).ravel()

    def energy(self, y) -> float:
        """Kinetic plus potential energy [J]."""
        q, w = self.split(y)
        v = np.cross(w, q)
        return float(0.5 * np.einsum("jk,jd,kd->", self.C, v, v) - np.sum(self.force * q))

    def problem(self) -> "NPendulumProblem":
        return NPendulumProblem(self)


class NPendulumProblem(ActionProblem):
    """The pendulum's ODE on ``(TS^2)^n`` (RKMK methods) with its RATTLE splitting
    (:meth:`split_steps`, the symplectic compositions)."""

    def __init__(self, pendulum: NPendulum):
        super().__init__(pendulum.space, pendulum.generator)
        self.pendulum = pendulum
        self._Cinv = np.linalg.inv(pendulum.C)
        self._acc = self._Cinv @ pendulum.force  # C^-1 F: the constant part of the accelerations

    def split_steps(self, y, h: float, gammas: np.ndarray, n: int, t: float = 0.0) -> np.ndarray:
        """``n`` steps of length ``h`` of the symmetric composition ``gammas`` of RATTLE from
        ``y``; a new flat state (autonomous: ``t`` unused)."""
        from .n_pendulum_rattle import rattle_steps

        pd = self.pendulum
        q, w = pd.split(y)
        q, v = np.ascontiguousarray(q), np.ascontiguousarray(np.cross(w, q))
        if not rattle_steps(q, v, self._Cinv, self._acc, np.asarray(gammas, dtype=float), float(h), int(n)):
            return np.full(6 * pd.n, np.nan)  # a step whose constraints did not converge: reported as a blow-up
        return np.concatenate([q, np.cross(q, v)], axis=1).ravel()
