"""Work-precision of beam scenes: tip-history error against CPU time, ours and PyElastica.

For a :class:`~liegroup_int.bench.plans.Plan`:

1. The reference: RKMK6 on ``plan.reference`` (``plan.reference_formulation``) at
   ``|lambda|max dt = plan.reference_y``; the same on the next coarser mesh (knot spans
   doubled): its distance to the reference bounds the reference's space error (the error
   falls with the mesh), RKMK65 at twice the step bounds its time error. The table states
   both and how much more accurate than the best run the reference is (at least
   :data:`REFERENCE_MARGIN` times, or it says which errors it does not resolve).
2. Our runs: every formulation x discretization x fixed-step method at that method's
   stable step (:func:`~liegroup_int.integrators.stable_step` on the spectral radius at
   the initial state); on the primal time-study discretization every method over fractions
   of its stable step and every embedded pair x tolerance (step capped by the stable step).
   Every run is undamped.
3. The peer: PyElastica ``PositionVerlet`` at each element count, at the largest step of a
   ladder that stays finite over the span (its "own stable dt"); optionally its
   discretization of our continuum model at the finest count.

The error of a run is ``max_k |x_tip(t_k) - x_tip,ref(t_k)|`` over the output grid
(metres). CPU time is ``time.process_time`` around the time loop only, after a warm-up
that compiles the kernels (ours: numba backend; PyElastica: its own numba kernels); tip
recording costs the same in both. Every finished run is cached in ``out/runs/`` and
reused by the next call with the same settings, so an interrupted benchmark continues
where it stopped (``fresh=True`` recomputes).

Ratios against each peer run with error ``e_p`` and CPU ``t_p``, for each formulation of
ours: *CPU ratio* = ``t_p`` over the CPU of our cheapest run of that formulation with
error <= ``e_p``; *accuracy ratio* = ``e_p`` over the error of our most accurate run of
that formulation with CPU <= ``t_p``. Both are given for PyElastica's own rod model and
for its discretization of our continuum model, and both again *certified*: with the
reference's own error bound ``b`` added to each of our errors (a run counts as at least as
accurate when ``e + b <= e_p``; the accuracy ratio is ``e_p / (e + b)``), which holds
however the reference errs within its bound.
"""

from __future__ import annotations

import hashlib
import json
import math
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from functools import partial
from pathlib import Path

import numpy as np

from ..integrators import (
    IntegrationError,
    growth_check,
    integrate_adaptive,
    integrate_fixed,
    resolve_method,
    spectral_radius,
    stable_split_step,
    stable_step,
)
from ..integrators.splitting import integrate_composition
from ..tableaux import COMPOSITIONS
from ..iga.quadrature import DEFAULT_RULE, RULE_DESCRIPTIONS
from ..scenes import load_scene
from ..scenes.beam import problem as scene_problem
from .plans import VARIANTS, Plan

#: Fixed-step factors tried for the peer's stable step, largest first (times its estimate).
PEER_DT_FACTORS = (2.0, 1.5, 1.2, 1.0, 0.8, 0.6, 0.5, 0.4)


@dataclass
class Run:
    """One timed run and its tip history.

    ``family`` groups runs in tables and plots ("RKMK4", "RKMK65 adaptive",
    "PyElastica"); ``resolution`` is ``"p4 n31"`` or ``"400 el"``; ``formulation`` is
    ``"primal"`` or ``"galerkin"`` for ours (None for the peer), ``kelvin_voigt`` the
    retardation time of the run [s]; ``status`` is ``"ok"``, ``"skipped"`` (predicted CPU
    over budget) or the one-line failure.
    """

    family: str
    resolution: str
    dt: float
    formulation: str | None = None
    kelvin_voigt: float = 0.0
    rtol: float | None = None
    steps: int = 0
    rejected: int = 0
    rhs_evals: int = 0
    cpu_s: float = math.nan
    status: str = "ok"
    error: float = math.nan
    time_error: float = math.nan
    t: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    tip: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)), repr=False)
    cached: bool = False

    def row(self) -> dict:
        d = asdict(self)
        del d["t"], d["tip"]
        return d


# ----------------------------------------------------------------------------- cache
#: Part of the cache key of every run of ours: runs cached with another Galerkin stiffness
#: rule are not reused, nor those of another choice of ``auto`` (its description says which
#: rule it takes where).
OURS_TAG = ("space.quadrature", DEFAULT_RULE, RULE_DESCRIPTIONS[DEFAULT_RULE])


def _key(*parts) -> str:
    return hashlib.sha1(json.dumps(parts, default=str).encode()).hexdigest()[:16]


def _load_cached(cache: Path | None, key: str) -> Run | None:
    if cache is None or not (cache / f"{key}.npz").exists():
        return None
    z = np.load(cache / f"{key}.npz", allow_pickle=False)
    meta = json.loads(str(z["meta"]))
    return Run(**meta, t=z["t"], tip=z["tip"], cached=True)


def _store(cache: Path | None, key: str, run: Run) -> None:
    if cache is None:
        return
    cache.mkdir(parents=True, exist_ok=True)
    meta = {k: v for k, v in run.row().items() if k not in ("error", "time_error", "cached")}
    tmp = cache / f"{key}.tmp.npz"
    np.savez(tmp, meta=json.dumps(meta), t=run.t, tip=run.tip)
    tmp.replace(cache / f"{key}.npz")


# ----------------------------------------------------------------------------- ours
def _problem(scene: str, degree: int, n_ctrl: int, t_end: float, every: float, backend: str,
             formulation: str = "primal"):
    # the scene's own step and output keys are replaced (the benchmark chooses its steps);
    # built without sizing ``kelvin_voigt = "auto"`` (undamped)
    return scene_problem(load_scene(scene, {"space.degree": degree, "space.n_ctrl": n_ctrl, "t_end": t_end,
                                            "output.every": every, "integrator.dt": every,
                                            "integrator.backend": backend,
                                            **VARIANTS.get(formulation, {"space.formulation": formulation})}))


def fit_step(dt: float, every: float) -> float:
    """Largest step ``<= dt`` with a whole number of steps per output interval."""
    return every / math.ceil(every / dt - 1e-9)


@dataclass
class Discretized:
    """A built problem with its spectral radius, the largest real part of its linearized
    spectrum at the initial state (nan if too large for a dense eigenvalue problem) and
    the measured cost per stage (CPU s)."""

    problem: object
    lam_max: float
    stage_cost_s: float
    max_real: float = math.nan
    formulation: str = "primal"

    @property
    def tau(self) -> float:
        """Kelvin-Voigt retardation time of the problem [s]."""
        return 0.0 if self.problem is None else float(self.problem.tau)


def prepare(scene: str, degree: int, n_ctrl: int, t_end: float, every: float, backend: str,
            formulation: str = "primal") -> Discretized:
    """Build, compile (warm-up steps), measure ``|lambda|max`` and the cost of a stage."""
    pb = _problem(scene, degree, n_ctrl, t_end, every, backend, formulation)
    y0 = pb.initial_state()
    lam = spectral_radius(pb, 0.0, y0)
    tab = resolve_method("rkmk4")
    dt = 0.5 / lam
    integrate_fixed(pb, tab, (0.0, 2 * dt), y0, dt)  # compile / warm caches
    n = 20
    c0 = time.process_time()
    integrate_fixed(pb, tab, (0.0, n * dt), y0, dt)
    cost = (time.process_time() - c0) / (n * tab.stages)
    try:
        max_real = growth_check(pb, 0.0, y0, t_end).max_real
    except ValueError:  # too many unknowns for the dense check
        max_real = math.nan
    return Discretized(pb, lam, cost, max_real, formulation)


def _record(pb, rec_t: list, rec_tip: list) -> Callable:
    def observer(t, y):
        rec_t.append(float(t))
        rec_tip.append(pb.tip(y))
    return observer


def run_fixed(d: Discretized, method: str, dt: float, t_end: float, every: float, resolution: str,
              budget_s: float = math.inf) -> Run:
    """One fixed-step run of ours at step ``dt`` (a whole number of steps per output): an
    RKMK method, or a splitting composition (``strang``, ``yoshida4``, ...) through the
    problem's ``split_steps``."""
    comp = COMPOSITIONS.get(method)
    stages = comp.stages if comp is not None else resolve_method(method).stages
    family = method.upper()
    steps = int(round(t_end / dt))
    predicted = steps * stages * d.stage_cost_s
    if predicted > budget_s:
        return Run(family, resolution, dt, d.formulation, d.tau, steps=steps,
                   status=f"skipped (predicted {predicted:.0f} s CPU)")
    pb = d.problem
    rec_t, rec_tip = [], []
    t_out = every * np.arange(1, int(round(t_end / every)) + 1)
    run = Run(family, resolution, dt, d.formulation, d.tau)

    def go(span, observer=None, outputs=None):
        if comp is not None:
            return integrate_composition(pb, comp, span, pb.initial_state(), dt, observer, outputs)
        return integrate_fixed(pb, resolve_method(method), span, pb.initial_state(), dt, observer=observer,
                               t_out=outputs)

    try:  # untimed: compiles whatever this method needs that the warm-up of prepare did not
        go((0.0, 2 * dt))
    except (IntegrationError, ValueError):
        pass
    c0 = time.process_time()
    try:
        _, _, stats = go((0.0, t_end), _record(pb, rec_t, rec_tip), t_out)
        run.steps, run.rhs_evals = stats.steps, stats.rhs_evals
    except (IntegrationError, ValueError) as exc:
        run.status = f"failed: {exc}"
    run.cpu_s = time.process_time() - c0
    run.t, run.tip = np.array(rec_t), np.array(rec_tip).reshape(-1, 3)
    return run


class _OverBudget(Exception):
    def __init__(self, t: float):
        super().__init__(t)
        self.t = t


def run_adaptive(d: Discretized, method: str, rtol: float, h_max: float, t_end: float, every: float,
                 resolution: str, budget_s: float = math.inf) -> Run:
    """One adaptive run of ours (``atol = 1e-3 rtol``, steps capped at ``h_max``); stopped
    (status ``"skipped ..."``) once it has used more than ``budget_s`` CPU seconds (checked
    at every output time: no per-step monitor, so the compiled adaptive loop of the beam,
    the compiled engine's adaptive loop, runs between outputs)."""
    tab = resolve_method(method)
    pb = d.problem
    rec_t, rec_tip = [], []
    t_out = every * np.arange(1, int(round(t_end / every)) + 1)
    run = Run(f"{method.upper()} adaptive", resolution, h_max, d.formulation, d.tau, rtol=rtol)
    try:  # untimed, one output interval: compiles the adaptive loop (seconds with a cold numba cache)
        integrate_adaptive(pb, tab, (0.0, every), pb.initial_state(), rtol=rtol, atol=1e-3 * rtol, t_out=[every],
                           h_max=h_max)
    except IntegrationError:
        pass
    c0 = time.process_time()
    record = _record(pb, rec_t, rec_tip)

    def observer(t, y):
        record(t, y)
        if np.isfinite(budget_s) and time.process_time() - c0 > budget_s:
            raise _OverBudget(t)

    try:
        _, _, stats = integrate_adaptive(pb, tab, (0.0, t_end), pb.initial_state(), rtol=rtol, atol=1e-3 * rtol,
                                         observer=observer, t_out=t_out, h_max=h_max)
        run.steps, run.rejected, run.rhs_evals = stats.steps, stats.rejected, stats.rhs_evals
    except _OverBudget as exc:
        run.status = f"skipped (over the {budget_s:g} s CPU budget at t={exc.t:.3g})"
    except IntegrationError as exc:
        run.status = f"failed: {exc}"
    run.cpu_s = time.process_time() - c0
    run.t, run.tip = np.array(rec_t), np.array(rec_tip).reshape(-1, 3)
    return run


# ----------------------------------------------------------------------------- peer
def peer_case(scene: str):
    """PyElastica set-up of a built-in scene, or None when there is none."""
    from . import pyelastica_peer as P

    make = P.CASES.get(scene)
    return None if make is None else make()


def _peer_ok(r, length: float) -> bool:
    """Finite, and the tip within 1.5 L of the fixed end at the origin."""
    return bool(r.finite and np.all(np.linalg.norm(r.tip, axis=1) < 1.5 * length))


def run_peer(case, n_elements: int, t_end: float, every: float, model: str = "pyelastica",
             trial_steps: int = 20000) -> Run:
    """PyElastica at its largest stable step from :data:`PEER_DT_FACTORS` times the
    wave/shear estimate. A candidate must first survive ``trial_steps`` steps (whatever
    the span: an unstable mode of a step just above the limit needs thousands of steps to
    show), then the span itself; a step that fails moves to the next factor."""
    from . import pyelastica_peer as P

    w_sr = math.sqrt(case.G * case.A / (case.rho * min(case.I1, case.I2)))
    est = min(case.length / n_elements / case.wave_speed, 2.0 / w_sr)
    family = "PyElastica" if model == "pyelastica" else "PyElastica, our continuum model"
    for f in PEER_DT_FACTORS:
        dt = fit_step(f * est, every)
        trial_t = every * math.ceil(trial_steps * dt / every)
        if trial_t > t_end and not _peer_ok(P.run(case, n_elements, dt, trial_t, every, model), case.length):
            continue
        r = P.run(case, n_elements, dt, t_end, every, model)
        if _peer_ok(r, case.length):
            return Run(family, f"{n_elements} el", dt, steps=r.steps, rhs_evals=r.steps, cpu_s=r.cpu_s,
                       t=r.t, tip=r.tip)
    return Run(family, f"{n_elements} el", math.nan, status="failed: no finite step in the ladder")


def peer_dt_max(P, case, n_elements: int, t_end: float, every: float):
    """Largest stable PyElastica step over ``[0, t_end]`` from :data:`PEER_DT_FACTORS`
    times the wave/shear estimate (stable: finite and ``|tip| < 2 L``), with ``P`` the
    :mod:`pyelastica_peer` module. Returns ``(dt_max, dt_unstable, run_at_dt_max)``
    (``dt_unstable``: the next larger step tried, which failed; nan if the first worked)."""
    w_sr = math.sqrt(case.G * case.A / (case.rho * min(case.I1, case.I2)))
    est = min(case.length / n_elements / case.wave_speed, 2.0 / w_sr)
    bad = math.nan
    for f in PEER_DT_FACTORS:
        dt = fit_step(f * est, every)
        r = P.run(case, n_elements, dt, t_end, every)
        if r.finite and np.all(np.abs(r.tip) < 2 * case.length):
            return dt, bad, r
        bad = dt
    raise RuntimeError(f"{case.name} n={n_elements}: no stable PyElastica step found")


# ----------------------------------------------------------------------------- errors and ratios
def tip_error(run: Run, ref: Run) -> float:
    """``max_k |tip(t_k) - tip_ref(t_k)|`` over the common output grid (nan if incomplete)."""
    if run.status != "ok" or len(run.t) != len(ref.t) or not np.allclose(run.t, ref.t, atol=1e-9):
        return math.nan
    return float(np.max(np.linalg.norm(run.tip - ref.tip, axis=1)))


def _label(r: Run) -> str:
    return f"{r.family} {r.resolution} dt={r.dt:.3g}" + ("" if r.rtol is None else f" rtol={r.rtol:g}")


def ratios(ours: list[Run], peers: list[Run], bound: float = math.nan) -> list[dict]:
    """CPU and accuracy ratios of our runs against each finished peer run (module doc):
    one entry per peer run and formulation of ours (in the order of ``ours``); with the
    reference's error ``bound``, also the certified ratios (``*_certified``; None without)."""
    mine = [r for r in ours if r.status == "ok" and np.isfinite(r.error)]
    b = bound if np.isfinite(bound) else None
    formulations = list(dict.fromkeys(r.formulation for r in mine))
    out = []
    for p in peers:
        if p.status != "ok" or not np.isfinite(p.error):
            continue
        for form in formulations:
            group = [r for r in mine if r.formulation == form]
            as_good = [r for r in group if r.error <= p.error]
            cheap = min(as_good, key=lambda r: r.cpu_s) if as_good else None
            within = [r for r in group if r.cpu_s <= p.cpu_s]
            best = min(within, key=lambda r: r.error) if within else None
            sure = [r for r in group if b is not None and r.error + b <= p.error]
            sure_cheap = min(sure, key=lambda r: r.cpu_s) if sure else None
            out.append({
                "peer": f"{p.family} {p.resolution}", "peer_error": p.error, "peer_cpu_s": p.cpu_s,
                "formulation": form,
                "ours_at_error": None if cheap is None else _label(cheap),
                "ours_at_error_cpu_s": None if cheap is None else cheap.cpu_s,
                "cpu_ratio": None if cheap is None else p.cpu_s / cheap.cpu_s,
                "ours_at_cpu": None if best is None else _label(best),
                "ours_at_cpu_error": None if best is None else best.error,
                "accuracy_ratio": None if best is None else p.error / best.error,
                "cpu_ratio_certified": None if sure_cheap is None else p.cpu_s / sure_cheap.cpu_s,
                "accuracy_ratio_certified": None if best is None or b is None else p.error / (best.error + b),
            })
    return out


# ----------------------------------------------------------------------------- the study
#: How much more accurate than the best run it ranks the reference must be (its space and
#: time error bounds against that run's error).
REFERENCE_MARGIN = 10.0


@dataclass
class Result:
    plan: Plan
    reference: Run
    reference_check: Run | None
    time_reference: Run
    ours: list[Run]
    peers: list[Run]
    ratios: list[dict]
    lam_max: dict[str, tuple[float, float, float]]
    peer_version: str | None = None
    peer_note: str | None = None
    reference_coarse: Run | None = None

    def reference_bound(self) -> float:
        """Bound on the reference's own error: its distance to the coarser reference
        (space) plus RKMK65 at twice its step (time); NaN when neither was measured."""
        return _bound(self.reference_coarse, self.reference_check)


def _bound(coarse: Run | None, check: Run | None) -> float:
    """The reference's error bound from its coarser twin and its time check (NaN if neither)."""
    parts = [r.error for r in (coarse, check) if r is not None and r.status == "ok" and np.isfinite(r.error)]
    return float(sum(parts)) if parts else math.nan


def _say(log: Callable | None, msg: str) -> None:
    if log is not None:
        log(msg)


def _describe(r: Run) -> str:
    extra = f" rtol={r.rtol:g}" if r.rtol is not None else ""
    head = f"{r.family:>22s} {r.formulation or '':>6s} {r.resolution:>8s} dt={r.dt:.3g}{extra}"
    if r.status != "ok":
        return f"{head}: {r.status}"
    err = f" err={r.error:.3e}" if np.isfinite(r.error) else ""
    return f"{head}: {r.steps} steps, {r.cpu_s:.2f} s CPU{err}{' (cached)' if r.cached else ''}"


def _peer_runs(plan: Plan, cached: Callable, ref: Run, log: Callable | None) -> tuple[list[Run], str | None, str | None]:
    """PyElastica at every element count of the plan (and its discretization of our model
    at the finest, if asked): ``(runs, PyElastica version, note)``; no runs and a note when
    PyElastica is missing or has no set-up for the scene."""
    try:
        from . import pyelastica_peer as P
    except ImportError as exc:
        note = f"PyElastica not available ({exc}); install the peers extra: pip install -e \".[peers]\""
        _say(log, note)
        return [], None, note
    case = peer_case(Path(plan.scene).stem)
    if case is None:
        note = f"no PyElastica set-up for scene {plan.scene!r} ({', '.join(P.CASES)} only)"
        _say(log, note)
        return [], P.VERSION, note
    P.warm_up()
    models = [("pyelastica", n) for n in plan.peer_elements]
    if plan.peer_linear:
        models.append(("linear", plan.peer_elements[-1]))
    peers = []
    for model, n in models:
        r = cached(("peer", model, n), partial(run_peer, case, n, plan.t_end, plan.every, model), tag=())
        r.error = tip_error(r, ref)
        peers.append(r)
        _say(log, _describe(r))
    return peers, P.VERSION, None


def _coarse_reference(plan: Plan, disc: Callable, cached: Callable, ref: Run, log: Callable | None) -> Run | None:
    """RKMK6 on the reference's next coarser mesh (knot spans doubled, ``n -> (n + p) / 2``)
    at the same ``|lambda| dt``; its distance to the reference bounds the reference's space
    error. None when that mesh would have too few control points."""
    p, n = plan.reference
    n_c = (n + p) // 2
    if n_c < p + 2:
        return None
    d = disc(p, n_c, plan.reference_formulation)
    y = min(plan.reference_y, stable_step(resolve_method("rkmk6"), d.lam_max, plan.t_end).y)
    dt = fit_step(y / d.lam_max, plan.every)
    run = cached(("ref-coarse", plan.reference_formulation, p, n_c, dt),
                 partial(run_fixed, d, "rkmk6", dt, plan.t_end, plan.every, f"p{p} n{n_c}"))
    run.formulation = plan.reference_formulation
    run.error = tip_error(run, ref) if run.status == "ok" else math.nan
    _say(log, "  space-error bound of the reference (the next coarser mesh): " + _describe(run))
    return run


class _Bench:
    """The state of one :func:`work_precision` run: the plan, the run cache, the built
    discretizations, the references and our runs so far."""

    def __init__(self, plan: Plan, cache: Path | None, backend: str, log: Callable | None):
        self.plan, self.cache, self.backend, self.log = plan, cache, backend, log
        self.built: dict[tuple[int, int, str], Discretized] = {}
        self.ours: dict[str, Run] = {}

    def disc(self, p: int, n: int, form: str = "primal") -> Discretized:
        if (p, n, form) not in self.built:
            plan = self.plan
            self.built[(p, n, form)] = d = prepare(plan.scene, p, n, plan.t_end, plan.every, self.backend, form)
            _say(self.log, f"  p={p} n_ctrl={n} {form}: |lambda|max = {d.lam_max:.4g} 1/s, max Re lambda = "
                           f"{d.max_real:.3g} 1/s, {1e6 * d.stage_cost_s:.1f} us CPU per stage")
        return self.built[(p, n, form)]

    def cached(self, key_parts, make: Callable[[], Run], tag: tuple | None = None) -> Run:
        """The run of ``key_parts`` (and ``tag``, default :data:`OURS_TAG` as it is now) from
        the cache, or made and stored."""
        tag = OURS_TAG if tag is None else tag
        key = _key(self.plan.scene, self.plan.t_end, self.plan.every, self.backend, *key_parts, *tag)
        hit = _load_cached(self.cache, key)
        if hit is not None:
            return hit
        run = make()
        if not run.status.startswith("skipped"):
            _store(self.cache, key, run)
        return run

    def _rkmk6_reference(self, d: Discretized, p: int, n: int, form: str, key_parts: tuple) -> Run:
        """RKMK6 on ``d`` at the plan's reference step fraction (its key: ``key_parts`` and the step)."""
        plan, res = self.plan, f"p{p} n{n}"
        y = min(plan.reference_y, stable_step(resolve_method("rkmk6"), d.lam_max, plan.t_end).y)
        dt = fit_step(y / d.lam_max, plan.every)
        run = self.cached((*key_parts, dt), partial(run_fixed, d, "rkmk6", dt, plan.t_end, plan.every, res))
        run.formulation = form
        if run.status != "ok":
            raise RuntimeError(f"bench {plan.scene}: the reference run ({res}) failed: {run.status}")
        return run

    def references(self) -> None:
        """The reference, the bounds on its space and time errors, and the time study's reference."""
        plan, log = self.plan, self.log
        (p_ref, n_ref), f_ref = plan.reference, plan.reference_formulation
        _say(log, f"reference: RKMK6, {f_ref} p{p_ref} n{n_ref}")
        d_ref = self.disc(p_ref, n_ref, f_ref)
        # primal keys are those of the references cached before the formulation was a setting
        key = ("ref", p_ref, n_ref) if f_ref == "primal" else ("ref", f_ref, p_ref, n_ref)
        self.ref = ref = self._rkmk6_reference(d_ref, p_ref, n_ref, f_ref, key)
        _say(log, _describe(ref))
        self.coarse = _coarse_reference(plan, self.disc, self.cached, ref, log)
        # a second 6th-order method (RKMK65, stable on the imaginary axis) at twice the step:
        # its distance to the reference bounds the reference's time error (RKMK6 itself is
        # weakly unstable, so doubling its step would measure its growth, not its accuracy)
        dt_chk = fit_step(2 * ref.dt, plan.every)
        chk_key = ("ref-check", "rkmk65", p_ref, n_ref, dt_chk) if f_ref == "primal" else \
            ("ref-check", "rkmk65", f_ref, p_ref, n_ref, dt_chk)
        self.check = check = self.cached(chk_key, partial(run_fixed, d_ref, "rkmk65", dt_chk, plan.t_end, plan.every,
                                                          f"p{p_ref} n{n_ref}"))
        check.formulation = f_ref
        check.error = tip_error(check, ref)
        _say(log, "  time-error bound of the reference (RKMK65 at 2 dt): " + _describe(check))
        p_t, n_t = plan.time_study
        self.tref = tref = self._rkmk6_reference(self.disc(p_t, n_t), p_t, n_t, "primal", ("ref", p_t, n_t))
        tref.error = tip_error(tref, ref)
        _say(log, "time-study reference: " + _describe(tref))

    def add(self, key_parts, d: Discretized, make: Callable[[], Run], timed: bool) -> None:
        k = _key(*key_parts)
        if k in self.ours:
            return
        r = self.cached(key_parts, make)
        r.formulation, r.kelvin_voigt = d.formulation, d.tau  # runs cached before formulations had none
        r.error = tip_error(r, self.ref)
        if timed:
            r.time_error = tip_error(r, self.tref)
        self.ours[k] = r
        _say(self.log, _describe(r))

    def fixed(self, p: int, n: int, form: str, fractions, timed: bool) -> None:
        plan = self.plan
        d, res = self.disc(p, n, form), f"p{p} n{n}"
        for m in plan.methods:
            if m in COMPOSITIONS and not hasattr(d.problem, "split_steps"):
                continue  # splitting methods: the Galerkin form's kick-drift-kick only
            dt_stable = (stable_split_step(COMPOSITIONS[m], d.lam_max) if m in COMPOSITIONS
                         else stable_step(resolve_method(m), d.lam_max, plan.t_end)).dt
            for f in fractions:
                dt = fit_step(f * dt_stable, plan.every)
                # primal keys are those of the runs cached before formulations were an axis
                key = (m, p, n, dt) if form == "primal" else (m, form, p, n, dt, d.tau)
                self.add(key, d, partial(run_fixed, d, m, dt, plan.t_end, plan.every, res, plan.budget_s), timed)

    def time_study(self) -> None:
        plan = self.plan
        (p_t, n_t), res_t = plan.time_study, "p{} n{}".format(*plan.time_study)
        d_t = self.disc(p_t, n_t)
        self.fixed(p_t, n_t, "primal", tuple(plan.dt_fractions), True)
        for m in plan.adaptive:
            h_max = stable_step(resolve_method(m), d_t.lam_max, plan.t_end).dt
            for rtol in plan.rtols:
                self.add((m, "adaptive", p_t, n_t, rtol, h_max), d_t,
                         partial(run_adaptive, d_t, m, rtol, h_max, plan.t_end, plan.every, res_t, plan.budget_s), True)

    def our_runs(self) -> None:
        """Every method at its stable step on every discretization and formulation, and the
        time study (primal)."""
        plan = self.plan
        for form in plan.formulations:
            for p, n in plan.discretizations:
                if not (form == "primal" and (p, n) == tuple(plan.time_study)):
                    self.fixed(p, n, form, (1.0,), False)
            if form == "primal":
                self.time_study()
        if "primal" not in plan.formulations:
            self.time_study()


def work_precision(plan: Plan, out: Path | None = None, backend: str = "numba", peer: bool = True,
                   fresh: bool = False, log: Callable | None = print) -> Result:
    """Run a plan (module doc). ``out/runs`` caches finished runs unless ``out`` is None."""
    cache = None if out is None else Path(out) / "runs"
    if fresh and cache is not None and cache.exists():
        for f in cache.glob("*.npz"):
            f.unlink()
    b = _Bench(plan, cache, backend, log)
    b.references()
    b.our_runs()
    peers, version, note = _peer_runs(plan, b.cached, b.ref, log) if peer and plan.peer_elements else ([], None, None)
    lam = {f"p{p} n{n} {form}": (d.lam_max, d.max_real, d.tau) for (p, n, form), d in b.built.items()}
    mine = list(b.ours.values())
    return Result(plan, b.ref, b.check, b.tref, mine, peers, ratios(mine, peers, _bound(b.coarse, b.check)), lam,
                  version, note, b.coarse)


# ----------------------------------------------------------------------------- reporting
def _fmt(x, spec: str) -> str:
    return "-" if x is None or (isinstance(x, float) and not np.isfinite(x)) else format(x, spec)


def _reference_lines(result: Result) -> list[str]:
    """The reference, the bounds on its own error, and its margin over the best run."""
    ref, chk, coarse = result.reference, result.reference_check, result.reference_coarse
    lines = [f"Reference: RKMK6, {ref.formulation} {ref.resolution}, dt = {ref.dt:.3g} s ({ref.steps} steps, "
             f"{ref.cpu_s:.1f} s CPU); max |tip_ref| = {np.max(np.linalg.norm(ref.tip, axis=1)):.4g} m."]
    if coarse is not None:
        lines.append(f"Bound on its space error (the same on the next coarser mesh, {coarse.resolution}, against it): "
                     + (f"{_fmt(coarse.error, '.2e')} m." if coarse.status == "ok" else f"not measured ({coarse.status})."))
    if chk is not None:
        lines.append(f"Bound on its time error (RKMK65 at dt = {chk.dt:.3g} s against it): "
                     + (f"{_fmt(chk.error, '.2e')} m." if chk.status == "ok" else f"not measured ({chk.status})."))
    bound = result.reference_bound()
    errs = [r.error for r in result.ours if r.status == "ok" and np.isfinite(r.error) and r.error > 0]
    if not errs or not np.isfinite(bound):
        return lines
    best = min(errs)
    if best >= REFERENCE_MARGIN * bound:
        lines.append(f"The reference is {best / bound:.3g}x more accurate than the best run ({best:.2e} m).")
    else:
        lines.append(f"WARNING: the reference is only {best / bound:.2g}x more accurate than the best run ({best:.2e} m): "
                     f"errors below {REFERENCE_MARGIN * bound:.2e} m ({REFERENCE_MARGIN:g}x its error bound) are not "
                     "resolved; use a finer plan.reference.")
    return lines


def markdown(result: Result) -> str:
    """Tables of all runs and of the ratios, as Markdown."""
    pl = result.plan
    lines = [f"### {pl.scene}: T = {pl.t_end:g} s, tip history every {pl.every:g} s", ""]
    lines += _reference_lines(result)
    tr = result.time_reference
    lines.append(f"Time study on primal {tr.resolution}: time errors against RKMK6 on that discretization at dt = {tr.dt:.3g} s "
                 f"(which is {_fmt(tr.error, '.2e')} m from the reference: the space error of {tr.resolution}).")
    lines.append("Linearized spectrum at the initial state, |lambda|max (max Re lambda) [1/s]: "
                 + ", ".join(f"{k}: {v[0]:.3g} ({v[1]:.2g})" for k, v in result.lam_max.items()) + ".")
    lines += ["", "| run | formulation | resolution | dt [s] | rtol | steps | rejected | CPU [s] | max tip error [m] | "
              "time error [m] | status |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in result.ours + result.peers:
        lines.append(f"| {r.family} | {r.formulation or '-'} | {r.resolution} | {_fmt(r.dt, '.3g')} | "
                     f"{_fmt(r.rtol, 'g')} | {r.steps} | "
                     f"{r.rejected if r.rtol is not None else '-'} | {_fmt(r.cpu_s, '.3g')} | {_fmt(r.error, '.3e')} | "
                     f"{_fmt(r.time_error, '.3e')} | {r.status} |")
    if result.peer_note:
        lines += ["", f"Peer: {result.peer_note}."]
    if result.ratios:
        lines += ["", f"Ratios against PyElastica {result.peer_version}, per formulation of ours (CPU ratio: peer CPU / "
                  "CPU of our cheapest run of that formulation at least as accurate; accuracy ratio: peer error / "
                  "error of our best run of that formulation within the peer's CPU; in brackets, certified: with the "
                  "reference's error bound added to ours):",
                  "", "| peer run | peer error [m] | peer CPU [s] | ours | ours at that error | CPU [s] | CPU ratio | "
                  "ours within that CPU | error [m] | accuracy ratio |",
                  "|---|---|---|---|---|---|---|---|---|---|"]
        for q in result.ratios:
            lines.append(f"| {q['peer']} | {q['peer_error']:.3e} | {q['peer_cpu_s']:.3g} | {q['formulation'] or '-'} | "
                         f"{q['ours_at_error'] or '-'} | "
                         f"{_fmt(q['ours_at_error_cpu_s'], '.3g')} | {_fmt(q['cpu_ratio'], '.1f')}"
                         f"{_certified(q, 'cpu_ratio')} | {q['ours_at_cpu'] or '-'} | "
                         f"{_fmt(q['ours_at_cpu_error'], '.3e')} | {_fmt(q['accuracy_ratio'], '.1f')}"
                         f"{_certified(q, 'accuracy_ratio')} |")
    return "\n".join(lines) + "\n"


def _certified(q: dict, key: str) -> str:
    """`` (at least X)`` for a ratio whose certified value is known (``q`` from :func:`ratios`)."""
    c = q.get(f"{key}_certified")
    return "" if c is None or q.get(key) is None else f" (at least {c:.1f})"


def _envelope(runs: list[Run]) -> tuple[list[float], list[float]]:
    """Lower envelope: the smallest error reached within each CPU time (a step line)."""
    xs, ys = [], []
    for r in sorted(runs, key=lambda r: r.cpu_s):
        if not ys or r.error < ys[-1]:
            if ys:
                xs.append(r.cpu_s)
                ys.append(ys[-1])
            xs.append(r.cpu_s)
            ys.append(r.error)
    return xs, ys


def plot(result: Result, path: Path) -> Path:
    """Two log-log panels. Left: error against the fine reference over CPU time, one colour
    per method, one marker per resolution, filled for primal collocation, grey for Galerkin, the lower envelope of each formulation in grey,
    PyElastica in black.
    Right: the time study, time error against CPU time per method (the paper's Fig. 4(b),
    5(b))."""
    from ..io.plots import _figures

    plt = _figures()

    fig, (ax, bx) = plt.subplots(1, 2, figsize=(13, 6.8))
    ok = [r for r in result.ours if r.status == "ok" and np.isfinite(r.error) and r.error > 0]
    families = sorted({r.family for r in result.ours})
    colors = {f: plt.get_cmap("tab10")(i % 10) for i, f in enumerate(families)}
    markers = dict(zip(sorted({r.resolution for r in result.ours}), "osD^v<>p*hPX"))
    forms = list(dict.fromkeys(r.formulation for r in result.ours))
    # line style, marker face (None: filled)
    styles = {"primal": ("-", None), "galerkin": (":", "0.8")}
    groups: dict[tuple[str, str, str], list[Run]] = {}
    for r in ok:
        groups.setdefault((r.family, r.formulation, r.resolution), []).append(r)
    for (fam, form, res), runs in sorted(groups.items(), key=lambda kv: tuple(map(str, kv[0]))):
        runs = sorted(runs, key=lambda r: r.cpu_s)
        ls, face = styles.get(form, ("-", None))
        ax.loglog([r.cpu_s for r in runs], [r.error for r in runs], marker=markers[res], color=colors[fam], lw=1,
                  ls=ls if len(runs) > 1 else "none", mfc=face)
    for fam in families:
        ax.plot([], [], color=colors[fam], marker="s", ls="none", label=fam)
    for res, mk in markers.items():
        ax.plot([], [], marker=mk, color="0.5", ls="none", label=res)
    for form in forms:
        xs, ys = _envelope([r for r in ok if r.formulation == form])
        if xs:
            ls, face = styles.get(form, ("-", None))
            name = form + {"galerkin": " (grey markers, undamped)"}.get(form, " (filled markers)")
            ax.loglog(xs, ys, color="0.4", ls=ls, lw=2.2, alpha=0.45, label=f"{name}: best within CPU")
    for fam, style in (("PyElastica", "k-"), ("PyElastica, our continuum model", "k--")):
        pr = sorted((r for r in result.peers if r.family == fam and r.status == "ok" and np.isfinite(r.error)),
                    key=lambda r: r.cpu_s)
        if pr:
            ax.loglog([r.cpu_s for r in pr], [r.error for r in pr], style, marker="x", ms=8,
                      label=f"{fam} ({', '.join(r.resolution for r in pr)})")
    ax.set_xlabel("CPU time [s]")
    ax.set_ylabel("max tip error against the fine RKMK6 reference [m]")
    ax.set_title(f"{result.plan.scene}, T = {result.plan.t_end:g} s: space + time error "
                 f"(reference: RKMK6, {result.reference.formulation} {result.reference.resolution})", fontsize=9)
    ax.legend(fontsize=7, ncol=3, loc="upper center", bbox_to_anchor=(0.5, -0.13))
    tr = result.time_reference
    for fam in families:
        runs = sorted((r for r in ok if r.family == fam and np.isfinite(r.time_error) and r.time_error > 0),
                      key=lambda r: r.cpu_s)
        if runs:
            bx.loglog([r.cpu_s for r in runs], [r.time_error for r in runs], marker="o", color=colors[fam], label=fam)
    bx.set_xlabel("CPU time [s]")
    bx.set_ylabel(f"max tip error against RKMK6 on primal {tr.resolution} [m]")
    bx.set_title(f"time error on primal {tr.resolution} (paper Fig. 4(b)/5(b))", fontsize=9)
    bx.legend(fontsize=7, ncol=3, loc="upper center", bbox_to_anchor=(0.5, -0.13))
    for a in (ax, bx):
        a.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return path


def write(result: Result, out: Path) -> list[Path]:
    """``work_precision.md``, ``work_precision.json`` (all runs, ratios) and the PNG."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    md = out / "work_precision.md"
    md.write_text(markdown(result))
    js = out / "work_precision.json"
    payload = {"plan": asdict(result.plan), "reference": result.reference.row(),
               "reference_check": None if result.reference_check is None else result.reference_check.row(),
               "reference_coarse": None if result.reference_coarse is None else result.reference_coarse.row(),
               "reference_error_bound": result.reference_bound(),
               "time_reference": result.time_reference.row(),
               "lambda_max": result.lam_max, "ours": [r.row() for r in result.ours],
               "peers": [r.row() for r in result.peers], "ratios": result.ratios,
               "peer_version": result.peer_version, "peer_note": result.peer_note}
    tmp = js.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(payload, indent=1, default=float))
    tmp.replace(js)
    return [md, js, plot(result, out / "work_precision.png")]


__all__ = [
    "Discretized",
    "Result",
    "Run",
    "fit_step",
    "markdown",
    "plot",
    "prepare",
    "ratios",
    "run_adaptive",
    "run_fixed",
    "run_peer",
    "tip_error",
    "work_precision",
    "write",
]
