"""The step-size controller of the adaptive loops: one object, shared by the Python driver
and the compiled engine.

The accept and reject rules are plain functions of floats (:func:`h_accepted`,
:func:`h_rejected`); :mod:`.engine` compiles the same functions with numba, so both paths
run the same arithmetic from the same source.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..tableaux import ButcherTableau


@dataclass(frozen=True)
class PIController:
    """PI step-size control (Hairer-Wanner II, IV.2).

    After an accepted step with error norm ``err`` (and ``err_prev`` for the one before)::

        h_new = min(h_max, h * min(fac_max, max(fac_min, safety err^(-beta1/k) err_prev^(beta2/k))))

    with ``k = min(order, order_hat) + 1``; ``err = 0`` gives ``fac_max``. The memory
    ``err_prev`` is ``max(err, err_floor)``. After a rejection::

        h_new = h * min(1, max(fac_min, safety err^(-1/k)))

    (``fac_min`` if ``err`` is not finite), and if the step's rotation ``angle`` exceeded
    the bound ``max_angle``, the factor is at most ``max_angle / (2 angle)``.

    Rotation rate. Once the rotation guard has rejected a step, the loops keep the rotation
    rate ``omega = angle / h`` measured at every attempt (:func:`rotation_rate`) and cap
    every proposal at ``safety * max_angle / omega`` (:func:`rotation_cap`), so that the
    controller does not alternate between a guard rejection and an accepted step.

    Parameters
    ----------
    safety : float
        In ``(0, 1]``.
    fac_min, fac_max : float
        Bounds on the step ratio, ``0 < fac_min < 1 < fac_max``.
    beta1, beta2 : float
        Integral and proportional gains (divided by ``k``), ``beta1 > 0``, ``beta2 >= 0``.
    err_floor : float
        Smallest error remembered as ``err_prev`` (avoids huge ratios after exact steps).
    """

    safety: float = 0.9
    fac_min: float = 0.2
    fac_max: float = 5.0
    beta1: float = 0.7
    beta2: float = 0.4
    err_floor: float = 1e-4

    def __post_init__(self):
        checks = (("safety", 0 < self.safety <= 1), ("fac_min", 0 < self.fac_min < 1),
                  ("fac_max", self.fac_max > 1), ("beta1", self.beta1 > 0), ("beta2", self.beta2 >= 0),
                  ("err_floor", 0 < self.err_floor < 1))
        for name, ok in checks:
            if not ok:
                raise ValueError(f"PIController: invalid {name}={getattr(self, name)!r}")

    def gains(self, tab: ButcherTableau) -> tuple[float, ...]:
        """``(safety, fac_min, fac_max, beta1/k, beta2/k, -1/k, err_floor)`` for the pair
        ``tab``: the argument ``g`` of :func:`h_accepted` and :func:`h_rejected`."""
        if tab.order_hat is None:
            raise ValueError(f"method {tab.name!r} has no embedded pair")
        k = min(tab.order, tab.order_hat) + 1
        return (float(self.safety), float(self.fac_min), float(self.fac_max), self.beta1 / k, self.beta2 / k,
                -1.0 / k, float(self.err_floor))


#: The controller of :func:`~liegroup_int.integrators.drivers.integrate_adaptive` by default.
DEFAULT_CONTROLLER = PIController()

# indices into the gains tuple
G_SAFETY, G_FAC_MIN, G_FAC_MAX, G_BETA1, G_BETA2, G_INV_K_NEG, G_ERR_FLOOR = range(7)


def h_accepted(err, err_prev, h_try, h_max, g):
    """Next step after an accepted step of size ``h_try``: ``(h, err_prev)``.

    (Written with conditional expressions only, so that numba compiles it as it is:
    ``x if x < y else y`` is Python's ``min(y, x)``.)"""
    if err > 0:
        fac = g[G_SAFETY] * err ** (-g[G_BETA1]) * err_prev ** g[G_BETA2]
    else:
        fac = g[G_FAC_MAX]
    fac = fac if fac > g[G_FAC_MIN] else g[G_FAC_MIN]
    fac = fac if fac < g[G_FAC_MAX] else g[G_FAC_MAX]
    h = h_try * fac
    h = h if h < h_max else h_max
    return h, (err if err > g[G_ERR_FLOOR] else g[G_ERR_FLOOR])


def h_rejected(err, angle, h_try, max_angle, g):
    """Retry step after a rejected step of size ``h_try`` (``err`` may be ``inf``)."""
    if math.isfinite(err):
        fac = g[G_SAFETY] * err ** g[G_INV_K_NEG] if err > 0 else 1.0
    else:
        fac = g[G_FAC_MIN]
    if angle > max_angle:
        cap = 0.5 * max_angle / angle
        fac = cap if cap < fac else fac
    fac = fac if fac > g[G_FAC_MIN] else g[G_FAC_MIN]
    fac = fac if fac < 1.0 else 1.0
    return h_try * fac


def rotation_rate(angle, h_try, max_angle, rate):
    """The rotation rate to remember after an attempt of size ``h_try`` whose increment
    rotated by ``angle``: measured (``angle / h_try``) once the guard has rejected a step
    (``angle > max_angle`` now, or ``rate > 0`` from before), else ``rate`` (0: none yet)."""
    if angle > max_angle or rate > 0:
        return angle / h_try
    return rate


def rotation_cap(h, rate, max_angle, g):
    """``h`` capped at ``safety * max_angle / rate`` when a rotation rate is known."""
    if rate > 0:
        cap = g[G_SAFETY] * max_angle / rate
        if cap < h:
            return cap
    return h
