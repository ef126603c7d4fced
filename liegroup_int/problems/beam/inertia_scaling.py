"""Rotary-inertia scaling: a larger stable step for a stated shift of the low modes.

An explicit step is bounded by the top of the linearized spectrum. On a shear-deformable
beam one branch of it, the shear-rotation branch, starts at the cut-off
``sqrt(k G A / (rho I))`` and does not fall as the mesh is refined. Multiplying the bending
rotary inertia ``rho I_1, rho I_2`` by ``s >= 1`` lowers that branch by ``sqrt(s)`` until
another branch (axial, transverse shear) sets the top, and moves the bending modes by their
rotary-inertia correction, ``O(s (r k)^2)`` with ``r`` the radius of gyration. Explicit
finite-element codes offer this for beams; here the factor is chosen from the Galerkin
modal analysis (:func:`~.galerkin_linear.natural_frequencies`):

* ``scale_for_tolerance``: the largest ``s`` whose lowest ``modes`` distinct frequencies
  move by at most ``tol`` (relative);
* or, if smaller, the smallest ``s`` whose top frequency is within :data:`SATURATION` of
  its floor (the top at :data:`MAX_SCALE`): beyond it the shear-rotation branch no longer
  sets the step, and more scaling costs accuracy for nothing.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .galerkin_linear import distinct_frequencies, natural_frequencies

__all__ = ["RotaryInertiaReport", "SATURATION", "MAX_SCALE", "MAX_UNKNOWNS", "given_scale_report",
           "rotary_inertia_shift", "size_rotary_inertia"]

#: A factor within which the top frequency counts as reached (1 %).
SATURATION = 0.01
#: Largest factor searched.
MAX_SCALE = 1e4
#: Largest number of unknowns (6 n_ctrl) of the dense generalized eigenproblem.
MAX_UNKNOWNS = 1500
#: Bisection ends when the bracket's ratio is below this.
_BRACKET = 1.005


@dataclass(frozen=True)
class RotaryInertiaReport:
    """A rotary-inertia factor and what it does to the spectrum at rest.

    Attributes
    ----------
    scale : float
        Factor on ``rho I_1, rho I_2``.
    modes, tol : int, float
        The lowest distinct modes checked and the relative shift allowed (``tol`` is None
        for a factor given by the user).
    shifts : tuple of float
        Relative frequency shift ``omega(s) / omega(1) - 1`` of each of those modes (<= 0).
    omega_max : (float, float)
        Top frequency [rad/s] unscaled and scaled; their ratio is the stable step's gain.
    limit : str
        What set the factor: ``"tolerance"``, ``"saturation"`` (the top no longer falls),
        ``"maximum"`` (:data:`MAX_SCALE`) or ``"given"``.
    """

    scale: float
    modes: int
    tol: float | None
    shifts: tuple
    omega_max: tuple
    limit: str

    @property
    def max_shift(self) -> float:
        return float(max(abs(x) for x in self.shifts))

    @property
    def step_gain(self) -> float:
        return float(self.omega_max[0] / self.omega_max[1])

    def as_dict(self) -> dict:
        return {"scale": self.scale, "limit": self.limit, "modes": self.modes, "tol": self.tol,
                "max_shift": self.max_shift, "shifts": list(self.shifts),
                "omega_max": list(self.omega_max), "step_gain": self.step_gain}


def _check_size(pb) -> None:
    if 6 * pb.n > MAX_UNKNOWNS:
        raise ValueError(f"the modal check is a dense eigenproblem of 6 n_ctrl = {6 * pb.n} unknowns, above "
                         f"{MAX_UNKNOWNS}; give a number")


def rotary_inertia_shift(pb, scale: float, modes: int, base: np.ndarray | None = None):
    """``(shifts, omega_max)`` of the Galerkin problem ``pb`` with its rotary inertia scaled:
    relative shifts of the lowest ``modes`` distinct frequencies (rigid modes below 1 rad/s
    left out) and the top frequency. ``base``: the unscaled spectrum, if known."""
    w1 = natural_frequencies(pb) if base is None else base
    ws = natural_frequencies(pb, scale)
    low1 = distinct_frequencies(w1, modes)
    lows = distinct_frequencies(ws, len(low1))
    return tuple(float(x) for x in lows / low1 - 1.0), float(ws[-1])


def _bisect(ok, lo: float, hi: float) -> tuple[float, float]:
    """The bracket ``(a, b)``, ``b / a`` below :data:`_BRACKET`, of the threshold of ``ok`` in
    ``[lo, hi]`` (``ok`` true below it, false above; ``ok(lo)`` true, ``ok(hi)`` false)."""
    while hi / lo > _BRACKET:
        mid = math.sqrt(lo * hi)
        lo, hi = (mid, hi) if ok(mid) else (lo, mid)
    return lo, hi


def size_rotary_inertia(pb, modes: int = 6, tol: float = 1e-3) -> RotaryInertiaReport:
    """The factor of ``section.rotary_inertia_scale = "auto"`` for the Galerkin problem ``pb``
    built unscaled (module docstring)."""
    if not (modes >= 1 and tol > 0):
        raise ValueError(f"need modes >= 1 and tol > 0, got {modes!r}, {tol!r}")
    _check_size(pb)
    base = natural_frequencies(pb)
    if not len(distinct_frequencies(base[base > 1.0], modes)):
        raise ValueError("no mode above 1 rad/s to check")

    def shift(s):
        return max(abs(x) for x in rotary_inertia_shift(pb, s, modes, base)[0])

    if shift(MAX_SCALE) <= tol:
        scale, limit = MAX_SCALE, "maximum"
    else:
        scale, limit = _bisect(lambda s: shift(s) <= tol, 1.0, MAX_SCALE)[0], "tolerance"
    floor = (1 + SATURATION) * natural_frequencies(pb, MAX_SCALE)[-1]
    if base[-1] <= floor:
        scale, limit = 1.0, "saturation"
    elif natural_frequencies(pb, scale)[-1] <= floor:
        scale, limit = _bisect(lambda s: natural_frequencies(pb, s)[-1] > floor, 1.0, scale)[1], "saturation"
    shifts, top = rotary_inertia_shift(pb, scale, modes, base)
    return RotaryInertiaReport(float(scale), len(shifts), float(tol), shifts, (float(base[-1]), top), limit)


def given_scale_report(pb, scale: float, modes: int = 6) -> RotaryInertiaReport:
    """The report of a factor given by the user, for ``pb`` built with it."""
    _check_size(pb)
    base = natural_frequencies(pb, 1.0 / scale)
    ws = natural_frequencies(pb)
    low1 = distinct_frequencies(base, modes)
    shifts = tuple(float(x) for x in distinct_frequencies(ws, len(low1)) / low1 - 1.0)
    return RotaryInertiaReport(float(scale), len(shifts), None, shifts, (float(base[-1]), float(ws[-1])), "given")
