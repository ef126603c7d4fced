"""What every beam formulation shares: validation, supports, end loads, energies,
Kelvin-Voigt damping, the backend; and :class:`BeamModel`, what scenes and writers read
from a beam.

:class:`BeamBase` is the base of :class:`~.problem.BeamProblem` (collocation) and
:class:`~.galerkin.GalerkinBeamProblem` (weak form). A formulation sets ``state_cls``
and implements ``_make_kernels`` (its compiled kernels), ``initial_state``,
``energy_parts``, ``section_fields``, ``reactions`` and the RKMK contract.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

from ...groups.so3 import SO3, cross
from ...integrators import Problem
from .model import BoundaryConditions, InitialConditions, Loads, SectionConstants

#: Section quantities ``section_fields`` computes (``output.fields``).
SECTION_FIELDS = ("Gamma", "K", "N", "M", "n", "m", "velocity", "angular_velocity")


@runtime_checkable
class BeamModel(Protocol):
    """What scenes, outputs and studies read from a beam problem (every formulation)."""

    formulation: str
    tau: float
    damping_report: object
    rotary_inertia_report: object
    space: object
    n: int

    @property
    def frame_points(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]: ...

    def initial_state(self): ...

    def with_kelvin_voigt(self, tau: float): ...

    def tip(self, y) -> np.ndarray: ...

    def energy_parts(self, y, t: float = 0.0) -> dict[str, float]: ...

    def energy(self, y, t: float = 0.0) -> float: ...

    def mechanical_energy(self, y) -> float: ...

    def momentum(self, y) -> tuple[np.ndarray, np.ndarray]: ...

    def orth_error(self, y) -> float: ...

    def section_fields(self, y, names=SECTION_FIELDS) -> dict[str, np.ndarray]: ...

    def supports(self) -> dict[str, int]: ...

    def reactions(self, y, t: float = 0.0) -> dict[str, tuple[np.ndarray, np.ndarray]]: ...

    def centreline(self, y, u: np.ndarray) -> np.ndarray: ...


class BeamBase(Problem):
    """Shared set-up and diagnostics of the beam formulations (module docstring)."""

    state_cls: type = object
    formulation = ""

    def _setup(self, space, constants: SectionConstants, bcs: BoundaryConditions, loads: Loads,
               initial: InitialConditions, backend: str, kelvin_voigt: float) -> None:
        """Checked common attributes: data, damping ``tau``, backend."""
        kelvin_voigt = float(kelvin_voigt)
        if not (np.isfinite(kelvin_voigt) and kelvin_voigt >= 0.0):
            raise ValueError(f"kelvin_voigt: expected a retardation time >= 0 [s], got {kelvin_voigt!r}")
        if backend not in ("numpy", "numba"):
            raise ValueError(f"backend must be 'numpy' or 'numba', got {backend!r}")
        if backend == "numba":
            import importlib.util

            if importlib.util.find_spec("numba") is None:  # pragma: no cover - depends on the environment
                raise ImportError("backend='numba' needs numba (pip install numba); use backend='numpy'")
        self.tau = kelvin_voigt
        #: :class:`~.damping.DampingReport` when ``tau`` was sized automatically
        self.damping_report = None
        #: :class:`~.inertia_scaling.RotaryInertiaReport` when the rotary inertia was scaled
        self.rotary_inertia_report = None
        self.space, self.constants = space, constants
        self.bcs, self.loads, self.initial = bcs, loads, initial
        self.backend = backend
        self._nb_kernels = None

    @property
    def _nb(self):
        """The compiled kernels (backend="numba"), built at first use: checking a scene
        (building its problem) imports no numba."""
        if self._nb_kernels is None and self.backend == "numba":
            self._nb_kernels = self._make_kernels()
        return self._nb_kernels

    def _make_kernels(self):  # pragma: no cover - every formulation implements it
        raise NotImplementedError

    def compiled_kernels(self):
        """The compiled engine's kernels (stage rates, action, Newton-Schulz end step,
        rotation angle, error scale), so that the drivers run all the steps between two
        output times in one compiled call. ``None`` with the NumPy backend, and when a
        load profile is not a plain :class:`~.model.Profile` (the generic path then calls
        it in Python)."""
        if self._nb is None:
            return None
        return self._nb.compiled_problem(self.state_cls)

    # ------------------------------------------------------------------ supports and loads
    @staticmethod
    def check_end_load(kind: str, load, normal: float) -> None:
        """Refuse a load a support would take: any load on a clamped end, a force on a
        hinged one (``normal`` -1 at s = 0, +1 at s = L)."""
        where = "start" if normal < 0 else "end"
        if kind == "clamped" and load.active:
            raise ValueError(f"loads.{where}: a load on a clamped end does no work; remove it or free the end")
        if kind in ("hinged", "pinned") and np.any(load.force):
            raise ValueError(f"loads.{where}.force: a force on a {kind} end is taken by the support; remove it "
                             "or free the end")

    @staticmethod
    def joint_loads(space, loads: Loads) -> list:
        """``(k, (a, b), load or None)`` per rigid joint of a patched space, the loads
        checked (one per joint, dead)."""
        rows = getattr(space, "joints", ())
        if loads.joints and len(loads.joints) != len(rows):
            raise ValueError(f"loads.joints: {len(loads.joints)} joint load(s) for {len(rows)} joint(s)")
        out = []
        for k, ab in enumerate(rows):
            ld = loads.joints[k] if loads.joints else None
            if ld is not None and ld.follower:
                raise ValueError(f"loads.joints[{k}]: a joint load is a dead load (follower = false)")
            out.append((k, ab, ld if ld is not None and ld.active else None))
        return out

    @staticmethod
    def _end_force(ld, t: float, R_end: np.ndarray) -> np.ndarray:
        """Spatial end force at ``t``: dead, or turned by the end rotation (follower)."""
        f = np.asarray(ld.force, float) * ld.force_profile(t)
        return R_end @ f if ld.follower else f

    @staticmethod
    def _end_couple(ld, t: float, R_end: np.ndarray) -> np.ndarray:
        """Spatial end couple at ``t``: dead, or turned by the end rotation (follower)."""
        m = np.asarray(ld.couple, float) * ld.couple_profile(t)
        return R_end @ m if ld.follower else m

    def supports(self) -> dict[str, int]:
        """The supported ends (clamped or hinged): ``{"start" | "end": control index}``."""
        return {("start" if e.normal < 0 else "end"): e.index for e in self.ends if e.fix_position}

    # ------------------------------------------------------------------ initial state
    def _initial_motion(self):
        """Control points, control values of the initial velocity field (a rigid motion:
        it lies in the trial space) and the initial angular velocity ``omega``."""
        sp, ic = self.space, self.initial
        c = np.array(sp.control_points if hasattr(sp, "patches") else sp.curve.control_points, dtype=float)
        omega = np.asarray(ic.omega, float)
        v_c = np.asarray(ic.velocity, float) + cross(np.broadcast_to(omega, sp.c0.shape),
                                                     sp.c0 - np.asarray(ic.axis_point, float))
        return c, sp.solve(v_c), omega

    @staticmethod
    def _check_initial_end(e, v: np.ndarray, omega: np.ndarray) -> None:
        """Refuse an initial motion a support does not allow."""
        if e.fix_position and np.any(v[e.index]):
            raise ValueError(f"initial: the velocity field moves the supported end at s = "
                             f"{'0' if e.normal < 0 else 'L'}; put initial.axis_point on the support")
        if e.motion is not None:
            a = e.motion.unit_axis
            if np.any(omega) and not np.allclose(omega, e.motion.velocity(0.0) * a, rtol=1e-12, atol=0.0):
                raise ValueError("initial.omega: differs from the prescribed rotation rate of the support at t = 0")
        elif e.fix_rotation and np.any(omega):
            raise ValueError("initial.omega: a clamped end cannot rotate")

    # ------------------------------------------------------------------ RKMK contract
    def zero_increment(self, y) -> np.ndarray:
        return np.zeros((4, self.n, 3))

    def vector_field(self, t: float, y) -> np.ndarray:
        """``f(t, y)`` as control values (no dexpinv): the stage rate at ``u = 0``."""
        return self.increment_rate(t, y, np.zeros((4, self.n, 3)))

    def increment_scale(self, y) -> np.ndarray:
        scale = np.ones((4, self.n, 3))
        scale[0] = np.abs(y.c)
        return scale

    def end_step(self, y):
        """One Newton-Schulz step toward the nearest rotation, ``R <- R (3 I - R^T R) / 2``.

        ``R`` is orthogonal up to round-off, but the round-off accumulates (measured
        ~6e-12 after 2e5 steps); the correction is quadratic in the orthogonality error,
        so it changes R by ~1e-24 and keeps it at ~1e-15 for ever.
        """
        y.R = SO3.normalize(y.R)
        return y

    # ------------------------------------------------------------------ diagnostics
    def tip(self, y) -> np.ndarray:
        """Centroid at ``s = L`` (last control point of an open knot vector), ``(3,)``."""
        return y.c[-1].copy()

    def mechanical_energy(self, y) -> float:
        """Kinetic plus strain energy [J]; minus the work of the loads
        (``quadrature_rate`` integrated in time) it is conserved."""
        p = self.energy_parts(y)
        return p["kinetic"] + p["strain"]

    def energy(self, y, t: float = 0.0) -> float:
        """Total energy at time ``t``: kinetic + strain + load potential (distributed load
        with its profile at ``t``, constant dead end forces)."""
        p = self.energy_parts(y, t)
        return p["kinetic"] + p["strain"] + p["potential"]

    def orth_error(self, y) -> float:
        """Largest ``|R^T R - I|`` (Frobenius) over the points."""
        E = np.swapaxes(y.R, -1, -2) @ y.R - np.eye(3)
        return float(np.sqrt(np.max(np.einsum("nij,nij->n", E, E))))

    @staticmethod
    def _check_fields(names) -> set:
        want = set(names)
        unknown = want - set(SECTION_FIELDS)
        if unknown:
            raise ValueError(f"unknown section field(s) {sorted(unknown)}; known: {', '.join(SECTION_FIELDS)}")
        return want

    def centreline(self, y, u: np.ndarray) -> np.ndarray:
        """Centroid positions at parameters ``u``, ``(m, 3)`` (the members' control values: a
        Galerkin state's nodes come after them)."""
        P = self.space.point_matrix(u)
        return P @ y.c[:P.shape[1]]

    def is_finite(self, y) -> bool:
        return bool(np.all(np.isfinite(y.c)) and np.all(np.isfinite(y.R)))
