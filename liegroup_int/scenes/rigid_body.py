"""Scene kind ``rigid_body``: free rigid body and heavy top on SO(3) x R^3."""

from __future__ import annotations

import numpy as np

from ..groups import SO3
from ..problems.errors import ParameterError
from ..problems.rigid_body import RigidBody
from .scene import ProblemKind, Scene, Simulation, register_kind
from .schema import Key, SceneError, non_negative

KEYS = {
    k.name: k
    for k in [
        Key("body.inertia", "vec3", (1.0, 2.0, 3.0), "principal moments of inertia about the fixed point", "kg m^2",
            lambda v: None if min(v) > 0 else "three positive moments"),
        Key("body.mass", "float", 0.0, "mass (0: free rigid body)", "kg", non_negative),
        Key("body.com", "vec3", (0.0, 0.0, 0.0), "centre of mass in body coordinates, from the fixed point", "m"),
        Key("body.gravity", "float", 9.81, "gravitational acceleration along -x3", "m/s^2", non_negative),
        Key("initial.rotation", "vec3", (0.0, 0.0, 0.0), "initial attitude as a rotation vector (R0 = exp(hat(v)))", "rad"),
        Key("initial.omega", "vec3", (0.0, 0.0, 0.0), "initial body angular velocity", "rad/s"),
    ]
}


def _body(scene: Scene) -> RigidBody:
    try:
        return RigidBody(inertia=scene["body.inertia"], mass=scene["body.mass"], com=scene["body.com"],
                         gravity=scene["body.gravity"])
    except ParameterError as exc:
        raise SceneError(f"{scene.source}: key 'body.{exc.field}': {exc.reason}") from None


def no_auto_step(scene: Scene) -> None:
    """Refuse ``integrator.dt = "auto"`` (a stable-step estimate exists for beams only)."""
    if scene.integrator.dt == "auto":
        raise SceneError(f"{scene.source}: key 'integrator.dt' = 'auto': automatic steps are available for beam scenes only")


def check(scene: Scene) -> None:
    _body(scene)
    no_auto_step(scene)


#: Fixed-step runs of fewer stage evaluations than this stay in NumPy: numba's start-up in
#: a process (import, loading the cached kernels: about 0.8 s) costs as much as about
#: 20,000 stages of the NumPy path (measured 35-45 us per stage on the heavy top; the
#: compiled engine takes 0.2 us). benchmarks/run_overhead.py measures both sides.
NUMPY_BELOW_STAGES = 20_000


def compiles(scene: Scene) -> bool:
    """Whether the run uses the compiled kernels: adaptive runs, and fixed-step runs of at
    least :data:`NUMPY_BELOW_STAGES` stage evaluations."""
    spec = scene.integrator
    if not isinstance(spec.dt, float):
        return True
    from ..integrators import resolve_scheme

    return scene.t_end / spec.dt * resolve_scheme(spec.method).stages >= NUMPY_BELOW_STAGES


def build(scene: Scene) -> Simulation:
    body = _body(scene)
    R0 = SO3.exp(np.asarray(scene["initial.rotation"]))
    y0 = body.state(R0, np.asarray(scene["initial.omega"]))
    available = body.diagnostics()
    diagnostics = {q: available[q] for q in scene.output.quantities}

    def final_state(y):
        R, W = body.split(y)
        return {"R": R.tolist(), "omega_body": W.tolist(), "omega_spatial": (R @ W).tolist()}

    compiled = compiles(scene)
    return Simulation(problem=body.problem(compiled), y0=y0, diagnostics=diagnostics, final_state=final_state,
                      info={"kernels": "numba" if compiled else "numpy (short run)"})


KIND = register_kind(ProblemKind(
    name="rigid_body",
    keys=KEYS,
    quantities=("energy", "casimir", "orth_error"),
    default_quantities=("energy", "casimir", "orth_error"),
    build=build,
    check=check,
    compiles=compiles,
))
