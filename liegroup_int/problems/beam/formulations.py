"""One constructor for every beam formulation: primal collocation or Galerkin."""

from __future__ import annotations

from ...iga.quadrature import DEFAULT_RULE
from .galerkin import GalerkinBeamProblem
from .model import BoundaryConditions, InitialConditions, Loads
from .problem import ALL_FORMULATIONS, BeamProblem


def beam_problem(space, constants, bcs: BoundaryConditions = BoundaryConditions(), loads: Loads = Loads(),
                 initial: InitialConditions = InitialConditions(), backend: str = "numpy",
                 kelvin_voigt: float = 0.0, formulation: str = "galerkin", quadrature: str = DEFAULT_RULE,
                 bodies: tuple = ()):
    """A :class:`~.galerkin.GalerkinBeamProblem` (``"galerkin"``, the default, with its
    ``quadrature`` rule and end ``bodies``) or a :class:`~.problem.BeamProblem` (``"primal"``
    collocation) with these arguments, as ``space.formulation`` of a scene."""
    if formulation not in ALL_FORMULATIONS:
        raise ValueError(f"formulation: expected one of {', '.join(ALL_FORMULATIONS)}, got {formulation!r}")
    if formulation == "galerkin":
        return GalerkinBeamProblem(space, constants, bcs, loads, initial, backend=backend, kelvin_voigt=kelvin_voigt,
                                   quadrature=quadrature, bodies=bodies)
    if bodies:
        raise ValueError(f'bodies need space.formulation = "galerkin" (got {formulation!r})')
    return BeamProblem(space, constants, bcs, loads, initial, backend=backend, kelvin_voigt=kelvin_voigt,
                       formulation=formulation)
