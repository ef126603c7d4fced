"""Isogeometric collocation layer: splines, collocation matrices, reference geometry.

Depends only on numpy and scipy.
"""

from .bspline import (
    band_widths,
    band_widths_from_spans,
    basis_derivatives,
    basis_derivatives_local,
    find_spans,
    to_banded,
)
from .collocation import (
    DEFAULT_MIN_ANGLE,
    CollocationSpace,
    arc_length,
    default_reference_vector,
    projection_frame,
    tangent_derivatives,
    vee,
)
from .galerkin import BandedSPD, GalerkinSpace, gauss_points
from .geometry import (
    ARCH_RADIUS,
    HELIX_RADIUS,
    arc_exact,
    arc_nurbs_quadratic,
    helix_quarter,
    helix_quarter_exact,
    straight,
)
from .knots import greville, open_uniform_knots, validate_knots
from .nurbs import (
    NurbsCurve,
    elevate_degree,
    insert_knots,
    interpolate_at_greville,
    k_refine,
    max_geometric_error,
    rational_derivatives,
)

__all__ = [
    "ARCH_RADIUS",
    "HELIX_RADIUS",
    "DEFAULT_MIN_ANGLE",
    "BandedSPD",
    "CollocationSpace",
    "GalerkinSpace",
    "NurbsCurve",
    "arc_exact",
    "arc_length",
    "arc_nurbs_quadratic",
    "band_widths",
    "band_widths_from_spans",
    "basis_derivatives",
    "basis_derivatives_local",
    "default_reference_vector",
    "elevate_degree",
    "find_spans",
    "gauss_points",
    "greville",
    "helix_quarter",
    "helix_quarter_exact",
    "insert_knots",
    "interpolate_at_greville",
    "k_refine",
    "max_geometric_error",
    "open_uniform_knots",
    "projection_frame",
    "rational_derivatives",
    "straight",
    "tangent_derivatives",
    "to_banded",
    "validate_knots",
    "vee",
]
