"""Homogeneous spaces: manifolds with a group of ours acting on them (RKMK on manifolds)."""

from .base import HomogeneousSpace
from .spaces import Isospectral, ProductSpace, RnSpace, Sphere, Stiefel

__all__ = ["HomogeneousSpace", "Sphere", "Stiefel", "Isospectral", "RnSpace", "ProductSpace"]
