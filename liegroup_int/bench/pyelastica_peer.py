"""PyElastica (``pip install -e ".[peers]"``, import ``elastica``) set-ups of the built-in
``pendulum``, ``cantilever`` and ``spinning_helix`` scenes: the peer of ``liegroup-int bench``
and of ``benchmarks/pyelastica_compare.py``. Importing this module needs PyElastica.

The pendulum and the cantilever lie along +x1 from the origin; the tip is the last node.
The spinning helix (:func:`helix_rod_state`): nodes on the exact quarter helix
(``liegroup_int.iga.geometry.helix_quarter_exact``, equal arc-length spacing), directors our
reference frame (``frame`` of the scene's space) at the element midpoints, each turned by the
least rotation that puts ``d3`` on the element's chord (PyElastica requires ``d3`` along the
chord; the turn is O(h^2)); rest strains and curvatures set to those of this initial
configuration (``rest_sigma = sigma``, ``rest_kappa = kappa``: PyElastica computes ``sigma``
and ``kappa`` at creation but leaves the rest values zero, which would make a curved rod
spring straight); velocities ``omega x x`` at the nodes and angular velocities ``Q omega``
(material frame) on the elements, the rigid rotation of the scene. PyElastica's
``CosseratRod.straight_rod`` derives everything from a radius (circle): area
``A = pi r^2``, ``I1 = I2 = A^2 / (4 pi)``, ``I3 = 2 I1``, shear factor
``alpha_c = 27/28`` (PyElastica 1.0.0; older versions used 4/3). After creation we
overwrite, per element / Voronoi node, so the constants equal ours exactly
(``liegroup_int.problems.beam.model.SectionConstants.from_material``):

* ``shear_matrix      = diag(G A, G A, E A)``                (shear factor 1)
* ``bend_matrix       = diag(E I1, E I2, G J)``              (J = torsion constant)
* ``mass_second_moment_of_inertia = rho dl diag(I1, I2, I1 + I2)`` (and its inverse)

and the radius is chosen so that ``pi r^2 = A`` (volume and node masses use it).
No damping is added: PyElastica runs undamped here (it needs none for stability at
these step sizes).

``model="linear"`` (diagnostic variant, not PyElastica's own model): PyElastica's rod
treats the section as incompressible, so with the stretch e = |x'| (``dilatation``) its
internal force is ``Q^T S sigma / e``, its couple ``B kappa / e^3`` (Voronoi e) and its
element rotational inertia ``J / e`` (with the matching ``J omega / e^2 de/dt`` term). Ours
(docs/theory.md section 6) is the Simo-Reissner rod with constant ``C_N, C_M, J``. ``LinearCosseratRod``
swaps in forces, torques and accelerations without these factors (the same discrete
operators, kinematics and strains otherwise), i.e. PyElastica's discretization of *our*
continuum model.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from math import pi, sqrt

import elastica as ea
import numba
import numpy as np
from elastica._calculus import (
    difference_kernel_for_block_structure,
    quadrature_kernel_for_block_structure,
)
from elastica._linalg import _batch_cross, _batch_matvec
from elastica.memory_block.memory_block_rod import MemoryBlockCosseratRod
from elastica.rod.cosserat_rod import (
    _compute_internal_bending_twist_stresses_from_model,
    _compute_internal_shear_stretch_stresses_from_model,
    _update_accelerations,
)
from elastica.version import VERSION  # noqa: F401  (reported by the benchmarks)


@dataclass(frozen=True)
class Case:
    """One of the scenes in PyElastica's terms."""

    name: str
    E: float
    G: float
    rho: float
    A: float
    I1: float
    I2: float
    J: float            # torsion constant (stiffness G J)
    length: float = 1.0
    bc: str = "clamped"  # "clamped" (OneEndFixedBC) or "pinned" (position only)
    line_load: tuple = (0.0, 0.0, 0.0)   # N/m, applied as GravityForces with g = q / (rho A)
    tip_force: tuple = (0.0, 0.0, 0.0)   # N, EndpointForces on the last node
    axial_factor: float = 1.0            # multiplies E A (diagnostic variant only)
    geometry: str = "straight"           # "straight" (along +x1) or "helix" (helix_rod_state)
    omega: tuple = (0.0, 0.0, 0.0)       # rad/s, initial rigid angular velocity about the origin

    @property
    def radius(self) -> float:
        """Radius whose circle has the area ``A`` (volume, nodal masses)."""
        return sqrt(self.A / pi)

    @property
    def gravity(self) -> np.ndarray:
        return np.asarray(self.line_load, float) / (self.rho * self.A)

    @property
    def wave_speed(self) -> float:
        return sqrt(self.axial_factor * self.E / self.rho)


def pendulum_case() -> Case:
    d, E = 0.01, 5e6
    A, I = pi * d**2 / 4, pi * d**4 / 64
    return Case("pendulum", E=E, G=E / 3.0, rho=1100.0, A=A, I1=I, I2=I, J=2 * I, bc="pinned",
                line_load=(0.0, 0.0, -0.8475))


def cantilever_case() -> Case:
    t, E, nu = 0.01, 2.1e11, 0.2
    return Case("cantilever", E=E, G=E / (2 * (1 + nu)), rho=7800.0, A=t**2, I1=t**4 / 12,
                I2=t**4 / 12, J=0.1406 * t**4, bc="clamped", tip_force=(0.0, 0.0, -100.0))


def spinning_helix_case() -> Case:
    d, E = 0.01, 5e6
    A, I = pi * d**2 / 4, pi * d**4 / 64
    return Case("spinning_helix", E=E, G=E / 3.0, rho=1100.0, A=A, I1=I, I2=I, J=2 * I, length=sqrt(13.0) / 4.0,
                bc="pinned", line_load=(0.0, 0.0, -0.8475), geometry="helix", omega=(0.0, 0.0, 2.0 * pi))


CASES = {"pendulum": pendulum_case, "cantilever": cantilever_case, "spinning_helix": spinning_helix_case}


def helix_rod_state(n_elements: int, omega=(0.0, 0.0, 0.0)) -> dict:
    """Initial state of the quarter-helix rod (module doc): ``position`` (3, n + 1),
    ``directors`` (3, 3, n) (rows d1, d2, d3), ``velocity`` (3, n + 1) and ``omega``
    (3, n) (material frame); and ``frame_turn`` (n,), the angle [rad] by which each
    element's directors were turned from our frame to put ``d3`` on the chord."""
    from ..groups.so3 import exp_so3
    from ..iga.geometry import helix_quarter_exact
    from ..scenes import load_scene
    from ..scenes.beam import frame_space

    x = helix_quarter_exact(np.linspace(0.0, 1.0, n_elements + 1))          # (n + 1, 3)
    chord = np.diff(x, axis=0)
    chord /= np.linalg.norm(chord, axis=1, keepdims=True)
    space = frame_space(load_scene("spinning_helix"))[0]
    r0 = space.frame((np.arange(n_elements) + 0.5) / n_elements)[0]       # columns d1, d2, d3
    axis = np.cross(r0[:, :, 2], chord)
    sin, cos = np.linalg.norm(axis, axis=1), np.einsum("ki,ki->k", r0[:, :, 2], chord)
    turn = np.arctan2(sin, cos)
    safe = np.where(sin > 0.0, sin, 1.0)[:, None]
    r = exp_so3(axis * (turn[:, None] / safe)) @ r0
    r[:, :, 2] = chord                                                        # exact to round-off
    w = np.asarray(omega, float)
    return {"position": x.T.copy(), "directors": np.ascontiguousarray(np.transpose(r, (2, 1, 0))),
            "velocity": np.cross(w, x).T.copy(), "omega": np.einsum("kji,j->ik", r, w),
            "frame_turn": turn}


# ----------------------------------------------------------------------------- linear variant
@numba.njit(cache=False)
def _linear_forces(position, volume, lengths, tangents, radius, rest_lengths, rest_voronoi_lengths, dilatation,
                   voronoi_dilatation, directors, sigma, rest_sigma, shear_matrix, internal_stress,
                   internal_forces, ghost_elems_idx):
    """Internal force ``Delta(Q^T S sigma)`` (PyElastica: ``Delta(Q^T S sigma / e)``)."""
    _compute_internal_shear_stretch_stresses_from_model(
        position, volume, lengths, tangents, radius, rest_lengths, rest_voronoi_lengths, dilatation,
        voronoi_dilatation, directors, sigma, rest_sigma, shear_matrix, internal_stress)
    blocksize = internal_stress.shape[1]
    spatial = np.zeros((3, blocksize))
    for i in range(3):
        for j in range(3):
            for k in range(blocksize):
                spatial[i, k] += directors[j, i, k] * internal_stress[j, k]
    internal_forces[:] = difference_kernel_for_block_structure(spatial, ghost_elems_idx)


@numba.njit(cache=False)
def _linear_torques(directors, tangents, rest_lengths, rest_voronoi_lengths, dilatation, bend_matrix, rest_kappa,
                    kappa, J, omega, internal_stress, internal_couple, internal_torques, ghost_voronoi_idx):
    """``Delta(B kappa) + A[(kappa x B kappa) D] + (e Q t x S sigma) l + (J w) x w``
    (PyElastica: the couple divided by eps^3, the shear couple without e, J / e and the
    ``J w / e^2 de/dt`` term)."""
    _compute_internal_bending_twist_stresses_from_model(directors, rest_voronoi_lengths, internal_couple,
                                                        bend_matrix, kappa, rest_kappa)
    b2 = difference_kernel_for_block_structure(internal_couple, ghost_voronoi_idx)
    b3 = quadrature_kernel_for_block_structure(_batch_cross(kappa, internal_couple) * rest_voronoi_lengths,
                                               ghost_voronoi_idx)
    sc = _batch_cross(_batch_matvec(directors, tangents), internal_stress) * rest_lengths * dilatation
    lt = _batch_cross(_batch_matvec(J, omega), omega)
    internal_torques[:] = b2 + b3 + sc + lt


class LinearMemoryBlock(MemoryBlockCosseratRod):
    """Memory block whose rods follow our constitutive/inertia model (see module doc)."""

    def compute_internal_forces_and_torques(self, time):
        _linear_forces(self.position_collection, self.volume, self.lengths, self.tangents, self.radius,
                       self.rest_lengths, self.rest_voronoi_lengths, self.dilatation, self.voronoi_dilatation,
                       self.director_collection, self.sigma, self.rest_sigma, self.shear_matrix,
                       self.internal_stress, self.internal_forces, self.ghost_elems_idx)
        _linear_torques(self.director_collection, self.tangents, self.rest_lengths, self.rest_voronoi_lengths,
                        self.dilatation, self.bend_matrix, self.rest_kappa, self.kappa,
                        self.mass_second_moment_of_inertia, self.omega_collection, self.internal_stress,
                        self.internal_couple, self.internal_torques, self.ghost_voronoi_idx)

    def update_accelerations(self, time, dt):
        _update_accelerations(self.acceleration_collection, self.internal_forces, self.external_forces, self.mass,
                              self.alpha_collection, self.inv_mass_second_moment_of_inertia,
                              self.internal_torques, self.external_torques, np.ones_like(self.dilatation))


class LinearCosseratRod(ea.CosseratRod):
    """Marker type: gets a :class:`LinearMemoryBlock` (``enable_block_supports``)."""


# ----------------------------------------------------------------------------- set-up
def make_rod(case: Case, n_elements: int, model: str = "pyelastica") -> ea.CosseratRod:
    """``straight_rod`` with the section constants overwritten to match ours exactly (the
    helix: given nodes and directors, rest strains and initial motion as in the module doc)."""
    cls = {"pyelastica": ea.CosseratRod, "linear": LinearCosseratRod}[model]
    shape = {}
    if case.geometry == "helix":
        state = helix_rod_state(n_elements, case.omega)
        shape = {"position": state["position"], "directors": state["directors"]}
    rod = cls.straight_rod(
        n_elements, start=np.zeros(3), direction=np.array([1.0, 0.0, 0.0]),
        normal=np.array([0.0, 1.0, 0.0]), base_length=case.length, base_radius=case.radius,
        density=case.rho, youngs_modulus=case.E, shear_modulus=case.G, **shape)
    if shape:  # stress-free in the curved initial configuration, moving with the rigid rotation
        rod.rest_sigma[...] = rod.sigma
        rod.rest_kappa[...] = rod.kappa
        rod.velocity_collection[...] = state["velocity"]
        rod.omega_collection[...] = state["omega"]
    dl = rod.rest_lengths
    S = np.diag([case.G * case.A, case.G * case.A, case.axial_factor * case.E * case.A])
    B = np.diag([case.E * case.I1, case.E * case.I2, case.G * case.J])
    Jd = np.array([case.I1, case.I2, case.I1 + case.I2])
    rod.shear_matrix[...] = S[:, :, None]
    rod.bend_matrix[...] = B[:, :, None]           # uniform rod: Voronoi averaging is exact
    rod.mass_second_moment_of_inertia[...] = 0.0
    rod.inv_mass_second_moment_of_inertia[...] = 0.0
    for k in range(3):
        rod.mass_second_moment_of_inertia[k, k, :] = case.rho * Jd[k] * dl
        rod.inv_mass_second_moment_of_inertia[k, k, :] = 1.0 / (case.rho * Jd[k] * dl)
    return rod


def check_rod(case: Case, rod) -> dict:
    """Per-length constants as PyElastica will use them (for the report)."""
    dl = rod.rest_lengths
    return {
        "A": float(np.pi * rod.radius[0] ** 2),
        "GA": float(rod.shear_matrix[0, 0, 0]), "EA": float(rod.shear_matrix[2, 2, 0]),
        "EI1": float(rod.bend_matrix[0, 0, 0]), "EI2": float(rod.bend_matrix[1, 1, 0]),
        "GJ": float(rod.bend_matrix[2, 2, 0]),
        "rhoA": float(rod.mass[1:-1].mean() / dl[0]),
        "rhoJ": [float(rod.mass_second_moment_of_inertia[k, k, 0] / dl[0]) for k in range(3)],
        "line_load": float(np.linalg.norm(case.gravity) * rod.mass.sum() / case.length),
    }


class TipRecorder(ea.CallBackBaseClass):
    """Tip (last node) every ``step_skip`` steps."""

    def __init__(self, step_skip: int, out: dict):
        super().__init__()
        self.every, self.out = step_skip, out

    def make_callback(self, system, time, current_step: int):
        if current_step % self.every == 0:
            self.out["t"].append(float(time))
            self.out["tip"].append(system.position_collection[:, -1].copy())


class _Sim(ea.BaseSystemCollection, ea.Constraints, ea.Forcing, ea.CallBacks):
    pass


@dataclass
class PeerResult:
    n_elements: int
    dt: float
    steps: int
    cpu_s: float
    wall_s: float
    t: np.ndarray
    tip: np.ndarray
    finite: bool
    constants: dict = field(default_factory=dict)


def run(case: Case, n_elements: int, dt: float, t_end: float, every: float,
        model: str = "pyelastica") -> PeerResult:
    """Integrate with ``PositionVerlet`` at step ``dt``; tip recorded every ``every`` s
    (``every`` must be a multiple of ``dt``; ``t_end`` of ``every``). ``model="linear"``:
    the diagnostic variant with our constitutive/inertia model (module doc)."""
    steps = int(round(t_end / dt))
    skip = int(round(every / dt))
    if abs(skip * dt - every) > 1e-9 * every or abs(steps * dt - t_end) > 1e-9 * t_end:
        raise ValueError(f"dt={dt} must divide every={every} and t_end={t_end}")
    sim = _Sim()
    rod = make_rod(case, n_elements, model)
    if model == "linear":
        sim.enable_block_supports(LinearCosseratRod, LinearMemoryBlock)
    sim.append(rod)
    if case.bc == "clamped":
        sim.constrain(rod).using(ea.OneEndFixedBC, constrained_position_idx=(0,),
                                 constrained_director_idx=(0,))
    else:  # pinned: node 0 fixed in all three directions, directors free
        sim.constrain(rod).using(ea.GeneralConstraint, constrained_position_idx=(0,),
                                 translational_constraint_selector=np.array([True, True, True]))
    if np.any(case.line_load):
        sim.add_forcing_to(rod).using(ea.GravityForces, acc_gravity=case.gravity)
    if np.any(case.tip_force):
        # ramp_up_time must be > 0 in PyElastica; forces are first evaluated at t = dt/2,
        # so any ramp shorter than dt/2 gives the full force at every evaluation.
        sim.add_forcing_to(rod).using(ea.EndpointForces, start_force=np.zeros(3),
                                      end_force=np.asarray(case.tip_force, float),
                                      ramp_up_time=1e-3 * dt)
    out = {"t": [], "tip": []}  # sim.finalize() calls the callback once at t = 0
    sim.collect_diagnostics(rod).using(TipRecorder, step_skip=skip, out=out)
    constants = check_rod(case, rod)
    sim.finalize()
    stepper = ea.PositionVerlet()
    t = np.float64(0.0)
    finite = True
    c0, w0 = time.process_time(), time.perf_counter()
    check_every = max(1, steps // 200)
    for i in range(steps):
        t = stepper.step(sim, t, dt)
        if i % check_every == 0 and not np.all(np.isfinite(rod.position_collection)):
            finite = False
            break
    cpu, wall = time.process_time() - c0, time.perf_counter() - w0
    finite = finite and bool(np.all(np.isfinite(rod.position_collection)))
    if not out["t"] or out["t"][0] != 0.0:
        raise RuntimeError("expected the t = 0 callback from sim.finalize()")
    return PeerResult(n_elements, dt, steps, cpu, wall, np.array(out["t"]), np.array(out["tip"]),
                      finite, constants)


def warm_up() -> None:
    """Compile PyElastica's numba kernels (cache=True) before any timing."""
    for make in CASES.values():
        case = make()
        for model in ("pyelastica", "linear"):
            run(case, 10, 1e-7, 1e-6, 1e-6, model)
