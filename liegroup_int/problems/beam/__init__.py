"""Geometrically exact beam: explicit RKMK isogeometric collocation (Ferri & Marino) and the
isogeometric Galerkin (weak) form."""

from .kinematics import curvature_update, jr_theta_s_derivative, jr_times, strains
from .model import (
    BoundaryConditions,
    EndBody,
    EndLoad,
    InitialConditions,
    Loads,
    Material,
    Profile,
    Section,
    SectionConstants,
    SupportMotion,
)
from .formulations import beam_problem
from .galerkin import GalerkinBeamProblem, GalerkinBeamState
from .problem import BeamProblem, BeamState, quadrature_weights
from .statics import StaticDivergence, StaticResult, Tangent, solve_static, tangent_matrix
from .buckling import BucklingResult, PrestressedModes, buckling_loads, prestressed_modes

__all__ = [
    "BeamProblem", "BeamState", "GalerkinBeamProblem", "GalerkinBeamState", "beam_problem", "Material", "Section", "SectionConstants", "Profile", "EndLoad", "EndBody", "Loads",
    "BoundaryConditions", "SupportMotion", "InitialConditions", "curvature_update", "jr_times",
    "jr_theta_s_derivative", "strains", "quadrature_weights", "solve_static", "StaticResult", "StaticDivergence",
    "Tangent", "tangent_matrix", "BucklingResult", "PrestressedModes", "buckling_loads", "prestressed_modes",
]
