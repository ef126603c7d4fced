"""Registry of named explicit Runge-Kutta tableaux.

Every constant is a :class:`~liegroup_int.tableaux.base.ButcherTableau`, so
each one has been checked exactly (row sums, consistency, all order
conditions up to its claimed order) when this module was imported.  The
imaginary-axis stability limits quoted below are the values computed by
:func:`liegroup_int.tableaux.stability.imaginary_axis_limit` (the tests check
the quoted value in each ``description`` against the computation).

Errata in Ferri & Marino, Appendix A (checked in the tests):

* Table A.2 (RK3) prints ``A32 = 1/2``; Kutta's method has ``A32 = 2``.  The
  printed row violates the row-sum condition (``-1 + 1/2 != c3 = 1``) and,
  with ``c = A 1``, only reaches order 1.
* Table A.4 (RK6, captioned "fourth-order") shifts row 6 one column to the
  left; Butcher's method has row 6 ``(0, 9/8, -3/8, -3/4, 1/2, 0)``.  The
  printed version passes the row sums but reaches only order 2.
"""

from __future__ import annotations

from .base import ButcherTableau
from .commutator_free import CF_REGISTRY, CommutatorFreeTableau


def _vec(text: str) -> tuple[str, ...]:
    """Whitespace-separated rationals ``'0 1/2 -3/4'`` -> tuple of strings."""
    return tuple(text.split())


def _lower(*rows: str) -> tuple[tuple[str, ...], ...]:
    """Strictly lower-triangular ``A`` from its nonempty rows 2..s.

    ``_lower('1/2', '0 3/4')`` is the 3x3 matrix with ``A21 = 1/2``,
    ``A31 = 0``, ``A32 = 3/4``; the first (zero) row is implicit and rows are
    zero-padded on the right.
    """
    s = len(rows) + 1
    full = [("0",) * s]
    for i, row in enumerate(rows, start=1):
        entries = _vec(row)
        if len(entries) > i:
            raise ValueError(f"_lower: row {i + 1} has {len(entries)} entries, at most {i} allowed")
        full.append(entries + ("0",) * (s - len(entries)))
    return tuple(full)


EULER = ButcherTableau(
    name="euler",
    method="rkmk1",
    A=(("0",),), b=("1",), c=("0",), order=1,
    description="Forward Euler (Euler 1768); imaginary-axis limit 0 (unstable on iR).",
)
"""Forward Euler, order 1, 1 stage.  Imaginary-axis limit 0: ``|R(iy)|^2 = 1 + y^2``."""

RK2 = ButcherTableau(
    name="rk2",
    method="rkmk2",
    A=_lower("1/2"), b=_vec("0 1"), c=_vec("0 1/2"), order=2,
    description="Explicit midpoint rule (Runge 1895; Ferri & Marino Table A.1); "
                "imaginary-axis limit 0 (|R(iy)| = sqrt(1 + y^4/4)).",
)
"""Explicit midpoint, order 2, 2 stages.  Imaginary-axis limit 0 (weakly unstable:
``|R(iy)| = sqrt(1 + y^4/4) ~ 1 + y^4/8``)."""

RK3 = ButcherTableau(
    name="rk3",
    method="rkmk3",
    A=_lower("1/2", "-1 2"), b=_vec("1/6 2/3 1/6"), c=_vec("0 1/2 1"), order=3,
    description="Kutta's third-order method (Kutta 1901; Ferri & Marino Table A.2 "
                "with the A32 misprint 1/2 -> 2 corrected); imaginary-axis limit 1.7321.",
)
"""Kutta's RK3, order 3, 3 stages.  Imaginary-axis limit ``sqrt(3) ~ 1.7321``.
The paper's Table A.2 prints ``A32 = 1/2`` (misprint, see module docstring)."""

RK4 = ButcherTableau(
    name="rk4",
    method="rkmk4",
    A=_lower("1/2", "0 1/2", "0 0 1"), b=_vec("1/6 1/3 1/3 1/6"), c=_vec("0 1/2 1/2 1"),
    order=4,
    description="Classical Runge-Kutta method (Kutta 1901; Ferri & Marino Table A.3); "
                "imaginary-axis limit 2.8284.",
)
"""Classical RK4, order 4, 4 stages.  Imaginary-axis limit ``2 sqrt(2) ~ 2.8284``."""

RK6 = ButcherTableau(
    name="rk6",
    method="rkmk6",
    A=_lower("1/3",
             "0 2/3",
             "1/12 1/3 -1/12",
             "-1/16 9/8 -3/16 -3/8",
             "0 9/8 -3/8 -3/4 1/2",
             "9/44 -9/11 63/44 18/11 0 -16/11"),
    b=_vec("11/120 0 27/40 27/40 -4/15 -4/15 11/120"),
    c=_vec("0 1/3 2/3 1/3 1/2 1/2 1"),
    order=6,
    description="Butcher's 7-stage sixth-order method (Butcher 1964, J. Austral. Math. "
                "Soc. 4; Ferri & Marino Table A.4 with row 6 corrected); "
                "imaginary-axis limit 0 (unstable on iR).",
)
"""Butcher's RK6, order 6, 7 stages.  Imaginary-axis limit 0 (``|R(iy)| > 1`` for
all small ``y > 0``).  The paper's Table A.4 shifts row 6 and calls the method
"fourth-order" (see module docstring)."""

BS32 = ButcherTableau(
    name="bs32",
    method="rkmk32",
    A=_lower("1/2", "0 3/4", "2/9 1/3 4/9"),
    b=_vec("2/9 1/3 4/9 0"), c=_vec("0 1/2 3/4 1"), order=3,
    b_hat=_vec("7/24 1/4 1/3 1/8"), order_hat=2, fsal=True,
    description="Bogacki-Shampine 3(2) FSAL pair (Bogacki & Shampine 1989, Appl. Math. "
                "Lett. 2); imaginary-axis limit 1.7321.",
)
"""Bogacki-Shampine 3(2), order 3 (embedded 2), 4 stages (3 effective, FSAL).
Imaginary-axis limit ``sqrt(3) ~ 1.7321`` (same ``R`` as every 3-stage RK3)."""

DP54 = ButcherTableau(
    name="dp54",
    method="rkmk45",
    A=_lower("1/5",
             "3/40 9/40",
             "44/45 -56/15 32/9",
             "19372/6561 -25360/2187 64448/6561 -212/729",
             "9017/3168 -355/33 46732/5247 49/176 -5103/18656",
             "35/384 0 500/1113 125/192 -2187/6784 11/84"),
    b=_vec("35/384 0 500/1113 125/192 -2187/6784 11/84 0"),
    c=_vec("0 1/5 3/10 4/5 8/9 1 1"),
    order=5,
    b_hat=_vec("5179/57600 0 7571/16695 393/640 -92097/339200 187/2100 1/40"),
    order_hat=4, fsal=True,
    description="Dormand-Prince 5(4) FSAL pair (Dormand & Prince 1980, J. Comput. Appl. "
                "Math. 6); imaginary-axis limit 0.9972.",
)
"""Dormand-Prince 5(4), order 5 (embedded 4), 7 stages (6 effective, FSAL).
Imaginary-axis limit ~0.9972 (``|R(iy)|^2 - 1 = y^6 (-1/1800 + y^2/1600 - ...)``);
real-axis limit ~3.3066."""

VERNER65 = ButcherTableau(
    name="verner65",
    method="rkmk65",
    A=_lower(
        "3/50",
        "519479/27000000 2070721/27000000",
        "1439/40000 0 4317/40000",
        "109225017611/82828840000 0 -417627820623/82828840000 43699198143/10353605000",
        "-8036815292643907349452552172369/191934985946683241245914401600 0 "
        "246134619571490020064824665/1543816496655405117602368 "
        "-13880495956885686234074067279/113663489566254201783474344 "
        "755005057777788994734129/136485922925633667082436",
        "-1663299841566102097180506666498880934230261/30558424506156170307020957791311384232000 0 "
        "130838124195285491799043628811093033/631862949514135618861563657970240 "
        "-3287100453856023634160618787153901962873/20724314915376755629135711026851409200 "
        "2771826790140332140865242520369241/396438716042723436917079980147600 "
        "-1799166916139193/96743806114007800",
        "-832144750039369683895428386437986853923637763/15222974550069600748763651844667619945204887 0 "
        "818622075710363565982285196611368750/3936576237903728151856072395343129 "
        "-9818985165491658464841194581385463434793741875/61642597962658994069869370923196463581866011 "
        "31796692141848558720425711042548134769375/4530254033500045975557858016006308628092 "
        "-14064542118843830075/766928748264306853644 "
        "-1424670304836288125/2782839104764768088217",
        "382735282417/11129397249634 0 0 5535620703125000/21434089949505429 "
        "13867056347656250/32943296570459319 626271188750/142160006043 "
        "-51160788125000/289890548217 163193540017/946795234",
    ),
    b=_vec("382735282417/11129397249634 0 0 5535620703125000/21434089949505429 "
           "13867056347656250/32943296570459319 626271188750/142160006043 "
           "-51160788125000/289890548217 163193540017/946795234 0"),
    c=_vec("0 3/50 1439/15000 1439/10000 4973/10000 389/400 1999/2000 1 1"),
    order=6,
    b_hat=_vec("124310637869885675646798613/2890072468789466426596827670 0 0 "
               "265863151737164990361330921875/1113197271463372303940319369579 "
               "3075493557174030806536302953125/6843749922042323876546949699876 "
               "67798000008733879813263055/29532792147666737550036372 "
               "-1099436585155390846238326375/15055706496446408859196167 "
               "26171252653086373181571802/368794478890732346033505 1/30"),
    order_hat=5, fsal=True,
    description="Verner's 'most efficient' 9-stage 6(5) FSAL pair (Verner 2010, Numer. "
                "Algorithms 53; coefficients as in OrdinaryDiffEq.jl Vern6); "
                "imaginary-axis limit 2.5842.",
)
"""Verner 6(5) 'efficient' pair, order 6 (embedded 5), 9 stages (8 effective, FSAL).
Imaginary-axis limit ~2.5842, real-axis limit ~4.8553."""

REGISTRY: dict[str, ButcherTableau] = {
    "euler": EULER,
    "rk2": RK2,
    "rk3": RK3,
    "rk4": RK4,
    "rk6": RK6,
    "bs32": BS32,
    "dp54": DP54,
    "verner65": VERNER65,
}
"""All named tableaux, keyed by registry name (``REGISTRY[k].name == k``)."""


def _names(tableaux) -> dict[str, ButcherTableau]:
    """Every accepted name (registry name and RKMK method name) -> tableau; names unique."""
    names: dict[str, ButcherTableau] = {}
    for tab in tableaux:
        for key in dict.fromkeys(filter(None, (tab.name, tab.method))):
            if key in names:
                raise ValueError(f"tableau name {key!r} is registered twice")
            names[key] = tab
    return names


NAMES: dict[str, ButcherTableau] = _names([*REGISTRY.values(), *CF_REGISTRY.values()])
"""Every name :func:`resolve` accepts: the registry names and the RKMK method names
(``"rkmk4"``), and the commutator-free schemes (``"cf4"``, ``"cg4a"``,
:mod:`.commutator_free`): the one list scenes, the CLI and ``integrate`` share."""


class UnknownTableauError(KeyError, ValueError):
    """Unknown tableau name (both a ``KeyError`` and a ``ValueError``)."""

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""


def resolve(name_or_tableau: str | ButcherTableau) -> ButcherTableau:
    """Return the tableau itself, or the registry entry of that name.

    Parameters
    ----------
    name_or_tableau : str or ButcherTableau
        Registry name or RKMK method name (:data:`NAMES`, case-insensitive), or a
        tableau.

    Returns
    -------
    ButcherTableau

    Raises
    ------
    UnknownTableauError
        Unknown name (subclass of both ``KeyError`` and ``ValueError``).
    TypeError
        Neither a string nor a tableau.
    """
    if isinstance(name_or_tableau, (ButcherTableau, CommutatorFreeTableau)):
        return name_or_tableau
    if not isinstance(name_or_tableau, str):
        raise TypeError(f"expected a tableau name or ButcherTableau, got "
                        f"{type(name_or_tableau).__name__}")
    key = name_or_tableau.strip().lower()
    if key not in NAMES:
        raise UnknownTableauError(f"unknown method {name_or_tableau!r}; expected one of: "
                                  f"{', '.join(sorted(NAMES))}")
    return NAMES[key]
