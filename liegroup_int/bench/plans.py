"""What a work-precision benchmark runs: frozen plans, one per built-in beam scene.

A plan fixes the span, the output grid on which tip histories are compared, the reference
run (RKMK6 on a finer discretization of the default formulation, its space error bounded
by the same run on the next coarser mesh), our runs and the peer's
resolutions. Our runs are of two kinds: every method at its stable step on every
discretization, once per spatial formulation (``galerkin``: the default weak form;
``primal``: the paper's collocation), whose error against the fine reference is mostly
space error, the fair comparison with a peer; and a time study on one primal
discretization (the paper's p = 4, n = 30): every method over fractions of its stable step
and the adaptive pairs over tolerances, whose *time* error is also measured against an
RKMK6 run on that same discretization (the paper's Fig. 4(b), 5(b)). ``quick`` plans are
the same studies on short spans and coarse ladders (a minute, for tests and smoke runs).
"""

from __future__ import annotations

from dataclasses import dataclass, replace


@dataclass(frozen=True)
class Plan:
    """A work-precision study of one beam scene.

    Attributes
    ----------
    scene : str
        Built-in scene name or TOML path (a beam scene).
    t_end, every : float
        Span [s] and output interval [s] of the compared tip history.
    reference : (int, int)
        ``(degree, n_ctrl)`` of the RKMK6 reference run.
    reference_formulation : str
        Its spatial formulation (default: the default formulation, ``"galerkin"``). The same
        run on the next coarser mesh (knot spans doubled) bounds its space error.
    reference_y : float
        ``|lambda|max * dt`` of the reference run (capped by RKMK6's growth-budget rule).
    discretizations : tuple of (int, int)
        ``(degree, n_ctrl)`` of our runs at each method's stable step.
    formulations : tuple of str
        Spatial formulations of those runs (``"primal"``, ``"galerkin"``;
        ``space.formulation``), or a variant of :data:`VARIANTS` (``"galerkin-ri"``).
        Every run is undamped. The time study is primal whatever this says.
    time_study : (int, int)
        ``(degree, n_ctrl)`` of the time study (primal).
    methods : tuple of str
        Fixed-step methods: RKMK tableaux, and splitting compositions (``strang``: kick-drift-kick
        leapfrog), which run on the Galerkin formulation only.
    dt_fractions : tuple of float
        Fractions of each method's stable step in the time study.
    adaptive : tuple of str
        Embedded pairs run in the time study with ``rtols`` (``atol = 1e-3 rtol``), step
        capped by the stable step.
    rtols : tuple of float
    peer_elements : tuple of int
        PyElastica element counts (empty: no peer runs).
    peer_linear : bool
        Also run PyElastica's discretization of our continuum model at the finest count.
    budget_s : float
        A run whose predicted CPU time exceeds this is skipped (and listed as skipped).
    """

    scene: str
    t_end: float
    every: float
    reference: tuple[int, int]
    reference_y: float
    discretizations: tuple[tuple[int, int], ...]
    reference_formulation: str = "galerkin"
    formulations: tuple[str, ...] = ("primal", "galerkin")
    time_study: tuple[int, int] = (4, 31)
    methods: tuple[str, ...] = ("rkmk2", "rkmk3", "rkmk4", "rkmk6", "rkmk65", "strang")
    dt_fractions: tuple[float, ...] = (1.0, 0.5, 0.25, 0.125)
    adaptive: tuple[str, ...] = ("rkmk65",)
    rtols: tuple[float, ...] = (1e-5, 1e-7, 1e-9)
    peer_elements: tuple[int, ...] = (50, 100, 200, 400)
    peer_linear: bool = True
    budget_s: float = 60.0

    def __post_init__(self):
        if not (self.t_end > 0 and 0 < self.every <= self.t_end):
            raise ValueError(f"plan {self.scene}: need 0 < every <= t_end, got every={self.every}, t_end={self.t_end}")
        if abs(self.t_end / self.every - round(self.t_end / self.every)) > 1e-9:
            raise ValueError(f"plan {self.scene}: every={self.every} must divide t_end={self.t_end}")
        if not self.discretizations:
            raise ValueError(f"plan {self.scene}: no discretizations")
        from .beam_internals import ALL_FORMULATIONS

        FORMULATIONS = ALL_FORMULATIONS + tuple(VARIANTS)
        if not self.formulations or any(f not in FORMULATIONS for f in self.formulations) \
                or len(set(self.formulations)) != len(self.formulations):
            raise ValueError(f"plan {self.scene}: formulations must be distinct, from {', '.join(FORMULATIONS)}; "
                             f"got {self.formulations}")
        if not all(0 < f <= 1 for f in self.dt_fractions):
            raise ValueError(f"plan {self.scene}: dt_fractions must lie in (0, 1], got {self.dt_fractions}")


#: Variants of a formulation a plan may name among its ``formulations``: a label and the
#: scene keys it sets. ``galerkin-ri``: Galerkin with ``section.rotary_inertia_scale = "auto"``
#: (rotary-inertia scaling; its errors are measured against the unscaled reference).
VARIANTS: dict[str, dict] = {
    "galerkin-ri": {"space.formulation": "galerkin", "section.rotary_inertia_scale": "auto"},
}

#: Built-in plans (cantilever over 0.05 s, pendulum over 1 s, spinning helix over 0.5 s: half a
#: turn, which keeps its full study near 20 min of CPU on two cores). The coarsest meshes
#: (cantilever p = 3, 4 at n_ctrl 11; pendulum p = 4 at 17, 18) are where the Galerkin form
#: first reaches PyElastica's finest error, so the CPU ratio is not capped by the ladder; the
#: pendulum and the cantilever also run ``galerkin-ri`` (rotary-inertia scaling, whose
#: stable-step gain on the helix is 1.03x only). Every
#: discretization here is stable at rest in primal collocation (max Re lambda of the
#: linearized operator < 1e-3 1/s); some nearby ones are not (cantilever p = 8, n_ctrl = 61
#: or 71: +1e4 1/s; see docs/verification.md, "Stability of the semi-discretization"). The
#: helix is linearized about its spinning start: max Re lambda is 0.051 1/s in Galerkin on
#: every mesh (a mode of the spinning rod, not of the mesh), 0.12 to 2.2 1/s in primal
#: collocation (a factor e^1.1 at most over the 0.5 s).
PLANS: dict[str, Plan] = {
    "cantilever": Plan(
        scene="cantilever", t_end=0.05, every=2.5e-4, reference=(8, 51), reference_y=0.4,
        discretizations=((3, 11), (4, 11), (4, 15), (4, 21), (4, 31), (4, 41), (6, 21), (6, 31), (6, 41)),
        formulations=("primal", "galerkin", "galerkin-ri"),
    ),
    "pendulum": Plan(
        scene="pendulum", t_end=1.0, every=5e-3, reference=(8, 81), reference_y=0.4,
        discretizations=((4, 17), (4, 18), (4, 21), (4, 31), (4, 61), (6, 21), (6, 31), (6, 41), (6, 61), (8, 41)),
        formulations=("primal", "galerkin", "galerkin-ri"),
    ),
    "spinning_helix": Plan(
        scene="spinning_helix", t_end=0.5, every=5e-3, reference=(8, 101), reference_y=0.4,
        discretizations=((4, 21), (4, 31), (4, 41), (4, 61), (6, 21), (6, 31), (6, 41), (6, 61)),
    ),
}

#: Short versions: the same comparisons in about a minute.
QUICK: dict[str, Plan] = {
    "cantilever": replace(PLANS["cantilever"], t_end=0.002, reference=(6, 31), discretizations=((4, 21), (4, 31)),
                          time_study=(4, 21), methods=("rkmk3", "rkmk4", "strang"), dt_fractions=(1.0, 0.5, 0.25),
                          rtols=(1e-6, 1e-8),
                          peer_elements=(50, 100), peer_linear=False, budget_s=20.0),
    "pendulum": replace(PLANS["pendulum"], t_end=0.1, reference=(6, 41), discretizations=((4, 21), (4, 31)),
                        time_study=(4, 21), methods=("rkmk3", "rkmk4", "strang"), dt_fractions=(1.0, 0.5, 0.25),
                        rtols=(1e-6, 1e-8),
                        peer_elements=(50, 100), peer_linear=False, budget_s=20.0),
    "spinning_helix": replace(PLANS["spinning_helix"], t_end=0.1, reference=(6, 41),
                              discretizations=((4, 21), (4, 31)), time_study=(4, 21), methods=("rkmk3", "rkmk4", "strang"),
                              dt_fractions=(1.0, 0.5, 0.25), rtols=(1e-6, 1e-8),
                              peer_elements=(50, 100), peer_linear=False, budget_s=20.0),
}


def plan_for(scene: str, quick: bool = False, t_end: float | None = None) -> Plan:
    """The plan of a built-in scene; any other beam scene gets a generic one.

    Generic plan: the scene's own span and output interval, our runs at the scene's
    ``(degree, n_ctrl)`` and at about half ``n_ctrl``, the reference at ``2 n_ctrl - 1``,
    no peer (PyElastica set-ups exist for ``pendulum``, ``cantilever`` and ``spinning_helix`` only).
    """
    table = QUICK if quick else PLANS
    if scene in table:
        plan = table[scene]
    else:
        from ..scenes import load_scene

        sc = load_scene(scene)
        if sc.kind != "beam":
            raise ValueError(f"bench: {scene!r} is a {sc.kind} scene; the work-precision benchmark is for beam scenes")
        p, n = int(sc["space.degree"]), int(sc["space.n_ctrl"])
        span = sc.t_end if not quick else min(sc.t_end, 20 * sc.output.every)
        half = max(p + 2, (n + 1) // 2)
        plan = Plan(scene=scene, t_end=span, every=sc.output.every, reference=(p, 2 * n - 1), reference_y=0.4,
                    discretizations=((p, half), (p, n)), time_study=(p, n), peer_elements=(), peer_linear=False,
                    methods=("rkmk3", "rkmk4") if quick else Plan.methods,
                    dt_fractions=(1.0, 0.5, 0.25) if quick else Plan.dt_fractions,
                    budget_s=20.0 if quick else Plan.budget_s)
    if t_end is not None:
        every = plan.every if t_end / plan.every >= 4 else t_end / 4
        plan = replace(plan, t_end=t_end, every=every)
    return plan
