"""Problem plugins for the RKMK integrators."""

from .errors import ParameterError
from .n_pendulum import NPendulum, NPendulumProblem
from .rigid_body import RigidBody, RigidBodyProblem, axisymmetric_free_rotation

__all__ = ["NPendulum", "NPendulumProblem", "ParameterError", "RigidBody", "RigidBodyProblem",
           "axisymmetric_free_rotation"]
