"""Named RKMK methods: one explicit registry from method name to Butcher tableau."""

from __future__ import annotations

from ..tableaux import REGISTRY as TABLEAUX
from ..tableaux import ButcherTableau

#: Method names used by scenes and the CLI. On R^n problems they are classical RK.
METHODS: dict[str, str] = {
    "rkmk1": "euler",  # Lie-Euler
    "rkmk2": "rk2",  # explicit midpoint (paper Table A.1)
    "rkmk3": "rk3",  # Kutta's RK3 (paper Table A.2, corrected)
    "rkmk4": "rk4",  # classical RK4 (paper Table A.3)
    "rkmk6": "rk6",  # Butcher's 7-stage RK6 (paper Table A.4, corrected)
    "rkmk32": "bs32",  # Bogacki-Shampine 3(2)
    "rkmk45": "dp54",  # Dormand-Prince 5(4)
    "rkmk65": "verner65",  # Verner 6(5)
}


def resolve_method(method: "str | ButcherTableau") -> ButcherTableau:
    """Tableau for a method name (``"rkmk4"``), a tableau name (``"rk4"``) or a tableau."""
    if isinstance(method, ButcherTableau):
        return method
    name = str(method)
    if name in METHODS:
        return TABLEAUX[METHODS[name]]
    if name in TABLEAUX:
        return TABLEAUX[name]
    valid = ", ".join(sorted(METHODS) + sorted(TABLEAUX))
    raise KeyError(f"unknown method {name!r}; expected one of: {valid}")


def is_adaptive(tab: ButcherTableau) -> bool:
    """Whether the tableau carries embedded weights for error control."""
    return tab.b_hat is not None
