"""Geometrically exact beam in weak (isogeometric Galerkin) form, as an RKMK plugin.

Same basis, loads and end conditions as the collocation formulations
(:class:`~.problem.BeamProblem`); docs/theory.md section 15 derives the equations.

State (:class:`GalerkinBeamState`) at time ``t_n``:

* ``c, v``: control values of centroid position and velocity, ``(n, 3)``;
* ``w``: control values of the *material* angular velocity ``Omega = R^T omega``, ``(n, 3)``
  (its mass matrix ``J M`` is then constant);
* ``R, K``: rotations and material curvature at the points of the
  :class:`~liegroup_int.iga.GalerkinSpace` (Gauss points and ends), ``(m, 3, 3)``, ``(m, 3)``.

Increment (``(4, n, 3)``): control values of ``(eta, Theta, dv, dW)``. The action adds
``eta, dv, dW`` to ``c, v, w``, turns the point rotations by the interpolated *right*
increment, ``R <- R exp(hat(Theta))``, and updates ``K <- exp(-Theta) K + J_r(Theta) Theta_s``.
The stage rate solves, with the consistent mass matrix ``M`` factored once,

    eta' = v,   M Theta' = P[dexpinv_{-Theta} Omega],
    mu M v' = -int N' n + int N q + F,
    J M W' = -int (N' M + N (M x K)) + int N (Gamma~ x N) - int N (Omega x J Omega)
             + int N R^T m_d + R^T C

(``N`` the basis, ``Gamma~ = R^T c_s``; end loads ``F, C`` on the end control values;
Dirichlet values imposed strongly on the end control values). The stiffness terms are the
gradient of the strain energy at the same quadrature, so the semi-discrete energy
``1/2 mu v.Mv + 1/2 W.(J M)W + U`` is conserved for conservative loads.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from ...groups.so3 import angle, cross, dexpinv_so3, exp_so3, hat, left_jacobian
from ...iga import CollocationSpace
from ...iga.galerkin import BandedSPD, GalerkinSpace
from ...iga.quadrature import DEFAULT_RULE
from .base import SECTION_FIELDS, BeamBase
from .kinematics import jr_times, perpendicular_rows, rot, rot_T
from .model import BoundaryConditions, InitialConditions, Loads, SectionConstants
from .nodes import NodedSpace

#: Quadrature of the axial and shear terms (``GalerkinBeamProblem(integration=...)``).
INTEGRATIONS = ("reduced", "full")


@dataclass
class GalerkinBeamState:
    """Galerkin beam state (see the module docstring); ``w`` is the material angular
    velocity's control values."""

    c: np.ndarray
    v: np.ndarray
    w: np.ndarray
    R: np.ndarray
    K: np.ndarray

    def copy(self) -> "GalerkinBeamState":
        return GalerkinBeamState(self.c.copy(), self.v.copy(), self.w.copy(), self.R.copy(), self.K.copy())

    def arrays(self) -> dict[str, np.ndarray]:
        return {"c": self.c, "v": self.v, "w": self.w, "R": self.R, "K": self.K}


class _SplitData(NamedTuple):
    """What :meth:`GalerkinBeamProblem.split_steps` passes its compiled loop: the engine's
    data (a private copy of the flat kernel data, which the loop writes the stage loads
    into, the load table and the compiled entries), and work arrays."""

    data: tuple
    entry: object  # call_split_steps compiled for these data's types (numba's entry point)
    work: tuple
    tmp: np.ndarray


class _GJoint(NamedTuple):
    """One joint pair: control rows ``a, b`` of the two patch ends, the point at ``a``,
    ``Q = R0_a^T R0_b``, the point load (or None, acting on row ``a``), the point at ``b``,
    rigid (else a ball joint or a hinge), ``D`` ``(3, 3)``: the rows of the constant
    constrained directions of the rotational residual ``x[b] - Q^T x[a]`` (material
    components at ``b``): the identity (rigid) or zero (ball; hinge, whose constraints
    depend on the state: :class:`_GHinge`), and the kind."""

    a: int
    b: int
    point: int
    Q: np.ndarray
    load: object
    point_b: int
    rigid: bool
    D: np.ndarray
    kind: str = "rigid"


class _GHinge(NamedTuple):
    """One hinge pair: the index of its :class:`_GJoint`, its control rows and points,
    ``E`` ``(2, 3)``: two orthonormal rows perpendicular to the material axis at ``b``
    (``R0_b^T axis``), and per rotational field (``"theta"``, ``"rotation"``) the responses
    ``Z`` ``(2, 3, n, 3)`` of the mass matrix constrained by the constant joints,
    ``M_c^-1 (e_row e_c^T)``, for the rows ``a`` then ``b`` and the components ``c``.

    Its constraints keep the deformed axes of both ends equal, ``R_a R0_a^T axis = R_b
    R0_b^T axis``: on the material angular velocities ``E (W_b - G^T W_a) = 0`` and on the
    rotation rates ``E (A_b Theta'_b - G^T A_a Theta'_a) = 0`` with ``G = R_a^T R_b`` and
    ``A = dexp_{-Theta}`` at the ends (:meth:`GalerkinBeamProblem._hinge_rows`). ``axis``:
    the unit material axis at ``b`` ``(3,)`` (``E[0], E[1], axis`` right-handed), ``Q`` as
    the joint's, ``stiffness`` and ``damping`` of its rotational spring-damper."""

    joint: int
    a: int
    b: int
    point: int
    point_b: int
    E: np.ndarray
    Z: dict
    axis: np.ndarray
    Q: np.ndarray
    stiffness: float
    damping: float


class _GBody(NamedTuple):
    """One end body: its control row and point, the :class:`~.model.EndBody`, its offset
    ``c`` ``(3,)`` and inertia about the end point ``J`` ``(3, 3)`` (section frame), its
    weight ``m g`` ``(3,)``."""

    row: int
    point: int
    body: object
    c: np.ndarray
    J: np.ndarray
    weight: np.ndarray


class _GCoupling(NamedTuple):
    """The mass coupling of the bodies off their end points (:meth:`GalerkinBeamProblem.
    _couple_bodies`): their indices in ``bodies``, the responses ``P`` ``(6 k, n, 3)`` of the
    constrained mass matrices to unit forces (three components, field 2) and couples (three,
    field 3) on each body's row, and ``G`` ``(6 k, 6 k)``, those responses read back on the
    bodies' rows."""

    index: tuple
    P: np.ndarray
    G: np.ndarray


@dataclass(frozen=True)
class _GEnd:
    """One end: its control index, point index, outward normal, supports, loads."""

    index: int
    point: int
    normal: float
    fix_position: bool
    fix_rotation: bool
    load: object
    motion: object = None
    translation: object = None

    @property
    def name(self) -> str:
        return "start" if self.normal < 0 else "end"


class GalerkinBeamProblem(BeamBase):
    """Explicit RKMK isogeometric Galerkin beam (``space.formulation = "galerkin"``).

    Parameters
    ----------
    space : CollocationSpace or PatchedSpace
        Basis and reference geometry; a :class:`~liegroup_int.iga.patches.PatchedSpace`
        is a frame of members joined rigidly (docs/theory.md section 15c).
    constants : SectionConstants or tuple of SectionConstants
        One section, or one per patch.
    bcs, loads, initial
        As :class:`~.problem.BeamProblem` (``loads.joints``: dead point loads at the joints).
    backend : {"numpy", "numba"}
    kelvin_voigt : float
        Retardation time [s] of the strain-rate damping, as :class:`~.problem.BeamProblem`.
    integration : {"reduced", "full"}
        Gauss points per knot interval for the axial and shear terms: ``p`` (reduced,
        the default: locking-free at low degree) or ``p + 1`` (the rule ``"gauss-full"``).
    quadrature : str
        Quadrature rule of the stiffness (:data:`liegroup_int.iga.quadrature.RULES`) with
        ``integration = "reduced"``; ``"auto"`` (the default): the reduced Gaussian spline
        rule ``"gauss-spline-reduced"`` for p = 3..6, else ``"gauss-spline"`` for p = 3..7,
        where found and determining the basis, else ``"gauss-p"``.
    bodies : tuple of EndBody
        Rigid bodies fixed to the ends (at most one per end): their mass and inertia about
        the end point join the end rows of the consistent mass matrices (the B-spline basis
        interpolates at the ends, so the end values are the end's velocity and material
        angular velocity), their weight and loads the load vector, their gyroscopic couple
        the rate. A body whose centre is off the end point couples the end's translation
        and rotation through the mass ``-m R hat(c)`` (:meth:`_couple_bodies`), its weight
        and force act with the arm ``R c``, and its centripetal force joins the rate.
    """

    formulation = "galerkin"
    state_cls = GalerkinBeamState

    def __init__(self, space: CollocationSpace, constants: SectionConstants,
                 bcs: BoundaryConditions = BoundaryConditions(), loads: Loads = Loads(),
                 initial: InitialConditions = InitialConditions(), backend: str = "numpy",
                 kelvin_voigt: float = 0.0, integration: str = "reduced", quadrature: str = DEFAULT_RULE,
                 bodies: tuple = ()):
        if integration not in INTEGRATIONS:
            raise ValueError(f"integration: expected one of {', '.join(INTEGRATIONS)}, got {integration!r}")
        self._setup(space, constants, bcs, loads, initial, backend, kelvin_voigt)
        self.integration = integration
        self.quadrature = quadrature
        self.gs = GalerkinSpace(space, rule="gauss-full" if integration == "full" else quadrature)
        #: the members' control rows and points (the nodes of bodies on joints come after them)
        self.n_beam, self.m_beam = self.gs.n, self.gs.m
        self._add_nodes(bodies)
        self.n, self.m = self.gs.n, self.gs.m
        self._section_fields(space, constants)
        g = np.asarray(loads.gravity, float)
        self._distributed_loads(loads, g)
        self.bodies = self._bodies(bodies, g)
        self._supports(bcs, loads)
        self.joints = self._joints(space, loads)
        #: ``(row, point, EndLoad, arm)`` of every loaded end, joint and body (``arm`` ``(3,)``:
        #: the point of application from the row's point, section frame; a body's offset)
        zero = np.zeros(3)
        self.point_loads = tuple((e.index, e.point, e.load, zero) for e in self.ends if e.load.active) + tuple(
            (j.a, j.point, j.load, zero) for j in self.joints if j.load is not None) + tuple(
            (b.row, b.point, b.body.load, b.c) for b in self.bodies if b.body.load.active)
        self._masses()
        self._constraints = self._joint_constraints()
        self.hinges = self._hinges(space)
        self._coupling = self._body_coupling()
        self.quad = self.gs.w_full
        self.has_quadrature = bool(self.tau > 0.0 or self.has_q or self.has_m or self.moving_ends
                                   or self.translating_ends or self.point_loads
                                   or any(h.damping > 0.0 for h in self.hinges))

    def _add_nodes(self, bodies) -> None:
        """A node (:mod:`.nodes`) per body on a ball or hinge joint, at its member end."""
        places = [self._body_place(b) for b in bodies if b.joint != "rigid"]
        if places:
            self.gs = NodedSpace(self.gs, places)

    @property
    def node_points(self) -> np.ndarray:
        """The points of the nodes (none without bodies on joints)."""
        return np.arange(self.m_beam, self.m)

    def _section_fields(self, space, constants) -> None:
        """The section stiffnesses and inertias at the points (zero at the nodes), and the
        point bases."""
        gs, pp = self.gs, self.gs.point_patch
        sections = self._sections(space, constants)
        self.CN = np.array([sec.CN for sec in sections], dtype=float)[pp]
        self.CM = np.array([sec.CM for sec in sections], dtype=float)[pp]
        self.Jm = np.array([sec.Jm for sec in sections], dtype=float)[pp]
        self.mu = np.array([sec.mu for sec in sections], dtype=float)[pp]
        for a in (self.CN, self.CM, self.Jm, self.mu):
            a[self.node_points] = 0.0
        self.B0, self.B1 = gs.B0, gs.B1
        self.wf, self.wa = gs.w_full, gs.w_axial

    def _distributed_loads(self, loads: Loads, g: np.ndarray) -> None:
        """The distributed force (gravity included) and couple, and the momentum weights."""
        gs = self.gs
        self.has_q = bool(np.any(loads.distributed_force) or np.any(g))
        q_pt = np.asarray(loads.distributed_force, float) + self.mu[:, None] * g
        q_pt[self.node_points] = 0.0
        #: ``int N_i q ds`` (gravity included), ``(n, 3)``, times the distributed profile
        self.load_vector = gs.B0.T @ (gs.w_full[:, None] * q_pt)
        self.m_dist = np.asarray(loads.distributed_couple, float)
        self.has_m = bool(np.any(self.m_dist))
        if self.has_m and self.m > self.m_beam:
            raise ValueError("loads.distributed_couple: not supported with a body on a ball or hinge joint")
        #: ``int mu N_i ds``, ``(n,)``: the linear momentum is ``mass_weights @ v``
        self.mass_weights = gs.weighted_mass(self.mu).sum(axis=0)

    def _supports(self, bcs: BoundaryConditions, loads: Loads) -> None:
        """The two ends, the rollers, and the rows with fixed positions and rotations."""
        n = self.n
        self.ends = (self._end(0, 0, -1.0, bcs.start, loads.start, bcs.start_motion, bcs.start_translation),
                     self._end(self.n_beam - 1, self.m_beam - 1, 1.0, bcs.end, loads.end, bcs.end_motion,
                               bcs.end_translation))
        self.moving_ends = tuple(e for e in self.ends if e.motion is not None)
        self.translating_ends = tuple(e for e in self.ends if e.translation is not None)
        #: ``(row, axis)`` of each roller end: its free position component (static analyses)
        self.rollers = tuple(self._roller(e, kind, self.gs) for e, kind in zip(self.ends, (bcs.start, bcs.end))
                             if kind == "roller")
        #: ``(row, component)`` of each pinned end: the material rotation component it turns by
        self.pins = tuple(self._pin(e, bcs.pin_axis, self.gs) for e, kind in zip(self.ends, (bcs.start, bcs.end))
                          if kind == "pinned")
        fixp, fixr = np.zeros(n, bool), np.zeros(n, bool)
        for e in self.ends:
            fixp[e.index] |= e.fix_position
            fixr[e.index] |= e.fix_rotation
        self.fix_position, self.fix_rotation = fixp, fixr

    def _masses(self) -> None:
        """The consistent mass matrices (the end bodies' mass and inertia on their rows),
        factored with the supports' rows fixed."""
        gs = self.gs
        self._M_mu = gs.weighted_mass(self.mu)
        self._M_J = tuple(gs.weighted_mass(self.Jm[:, d]) for d in range(3))
        for b in self.bodies:
            self._M_mu[b.row, b.row] += b.body.mass
            for d in range(3):
                self._M_J[d][b.row, b.row] += b.J[d, d]
        self.mass_position = BandedSPD(self._M_mu, self.fix_position)
        self.mass_theta = BandedSPD(gs.point_mass, self.fix_rotation)
        self.mass_rotation = tuple(BandedSPD(M, self.fix_rotation) for M in self._M_J)

    def _bodies(self, bodies, g: np.ndarray) -> tuple:
        """:class:`_GBody` of each end body; their mass joins the momentum weights and their
        weight the load vector (its moment about the end point: :meth:`_body_terms`)."""
        out, seen = [], {}
        nodes = zip(range(self.n_beam, self.n), range(self.m_beam, self.m))
        for b in bodies:
            row, point = self._body_place(b)
            if row in seen:
                where = f"bodies: two bodies at the {b.at}" + (f" of patch {b.patch}" if b.patch >= 0 else "")
                raise ValueError(where + ("; combine them into one" if seen[row] == b.joint == "rigid" else
                                          "; one body per end when one is on a ball or hinge joint"))
            seen[row] = b.joint
            if b.joint != "rigid":  # on its node, in the order of _add_nodes
                row, point = next(nodes)
            self.mass_weights[row] += b.mass
            self.load_vector[row] += b.mass * g
            self.has_q = self.has_q or bool(b.mass and np.any(g))
            out.append(_GBody(row, point, b, np.asarray(b.offset, float), b.end_inertia, b.mass * g))
        return tuple(out)

    @property
    def end_bodies(self) -> tuple:
        """The :class:`~.model.EndBody` objects the problem was built with."""
        return tuple(b.body for b in self.bodies)

    def _body_coupling(self) -> _GCoupling | None:
        """:class:`_GCoupling` of the bodies off their end points (None if there is none)."""
        index = tuple(k for k, b in enumerate(self.bodies) if b.body.mass > 0.0 and np.any(b.c))
        if not index:
            return None
        P = np.zeros((6 * len(index), self.n, 3))
        for k, i in enumerate(index):
            for e in range(3):
                r = np.zeros((self.n, 3))
                r[self.bodies[i].row, e] = 1.0
                P[6 * k + e] = self._constrain(self.mass_position.solve(r), "position")
                P[6 * k + 3 + e] = self._constrain(self._solve_rotation(r, 0.0), "rotation")
        return _GCoupling(index, P, self._read_back(P, [self.bodies[i].row for i in index]))

    @staticmethod
    def _read_back(P: np.ndarray, rows) -> np.ndarray:
        """``G = U^T P``: the responses ``P`` read on the bodies' ``rows``, ``(6 k, 6 k)``."""
        G = np.zeros((P.shape[0],) * 2)
        for l in range(P.shape[0]):
            for k, r in enumerate(rows):
                G[6 * k:6 * k + 3, l] = P[l, r] if l % 6 < 3 else 0.0
                G[6 * k + 3:6 * k + 6, l] = P[l, r] if l % 6 >= 3 else 0.0
        return G

    def _responses(self, y) -> tuple:
        """``(P, G)`` of the coupling at ``y``: with hinges, the couples' responses projected
        on the hinges' constraints ``x - Y S^-1 C x`` (their rows follow the state, so the
        responses of the hinge-constrained solve do too); the forces' are those of the
        position field, which the hinges do not constrain."""
        cp = self._coupling
        if not self.hinges:
            return cp.P, cp.G
        P = np.array(cp.P)
        for l in range(3, P.shape[0]):
            if l % 6 >= 3:
                P[l] = self._constrain_hinges(P[l], y, None, "rotation", affine=False)
        return P, self._read_back(P, [self.bodies[i].row for i in cp.index])

    def _body_mass(self, y) -> np.ndarray:
        """The coupled bodies' mass blocks not in the banded matrices, ``(6 k, 6 k)``: per body
        ``[[0, -m R hat(c)], [m hat(c) R^T, J - diag(J)]]`` (``R`` the end's rotation; rows and
        columns: the end's acceleration, then its material angular acceleration)."""
        cp = self._coupling
        C = np.zeros((6 * len(cp.index),) * 2)
        for k, i in enumerate(cp.index):
            b = self.bodies[i]
            B = -b.body.mass * y.R[b.point] @ hat(b.c)
            C[6 * k:6 * k + 3, 6 * k + 3:6 * k + 6] = B
            C[6 * k + 3:6 * k + 6, 6 * k:6 * k + 3] = B.T
            C[6 * k + 3:6 * k + 6, 6 * k + 3:6 * k + 6] = b.J - np.diag(np.diag(b.J))
        return C

    def _couple_bodies(self, y, xp: np.ndarray, xr: np.ndarray) -> tuple:
        """The accelerations ``xp`` and material angular accelerations ``xr`` of the banded
        (and joint-constrained) solves corrected for the coupled bodies' mass blocks ``C``
        (:meth:`_body_mass`): ``x = x0 - P z`` with ``(I + C G) z = C U^T x0`` (Woodbury's
        identity on the constrained solve, ``U`` the bodies' rows), and ``z = C U^T x``, the
        coupling forces and couples on those rows, ``(6 k,)``."""
        cp = self._coupling
        if cp is None:
            return xp, xr, np.zeros(0)
        C = self._body_mass(y)
        P, G = self._responses(y)
        z = np.linalg.solve(np.eye(C.shape[0]) + C @ G, C @ self._body_rows(xp, xr))
        pos = (np.arange(z.size) % 6) < 3
        return (xp - np.tensordot(z[pos], P[pos], axes=1), xr - np.tensordot(z[~pos], P[~pos], axes=1), z)

    def _forces_on_rows(self, t: float, y, k: np.ndarray | None = None) -> tuple:
        """:meth:`_forces` less the coupled bodies' coupling forces ``U C U^T x`` at the rates
        ``k`` (computed if None): what the banded mass matrices balance row by row."""
        F, T = self._forces(t, y, self.B0 @ y.w)
        if self._coupling is None:
            return F, T
        if k is None:
            k = self.increment_rate(t, y, np.zeros((4, self.n, 3)))
        Fz, Tz = self._coupling_loads(self._body_mass(y) @ self._body_rows(k[2], k[3]))
        return F - Fz, T - Tz

    def _body_rows(self, xp: np.ndarray, xr: np.ndarray) -> np.ndarray:
        """``U^T x``: the coupled bodies' rows of the two fields, ``(6 k,)``."""
        return np.concatenate([np.concatenate([xp[self.bodies[i].row], xr[self.bodies[i].row]])
                               for i in self._coupling.index])

    def _coupling_loads(self, z: np.ndarray) -> tuple:
        """``U z`` of :meth:`_couple_bodies` as forces and couples on the control rows,
        ``(n, 3)`` each."""
        Fz, Tz = np.zeros((self.n, 3)), np.zeros((self.n, 3))
        for k, i in enumerate(self._coupling.index if self._coupling else ()):
            Fz[self.bodies[i].row] += z[6 * k:6 * k + 3]
            Tz[self.bodies[i].row] += z[6 * k + 3:6 * k + 6]
        return Fz, Tz

    def _body_terms(self, y, F: np.ndarray, T: np.ndarray, f: float) -> None:
        """The bodies' inertial terms and the moment of their weight into ``F, T``: the
        gyroscopic couple ``-W x J W``; off the end point the centripetal force ``-m R (W x
        (W x c))`` and the weight's moment ``c x R^T (f m g)`` (``f`` its profile)."""
        for b in self.bodies:
            W = y.w[b.row]
            T[b.row] -= np.cross(W, b.J @ W)
            if np.any(b.c):
                Rr = y.R[b.point]
                F[b.row] -= b.body.mass * (Rr @ np.cross(W, np.cross(W, b.c)))
                T[b.row] += f * np.cross(b.c, Rr.T @ b.weight)

    def _body_place(self, b) -> tuple[int, int]:
        """Control row and point of a body's end."""
        if b.patch < 0:
            return (0, 0) if b.at == "start" else (self.n_beam - 1, self.m_beam - 1)
        if not hasattr(self.space, "end_row") or b.patch >= len(self.gs.patch_ends):
            raise ValueError(f"bodies: patch {b.patch}: the space has {len(self.gs.patch_ends)} patch(es)")
        ends = self.gs.patch_ends[b.patch]
        return self.space.end_row(b.patch, b.at), ends[0] if b.at == "start" else ends[1]

    @staticmethod
    def _sections(space, constants) -> tuple:
        """One :class:`SectionConstants` per patch."""
        patches = getattr(space, "patches", (space,))
        if isinstance(constants, SectionConstants):
            return (constants,) * len(patches)
        sections = tuple(constants)
        if len(sections) != len(patches) or not all(isinstance(c, SectionConstants) for c in sections):
            raise ValueError(f"constants: one SectionConstants, or one per patch ({len(patches)} patch(es), "
                             f"got {len(sections)})")
        return sections

    def _joints(self, space, loads) -> tuple:
        """:class:`_GJoint` of each joint pair: the control rows of the two patch ends, the
        points there, the relative reference rotation ``Q = R0_a^T R0_b``, the point load
        (or None), whether it is rigid and its constrained rotational directions ``D``."""
        kinds = getattr(space, "joint_kinds", ())
        points = self._end_points(space)
        out = []
        for k, (a, b), ld in self.joint_loads(space, loads):
            pa, pb = points[a], points[b]
            kind = kinds[k] if kinds else "rigid"
            D = np.eye(3) if kind == "rigid" else np.zeros((3, 3))
            out.append(_GJoint(a, b, pa, self.gs.R0[pa].T @ self.gs.R0[pb], ld, pb, kind == "rigid", D, kind))
        for b in self._jointed_bodies():  # a body's node joined to its member end (same reference frame)
            a, pa = self._body_place(b.body)
            out.append(_GJoint(a, b.row, pa, np.eye(3), None, b.point, False, np.zeros((3, 3)), b.body.joint))
        return tuple(out)

    def _jointed_bodies(self) -> tuple:
        """The :class:`_GBody` of the bodies on ball or hinge joints (on their nodes), in
        the order of their joints after the frame's."""
        return tuple(b for b in self.bodies if b.body.joint != "rigid")

    def _joint_constraints(self) -> dict:
        """``(Y, S^-1 D)`` of the constant joint constraints per field (:meth:`_constraint`)."""
        if not self.joints:
            return {}
        return {"position": self._constraint(lambda r: self.mass_position.solve(r), rotational=False),
                "theta": self._constraint(lambda r: self.mass_theta.solve(r), rotational=True),
                "rotation": self._constraint(lambda r: self._solve_rotation(r, 0.0), rotational=True)}

    def _hinges(self, space) -> tuple:
        """:class:`_GHinge` of each hinge pair (after the constant constraints)."""
        axes, springs = getattr(space, "joint_axes", ()), getattr(space, "joint_springs", ())
        jb = self._jointed_bodies()
        if jb:  # the frame's pairs, then the bodies'
            frame = len(self.joints) - len(jb)
            axes = tuple(axes[:frame]) + tuple(np.asarray(b.body.axis, float) for b in jb)
            springs = tuple(springs[:frame]) + tuple((b.body.stiffness, b.body.damping) for b in jb)
        out = []
        for k, j in enumerate(self.joints):
            if j.kind != "hinge":
                continue
            axis = self.gs.R0[j.point_b].T @ axes[k]
            E = perpendicular_rows(axis)
            Z = {}
            for field, solve in (("theta", self.mass_theta.solve), ("rotation", lambda r: self._solve_rotation(r, 0.0))):
                Z[field] = np.zeros((2, 3, self.n, 3))
                for e, row in enumerate((j.a, j.b)):
                    for c in range(3):
                        r = np.zeros((self.n, 3))
                        r[row, c] = 1.0
                        Z[field][e, c] = self._constrain(solve(r), field)
            out.append(_GHinge(k, j.a, j.b, j.point, j.point_b, E, Z, axis / np.linalg.norm(axis), j.Q, *springs[k]))
        return tuple(out)

    def _hinge_springs(self, y) -> list:
        """``(phi, dphi/dt, k phi + c dphi/dt)`` of each hinge: the relative rotation angle
        about the axis, ``H = Q^T R_a^T R_b = exp(phi hat(axis))`` read as ``phi =
        atan2(E_1 . H E_0, E_0 . H E_0)`` in ``(-pi, pi]``, its rate ``axis . (W_b - G^T W_a)``
        and the spring-damper couple. Its generalized forces are ``-m axis`` on row ``b`` and
        ``m G axis`` on row ``a`` (material), the gradient of ``1/2 k phi^2`` for the elastic
        part: ``dphi = axis . (dTheta_b - G^T dTheta_a)``."""
        out = []
        for h in self.hinges:
            G = y.R[h.point].T @ y.R[h.point_b]
            He = h.Q.T @ G @ h.E[0]
            phi = float(np.arctan2(h.E[1] @ He, h.E[0] @ He))
            rate = float(h.axis @ (y.w[h.b] - G.T @ y.w[h.a]))
            out.append((phi, rate, h.stiffness * phi + h.damping * rate))
        return out

    def _hinge_rows(self, y, u: np.ndarray, field: str) -> tuple:
        """Per hinge the constraint rows on row ``a`` and row ``b`` and the right-hand side,
        ``(Ca, Cb, g)`` with ``(2, 3), (2, 3), (2,)``: ``W`` (``"rotation"``): ``Cb = E``,
        ``Ca = -E G^T``, ``g = -E (W_b x G^T W_a)`` (the time derivative of ``G^T``
        acting on ``W_a``); ``Theta'`` (``"theta"``): ``Cb = E A_b``, ``Ca = -E G^T A_a``,
        ``g = 0``."""
        out = []
        for h in self.hinges:
            G = y.R[h.point].T @ y.R[h.point_b]
            if field == "rotation":
                g = -h.E @ np.cross(y.w[h.b], G.T @ y.w[h.a])
                out.append((-h.E @ G.T, h.E, g))
            else:
                Aa, Ab = left_jacobian(-u[1][h.a]), left_jacobian(-u[1][h.b])
                out.append((-h.E @ G.T @ Aa, h.E @ Ab, np.zeros(2)))
        return tuple(out)

    def _hinge_multipliers(self, x: np.ndarray, y, u: np.ndarray, field: str, affine: bool = True):
        """``(lambda, Y)``: the hinges' multipliers ``(H, 2)`` for the solution ``x`` of one
        rotational field (constant joints applied) and their columns ``Y`` ``(2 H, n, 3)``;
        without ``affine``, of the constraints' linear part ``C x = 0``."""
        rows = self._hinge_rows(y, u, field)
        Ys = [np.tensordot(Ca[k], h.Z[field][0], 1) + np.tensordot(Cb[k], h.Z[field][1], 1)
              for h, (Ca, Cb, _) in zip(self.hinges, rows) for k in range(2)]

        def C(v):
            return np.concatenate([Ca @ v[h.a] + Cb @ v[h.b] for h, (Ca, Cb, _) in zip(self.hinges, rows)])

        S = np.array([C(Yl) for Yl in Ys]).T
        g = np.concatenate([r[2] for r in rows]) if affine else 0.0
        return np.linalg.solve(S, C(x) - g).reshape(-1, 2), np.array(Ys)

    def _constrain_hinges(self, x: np.ndarray, y, u: np.ndarray, field: str, affine: bool = True) -> np.ndarray:
        """``x - Y S^-1 (C x - g)``: the hinges' constraints on one rotational field (``g = 0``
        without ``affine``)."""
        if not self.hinges:
            return x
        lam, Y = self._hinge_multipliers(x, y, u, field, affine)
        return x - np.tensordot(lam.ravel(), Y, axes=1)

    def _end_points(self, space) -> dict:
        """``{control row: point}`` of every patch end (the basis interpolates there)."""
        offsets = getattr(space, "offsets", (0, self.n))
        out = {}
        for k, (first, last) in enumerate(self.gs.patch_ends):
            out[offsets[k]], out[offsets[k + 1] - 1] = first, last
        return out

    def _joint_residual(self, x: np.ndarray, rotational: bool) -> np.ndarray:
        """``x[b] - Q^T x[a]`` (``x[b] - x[a]`` for positions) per joint pair, ``(3 J,)``:
        ``C x`` for the rigid pairs; the constraints are its components along the rows of
        each pair's ``D`` (positions: all three)."""
        return np.concatenate([x[j.b] - (j.Q.T @ x[j.a] if rotational else x[j.a]) for j in self.joints])

    def _directions(self, rotational: bool) -> np.ndarray:
        """Block diagonal ``(3 J, 3 J)`` of the pairs' constrained directions ``D`` (the
        identity for positions)."""
        D = np.zeros((3 * len(self.joints),) * 2)
        for j, jt in enumerate(self.joints):
            D[3 * j:3 * j + 3, 3 * j:3 * j + 3] = jt.D if rotational else np.eye(3)
        return D

    def _constraint(self, solve, rotational: bool):
        """``(Y, S^-1)`` of the joint constraints ``C x = 0`` for one field, ``C x = D r``
        with ``r`` the residual :meth:`_joint_residual`: the columns ``Y = M^-1 C^T``
        ``(3 J, n, 3)`` and ``S^-1 D`` ``(3 J, 3 J)`` with ``S = C M^-1 C^T`` on the
        constrained directions (so ``S^-1 D r`` are the multipliers). The zero rows of ``D``
        (ball joints, and hinges: :meth:`_constrain_hinges`) are zero in ``Y`` and
        ``S^-1 D``: their multipliers are exactly 0."""
        k = 3 * len(self.joints)
        D = self._directions(rotational)
        Y = np.zeros((k, self.n, 3))
        for j, jt in enumerate(self.joints):
            for e in range(3):
                d = D[3 * j + e, 3 * j:3 * j + 3]
                if not np.any(d):
                    continue
                r = np.zeros((self.n, 3))
                r[jt.b] = d
                r[jt.a] -= jt.Q @ d if rotational else d
                Y[3 * j + e] = solve(r)
        live = np.any(D != 0.0, axis=1)
        Sinv = np.zeros((k, k))
        if np.any(live):
            S = (D @ np.array([self._joint_residual(y, rotational) for y in Y[live]]).T)[live]
            Sinv[live] = np.linalg.solve(S, D[live])
        return Y, Sinv

    def _multipliers(self, x: np.ndarray, field: str) -> np.ndarray:
        """The joints' multipliers ``S^-1 C x`` of the unconstrained solution ``x`` of one
        field, ``(J, 3)``, along the rows of each pair's ``D`` (zero for the free
        directions)."""
        Y, Sinv = self._constraints[field]
        return (Sinv @ self._joint_residual(x, field != "position")).reshape(-1, 3)

    def _constrain(self, x: np.ndarray, field: str) -> np.ndarray:
        """The solution ``x`` of ``M x = f`` corrected by the joints' multipliers:
        ``x - Y S^-1 C x`` (the constraint forces do no work)."""
        if not self.joints:
            return x
        lam = self._multipliers(x, field).ravel()
        return x - np.tensordot(lam, self._constraints[field][0], axes=1)

    def _solve_rotation(self, T: np.ndarray, fixed) -> np.ndarray:
        """``W'`` from ``(J M) W' = T`` component by component, ``(n, 3)``."""
        fixed = np.broadcast_to(np.asarray(fixed, float), (int(np.sum(self.fix_rotation)), 3))
        return np.stack([self.mass_rotation[d].solve(T[:, d], fixed[:, d]) for d in range(3)], axis=1)

    # ------------------------------------------------------------------ set-up
    @staticmethod
    def _end(index, point, normal, kind, load, motion, translation):
        BeamBase.check_end_load(kind, load, normal)  # a roller's are checked with its axis (_roller)
        return _GEnd(index=index, point=point, normal=normal, fix_position=kind in ("clamped", "hinged", "pinned"),
                     fix_rotation=kind == "clamped", load=load, motion=motion, translation=translation)

    @staticmethod
    def _roller(e, kind, gs) -> tuple[int, int]:
        """``(row, axis)`` of a roller end: the coordinate axis its reference tangent lies along."""
        where = "start" if e.normal < 0 else "end"
        tangent = gs.R0[e.point][:, 2]
        axis = int(np.argmax(np.abs(tangent)))
        if abs(abs(tangent[axis]) - 1.0) > 1e-9:
            raise ValueError(f"bc.{where} = 'roller': the end's tangent {np.round(tangent, 6).tolist()} must lie "
                             "along a coordinate axis (the roller slides along it)")
        if np.any(np.delete(e.load.force, axis)):
            raise ValueError(f"loads.{where}.force: a roller takes the force across its axis; give only the "
                             f"component along axis {'xyz'[axis]}")
        return e.index, axis

    @staticmethod
    def _pin(e, axis, gs) -> tuple[int, int]:
        """``(row, component)`` of a pinned end: the axis of its reference section frame that
        the pin axis lies along (the end turns about it only)."""
        where = "start" if e.normal < 0 else "end"
        local = gs.R0[e.point].T @ np.asarray(axis, dtype=float)
        k = int(np.argmax(np.abs(local)))
        if abs(abs(local[k]) - 1.0) > 1e-9:
            raise ValueError(f"bc.pin_axis = {np.round(axis, 6).tolist()}: must lie along an axis of the {where} "
                             f"section (d1, d2, d3 = {np.round(gs.R0[e.point].T, 6).tolist()})")
        if np.linalg.norm(np.cross(e.load.couple, axis)) > 0.0:
            raise ValueError(f"loads.{where}.couple: a pinned end takes the couple across its axis; give only the "
                             "component along bc.pin_axis")
        return e.index, k

    def _refuse_rollers(self) -> None:
        if self.rollers or self.pins:
            raise ValueError("a roller or pinned end (bc.start or bc.end = 'roller' or 'pinned') is for static "
                             "and buckling analyses; "
                             "use hinged or clamped ends for dynamics and modes")

    def _make_kernels(self):
        self._refuse_rollers()
        from .kernels.galerkin import NumbaGalerkinKernels

        return NumbaGalerkinKernels(self)

    def with_kelvin_voigt(self, tau: float) -> "GalerkinBeamProblem":
        """The same problem with damping ``tau`` [s]."""
        return GalerkinBeamProblem(self.space, self.constants, self.bcs, self.loads, self.initial,
                                   backend=self.backend, kelvin_voigt=tau, integration=self.integration,
                                   quadrature=self.quadrature, bodies=self.end_bodies)

    @property
    def frame_points(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(u, basis, s)`` of the members' points, which carry the rotations ``R[:m_beam]``:
        parameters ``(m_beam,)``, basis values ``(m_beam, n)`` and reference arc lengths
        ``(m_beam,)`` (the nodes of bodies on joints are not on the centreline)."""
        mb = self.m_beam
        return self.gs.u[:mb], self.gs.B0[:mb], self.gs.s[:mb]

    def initial_state(self) -> GalerkinBeamState:
        """Reference configuration with the initial velocity field."""
        gs = self.gs
        c, v, omega = self._initial_motion()
        w = np.zeros((self.n, 3))
        if np.any(omega):  # material Omega = R0^T omega, projected; exact at the patch ends
            w = gs.project(rot_T(gs.R0, np.broadcast_to(omega, (self.m, 3))))
            for row, pt in self._end_points(self.space).items():
                w[row] = gs.R0[pt].T @ omega
        R = np.array(gs.R0)
        for e in self.ends:
            self._check_initial_end(e, v, omega)
            if e.translation is not None:
                v[e.index] = e.translation.velocity(0.0) * e.translation.unit_axis
            if e.motion is not None:
                w[e.index] = e.motion.velocity(0.0) * (gs.R0[e.point].T @ e.motion.unit_axis)
            elif e.fix_rotation:
                w[e.index] = 0.0
        if self.n > self.n_beam:  # the nodes start at their joint points, moving with them
            c, v = (np.concatenate([x, x[gs.attached_rows]]) for x in (c, v))
        return GalerkinBeamState(c, v, w, R, np.array(gs.K0))

    # ------------------------------------------------------------------ RKMK contract
    def project_increment(self, u: np.ndarray) -> np.ndarray:
        """``u`` with the joints' second rows set from the first (``u_b = u_a`` for position
        and velocity; for Theta and W ``Q^T u_a`` at a rigid joint, the components along ``D``
        of ``u_b - Q^T u_a`` set to zero; a hinge's rotations, whose constraints depend on the
        state, are left to its rates): the increments that keep the members joined. The stage rates satisfy this already; a perturbation that breaks a
        joint (a finite-difference Jacobian's) then moves nothing, so the spectrum gets
        exact zeros for those directions instead of noise."""
        if not self.joints:
            return u
        u = np.array(u, dtype=float, copy=True)
        for j in self.joints:
            u[[0, 2], j.b] = u[[0, 2], j.a]
            if np.any(j.D):
                P = j.D.T @ j.D  # projector on the constrained directions
                u[[1, 3], j.b] -= (u[[1, 3], j.b] - u[[1, 3], j.a] @ j.Q) @ P
        return u

    def action(self, u: np.ndarray, y: GalerkinBeamState) -> GalerkinBeamState:
        u = self.project_increment(u)
        if self._nb is not None:
            return self._nb.action(u, y, GalerkinBeamState)
        th, th_s = self.B0 @ u[1], self.B1 @ u[1]
        E = exp_so3(th)
        K = rot_T(E, y.K) + jr_times(th, th_s)
        return GalerkinBeamState(y.c + u[0], y.v + u[2], y.w + u[3], y.R @ E, K)

    def dexpinv(self, u: np.ndarray, w: np.ndarray) -> np.ndarray:
        """Right-trivialized ``dexpinv_{-Theta}`` at the points, projected (``M^-1``)."""
        out = np.array(w, dtype=float, copy=True)
        out[1] = self._project_rotation(dexpinv_so3(-(self.B0 @ u[1]), self.B0 @ w[1]), w[1])
        return out

    def _project_rotation(self, values: np.ndarray, ends: np.ndarray) -> np.ndarray:
        """``M^-1 int N values`` with the clamped rows set to ``ends`` rows."""
        rhs = self.B0.T @ (self.wf[:, None] * values)
        return self._constrain(self.mass_theta.solve(rhs, ends[self.fix_rotation]), "theta")

    def increment_rate(self, t: float, y: GalerkinBeamState, u: np.ndarray) -> np.ndarray:
        self._refuse_rollers()
        if self._nb is not None:
            return self._nb.increment_rate(t, y, u)
        out = np.empty((4, self.n, 3))
        out[0] = y.v
        Om = self.B0 @ y.w
        # Theta' = dexpinv_{-Theta}(Omega), projected; at a clamp Theta' = W (parallel)
        out[1] = self._constrain_hinges(self._project_rotation(dexpinv_so3(-(self.B0 @ u[1]), Om), y.w), y, u, "theta")
        F, T = self._forces(t, y, Om)
        out[2] = self._constrain(self.mass_position.solve(F, self._prescribed_acceleration(t, "position")), "position")
        out[3] = self._constrain_hinges(
            self._constrain(self._solve_rotation(T, self._prescribed_acceleration(t, "rotation")), "rotation"), y, u,
            "rotation")
        out[2], out[3], _ = self._couple_bodies(y, out[2], out[3])
        return out

    def _prescribed_acceleration(self, t: float, which: str) -> np.ndarray:
        """Rows of the supported control values' accelerations (zero unless moving)."""
        fixed = self.fix_position if which == "position" else self.fix_rotation
        out = np.zeros((self.n, 3))
        for e in self.ends:
            if which == "position" and e.translation is not None:
                out[e.index] = e.translation.acceleration(t) * e.translation.unit_axis
            if which == "rotation" and e.motion is not None:
                out[e.index] = e.motion.acceleration(t) * (self.gs.R0[e.point].T @ e.motion.unit_axis)
        return out[fixed]

    def _resultants(self, y: GalerkinBeamState, Om: np.ndarray):
        """``Gamma~ = R^T c_s``, material resultants ``N, M`` at the points (with the
        Kelvin-Voigt part), the strain rates (or None)."""
        R, K = y.R, y.K
        c_s = self.B1 @ y.c
        Gt = rot_T(R, c_s)
        gam = Gt - self.gs.gamma0
        kap = K - self.gs.K0
        if self.tau > 0.0:
            gd, kd = self._strain_rates(y, Gt, Om)
            gam, kap = gam + self.tau * gd, kap + self.tau * kd
        return Gt, self.CN * gam, self.CM * kap

    def _strain_rates(self, y, Gt, Om):
        """``dGamma/dt = R^T v_s - Omega x Gamma~`` and ``dK/dt = Omega_s + K x Omega``."""
        gd = rot_T(y.R, self.B1 @ y.v) - cross(Om, Gt)
        kd = self.B1 @ y.w + cross(y.K, Om)
        return gd, kd

    def _forces(self, t: float, y: GalerkinBeamState, Om: np.ndarray, load_factor: float = 1.0):
        """Generalized forces on the control values: ``F`` (spatial) and ``T`` (material),
        ``(n, 3)`` each (internal, inertial and external; no Dirichlet rows). The external
        loads are scaled by ``load_factor`` (the load steps of the static solver)."""
        R, K = y.R, y.K
        Gt, N, M = self._resultants(y, Om)
        wa, wf = self.wa[:, None], self.wf[:, None]
        F = -(self.B1.T @ (wa * rot(R, N)))
        pt = wa * cross(Gt, N) - wf * (cross(M, K) + cross(Om, self.Jm * Om))
        f = load_factor * self.loads.distributed_profile(t) if (self.has_q or self.has_m) else 0.0
        if self.has_m:
            pt = pt + f * wf * rot_T(R, np.broadcast_to(self.m_dist, Om.shape))
        T = self.B0.T @ pt - self.B1.T @ (wf * M)
        if self.has_q:
            F += f * self.load_vector
        self._body_terms(y, F, T, f)
        for h, (_, _, m) in zip(self.hinges, self._hinge_springs(y)):
            T[h.b] -= m * h.axis
            T[h.a] += m * (y.R[h.point].T @ (y.R[h.point_b] @ h.axis))
        for row, point, ld, arm in self.point_loads:
            Re = R[point]
            if np.any(ld.force):
                fo = load_factor * self._end_force(ld, t, Re)
                F[row] += fo
                T[row] += np.cross(arm, Re.T @ fo)
            if np.any(ld.couple):
                T[row] += load_factor * (Re.T @ self._end_couple(ld, t, Re))
        return F, T

    def rotation_angle(self, u: np.ndarray) -> float:
        return float(np.max(angle(self.B0 @ u[1])))

    # ------------------------------------------------------------------ splitting methods
    def split_steps(self, y: GalerkinBeamState, h: float, gammas: np.ndarray, n: int,
                    t: float = 0.0, quadrature: np.ndarray | None = None) -> GalerkinBeamState:
        """``n`` steps of length ``h`` from ``(t, y)`` of the symmetric composition ``gammas``
        of kick-drift-kick (Stormer-Verlet; compiled: :func:`.kernels.galerkin.split_steps`),
        for :func:`~liegroup_int.integrators.integrate` with a splitting method (``strang``,
        ``yoshida4``, ``yoshida6``). The drift is exact on the group; a kick takes the stage
        accelerations, so the composition is symmetric where they do not depend on the
        velocities. The gyroscopic couple does, which leaves order 2 whatever the
        composition's order. ``quadrature`` ``(1,)``, when given, gains the work of the
        loads and supports over the steps (trapezoidal rule over the synchronized states;
        :meth:`quadrature_rate` is its integrand)."""
        self._refuse_rollers()
        if self.tau > 0.0:
            raise ValueError(f"splitting methods are for undamped problems (kelvin_voigt = {self.tau:g} s): use an "
                             "RKMK method for Kelvin-Voigt damping")
        sd = self.__dict__.get("_split_data") or self._split_setup()  # built once: a call per output time
        self._split_data = sd
        ys = tuple(np.array(a, dtype=float, order="C") for a in (y.c, y.v, y.w, y.R, y.K))
        w = np.zeros(1)
        sd.entry(sd.data, ys, sd.work, np.ascontiguousarray(gammas, dtype=float), float(h), int(n), float(t), w, sd.tmp)
        if quadrature is not None:
            quadrature[0] += w[0]
        return self.state_cls(*ys)

    def _split_setup(self) -> "_SplitData":
        """The compiled leapfrog's data: the engine's (a private copy of the kernels' flat
        data, the load table, the compiled entries), and work arrays reused by every call."""
        cp = self._nb.compiled_problem(self.state_cls) if self._nb is not None else None
        if cp is None:
            raise ValueError('splitting methods run the compiled kernels: use integrator.backend = "numba" and '
                             "load profiles the kernels evaluate (no Python callables)")
        from ...integrators.engine import typed_entry
        from .kernels.galerkin import call_split_steps

        y = self.initial_state()
        work = tuple(np.empty(np.shape(a)) for a in (y.c, y.v, y.w, y.R, y.K))
        tmp, w = np.zeros((4, 4, self.n, 3)), np.zeros(1)
        # the entry compiled for the data's function types: a plain call would type the
        # first-class functions at every call (about 0.1 ms)
        entry = typed_entry(call_split_steps, (cp.data, work, work, w, 0.0, 0, 0.0, w, tmp), dict(cp.functions))
        return _SplitData(cp.data, entry, work=work, tmp=tmp)

    def __getstate__(self):
        """Pickled without the leapfrog's compiled entry (built again on first use)."""
        state = dict(self.__dict__)
        state.pop("_split_data", None)
        return state

    # ------------------------------------------------------------------ reactions and power
    def _support_loads(self, t: float, y: GalerkinBeamState):
        """Force (spatial) and couple (material) each support exerts on its control value:
        the residual of that row, ``mu (M v')_d - F_d`` and ``J (M W')_d - T_d``. With a roller
        the problem is static (no accelerations): a roller takes the force across its axis and
        the twisting couple; so with a pin, which takes the force and the couple across its
        axis."""
        zero = np.zeros((4, self.n, 3))
        k = zero if self.rollers or self.pins else self.increment_rate(t, y, zero)
        F, T = self._forces_on_rows(t, y, k)
        out = {}
        for row, axis in self.rollers:
            f, c = -F[row], np.zeros(3)
            f[axis], c[2] = 0.0, -T[row, 2]
            out["start" if row == 0 else "end"] = (f, c)
        pinned = dict(self.pins)
        for e in self.ends:
            if e.index in pinned:
                c = -T[e.index].copy()
                c[pinned[e.index]] = 0.0
                out[e.name] = (-F[e.index], c)
            elif e.fix_position or e.fix_rotation:
                i = e.index
                f = self._M_mu[i] @ k[2] - F[i] if e.fix_position else np.zeros(3)
                c = np.array([self._M_J[d][i] @ k[3][:, d] for d in range(3)]) - T[i] if e.fix_rotation \
                    else np.zeros(3)
                out[e.name] = (f, c)
        return out

    def quadrature_rate(self, t: float, y: GalerkinBeamState) -> float:
        """Power of the external loads and supports minus the viscous dissipation [W]
        (as :meth:`BeamProblem.quadrature_rate`, with the Galerkin quadrature)."""
        p = 0.0
        Om = self.B0 @ y.w
        if self.tau > 0.0:
            Gt = rot_T(y.R, self.B1 @ y.c)
            gd, kd = self._strain_rates(y, Gt, Om)
            p -= self.tau * float(self.wa @ np.sum(self.CN * gd**2, axis=1) + self.wf @ np.sum(self.CM * kd**2, axis=1))
        for h, (_, rate, _) in zip(self.hinges, self._hinge_springs(y)):
            p -= h.damping * rate**2
        if self.has_q or self.has_m:
            f = self.loads.distributed_profile(t)
            if self.has_q:
                p += f * float(np.sum(self.load_vector * y.v))
            if self.has_m:
                p += f * float(np.sum(self.wf[:, None] * rot_T(y.R, np.broadcast_to(self.m_dist, Om.shape)) * Om))
        if self.moving_ends or self.translating_ends:
            sup = self._support_loads(t, y)
            for e in self.moving_ends:
                p += float(sup[e.name][1] @ y.w[e.index])
            for e in self.translating_ends:
                p += float(sup[e.name][0] @ y.v[e.index])
        for row, point, ld, arm in self.point_loads:
            Re = y.R[point]
            if np.any(ld.force):
                fo = self._end_force(ld, t, Re)
                p += float(fo @ y.v[row] + np.cross(arm, Re.T @ fo) @ y.w[row])
            if np.any(ld.couple):
                p += float((Re.T @ self._end_couple(ld, t, Re)) @ y.w[row])
        if self.has_q:
            f = self.loads.distributed_profile(t)
            for b in self.bodies:  # the weight's moment about the end point
                p += f * float(np.cross(b.c, y.R[b.point].T @ b.weight) @ y.w[b.row])
        return p

    # ------------------------------------------------------------------ diagnostics
    def energy_parts(self, y, t: float = 0.0) -> dict[str, float]:
        """Kinetic (consistent mass), strain and load-potential energy [J]."""
        kin = 0.5 * (float(np.sum(y.v * (self._M_mu @ y.v)))
                     + sum(float(y.w[:, d] @ (self._M_J[d] @ y.w[:, d])) for d in range(3)))
        for b in self.bodies:  # off the diagonal blocks: m v . R (W x c) + 1/2 W . (J - diag J) W
            W = y.w[b.row]
            kin += b.body.mass * float(y.v[b.row] @ (y.R[b.point] @ np.cross(W, b.c)))
            kin += 0.5 * float(W @ ((b.J - np.diag(np.diag(b.J))) @ W))
        Gt, N, Mm = self._resultants_elastic(y)
        strain = 0.5 * (float(self.wa @ np.sum(N * (Gt - self.gs.gamma0), axis=1))
                        + float(self.wf @ np.sum(Mm * (y.K - self.gs.K0), axis=1))
                        + sum(h.stiffness * phi**2 for h, (phi, _, _) in zip(self.hinges, self._hinge_springs(y))))
        potential = 0.0
        if self.has_q:
            f = self.loads.distributed_profile(t)
            potential -= f * (float(np.sum(self.load_vector * y.c))
                              + sum(float(b.weight @ (y.R[b.point] @ b.c)) for b in self.bodies))
        for row, point, ld, arm in self.point_loads:
            if np.any(ld.force) and ld.force_profile.is_constant and not ld.follower:
                potential -= float(np.dot(ld.force, y.c[row] + y.R[point] @ arm))
        return {"kinetic": kin, "strain": strain, "potential": potential}

    def _resultants_elastic(self, y):
        Gt = rot_T(y.R, self.B1 @ y.c)
        return Gt, self.CN * (Gt - self.gs.gamma0), self.CM * (y.K - self.gs.K0)

    def momentum(self, y) -> tuple[np.ndarray, np.ndarray]:
        """Linear momentum and angular momentum about the origin, ``(3,)`` each."""
        c, v, Om = self.B0 @ y.c, self.B0 @ y.v, self.B0 @ y.w
        wf = self.wf[:, None]
        h = np.sum(wf * (cross(c, self.mu[:, None] * v) + rot(y.R, self.Jm * Om)), axis=0)
        p = self.mass_weights @ y.v
        for b in self.bodies:  # the centre x + R c moves with v + R (W x c)
            Rr, W = y.R[b.point], y.w[b.row]
            vc = b.body.mass * (y.v[b.row] + Rr @ np.cross(W, b.c))
            h += np.cross(y.c[b.row] + Rr @ b.c, vc) + Rr @ np.multiply(b.body.inertia, W)
            p += vc - b.body.mass * y.v[b.row]
        return p, h

    def body_motion(self, y) -> tuple:
        """Per body its centre of mass ``x + R c`` and spatial angular velocity ``R W``,
        ``((centre, omega), ...)`` with ``(3,)`` each (``x, R, W`` of its end, or of its node
        on a joint)."""
        return tuple((y.c[b.row] + y.R[b.point] @ b.c, y.R[b.point] @ y.w[b.row]) for b in self.bodies)

    def tip(self, y) -> np.ndarray:
        """Centroid at the end ``s = L``, ``(3,)``."""
        return y.c[self.ends[1].index].copy()

    def section_fields(self, y, names=SECTION_FIELDS) -> dict[str, np.ndarray]:
        """Section quantities at the points (:attr:`frame_points`), ``(m, 3)`` each, as
        :meth:`BeamProblem.section_fields`."""
        want = self._check_fields(names)
        out = {}
        Om = self.B0 @ y.w
        if want & {"Gamma", "N", "n", "K", "M", "m"}:
            Gt, N, M = self._resultants(y, Om)
            out.update({"Gamma": Gt - self.gs.gamma0, "K": y.K - self.gs.K0, "N": N, "M": M,
                        "n": rot(y.R, N), "m": rot(y.R, M)})
        if "velocity" in want:
            out["velocity"] = self.B0 @ y.v
        if "angular_velocity" in want:
            out["angular_velocity"] = rot(y.R, Om)
        return {k: out[k][:self.m_beam] for k in names if k in out}

    def joint_reactions(self, y, t: float = 0.0) -> tuple:
        """Force and couple (spatial) that the first end of each joint pair exerts on the
        second, ``((force, couple), ...)`` with ``(3,)`` each: minus the Lagrange multipliers
        of the position and rotation constraints (``M x = f - C^T lambda``; the couple is
        zero at a ball joint; at a hinge, the hinge's multipliers, perpendicular to the
        deformed axis, plus its spring-damper's couple along it). Joint point loads act on
        the first end."""
        if not self.joints:
            return ()
        F, T = self._forces_on_rows(t, y)
        lam_f = self._multipliers(self.mass_position.solve(F, self._prescribed_acceleration(t, "position")),
                                  "position")
        x = self._solve_rotation(T, self._prescribed_acceleration(t, "rotation"))
        couples = [j.D.T @ lam for j, lam in zip(self.joints, self._multipliers(x, "rotation"))]
        if self.hinges:
            lam_h, _ = self._hinge_multipliers(self._constrain(x, "rotation"), y, np.zeros((4, self.n, 3)), "rotation")
            r = np.zeros((self.n, 3))  # C_h^T lambda_h: the constant joints' share of it comes off theirs
            for h, (Ca, Cb, _), lam in zip(self.hinges, self._hinge_rows(y, None, "rotation"), lam_h):
                r[h.a] += Ca.T @ lam
                r[h.b] += Cb.T @ lam
                couples[h.joint] = h.E.T @ lam
            for h, (_, _, m) in zip(self.hinges, self._hinge_springs(y)):
                couples[h.joint] = couples[h.joint] + m * h.axis  # the spring-damper's couple -m axis on b
            share = self._multipliers(self._solve_rotation(r, 0.0), "rotation")
            couples = [c - j.D.T @ d for c, j, d in zip(couples, self.joints, share)]
        return tuple((-lam_f[k], -(y.R[j.point_b] @ couples[k])) for k, j in enumerate(self.joints))

    def reactions(self, y, t: float = 0.0) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        """Force and couple (spatial) each support exerts on the beam: the residuals of the
        supported rows of the weak form (variationally consistent reactions). A hinge
        takes no couple (zero)."""
        sup = self._support_loads(t, y)
        return {e.name: (sup[e.name][0], y.R[e.point] @ sup[e.name][1]) for e in self.ends if e.name in sup
                and (e.fix_position or any(row == e.index for row, _ in self.rollers))}
