"""Compile the numba kernels and engine loops of the built-in scenes ahead of the first run
(``liegroup-int compile``).

Numba compiles a kernel the first time it is called and keeps the machine code in its
on-disk cache (``__pycache__`` next to the sources, or ``NUMBA_CACHE_DIR``): only the first
run of a kind of problem pays for it. This module does that compilation up front, in
separate processes side by side on a machine's cores: one per kernel set, and for a beam
set one for its stage rate (about 24 s of the set's 37 s of CPU) and one for its action and
the engine's loop, which calls the stage rate through its address and so compiles without it.

A kernel set is what one family of runs compiles: the beam's Galerkin formulation (the
default), its primal collocation (opt-in), the rigid body, and the loops that run a user's
``numba.njit`` field (``user_field``: they take the field as a first-class function value,
so one compilation serves every field); each with the engine's
fixed-step loop and, on request, its adaptive loop. The loops' machine code does not depend on the scene's numbers (sizes,
constants, tableau), so warming one scene of a family serves every scene of it.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass
from typing import Callable

__all__ = ["KernelSet", "KERNEL_SETS", "compile_sets", "warm_scene", "write_bytecode"]

_ADAPTIVE = ("integrator.method=rkmk45", "integrator.dt=none", "integrator.rtol=1e-6")


@dataclass(frozen=True)
class KernelSet:
    """One family of runs: a built-in scene and the overrides that select the family."""

    name: str
    scene: str | None
    overrides: tuple[str, ...]
    description: str
    warm: Callable[[], float] | None = None  # instead of a scene: a function that warms the set
    parts: tuple[str, ...] = ()  # pieces (:data:`PARTS`) compiled side by side in place of the warm-up


def _built(ks: KernelSet):
    """``(scene, built simulation)`` of the set's scene."""
    from .scenes import KINDS, load_scene, parse_override

    scene = load_scene(ks.scene, dict(parse_override(s) for s in ks.overrides))
    return scene, KINDS[scene.kind].build(scene)


def _part_rates(ks: KernelSet) -> None:
    """A beam formulation's stage rate: the entry the Python side and the engine's loops
    call (the longest piece: about 24 s of the Galerkin set's 37 s of CPU)."""
    import numpy as np

    _, sim = _built(ks)
    pb = sim.problem
    pb.increment_rate(0.0, sim.y0, np.zeros((4, pb.n, 3)))


def _part_loop(ks: KernelSet) -> None:
    """A beam formulation's action and the engine's fixed-step loop, compiled without
    running it (it calls the stage rate through its address, so it compiles without it)."""
    import numpy as np

    from .integrators import resolve_scheme
    from .integrators.drivers import stepper_for

    scene, sim = _built(ks)
    pb = sim.problem
    pb.action(np.zeros((4, pb.n, 3)), sim.y0)
    stepper_for(pb, resolve_scheme(scene.integrator.method)).compile_fixed(sim.y0)


#: The pieces a kernel set may be split into (:attr:`KernelSet.parts`).
PARTS: dict[str, Callable[[KernelSet], None]] = {"rates": _part_rates, "loop": _part_loop}


def warm_user_fields() -> float:
    """Compile the engine's loops for a user's ``numba.njit`` field on the built-in groups
    (points of one and of two dimensions) and on ``Sphere()``, fixed-step and adaptive;
    returns the seconds it took."""
    import numpy as np
    from numba import njit

    from . import Product, Rn, SO3, Sphere, integrate

    c = time.perf_counter()
    zero3 = njit(lambda t, y: np.zeros(3))
    zero6 = njit(lambda t, y: np.zeros(6))
    cases = ((zero3, np.eye(3), SO3), (zero6, np.concatenate([np.eye(3).ravel(), np.zeros(3)]), Product(SO3, Rn(3))),
             (zero3, np.array([0.0, 0.0, 1.0]), Sphere()))
    for f, y0, space in cases:
        integrate(f, y0, (0.0, 1e-3), space=space, method="rkmk4", dt=1e-3)
        integrate(f, y0, (0.0, 1e-3), space=space, method="rkmk45", rtol=1e-6, atol=1e-9)
    return time.perf_counter() - c


#: The kernel sets: those of the built-in scenes as shipped first, then the opt-in ones.
KERNEL_SETS: dict[str, KernelSet] = {
    "beam_galerkin": KernelSet("beam_galerkin", "cantilever", ("space.formulation=galerkin",),
                               "beam, Galerkin (weak form, the default), fixed step (every built-in beam scene)",
                               parts=("rates", "loop")),
    "rigid_body": KernelSet("rigid_body", "heavy_top", (), "rigid body, fixed step (heavy_top, free_rigid_body)"),
    "beam_galerkin_adaptive": KernelSet("beam_galerkin_adaptive", "cantilever",
                                        ("space.formulation=galerkin",) + _ADAPTIVE, "beam, Galerkin, adaptive pairs"),
    "rigid_body_adaptive": KernelSet("rigid_body_adaptive", "heavy_top", _ADAPTIVE, "rigid body, adaptive pairs"),
    "beam_galerkin_split": KernelSet("beam_galerkin_split", "pendulum",
                                     ("space.formulation=galerkin", "integrator.method=strang", "integrator.dt=auto"),
                                     "beam, Galerkin, splitting methods (leapfrog and its compositions)"),
    "beam_primal": KernelSet("beam_primal", "cantilever", ("space.formulation=primal",),
                             "beam, primal collocation (the paper's method, opt-in), fixed step", parts=("rates", "loop")),
    "beam_primal_adaptive": KernelSet("beam_primal_adaptive", "cantilever", ("space.formulation=primal",) + _ADAPTIVE,
                                      "beam, primal collocation, adaptive pairs"),
    "user_field": KernelSet("user_field", None, (), "a user's numba.njit field on the groups and Sphere(), fixed "
                            "step and adaptive (integrate(f, ...))", warm=warm_user_fields),
}

#: What ``liegroup-int compile`` prepares without ``--all``: the built-in scenes as shipped
#: (every built-in beam scene runs the default Galerkin formulation).
DEFAULT_SETS = ("beam_galerkin", "rigid_body")


def warm_scene(scene_name: str, overrides: tuple[str, ...] = ()) -> float:
    """Build ``scene_name`` with ``overrides``, run its start-up checks and one throw-away
    step of its compiled loop; returns the seconds it took (compilation or cache loads)."""
    from .guards import start_checks
    from .integrators import resolve_scheme
    from .runner import warm_up
    from .scenes import KINDS, load_scene, parse_override

    c = time.perf_counter()
    scene = load_scene(scene_name, dict(parse_override(s) for s in overrides))
    sim = KINDS[scene.kind].build(scene)
    spec = scene.integrator
    dt = sim.info["dt_auto"] if spec.dt == "auto" else spec.dt
    tab = resolve_scheme(spec.method)
    start_checks(scene, sim, tab, dt, 0.0, sim.y0)
    warm_up(sim.problem, tab, 0.0, sim.y0, dt)
    return time.perf_counter() - c


def write_bytecode() -> bool:
    """Write the bytecode of the package's modules (``__pycache__/*.pyc``), as a regular
    ``pip install`` does: an editable install does not, and with ``PYTHONDONTWRITEBYTECODE``
    set Python never writes it, so every process would compile the package's sources again
    when it imports them (about 0.1-0.2 s a process). Returns whether every file was written
    (a read-only install leaves it as it is)."""
    import compileall
    from pathlib import Path

    return bool(compileall.compile_dir(str(Path(__file__).resolve().parent), quiet=2))


def _warm_set(name: str) -> tuple[str, float]:
    ks = KERNEL_SETS[name]
    return name, (ks.warm() if ks.warm is not None else warm_scene(ks.scene, ks.overrides))


def _task(name: str, part: str | None) -> tuple[str, str | None]:
    """One piece of a set (``part``) or, with ``None``, the whole set (in a worker)."""
    if part is None:
        _warm_set(name)
    else:
        PARTS[part](KERNEL_SETS[name])
    return name, part


def compile_sets(names, jobs: int | None = None, report=None) -> dict[str, float]:
    """Compile the kernel sets ``names`` (keys of :data:`KERNEL_SETS`) into numba's cache,
    ``jobs`` processes at a time (default: the machine's cores; 1 compiles in this
    process, one set after the other). Side by side, a set with :attr:`~KernelSet.parts`
    compiles its pieces in separate processes: together they are all its warm-up compiles.
    ``report(name, seconds)`` is called as each set is ready. Returns per set the seconds
    from the start until it was ready."""
    names = list(dict.fromkeys(names))
    unknown = [n for n in names if n not in KERNEL_SETS]
    if unknown:
        raise ValueError(f"unknown kernel set {unknown[0]!r}; known: {', '.join(KERNEL_SETS)}")
    jobs = max(1, min(jobs or os.cpu_count() or 1, sum(max(1, len(KERNEL_SETS[n].parts)) for n in names)))
    start, done = time.perf_counter(), {}

    def ready(n):
        done[n] = time.perf_counter() - start
        if report is not None:
            report(n, done[n])

    if jobs == 1:
        for n in names:
            _warm_set(n)
            ready(n)
        return done
    import multiprocessing
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait

    pending = {n: set(KERNEL_SETS[n].parts) for n in names}
    # longest first (the stage rates), then whole sets, then the other parts: on 2 cores the
    # rigid body and the beam's loop then share one worker while the rates take the other
    first = [(n, KERNEL_SETS[n].parts[0]) for n in names if pending[n]]
    rest = [(n, p) for n in names for p in KERNEL_SETS[n].parts[1:]]
    tasks = first + [(n, None) for n in names if not pending[n]] + rest
    # fresh interpreters: the workers import numba themselves (no fork of a process that has)
    with ProcessPoolExecutor(max_workers=jobs, mp_context=multiprocessing.get_context("spawn")) as pool:
        running = {pool.submit(_task, *t) for t in tasks}
        while running:
            finished, running = wait(running, return_when=FIRST_COMPLETED)
            for fut in finished:
                n, part = fut.result()
                if part is None:
                    ready(n)
                    continue
                pending[n].discard(part)
                if not pending[n]:  # its warm-up would only load them (tests/test_precompile.py)
                    ready(n)
    return done
