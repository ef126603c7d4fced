"""Butcher tableaux as exact, self-checking data.

This layer depends only on numpy and the standard library.  Public names:

* :class:`ButcherTableau` -- frozen dataclass with exact Fraction
  coefficients, validated on construction, plus float arrays ``A_f``,
  ``b_f``, ``c_f``, ``b_hat_f``, ``e_f``.
* Order conditions: :func:`trees_of_order`, :func:`trees_up_to`,
  :func:`tree_order`, :func:`density`, :func:`elementary_weight`,
  :func:`order_condition_residuals`, :func:`achieved_order`.
* Linear stability: :func:`stability_polynomial`,
  :func:`imaginary_axis_limit`, :func:`real_axis_limit`,
  :func:`imaginary_axis_growth`.
* Dense output: :func:`continuous_extension` (exact continuous weights, bootstrapped
  stages where needed), :class:`ContinuousExtension`.
* Registry: :data:`REGISTRY` (by tableau name), :data:`NAMES` (every accepted name,
  RKMK method names included), :func:`resolve` and one constant per method.
"""

from .base import ButcherTableau
from .continuous import ContinuousExtension, continuous_extension
from .commutator_free import CF3, CF4, CF_REGISTRY, CG3, CG4A, CommutatorFreeTableau
from .composition import COMPOSITIONS, STRANG, YOSHIDA4, YOSHIDA6, Composition
from .methods import (
    BS32,
    DP54,
    EULER,
    NAMES,
    REGISTRY,
    RK2,
    RK3,
    RK4,
    RK6,
    VERNER65,
    UnknownTableauError,
    resolve,
)
from .order_conditions import (
    KNOWN_TREE_COUNTS,
    LEAF,
    achieved_order,
    canonical,
    density,
    elementary_weight,
    first_failed_condition,
    order_condition_residuals,
    tree_order,
    tree_to_str,
    trees_of_order,
    trees_up_to,
)
from .stability import (
    imaginary_axis_growth,
    imaginary_axis_limit,
    real_axis_limit,
    stability_polynomial,
    stability_polynomial_exact,
)

__all__ = [
    "ButcherTableau",
    "Composition",
    "COMPOSITIONS",
    "STRANG",
    "YOSHIDA4",
    "YOSHIDA6",
    "CommutatorFreeTableau",
    "CF_REGISTRY",
    "CF3",
    "CF4",
    "CG3",
    "CG4A",
    "REGISTRY",
    "NAMES",
    "resolve",
    "UnknownTableauError",
    "EULER",
    "RK2",
    "RK3",
    "RK4",
    "RK6",
    "BS32",
    "DP54",
    "VERNER65",
    "KNOWN_TREE_COUNTS",
    "LEAF",
    "canonical",
    "tree_order",
    "density",
    "tree_to_str",
    "trees_of_order",
    "trees_up_to",
    "elementary_weight",
    "order_condition_residuals",
    "achieved_order",
    "first_failed_condition",
    "stability_polynomial",
    "stability_polynomial_exact",
    "imaginary_axis_limit",
    "real_axis_limit",
    "imaginary_axis_growth",
    "ContinuousExtension",
    "continuous_extension",
]
