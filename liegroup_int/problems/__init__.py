"""Problem plugins for the RKMK integrators."""

from .rigid_body import RigidBody, axisymmetric_free_rotation

__all__ = ["RigidBody", "axisymmetric_free_rotation"]
