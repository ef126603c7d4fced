"""Scenes: TOML files into validated frozen dataclasses, and the built-in scene registry."""

from . import beam as _beam  # noqa: F401  (registers the kind)
from . import rigid_body as _rigid_body  # noqa: F401  (registers the kind)
from . import rigid_body_se3 as _rigid_body_se3  # noqa: F401  (registers the kind)
from .registry import builtin_descriptions, builtin_names, builtin_path
from .scene import (KINDS, GuardSpec, IntegratorSpec, OutputSpec, ProblemKind, Scene, Simulation, Stability, build_scene,
                    load_scene, output_stride)
from .schema import Key, SceneError, parse_override

__all__ = [
    "KINDS", "Scene", "Simulation", "Stability", "ProblemKind", "IntegratorSpec", "OutputSpec", "GuardSpec", "Key",
    "SceneError",
    "load_scene", "build_scene", "parse_override", "builtin_names", "builtin_path", "builtin_descriptions",
    "output_stride",
]
