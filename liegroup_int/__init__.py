"""liegroup_int: high-order explicit Runge-Kutta-Munthe-Kaas integration on Lie groups."""

from .groups import SE3, SO3, LieGroup, Power, Product, Rn, SOn
from .integrators import (
    METHODS,
    ActionProblem,
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
from .manifolds import HomogeneousSpace, Isospectral, ProductSpace, RnSpace, Sphere, Stiefel, TangentSphere

__version__ = "0.1.0"

__all__ = [
    "SO3", "SE3", "SOn", "Rn", "Product", "Power", "LieGroup", "integrate", "Problem", "GroupProblem",
    "ActionProblem", "HomogeneousSpace", "Sphere", "TangentSphere", "Stiefel", "Isospectral", "RnSpace",
    "ProductSpace",
    "Solution", "StateRecorder", "DiagnosticsRecorder", "METHODS", "resolve_method",
    "IntegrationError", "BlowUpError", "__version__", "solve_static", "prestressed_modes", "buckling_loads",
]


def __getattr__(name):
    """``solve_static`` (:mod:`liegroup_int.problems.beam.statics`), ``prestressed_modes``
    and ``buckling_loads`` (:mod:`liegroup_int.problems.beam.buckling`), imported on first
    use so that ``import liegroup_int`` stays light."""
    if name == "solve_static":
        from .problems.beam.statics import solve_static

        return solve_static
    if name in ("prestressed_modes", "buckling_loads"):
        from .problems.beam import buckling

        return getattr(buckling, name)
    raise AttributeError(f"module 'liegroup_int' has no attribute {name!r}")
