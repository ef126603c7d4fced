"""Lie groups with batched operations: R^n, SO(3), SE(3), SO(n), products and powers."""

from .base import LieGroup
from .product import Power, Product
from .rn import Rn
from .se3 import SE3
from .son import SOn
from .so3 import SO3, hat, left_jacobian, left_jacobian_inv, log_so3, exp_so3, vee

REGISTRY = {"SO3": SO3, "SE3": SE3}


def resolve(name_or_group):
    """Group from a name (``"SO3"``, ``"SE3"``, ``"R3"``) or a :class:`LieGroup`."""
    if isinstance(name_or_group, LieGroup):
        return name_or_group
    name = str(name_or_group)
    if name in REGISTRY:
        return REGISTRY[name]
    if name.startswith("R") and name[1:].isdigit():
        return Rn(int(name[1:]))
    if name.startswith("SO") and name[2:].isdigit():
        return SOn(int(name[2:]))
    raise KeyError(f"unknown group {name!r}; expected one of {sorted(REGISTRY)}, 'R<n>' or 'SO<n>'")


__all__ = [
    "LieGroup", "Rn", "SO3", "SE3", "SOn", "Product", "Power", "hat", "vee",
    "left_jacobian", "left_jacobian_inv", "exp_so3", "log_so3", "resolve", "REGISTRY",
]
