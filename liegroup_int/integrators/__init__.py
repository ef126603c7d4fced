"""Explicit RK/RKMK integrators on any problem plugin (docs/theory.md section 2)."""

from .api import integrate
from .dense import DenseSolution
from .drivers import MAX_INCREMENT_ANGLE, initial_step, integrate_adaptive, integrate_fixed, stepper_for
from .methods import METHODS, is_adaptive, is_splitting, resolve_method, resolve_scheme
from .observers import DiagnosticsRecorder, Observers, StateRecorder
from .problem import ActionProblem, GroupProblem, Problem
from .result import BlowUpError, IntegrationError, Solution, Stats, StepSizeError
from .spectrum import GrowthReport, ModalReport, Mode, eigenvalues, growth_check, jacobian, modal_analysis, spectral_radius
from .stepsize import StableStep, stable_split_step, stable_step, step_limit
from .rkmk import combine, compute_stages, error_estimate, error_norm, rkmk_step

__all__ = [
    "integrate", "DenseSolution", "integrate_fixed", "integrate_adaptive", "initial_step", "stepper_for", "MAX_INCREMENT_ANGLE",
    "METHODS", "resolve_method", "resolve_scheme", "is_splitting", "is_adaptive", "StateRecorder", "DiagnosticsRecorder", "Observers",
    "Problem", "GroupProblem", "ActionProblem", "Solution", "Stats", "IntegrationError", "BlowUpError", "StepSizeError",
    "combine", "eigenvalues", "growth_check", "GrowthReport", "jacobian", "spectral_radius", "modal_analysis",
    "ModalReport", "Mode", "StableStep", "stable_split_step", "stable_step", "step_limit", "compute_stages", "error_estimate", "error_norm", "rkmk_step",
]
