"""Problem plugins for the RKMK integrators."""

from .rigid_body import RigidBody, RigidBodyProblem, axisymmetric_free_rotation

__all__ = ["RigidBody", "RigidBodyProblem", "axisymmetric_free_rotation"]
