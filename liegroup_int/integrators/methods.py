"""Named RKMK methods: the tableau registry, addressed by method name.

A method is registered once, as a tableau constant with its ``method`` name in
:mod:`liegroup_int.tableaux.methods`; :data:`METHODS` and :func:`resolve_method` are
derived from it, so scenes, the CLI and ``integrate`` accept the same names.
"""

from __future__ import annotations

from ..tableaux import CF_REGISTRY
from ..tableaux import REGISTRY as TABLEAUX
from ..tableaux import ButcherTableau, resolve

#: RKMK method name -> tableau name (``"rkmk4" -> "rk4"``). On R^n problems they are
#: classical RK.
METHODS: dict[str, str] = {tab.method: tab.name for tab in [*TABLEAUX.values(), *CF_REGISTRY.values()] if tab.method}


def resolve_method(method: "str | ButcherTableau") -> ButcherTableau:
    """Tableau for a method name (``"rkmk4"``), a tableau name (``"rk4"``, any case) or a
    tableau. An unknown name raises ``UnknownTableauError`` (a ``ValueError`` and a
    ``KeyError``) listing the choices."""
    return resolve(method)


def is_adaptive(tab: ButcherTableau) -> bool:
    """Whether the tableau carries embedded weights for error control."""
    return tab.b_hat is not None


def is_commutator_free(tab) -> bool:
    """Whether the method composes exponentials without dexpinv
    (:mod:`liegroup_int.tableaux.commutator_free`): the generic fixed-step loop runs it, the
    compiled engine and the adaptive driver do not."""
    return getattr(tab, "kind", "") == "commutator_free"
