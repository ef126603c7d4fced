"""Run guards: checks before the first step, the energy balance, and failure diagnosis.

A run must not return garbage with exit code 0, and a failure must name its real cause.
Three guards use the hooks a problem kind offers (:class:`~liegroup_int.scenes.scene.
Stability`, ``Simulation.conserved``):

* **Before the first step** (:func:`start_checks`): a fixed ``dt`` beyond the stable step
  of the discretization at ``t0`` is refused (the stable step is in the message), and a
  linearized mode that grows over the run (dense spectrum, small problems) is refused when
  the state is at rest, where an undamped structure has a purely imaginary spectrum.
* **During the run** (:class:`EnergyBalance`): ``E(y) - W - E(y0)`` at output times, with
  ``E`` the conserved mechanical energy and ``W`` the work of the loads
  (:attr:`~liegroup_int.integrators.Stats.quadrature`); the run stops when its magnitude
  exceeds a fraction of the energy scale.
* **After a failure** (:func:`diagnose`): at the last recorded state, ``dt |lambda|max``
  against the method's limit tells a step-size problem from a growing mode of the
  discretization; the dense spectrum there (small problems) gives the growth rate and
  whether the mode is a high-frequency complex pair (spurious) or a real one (divergence
  of nearby states, e.g. dynamic buckling under compression).
"""

from __future__ import annotations

import math

import numpy as np

from .integrators import GrowthReport, IntegrationError
from .integrators.spectrum import GROWTH_THRESHOLD
from .integrators.stepsize import SAFETY, step_limit
from .scenes import Scene, SceneError
from .tableaux import imaginary_axis_growth

#: A weakly unstable method (no imaginary-axis segment) is refused when its fastest mode
#: would grow by more than this factor over the run at the given step.
MAX_WEAK_GROWTH = 1e6


class BalanceError(IntegrationError):
    """The energy balance broke by more than the scene's tolerance."""


def _weak_growth(tab, y: float, steps: float) -> float:
    """Amplification ``|R(iy)|^steps`` of the fastest mode (inf on overflow)."""
    g = float(imaginary_axis_growth(tab, y))
    try:
        return math.exp(steps * math.log(g)) if g > 1.0 else 1.0
    except OverflowError:
        return math.inf


def check_step(scene: Scene, stab, tab, dt: float, t0: float, y0) -> dict:
    """Refuse a fixed ``dt`` beyond the stable step at ``(t0, y0)`` (raises SceneError).

    Returns the facts measured (``lambda_max``, ``stable_dt``) for the summary.
    """
    lam = float(stab.spectral_radius(t0, y0))
    if not lam > 0:
        return {"lambda_max": lam}
    limit = step_limit(tab)
    where = f"{scene.source}: key 'integrator.dt' = {dt:g} s"
    if limit > 0:
        stable = limit / lam
        if dt > stable * (1.0 + 1e-9):
            raise SceneError(
                f"{where} is beyond the stable step {stable:.3g} s of this discretization ({stab.describe}; "
                f"|lambda|max = {lam:.4g} 1/s, {tab.name} limit |lambda| dt <= {limit:.3g}): use dt <= "
                f"{SAFETY * stable:.3g} s or integrator.dt = \"auto\"")
        return {"lambda_max": lam, "stable_dt": stable}
    growth = _weak_growth(tab, lam * dt, (scene.t_end - t0) / dt)
    if growth > MAX_WEAK_GROWTH:
        raise SceneError(
            f"{where}: {tab.name} is unstable on the imaginary axis and would amplify the fastest mode of this "
            f"discretization ({stab.describe}; |lambda|max = {lam:.4g} 1/s) by {growth:.3g}x over the run: use "
            f"integrator.dt = \"auto\" or a method stable on the imaginary axis (rkmk3, rkmk4, rkmk65)")
    return {"lambda_max": lam, "weak_growth": growth}


def check_growth(scene: Scene, stab, t0: float, y0) -> tuple[dict, str | None]:
    """Dense spectrum at ``(t0, y0)``: ``(facts, warning)``; raises SceneError for a mode
    that grows over the run about a state at rest."""
    if stab.clean:
        return {"probe": f"skipped ({stab.clean})"}, None
    if stab.sized is not None:  # damping sized on the same spectrum: reuse it
        d = stab.sized
        rep = GrowthReport(d.lam_max, d.max_real_all, d.at_imag_all,
                           bool(d.max_real_all > GROWTH_THRESHOLD and d.max_real_all * (scene.t_end - t0) > 1.0),
                           0)
        probe = "spectrum of the damping sizing (kelvin_voigt = auto)"
    else:
        rep = stab.growth(t0, y0, scene.t_end - t0)
        probe = "dense spectrum at the start"
    if rep is None:
        return {"probe": f"skipped (more than {stab.max_unknowns} unknowns)"}, None
    facts = {"probe": probe, "max_re_lambda": rep.max_real, "at_imag": rep.at_imag, "lambda_max_dense": rep.lam_max}
    if not rep.growing:
        return facts, None
    e_folds = rep.max_real * (scene.t_end - t0)
    what = (f"mode growing like exp({rep.max_real:.3g} t) at |Im lambda| = {rep.at_imag:.4g} 1/s "
            f"({e_folds:.3g} e-folds over the run)")
    if stab.at_rest(y0):
        oscillatory = rep.at_imag > rep.max_real
        raise SceneError(
            f"{scene.source}: spurious growing mode of this discretization ({stab.describe}): {what}; about a "
            f"state at rest an undamped structure has a purely imaginary spectrum, so the run would be garbage "
            f"whatever dt: {stab.remedy if oscillatory else stab.remedy_real} (or guard.spectrum = false to run "
            f"anyway)")
    return facts, (f"{scene.source}: linearized {what} about the initial motion ({stab.describe}); part of it may "
                   f"be physical; if the run fails: {stab.remedy}")


def start_checks(scene: Scene, sim, tab, dt, t0: float, y0) -> tuple[dict, list[str]]:
    """The checks before the first step; ``(facts for summary.json, warnings)``.

    Raises
    ------
    SceneError
        One line naming the key and the cause: a fixed ``dt`` beyond the stable step, or
        a spurious growing mode at rest.
    """
    stab = sim.stability
    if stab is None:
        return {}, []
    facts, warnings = {}, []
    if dt is not None and scene.guard.dt and scene.integrator.dt != "auto":
        facts.update(check_step(scene, stab, tab, dt, t0, y0))
    if scene.guard.spectrum:
        more, warning = check_growth(scene, stab, t0, y0)
        facts.update(more)
        if warning:
            warnings.append(warning)
    return facts, warnings


class EnergyBalance:
    """``E(y) - W - E0`` at output times, and the guard on it.

    Parameters
    ----------
    conserved : callable
        ``E(y)``: energy whose change equals the work of the loads (beams: kinetic plus
        strain energy).
    stats : Stats
        The run's counters; ``stats.quadrature`` is the work ``W`` done so far.
    e0 : float
        ``E`` at the start of the (uninterrupted) run.
    tolerance : float
        Stop when ``|E - W - E0|`` exceeds this fraction of the energy scale, the largest
        ``|E|``, ``|W|`` seen (0: never).
    """

    def __init__(self, conserved, stats, e0: float, tolerance: float, scale: float = 0.0):
        self.conserved, self.stats, self.e0, self.tolerance = conserved, stats, float(e0), float(tolerance)
        self.scale = max(float(scale), abs(self.e0))
        self._t = None
        self.defect = 0.0
        self.worst = 0.0

    def evaluate(self, t: float, y) -> float:
        """The defect at output time ``t`` (computed once per time)."""
        if self._t != t:
            e, w = float(self.conserved(y)), float(self.stats.quadrature)
            self.defect = e - w - self.e0
            self.scale = max(self.scale, abs(e), abs(w))
            self.worst = max(self.worst, abs(self.defect) / self.scale if self.scale > 0 else 0.0)
            self._t = t
        return self.defect

    def work(self, t: float, y) -> float:
        return float(self.stats.quadrature)

    def __call__(self, t: float, y) -> None:
        d = self.evaluate(t, y)
        if not np.isfinite(d) or (self.tolerance > 0 and self.scale > 0 and abs(d) > self.tolerance * self.scale):
            raise BalanceError(
                f"energy balance broken at t={t:.6g}: E_kin + E_strain - W changed by {d:.3g} J, "
                f"{abs(d) / self.scale if self.scale > 0 else math.inf:.3g} of the energy scale {self.scale:.3g} J "
                f"(guard.energy_balance = {self.tolerance:g})", t, self.stats.steps)


def diagnose(scene: Scene, sim, tab, dt: float | None, t: float, y) -> str:
    """The cause of a failure, measured at the last recorded state ``(t, y)``: one clause.

    ``dt |lambda|max`` beyond the method's limit is a step-size problem (the cure is a
    smaller dt); otherwise the dense spectrum (small problems) names the growing mode.
    """
    stab = sim.stability
    if stab is None or y is None:
        return ""
    try:
        lam = float(stab.spectral_radius(t, y))
        limit = step_limit(tab)
        if dt is not None and lam > 0 and limit > 0 and dt * lam > limit:
            return (f"cause: the step is beyond the stability limit at t={t:.6g} (|lambda|max = {lam:.4g} 1/s, "
                    f"stable dt {limit / lam:.3g} s): reduce dt or use integrator.dt = \"auto\"")
        rep = stab.growth(t, y, max(scene.t_end - t, 1e-300))
    except Exception:  # the diagnosis must never mask the original error
        return ""
    step = f"dt |lambda|max = {dt * lam:.3g} within the {tab.name} limit {limit:.3g}, so not the step; " \
        if dt is not None and lam > 0 and limit > 0 else ""
    if rep is None:
        return (f"cause: {step}a growing mode of the discretization or an unresolved physical instability "
                f"({stab.describe}; spectrum not computed above {stab.max_unknowns} unknowns): {stab.remedy}")
    if rep.max_real <= 0 or not rep.growing:
        return (f"cause: {step}no growing linearized mode at t={t:.6g} (max Re lambda = {rep.max_real:.3g} 1/s): "
                f"the growth came from the nonlinear motion after it; {stab.remedy}")
    kind = ("a real eigenvalue: nearby states diverge (e.g. dynamic buckling under compression) faster than this "
            "discretization resolves" if rep.at_imag < 1e-3 * rep.lam_max else
            f"a complex pair at |Im lambda| = {rep.at_imag:.4g} 1/s: a spurious growing mode of this discretization")
    return (f"cause: {step}at t={t:.6g} a linearized mode grows like exp({rep.max_real:.3g} t), {kind} "
            f"({stab.describe}): {stab.remedy}")
