"""Homogeneous spaces: manifolds with a group of ours acting on them (RKMK on manifolds)."""

from .base import HomogeneousSpace
from .spaces import Isospectral, ProductSpace, RnSpace, Sphere, Stiefel, TangentSphere

__all__ = ["HomogeneousSpace", "Sphere", "TangentSphere", "Stiefel", "Isospectral", "RnSpace", "ProductSpace"]
