"""Stable fixed steps from a spectral radius and the tableau's stability polynomial."""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..tableaux import ButcherTableau, Composition, imaginary_axis_growth, imaginary_axis_limit

#: Fraction of the imaginary-axis stability limit used by ``dt = "auto"``.
SAFETY = 0.8
#: Largest amplification of an undamped mode allowed over a whole run for methods that
#: are unstable on the imaginary axis (Euler, the explicit midpoint rule, Butcher's RK6).
GROWTH_BUDGET = 2.0


@dataclass(frozen=True)
class StableStep:
    """A step size and why it was chosen.

    Attributes
    ----------
    dt : float
    y : float
        ``|lambda|max * dt``.
    rule : str
        ``"imaginary-axis limit"`` or ``"growth budget"``.
    warning : str or None
        Set for methods that amplify undamped modes at every step.
    """

    dt: float
    y: float
    rule: str
    warning: str | None


def step_limit(scheme) -> float:
    """Largest ``|lambda| dt`` of an undamped mode the method keeps bounded: the tableau's
    imaginary-axis limit (0 when it has none), or for a splitting composition of
    kick-drift-kick substeps ``2 / max |gamma|``."""
    if isinstance(scheme, Composition):
        return 2.0 / float(max(abs(g) for g in scheme.gammas_f))
    return imaginary_axis_limit(scheme)


def stable_step(tab: "ButcherTableau | Composition", lam_max: float, duration: float, safety: float = SAFETY,
                growth_budget: float = GROWTH_BUDGET) -> StableStep:
    """Step for an undamped problem whose linearized spectrum lies on the imaginary axis
    with largest magnitude ``lam_max``.

    Methods stable on a segment ``[-i y*, i y*]`` get ``dt = safety * y* / lam_max``, with
    ``y*`` computed from the stability polynomial. Methods with ``y* = 0`` amplify every
    undamped mode by ``|R(i y)| > 1`` per step; for them ``y`` is the largest value with
    ``|R(i y)|^(duration lam_max / y) <= growth_budget``, i.e. the highest mode grows by at
    most ``growth_budget`` over the run, and a warning says so. A splitting composition
    gets :func:`stable_split_step`.
    """
    if not (lam_max > 0 and duration > 0):
        raise ValueError(f"stable_step: need lam_max > 0 and duration > 0, got {lam_max!r}, {duration!r}")
    if isinstance(tab, Composition):
        return stable_split_step(tab, lam_max, safety)
    limit = imaginary_axis_limit(tab)
    if limit > 0:
        y = safety * limit
        return StableStep(y / lam_max, y, "imaginary-axis limit", None)
    budget = math.log(growth_budget) / (duration * lam_max)

    def excess(y):  # log growth per unit y, minus the budget: increasing in y
        return math.log(float(imaginary_axis_growth(tab, y))) / y - budget

    lo, hi = 1e-8, 3.0
    if excess(hi) <= 0:
        y = hi
    else:
        for _ in range(100):
            mid = math.sqrt(lo * hi)
            lo, hi = (mid, hi) if excess(mid) <= 0 else (lo, mid)
        y = lo
    warning = (f"{tab.name} is unstable on the imaginary axis (|R(iy)| > 1 for every y > 0); "
               f"dt chosen so the fastest mode grows by at most {growth_budget:g}x over {duration:g} s")
    return StableStep(y / lam_max, y, "growth budget", warning)


def stable_split_step(comp, lam_max: float, safety: float = SAFETY) -> StableStep:
    """Step of a symmetric composition ``comp`` of a kick-drift-kick (Stormer-Verlet)
    splitting for an undamped problem whose linearized spectrum lies on the imaginary axis
    with largest magnitude ``lam_max``: each substep of length ``gamma h`` is stable while
    ``|gamma| h lam_max < 2``, so ``dt = safety * 2 / (max |gamma| lam_max)``."""
    if not lam_max > 0:
        raise ValueError(f"stable_split_step: need lam_max > 0, got {lam_max!r}")
    y = safety * step_limit(comp)
    return StableStep(y / lam_max, y, "kick-drift-kick limit", None)
