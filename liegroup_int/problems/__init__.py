"""Problem plugins for the RKMK integrators."""

from .errors import ParameterError
from .rigid_body import RigidBody, RigidBodyProblem, axisymmetric_free_rotation

__all__ = ["ParameterError", "RigidBody", "RigidBodyProblem", "axisymmetric_free_rotation"]
