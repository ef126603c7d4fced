"""Nodes: control values and points of the Galerkin state that belong to no member.

A rigid body on a ball or hinge joint turns on its own, so it needs a rotation of its own in
the state. A node gives it one: one more control row (its position is the joint point, its
angular velocity the body's) and one more point (its rotation ``R``), appended after the
members' rows and points. The node's basis is one at its own point and zero elsewhere, so
the action turns its rotation by its own increment and the projection of ``Theta'`` onto
the control values keeps it exact (weight one, no stiffness, no section); the body's mass
and inertia are its mass rows, and a joint of the frame's kinds joins it to the member end.
"""

from __future__ import annotations

import numpy as np

from ...iga.galerkin import GalerkinSpace

__all__ = ["NodedSpace"]


def _pad(A: np.ndarray, k: int) -> np.ndarray:
    """``A`` ``(n, n)`` with ``k`` zero rows and columns appended."""
    out = np.zeros((A.shape[0] + k, A.shape[1] + k))
    out[:A.shape[0], :A.shape[1]] = A
    return out


class NodedSpace:
    """A :class:`~liegroup_int.iga.galerkin.GalerkinSpace` with nodes appended, one per
    ``(row, point)`` of the member ends they join, with the same attributes (``n`` and ``m``
    count the nodes; ``n_beam`` and ``m_beam`` do not).

    Parameters
    ----------
    gs : GalerkinSpace
    places : sequence of (int, int)
        The control row and point of the member end each node sits at (its reference
        position and frame).
    """

    def __init__(self, gs: GalerkinSpace, places):
        rows = np.array([r for r, _ in places], dtype=int)
        pts = np.array([p for _, p in places], dtype=int)
        k, n, m = len(places), gs.n, gs.m
        self.base, self.space, self.rule, self.rules_used = gs, gs.space, gs.rule, gs.rules_used
        self.n_beam, self.m_beam, self.n, self.m = n, m, n + k, m + k
        #: the member rows and points the nodes sit at, and the nodes' own
        self.attached_rows, self.attached_points = rows, pts
        self.node_rows, self.node_points = np.arange(n, n + k), np.arange(m, m + k)
        self.B0 = np.zeros((m + k, n + k))
        self.B0[:m, :n] = gs.B0
        self.B0[self.node_points, self.node_rows] = 1.0
        self.B1 = np.zeros((m + k, n + k))
        self.B1[:m, :n] = gs.B1
        self.w_full = np.concatenate([gs.w_full, np.ones(k)])  # the projection of Theta' only
        self.w_axial = np.concatenate([gs.w_axial, np.zeros(k)])
        self.R0 = np.concatenate([gs.R0, gs.R0[pts]])
        self.K0 = np.concatenate([gs.K0, np.zeros((k, 3))])
        self.gamma0 = np.concatenate([gs.gamma0, np.zeros((k, 3))])
        self.u, self.s = np.concatenate([gs.u, gs.u[pts]]), np.concatenate([gs.s, gs.s[pts]])
        self.point_patch = np.concatenate([gs.point_patch, gs.point_patch[pts]])
        self.patch_ends = gs.patch_ends
        self.mass = _pad(gs.mass, k)
        self.point_mass = _pad(gs.point_mass, k)
        self.point_mass[self.node_rows, self.node_rows] = 1.0

    def weighted_mass(self, density: np.ndarray) -> np.ndarray:
        """As :meth:`GalerkinSpace.weighted_mass` over the members' points; zero on the nodes."""
        return _pad(self.base.weighted_mass(np.asarray(density)[:self.m_beam]), self.n - self.n_beam)

    project = GalerkinSpace.project
