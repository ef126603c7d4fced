"""Kelvin-Voigt damping sized from the measured spectrum (``material.kelvin_voigt = "auto"``).

A collocation operator may have complex pairs of ``M_c^-1 K`` and so modes that grow like
``exp(Re(lambda) t)`` (docs/verification.md, "Stability of the semi-discretization").
Kelvin-Voigt strain-rate damping with retardation time ``tau`` shifts a mode of angular
frequency ``omega`` by about ``-tau omega^2 / 2``, so ``tau >= 2 Re(lambda) / |lambda|^2``
removes that mode's growth (the rule of thumb). :func:`size_kelvin_voigt` starts there
and checks each candidate on the dense linearized spectrum, doubling until no mode grows,
then narrows the bracket, so the damping is the least that does it (to a factor
``2^(1/2^refine)``), and reports the damping ratio it puts on the first mode.

Only oscillatory growth counts (``|Im lambda| > Re lambda``): the spurious modes of
collocation are complex pairs high in the spectrum, on which the damping acts. Real or
slow growth (a near-rigid mode, or about a moving state the physical divergence of
nearby motions) is not something strain-rate damping removes, and is left alone.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...integrators.spectrum import GROWTH_THRESHOLD, eigenvalues
#: Largest damping ratio on the first mode that ``"auto"`` accepts. Beyond it the growth
#: is not a high-frequency artefact that light damping removes (measured: primal
#: collocation of the arch at p = 2, locked, would need tau ~ 50 s; p = 8 with three
#: elements ~ 0.02): the sizing refuses and says so.
MAX_ZETA1 = 1e-3


@dataclass(frozen=True)
class DampingReport:
    """What :func:`size_kelvin_voigt` measured.

    Attributes
    ----------
    tau : float
        Retardation time chosen [s] (0 if no mode grows undamped).
    max_real_undamped : float
        Largest ``Re(lambda)`` of the oscillatory modes without damping [1/s].
    at_imag : float
        ``|Im(lambda)|`` of that mode [1/s].
    max_real : float
        Largest ``Re(lambda)`` of the oscillatory modes with ``tau`` [1/s].
    omega1 : float
        Smallest non-zero ``|Im(lambda)|`` [1/s] (the first mode).
    zeta1 : float
        Damping ratio on the first mode, ``tau omega1 / 2``.
    lam_max : float
        Largest ``|lambda|`` with ``tau`` [1/s] (stable steps).
    spectra : int
        Dense spectra computed.
    max_real_all, at_imag_all : float
        Largest ``Re(lambda)`` over all modes with ``tau`` (real and slow ones included,
        which the damping does not act on) and its ``|Im lambda|`` [1/s].
    """

    tau: float
    max_real_undamped: float
    at_imag: float
    max_real: float
    omega1: float
    zeta1: float
    lam_max: float
    spectra: int
    max_real_all: float = float("nan")
    at_imag_all: float = float("nan")

    def as_dict(self) -> dict:
        return {k: float(v) if k != "spectra" else int(v) for k, v in self.__dict__.items()}


def oscillatory_growth(lam: np.ndarray) -> float:
    """Largest ``Re lambda`` over the oscillatory modes (``|Im lambda| > Re lambda``),
    ``-inf`` if there are none."""
    osc = lam.real[np.abs(lam.imag) > lam.real]
    return float(np.max(osc)) if osc.size else -np.inf


def _top(lam: np.ndarray) -> tuple[float, float]:
    k = int(np.argmax(lam.real))
    return float(lam.real[k]), float(abs(lam.imag[k]))


def first_frequency(lam: np.ndarray) -> float:
    """Smallest non-zero ``|Im lambda|`` [1/s] of a spectrum (its first mode), 0 if none."""
    im = np.abs(lam.imag)
    im = im[im > 1e-6 * max(1.0, float(np.max(np.abs(lam))))]
    return float(np.min(im)) if im.size else 0.0


def size_kelvin_voigt(with_tau, y, t: float = 0.0, threshold: float = GROWTH_THRESHOLD, refine: int = 3,
                      max_doublings: int = 40, max_zeta1: float = MAX_ZETA1) -> DampingReport:
    """Least Kelvin-Voigt retardation time that leaves no growing linearized mode at ``y``.

    Parameters
    ----------
    with_tau : callable
        ``with_tau(tau) -> Problem``: the problem with damping ``tau`` (and everything
        else equal).
    y : state
        Where to linearize (the initial state for ``"auto"``).
    t : float
        Time of the linearization (load profiles).
    threshold : float
        ``Re(lambda)`` [1/s] above which a mode counts as growing.
    refine : int
        Bisections (in ``log tau``) after the first ``tau`` that works.
    max_doublings : int
        Bound on the search; raises ``ValueError`` beyond it.
    max_zeta1 : float
        Largest damping ratio on the first mode accepted; raises ``ValueError`` (naming
        the growth and the damping it would need) beyond it.

    Returns
    -------
    DampingReport
    """
    lam0 = eigenvalues(with_tau(0.0), t, y)
    count = 1
    osc = np.abs(lam0.imag) > lam0.real
    k0 = int(np.argmax(np.where(osc, lam0.real, -np.inf)))
    re0, im0 = float(lam0.real[k0]), float(abs(lam0.imag[k0]))
    omega1 = first_frequency(lam0)
    if re0 <= threshold:
        return DampingReport(0.0, re0, im0, re0, omega1, 0.0, float(np.max(np.abs(lam0))), count, *_top(lam0))
    grow = lam0[osc & (lam0.real > threshold)]
    tau = float(np.max(2.0 * grow.real / np.abs(grow) ** 2))  # rule of thumb, per growing mode
    lo = 0.0
    for _ in range(max_doublings):
        if omega1 > 0 and 0.5 * tau * omega1 > 2.0 * max_zeta1:
            raise ValueError(
                f"removing the growing mode (Re lambda = {re0:.3g} 1/s at |Im lambda| = {im0:.4g} 1/s) would take "
                f"tau > {tau:.3g} s, a damping ratio above {0.5 * tau * omega1:.2g} on the first mode "
                f"(auto accepts {max_zeta1:g}): not a high-frequency artefact")
        lam = eigenvalues(with_tau(tau), t, y)
        count += 1
        if oscillatory_growth(lam) <= threshold:
            break
        lo, tau = tau, 2.0 * tau
    else:
        raise ValueError(f"no Kelvin-Voigt retardation time up to {tau:.3g} s removes the growing mode "
                         f"(Re lambda = {re0:.3g} 1/s at |Im lambda| = {im0:.3g} 1/s)")
    best = lam
    hi = tau
    if lo > 0.0:
        for _ in range(refine):
            mid = float(np.sqrt(lo * hi))
            lam = eigenvalues(with_tau(mid), t, y)
            count += 1
            if oscillatory_growth(lam) <= threshold:
                hi, best = mid, lam
            else:
                lo = mid
    if omega1 > 0 and 0.5 * hi * omega1 > max_zeta1:
        raise ValueError(
            f"removing the growing mode (Re lambda = {re0:.3g} 1/s at |Im lambda| = {im0:.4g} 1/s) takes "
            f"tau = {hi:.3g} s, a damping ratio of {0.5 * hi * omega1:.2g} on the first mode (auto accepts "
            f"{max_zeta1:g}): not a high-frequency artefact")
    return DampingReport(hi, re0, im0, oscillatory_growth(best), omega1, 0.5 * hi * omega1,
                         float(np.max(np.abs(best))), count, *_top(best))
