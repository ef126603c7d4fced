"""Scene kind ``free_body_se3``: a free rigid body translating and rotating in SE(3)."""

from __future__ import annotations

import numpy as np

from ..groups import SO3
from ..problems.errors import ParameterError
from ..problems.rigid_body_se3 import FreeBody
from .rigid_body import no_auto_step
from .scene import ProblemKind, Scene, Simulation, register_kind
from .schema import Key, SceneError

KEYS = {
    k.name: k
    for k in [
        Key("body.mass", "float", 1.0, "mass", "kg", lambda v: None if v > 0 else "a positive mass"),
        Key("body.inertia", "vec3", (1.0, 2.0, 3.0), "principal moments of inertia about the centre of mass",
            "kg m^2", lambda v: None if min(v) > 0 else "three positive moments"),
        Key("body.gravity", "vec3", (0.0, 0.0, -9.81), "gravitational acceleration (spatial)", "m/s^2"),
        Key("initial.position", "vec3", (0.0, 0.0, 0.0), "centre of mass", "m"),
        Key("initial.rotation", "vec3", (0.0, 0.0, 0.0), "attitude as a rotation vector (R0 = exp(hat(v)))", "rad"),
        Key("initial.velocity", "vec3", (0.0, 0.0, 0.0), "velocity of the centre of mass (spatial)", "m/s"),
        Key("initial.omega", "vec3", (0.0, 0.0, 0.0), "angular velocity (body frame)", "rad/s"),
    ]
}

COLUMNS = {
    "position": ["x", "y", "z"],
    "momentum": ["p_x", "p_y", "p_z"],
    "angular_momentum": ["h_x", "h_y", "h_z"],
}


def _body(scene: Scene) -> FreeBody:
    try:
        return FreeBody(mass=scene["body.mass"], inertia=scene["body.inertia"], gravity=scene["body.gravity"])
    except ParameterError as exc:
        raise SceneError(f"{scene.source}: key 'body.{exc.field}': {exc.reason}") from None


def check(scene: Scene) -> None:
    _body(scene)
    no_auto_step(scene)


def build(scene: Scene) -> Simulation:
    body = _body(scene)
    R0 = SO3.exp(np.asarray(scene["initial.rotation"], dtype=float))
    V0 = R0.T @ np.asarray(scene["initial.velocity"], dtype=float)  # body-frame velocity
    y0 = body.state(R0, np.asarray(scene["initial.position"], dtype=float), V0, np.asarray(scene["initial.omega"]))
    available = body.diagnostics()
    diagnostics = {q: available[q] for q in scene.output.quantities}

    def final_state(y):
        R, x, V, W = body.split(y)
        return {"R": R.tolist(), "position": x.tolist(), "velocity": (R @ V).tolist(), "omega_body": W.tolist()}

    return Simulation(problem=body.problem(), y0=y0, diagnostics=diagnostics, final_state=final_state,
                      info={"columns": {k: v for k, v in COLUMNS.items() if k in scene.output.quantities}},
                      conserved=None)


KIND = register_kind(ProblemKind(
    name="free_body_se3",
    keys=KEYS,
    quantities=("position", "energy", "momentum", "angular_momentum", "orth_error"),
    default_quantities=("position", "energy", "angular_momentum"),
    build=build,
    check=check,
    compiles=lambda scene: True,
))
