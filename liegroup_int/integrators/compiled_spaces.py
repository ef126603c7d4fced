"""The one dispatch table of the compiled engine for ODEs on homogeneous spaces.

An :class:`~.problem.ActionProblem` whose ``f`` is a ``numba.njit`` function runs in the
compiled engine on the spaces listed in :data:`SPACE_KERNELS` (single points, exp
coordinates); on any other space it keeps the generic loop.
"""

from __future__ import annotations

from ..manifolds import Isospectral, ProductSpace, Sphere, Stiefel, TangentSphere
from .compiled_group import sphere_kernels, tangent_sphere_kernels
from .compiled_son import son_space_kernels
from .engine import CompiledProblem


def _tangent_sphere_power(problem, order):
    if order is not None or not all(type(f) is TangentSphere for f in problem.space.factors):
        return None
    return tangent_sphere_kernels(problem)


#: ``type(space) -> kernels(problem, dexpinv_order)``: the SO(3)/SE(3) spaces use the groups'
#: closed-form dexpinv (no truncation order), the SO(n) spaces the series to the order.
SPACE_KERNELS = {
    Sphere: lambda pb, order: sphere_kernels(pb) if order is None else None,
    TangentSphere: lambda pb, order: tangent_sphere_kernels(pb) if order is None else None,
    ProductSpace: _tangent_sphere_power,
    Stiefel: son_space_kernels,
    Isospectral: son_space_kernels,
}


def space_kernels(problem, order: int | None = None) -> CompiledProblem | None:
    """The engine's view of ``problem`` (an ``ActionProblem`` with a compiled ``f``) from
    :data:`SPACE_KERNELS`, or ``None`` (the generic loop)."""
    make = SPACE_KERNELS.get(type(problem.space))
    return None if make is None else make(problem, order)
