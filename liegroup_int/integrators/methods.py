"""Named methods: the tableau registry, addressed by method name, and the splitting
compositions.

A method is registered once, as a tableau constant with its ``method`` name in
:mod:`liegroup_int.tableaux.methods`; :data:`METHODS` and :func:`resolve_method` are
derived from it, so scenes, the CLI and ``integrate`` accept the same names. The
symplectic splitting compositions (``strang``, ``yoshida4``, ``yoshida6``,
:data:`~liegroup_int.tableaux.composition.COMPOSITIONS`) are the other kind of method:
:func:`resolve_scheme` takes either.
"""

from __future__ import annotations

from ..tableaux import CF_REGISTRY, COMPOSITIONS
from ..tableaux import REGISTRY as TABLEAUX
from ..tableaux import ButcherTableau, Composition, resolve

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


def resolve_scheme(method: "str | ButcherTableau | Composition") -> "ButcherTableau | Composition":
    """The splitting composition of a name in :data:`COMPOSITIONS` (or a composition),
    else the tableau of :func:`resolve_method`."""
    if isinstance(method, Composition):
        return method
    if isinstance(method, str) and method in COMPOSITIONS:
        return COMPOSITIONS[method]
    return resolve_method(method)


def is_splitting(scheme) -> bool:
    """Whether ``scheme`` is a splitting composition (fixed steps on the problem's own
    ``split_steps``, :mod:`liegroup_int.integrators.splitting`)."""
    return isinstance(scheme, Composition)
