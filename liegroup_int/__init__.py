"""liegroup_int: high-order explicit Runge-Kutta-Munthe-Kaas integration on Lie groups."""

from .groups import SE3, SO3, LieGroup, Power, Product, Rn
from .integrators import (
    METHODS,
    BlowUpError,
    DiagnosticsRecorder,
    GroupProblem,
    IntegrationError,
    Problem,
    Solution,
    StateRecorder,
    integrate,
    resolve_method,
)

__version__ = "0.1.0"

__all__ = [
    "SO3", "SE3", "Rn", "Product", "Power", "LieGroup", "integrate", "Problem", "GroupProblem",
    "Solution", "StateRecorder", "DiagnosticsRecorder", "METHODS", "resolve_method",
    "IntegrationError", "BlowUpError", "__version__",
]
