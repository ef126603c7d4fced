"""Geometrically exact beam as an RKMK plugin: explicit isogeometric collocation (docs/theory.md).

State (:class:`BeamState`) at time ``t_n``:

* ``c, v, w``: control values of centroid position, translational velocity and spatial
  angular velocity, ``(n, 3)`` each;
* ``R``: rotations at the collocation points, ``(n, 3, 3)``;
* ``K, K_s``: material curvature and its arc-length derivative there, ``(n, 3)``.

Increment (one array ``(4, n, 3)``): control values of ``(eta, theta, dv, dw)``. The
action adds ``eta, dv, dw`` to ``c, v, w`` and rotates ``R <- exp(hat(theta_c)) R`` at the
collocation points, updating ``K, K_s`` by eqs. (52)-(53). The stage rate is

    M_c k = [v_c,  dexpinv_{theta_c}(w_c),  psi / mu,  R J^-1 chi]

with the balance laws (16)-(17), enhanced collocation at Neumann ends and Dirichlet
rows set on the right-hand side before the (once factorized) ``M_c`` solve.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...groups.so3 import angle, cross, dexpinv_so3, exp_so3
from ...iga import CollocationSpace
from .base import SECTION_FIELDS, BeamBase
from .kinematics import curvature_update, rot, rot_T, strain_rates, strains
from .model import BoundaryConditions, InitialConditions, Loads, SectionConstants

C_STAR = 4.0

#: Spatial discretizations of the balance laws (:class:`BeamProblem` ``formulation``).
FORMULATIONS = ("primal",)
#: Every beam formulation: the collocation one and the weak form
#: (:class:`~.galerkin.GalerkinBeamProblem`, ``"galerkin"``).
ALL_FORMULATIONS = FORMULATIONS + ("galerkin",)


@dataclass
class BeamState:
    """Beam state (see module docstring)."""

    c: np.ndarray
    v: np.ndarray
    w: np.ndarray
    R: np.ndarray
    K: np.ndarray
    K_s: np.ndarray

    def copy(self) -> "BeamState":
        return BeamState(self.c.copy(), self.v.copy(), self.w.copy(), self.R.copy(), self.K.copy(),
                         self.K_s.copy())

    def arrays(self) -> dict[str, np.ndarray]:
        return {"c": self.c, "v": self.v, "w": self.w, "R": self.R, "K": self.K, "K_s": self.K_s}


@dataclass(frozen=True)
class _End:
    """Precomputed data of one end: row index, outward normal, Neumann factor, loads."""

    index: int
    normal: float
    factor: float  # C* / l_s
    fix_position: bool
    fix_rotation: bool
    force_neumann: bool
    moment_neumann: bool
    load: object
    motion: object = None  # SupportMotion of a clamped end: its rotation rows are prescribed
    translation: object = None  # SupportMotion read as a displacement: its position rows are prescribed


@dataclass(frozen=True)
class _Joint:
    """A rigid joint of two patches: rows ``a`` (end of one patch) and ``b`` (start of
    the next), their Neumann factors ``C* / l_s`` and the point load there (or None)."""

    a: int
    b: int
    factor_a: float
    factor_b: float
    load: object = None


def quadrature_weights(space: CollocationSpace, n_gauss: int = 12) -> np.ndarray:
    """Weights ``w`` with ``int_0^L f ds ~= sum_i w_i f(s_i)`` over collocation values.

    Exact for ``f`` in the trial space: ``w = M_c^-T b`` with ``b_j = int R_j J du``
    (patch by patch for a :class:`~liegroup_int.iga.PatchedSpace`).
    """
    if hasattr(space, "patches"):
        return np.concatenate([quadrature_weights(sp, n_gauss) for sp in space.patches])
    knots = np.unique(space.curve.knots)
    x, gw = np.polynomial.legendre.leggauss(n_gauss)
    a, b = knots[:-1, None], knots[1:, None]
    u = (0.5 * (b - a) * x + 0.5 * (a + b)).ravel()
    wu = (0.5 * (b - a) * gw).ravel()
    basis = space.curve.basis(u, 0)[0]
    jac = np.linalg.norm(space.curve.evaluate(u, 1)[1], axis=1)
    bj = basis.T @ (wu * jac)
    import scipy.linalg

    return scipy.linalg.solve(space.N0.T, bj)


class BeamProblem(BeamBase):
    """Explicit RKMK IGA-C beam (Ferri & Marino), one problem plugin.

    Parameters
    ----------
    space : CollocationSpace
        Basis, collocation points and reference geometry.
    constants : SectionConstants or tuple of SectionConstants
        Stiffness and inertia per length (``SectionConstants.from_material``); for a
        :class:`~liegroup_int.iga.PatchedSpace`, one per patch (a frame of members).
    bcs : BoundaryConditions
    loads : Loads
    initial : InitialConditions
    backend : {"numpy", "numba"}
        Stage kernels: NumPy arrays (default) or the compiled kernels of
        :mod:`.kernels.collocation` (same results to round-off; needs numba).
    kelvin_voigt : float
        Retardation time ``tau >= 0`` [s] of an optional Kelvin-Voigt (strain-rate)
        damping: the resultants become ``n = R C_N (Gamma + tau dGamma/dt)`` and
        ``m = R C_M (K - K0 + tau dK/dt)``, with the objective material rates
        ``dGamma/dt = R^T (v_s - omega x c_s)`` and ``dK/dt = R^T omega_s``, everywhere
        the elastic resultants enter (balance laws and enhanced-collocation end rows).
        A mode of angular frequency ``omega`` gets the damping ratio ``tau omega / 2``.
        Default 0 (conservative). It removes the spurious growing modes of the
        collocation operator (docs/verification.md, "Stability of the
        semi-discretization"): ``tau ~ 0.3 / |lambda|max`` suffices in every measured case.
    formulation : {"primal"}
        ``"primal"`` (the paper's method): the balance laws use the analytic
        s-derivatives of the pointwise resultants, which needs ``c_ss`` and ``K_s``.
    """

    state_cls = BeamState

    def __init__(self, space: CollocationSpace, constants: SectionConstants,
                 bcs: BoundaryConditions = BoundaryConditions(), loads: Loads = Loads(),
                 initial: InitialConditions = InitialConditions(), backend: str = "numpy",
                 kelvin_voigt: float = 0.0, formulation: str = "primal"):
        if formulation not in FORMULATIONS:
            raise ValueError(f"formulation: expected one of {', '.join(FORMULATIONS)}, got {formulation!r}")
        self.formulation = formulation
        self._setup(space, constants, bcs, loads, initial, backend, kelvin_voigt)
        n = space.n_ctrl
        self.n = n
        self.CN, self.CM, self.mu, self.Jm = self._section_arrays(space, constants)
        self.N0, self.N1, self.N2 = space.N0, space.N1, space.N2
        self.gamma0 = rot_T(space.R0, space.c0_s)
        self.K0, self.K0_s = space.K0, space.K0_s
        self.curved = bool(np.any(np.abs(space.K0) > 1e-14) or np.any(np.abs(space.K0_s) > 1e-14))
        self.q = np.asarray(loads.distributed_force, float) + self.mu * np.asarray(loads.gravity, float)
        self.has_q = bool(np.any(self.q))
        self.m_dist = np.asarray(loads.distributed_couple, float)
        self.has_m = bool(np.any(self.m_dist))
        self.ends = tuple(
            e for e in (self._end(0, -1.0, bcs.start, loads.start, space.l_s_start, bcs.start_motion,
                                  bcs.start_translation),
                        self._end(n - 1, 1.0, bcs.end, loads.end, space.l_s_end, bcs.end_motion, bcs.end_translation))
        )
        self.moving_ends = tuple(e for e in self.ends if e.motion is not None)
        self.translating_ends = tuple(e for e in self.ends if e.translation is not None)
        self.neumann_ends = tuple(e for e in self.ends if e.force_neumann or e.moment_neumann)
        self.joints = self._joints(space, loads)
        self.quad = quadrature_weights(space)
        self._fix_rows = self._dirichlet_mask()
        # loads that do work, or viscous dissipation: the drivers then integrate their
        # power (quadrature_rate)
        self.has_quadrature = bool(self.tau > 0.0 or self.has_q or self.has_m or self.moving_ends
                                   or self.translating_ends or any(
            (e.force_neumann and np.any(e.load.force)) or (e.moment_neumann and np.any(e.load.couple))
            for e in self.neumann_ends) or any(j.load is not None for j in self.joints))

    def _make_kernels(self):
        from .kernels.collocation import NumbaBeamKernels

        return NumbaBeamKernels(self)

    def with_kelvin_voigt(self, tau: float) -> "BeamProblem":
        """The same problem (space, data, backend, formulation) with damping ``tau`` [s]."""
        return BeamProblem(self.space, self.constants, self.bcs, self.loads, self.initial, backend=self.backend,
                           kelvin_voigt=tau, formulation=self.formulation)

    @property
    def frame_points(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(u, basis, s)`` of the points that carry the rotations ``R`` (the collocation
        points): parameters ``(n,)``, basis values ``N0`` ``(n, n)``, reference arc lengths."""
        return self.space.u_c, self.space.N0, self.space.s_c

    # ------------------------------------------------------------------ set-up
    @staticmethod
    def _end(index, normal, kind, load, l_s, motion=None, translation=None):
        if kind in ("roller", "pinned"):
            raise ValueError(f"bc.{'start' if normal < 0 else 'end'} = '{kind}' needs space.formulation = "
                             "\"galerkin\" (static and buckling analyses)")
        BeamProblem.check_end_load(kind, load, normal)
        return _End(
            index=index, normal=normal, factor=C_STAR / l_s,
            fix_position=kind in ("clamped", "hinged"), fix_rotation=kind == "clamped",
            force_neumann=kind == "free", moment_neumann=kind in ("free", "hinged"), load=load, motion=motion,
            translation=translation,
        )

    @staticmethod
    def _section_arrays(space, constants):
        """``CN, CM, mu, Jm``: ``(3,), (3,), float, (3,)`` for one section; per collocation
        point ``(n, 3), (n, 3), (n, 1), (n, 3)`` for one section per patch of a
        :class:`~liegroup_int.iga.PatchedSpace` (a tuple of :class:`SectionConstants`)."""
        if isinstance(constants, SectionConstants):
            return (np.asarray(constants.CN, dtype=float), np.asarray(constants.CM, dtype=float),
                    float(constants.mu), np.asarray(constants.Jm, dtype=float))
        sections = tuple(constants)
        patches = getattr(space, "patches", None)
        if patches is None or len(sections) != len(patches) or not all(
                isinstance(c, SectionConstants) for c in sections):
            raise ValueError("constants: one SectionConstants, or one per patch of a PatchedSpace "
                             f"({len(patches) if patches else 1} patch(es), got {len(sections)})")
        if all(c == sections[0] for c in sections):
            return BeamProblem._section_arrays(space, sections[0])
        sizes = [sp.n_ctrl for sp in patches]

        def per_point(get):
            return np.repeat(np.array([np.broadcast_to(np.asarray(get(c), float), (3,)) for c in sections]),
                             sizes, axis=0)

        return (per_point(lambda c: c.CN), per_point(lambda c: c.CM), per_point(lambda c: c.mu)[:, :1],
                per_point(lambda c: c.Jm))

    def _at(self, a, i: int):
        """Row ``i`` of a per-point constant (or the constant itself)."""
        a = np.asarray(a)
        return a[i] if a.ndim == 2 else a

    @staticmethod
    def _joints(space, loads) -> tuple:
        """The rigid joints of a :class:`~liegroup_int.iga.PatchedSpace` (none for one patch)."""
        if not getattr(space, "chain", True):
            raise ValueError("joints: the collocation formulations join patches in a chain only (each end to the "
                             'next start, rigidly); use space.formulation = "galerkin" for other joints')
        return tuple(_Joint(a, b, C_STAR / space.patches[k].l_s_end, C_STAR / space.patches[k + 1].l_s_start, ld)
                     for k, (a, b), ld in BeamBase.joint_loads(space, loads))

    def _dirichlet_mask(self) -> np.ndarray:
        """Boolean ``(n, 4)``: which (row, field) right-hand sides are prescribed rates
        (fields: position, rotation, velocity, angular velocity)."""
        mask = np.zeros((self.n, 4), dtype=bool)
        for e in self.ends:
            if e.fix_position and e.translation is None:  # a moving support: rows set in _rates
                mask[e.index, [0, 2]] = True
            if e.fix_rotation and e.motion is None:  # a moving support: rows set in _rates
                mask[e.index, [1, 3]] = True
        return mask

    def initial_state(self) -> BeamState:
        """Reference configuration with the initial velocity field."""
        c, v, omega = self._initial_motion()
        w = np.tile(omega, (self.n, 1))
        R = np.array(self.space.R0)
        for e in self.ends:  # supports do not move, unless prescribed
            self._check_initial_end(e, v, omega)
            if e.translation is not None:  # prescribed displacement d(t) a: d(0) = 0 for both kinds
                v[e.index] = e.translation.velocity(0.0) * e.translation.unit_axis
            if e.motion is not None:
                a = e.motion.unit_axis
                w[e.index] = e.motion.velocity(0.0) * a
                R[e.index] = exp_so3(e.motion.angle(0.0) * a) @ R[e.index]
        return BeamState(c, v, w, R, np.array(self.K0), np.array(self.K0_s))

    # ------------------------------------------------------------------ RKMK contract
    def action(self, u: np.ndarray, y: BeamState) -> BeamState:
        if self._nb is not None:  # backend="numba"
            return self._nb.action(u, y, BeamState)
        th = u[1]
        th_c, th_s = self.N0 @ th, self.N1 @ th
        K, K_s = curvature_update(y.R, y.K, y.K_s, th_c, th_s, self.N2 @ th)
        return BeamState(y.c + u[0], y.v + u[2], y.w + u[3], exp_so3(th_c) @ y.R, K, K_s)

    def dexpinv(self, u: np.ndarray, w: np.ndarray) -> np.ndarray:
        """``dexpinv`` on control values: pointwise at the collocation points on the
        rotational component, then projected back with ``M_c^-1``."""
        th_c = self.N0 @ u[1]
        out = np.array(w, dtype=float, copy=True)
        out[1] = self.space.solve(dexpinv_so3(th_c, self.N0 @ w[1]))
        return out

    def increment_rate(self, t: float, y: BeamState, u: np.ndarray) -> np.ndarray:
        if self._nb is not None:  # backend="numba"
            return self._nb.increment_rate(t, y, u)
        return self._solve(self._rates(t, y, self.N0 @ u[1]))

    def rotation_angle(self, u: np.ndarray) -> float:
        if self._nb is not None:  # backend="numba"
            return self._nb.rotation_angle(u)
        return float(np.max(angle(self.N0 @ u[1])))

    # ------------------------------------------------------------------ stage kernels
    def _solve(self, rhs: np.ndarray) -> np.ndarray:
        """Dirichlet rows, then one ``M_c`` solve for all 12 columns -> ``(4, n, 3)``."""
        rhs[self._fix_rows] = 0.0
        k = self.space.solve(rhs.reshape(self.n, 12))
        return k.reshape(self.n, 4, 3).transpose(1, 0, 2)

    def _rates(self, t: float, y: BeamState, th_c: np.ndarray) -> np.ndarray:
        """Right-hand sides at the collocation points, ``(n, 4, 3)``."""
        R, K = y.R, y.K
        w_c = self.N0 @ y.w
        c_s = self.N1 @ y.c
        c_ss = self.N2 @ y.c
        Rt_cs, gam, gam_s = strains(R, c_s, c_ss, K, self.gamma0)
        KM, KM_s = (K - self.K0, y.K_s - self.K0_s) if self.curved else (K, y.K_s)
        if self.tau > 0.0:  # Kelvin-Voigt: strains + tau * their material rates
            gam, gam_s, KM, KM_s = self._add_strain_rates(y, R, K, c_s, c_ss, w_c, gam, gam_s, KM, KM_s)
        N, M = self.CN * gam, self.CM * KM
        n_s = rot(R, cross(K, N) + self.CN * gam_s)
        tq = cross(K, M) + self.CM * KM_s
        Om = rot_T(R, w_c)
        tq = tq - cross(Om, self.Jm * Om) + cross(Rt_cs, N)
        f = self.loads.distributed_profile(t) if (self.has_q or self.has_m) else 0.0
        if self.has_q:
            n_s = n_s + f * self.q
        if self.has_m:
            tq = tq + rot_T(R, np.broadcast_to(f * self.m_dist, tq.shape))
        for e in self.neumann_ends:
            i, ld = e.index, e.load
            if e.force_neumann:
                n_c = self._end_force(ld, t, R[i]) if np.any(ld.force) else 0.0
                n_s[i] += e.factor * (n_c - e.normal * (R[i] @ N[i]))
            if e.moment_neumann:
                m_c = R[i].T @ self._end_couple(ld, t, R[i]) if np.any(ld.couple) else 0.0
                tq[i] += e.factor * (m_c - e.normal * M[i])
        rhs = np.empty((self.n, 4, 3))
        rhs[:, 0] = self.N0 @ y.v
        rhs[:, 1] = dexpinv_so3(th_c, w_c)
        rhs[:, 2] = n_s / self.mu
        rhs[:, 3] = rot(R, tq / self.Jm)
        for e in self.moving_ends:  # prescribed angular acceleration theta''(t) a (spatial)
            rhs[e.index, 3] = e.motion.acceleration(t) * e.motion.unit_axis
        for e in self.translating_ends:  # prescribed acceleration d''(t) a
            rhs[e.index, 2] = e.translation.acceleration(t) * e.translation.unit_axis
        if self.joints:
            self._joint_rows(rhs, t, R, N, M)
        return rhs

    def _joint_rows(self, rhs: np.ndarray, t: float, R: np.ndarray, N: np.ndarray, M: np.ndarray) -> None:
        """Rigid joints (docs/theory.md section 13): the rows ``a, b`` of the two patch ends
        get one common rate. Each end's own collocation row is completed by the
        enhanced-collocation term of the joint's balance residual ``r = n_b - n_a + F``
        (and ``m_b - m_a + C``); the common translational rate is the mass-weighted mean of
        the two rows, the angular one the inertia-weighted mean (spatial inertias
        ``R J R^T`` of both sections)."""
        for j in self.joints:
            a, b = j.a, j.b
            r_n = R[b] @ N[b] - R[a] @ N[a]
            r_m = R[b] @ M[b] - R[a] @ M[a]
            if j.load is not None:
                r_n = r_n + self._end_force(j.load, t, R[a])
                r_m = r_m + self._end_couple(j.load, t, R[a])
            fac = j.factor_a + j.factor_b
            Ia = R[a] @ np.diag(self._at(self.Jm, a)) @ R[a].T
            Ib = R[b] @ np.diag(self._at(self.Jm, b)) @ R[b].T
            mu_a, mu_b = float(np.ravel(self._at(self.mu, a))[0]), float(np.ravel(self._at(self.mu, b))[0])
            lin = (mu_a * rhs[a, 2] + mu_b * rhs[b, 2] + fac * r_n) / (mu_a + mu_b)
            ang = np.linalg.solve(Ia + Ib, Ia @ rhs[a, 3] + Ib @ rhs[b, 3] + fac * r_m)
            for f, val in ((0, 0.5 * (rhs[a, 0] + rhs[b, 0])), (1, 0.5 * (rhs[a, 1] + rhs[b, 1])), (2, lin), (3, ang)):
                rhs[a, f] = rhs[b, f] = val

    def _add_strain_rates(self, y, R, K, c_s, c_ss, w_c, gam, gam_s, KM, KM_s):
        """``(Gamma, Gamma_s, K_M, K_M,s) + tau * d/dt(...)`` at the collocation points.

        ``dGamma/dt = R^T (v_s - omega x c_s)`` and ``dK/dt = R^T omega_s`` (spatial
        ``omega``, ``dR/dt = hat(omega) R``); their s-derivatives use ``dR^T/ds = -hat(K) R^T``.
        """
        tau = self.tau
        v_s, v_ss, w_s, w_ss = self.N1 @ y.v, self.N2 @ y.v, self.N1 @ y.w, self.N2 @ y.w
        gd = rot_T(R, v_s - cross(w_c, c_s))
        gd_s = rot_T(R, v_ss - cross(w_s, c_s) - cross(w_c, c_ss)) - cross(K, gd)
        kd = rot_T(R, w_s)
        kd_s = rot_T(R, w_ss) - cross(K, kd)
        return gam + tau * gd, gam_s + tau * gd_s, KM + tau * kd, KM_s + tau * kd_s

    def quadrature_rate(self, t: float, y: BeamState) -> float:
        """Power of the external loads minus the viscous dissipation [W] at ``(t, y)``:
        the drivers integrate it into ``W(t)`` (:attr:`Stats.quadrature`), so
        ``E_kin + E_strain - W`` is conserved up to time and space error (the energy
        balance of the run guards).

        ``P = f_d(t) int (q . v + m_d . omega) ds + sum_ends (F(t) . v + M(t) . omega)
        - tau int (dGamma . C_N dGamma + dK . C_M dK) ds``
        with the distributed force ``q`` (gravity included) and couple ``m_d``, their
        profile ``f_d``, the end forces ``F`` and couples ``M`` at Neumann ends (spatial:
        follower loads turned by the end rotation),
        spatial velocities, and the Kelvin-Voigt strain rates; ``int ds`` by the
        collocation quadrature (exact on the trial space).
        """
        p = 0.0
        if self.tau > 0.0:
            gd, kd = strain_rates(y.R, self.N1 @ y.c, self.N1 @ y.v, self.N0 @ y.w, self.N1 @ y.w)
            p -= self.tau * float(self.quad @ (np.sum(self.CN * gd**2, axis=1) + np.sum(self.CM * kd**2, axis=1)))
        if self.has_q or self.has_m:
            f = self.loads.distributed_profile(t)
            if self.has_q:
                p += f * float(np.sum(self.quad[:, None] * self.q * (self.N0 @ y.v)))
            if self.has_m:
                p += f * float(self.m_dist @ (self.quad @ (self.N0 @ y.w)))
        if self.moving_ends or self.translating_ends:  # moving supports: their couple on the
            f = self.section_fields(y, ("n", "m"))  # end's angular velocity, their force on its velocity
            for e in self.moving_ends:
                p += float(np.dot(e.normal * f["m"][e.index], y.w[e.index]))
            for e in self.translating_ends:
                p += float(np.dot(e.normal * f["n"][e.index], y.v[e.index]))
        for e in self.neumann_ends:
            ld = e.load
            R_end = y.R[e.index]  # the end is a collocation point
            if e.force_neumann and np.any(ld.force):
                p += float(np.dot(self._end_force(ld, t, R_end), y.v[e.index]))
            if e.moment_neumann and np.any(ld.couple):
                p += float(np.dot(self._end_couple(ld, t, R_end), y.w[e.index]))
        for j in self.joints:
            if j.load is not None:
                p += float(np.dot(self._end_force(j.load, t, y.R[j.a]), y.v[j.a])
                           + np.dot(self._end_couple(j.load, t, y.R[j.a]), y.w[j.a]))
        return p

    # ------------------------------------------------------------------ diagnostics
    def energy_parts(self, y: BeamState, t: float = 0.0) -> dict[str, float]:
        """Kinetic, strain and load-potential energy [J] at time ``t`` by collocation
        quadrature (the distributed-load potential uses the load profile at ``t``)."""
        R, K = y.R, y.K
        c_c, v_c, w_c = self.N0 @ y.c, self.N0 @ y.v, self.N0 @ y.w
        _, gam, _ = strains(R, self.N1 @ y.c, self.N2 @ y.c, K, self.gamma0)
        KM = K - self.K0
        Om = rot_T(R, w_c)
        kin = 0.5 * (np.sum(self.mu * v_c**2, axis=1) + np.sum(self.Jm * Om**2, axis=1))
        strain = 0.5 * (np.sum(self.CN * gam**2, axis=1) + np.sum(self.CM * KM**2, axis=1))
        pot = -np.sum(c_c * self.q, axis=1) * self.loads.distributed_profile(t) if self.has_q else np.zeros(self.n)
        potential = float(self.quad @ pot)
        for e in self.neumann_ends:
            ld = e.load
            if e.force_neumann and np.any(ld.force) and ld.force_profile.is_constant and not ld.follower:
                potential -= float(np.dot(ld.force, y.c[e.index]))
        for j in self.joints:
            ld = j.load
            if ld is not None and np.any(ld.force) and ld.force_profile.is_constant:
                potential -= float(np.dot(ld.force, y.c[j.a]))
        return {"kinetic": float(self.quad @ kin), "strain": float(self.quad @ strain), "potential": potential}

    def momentum(self, y: BeamState) -> tuple[np.ndarray, np.ndarray]:
        """Linear momentum and angular momentum about the origin, ``(3,)`` each."""
        c_c, v_c, w_c = self.N0 @ y.c, self.N0 @ y.v, self.N0 @ y.w
        p = self.mu * v_c
        h = cross(c_c, p) + rot(y.R, self.Jm * rot_T(y.R, w_c))
        return self.quad @ p, self.quad @ h

    def section_fields(self, y: BeamState, names=SECTION_FIELDS) -> dict[str, np.ndarray]:
        """Section quantities at the collocation points, ``(n, 3)`` each, only those in
        ``names`` (:data:`SECTION_FIELDS`):

        * ``Gamma = R^T c_s - Gamma0`` and ``K`` (``K - K0``): material strains;
        * ``N = C_N (Gamma + tau dGamma/dt)``, ``M = C_M (K - K0 + tau dK/dt)``: material
          resultants (with the Kelvin-Voigt part when ``tau > 0``, as the balance laws);
        * ``n = R N``, ``m = R M``: spatial resultants (force and moment exerted on the part
          ``s' < s`` by the part ``s' > s``);
        * ``velocity``, ``angular_velocity``: spatial, at the points.
        """
        want = self._check_fields(names)
        out: dict[str, np.ndarray] = {}
        R = y.R
        need_strain = want & {"Gamma", "N", "n", "K", "M", "m"}
        if need_strain:
            c_s = self.N1 @ y.c
            _, gam, _ = strains(R, c_s, self.N2 @ y.c, y.K, self.gamma0)
            KM = y.K - self.K0
            if self.tau > 0.0:
                gam_t, K_t = strain_rates(R, c_s, self.N1 @ y.v, self.N0 @ y.w, self.N1 @ y.w)
                N, M = self.CN * (gam + self.tau * gam_t), self.CM * (KM + self.tau * K_t)
            else:
                N, M = self.CN * gam, self.CM * KM
            fields = {"Gamma": gam, "K": KM, "N": N, "M": M, "n": rot(R, N), "m": rot(R, M)}
            out.update({k: v for k, v in fields.items() if k in want})
        if "velocity" in want:
            out["velocity"] = self.N0 @ y.v
        if "angular_velocity" in want:
            out["angular_velocity"] = self.N0 @ y.w
        return {k: out[k] for k in names if k in out}

    def reactions(self, y: BeamState, t: float = 0.0) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        """Force and couple the supports exert on the beam, ``{"start" | "end": (f (3,),
        c (3,))}``: the end resultants with the outward normal, ``f = nu n``, ``c = nu m``
        (``nu = -1`` at ``s = 0``, ``+1`` at ``s = L``), from :meth:`section_fields` at the end
        collocation points (the ends are Greville points). A hinge takes no couple: ``c`` is
        then the discrete end moment, zero up to the collocation's error."""
        f = self.section_fields(y, ("n", "m"))
        return {("start" if e.normal < 0 else "end"): (e.normal * f["n"][e.index], e.normal * f["m"][e.index])
                for e in self.ends if e.fix_position}
