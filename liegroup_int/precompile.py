"""Compile the numba kernels and engine loops of the built-in scenes ahead of the first run
(``liegroup-int compile``).

Numba compiles a kernel the first time it is called and keeps the machine code in its
on-disk cache (``__pycache__`` next to the sources, or ``NUMBA_CACHE_DIR``): only the first
run of a kind of problem pays for it. This module does that compilation up front, one
process per kernel set, so the sets compile side by side on a machine's cores.

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

__all__ = ["KernelSet", "KERNEL_SETS", "compile_sets", "warm_scene"]

_ADAPTIVE = ("integrator.method=rkmk45", "integrator.dt=none", "integrator.rtol=1e-6")


@dataclass(frozen=True)
class KernelSet:
    """One family of runs: a built-in scene and the overrides that select the family."""

    name: str
    scene: str | None
    overrides: tuple[str, ...]
    description: str
    warm: Callable[[], float] | None = None  # instead of a scene: a function that warms the set


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
                               "beam, Galerkin (weak form, the default), fixed step (every built-in beam scene)"),
    "rigid_body": KernelSet("rigid_body", "heavy_top", (), "rigid body, fixed step (heavy_top, free_rigid_body)"),
    "beam_galerkin_adaptive": KernelSet("beam_galerkin_adaptive", "cantilever",
                                        ("space.formulation=galerkin",) + _ADAPTIVE, "beam, Galerkin, adaptive pairs"),
    "rigid_body_adaptive": KernelSet("rigid_body_adaptive", "heavy_top", _ADAPTIVE, "rigid body, adaptive pairs"),
    "beam_primal": KernelSet("beam_primal", "cantilever", ("space.formulation=primal",),
                             "beam, primal collocation (the paper's method, opt-in), fixed step"),
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


def _warm_set(name: str) -> tuple[str, float]:
    ks = KERNEL_SETS[name]
    return name, (ks.warm() if ks.warm is not None else warm_scene(ks.scene, ks.overrides))


def compile_sets(names, jobs: int | None = None, report=None) -> dict[str, float]:
    """Compile the kernel sets ``names`` (keys of :data:`KERNEL_SETS`) into numba's cache,
    ``jobs`` processes at a time (default: the machine's cores; 1 compiles in this
    process). ``report(name, seconds)`` is called as each set finishes. Returns the
    seconds per set."""
    names = list(dict.fromkeys(names))
    unknown = [n for n in names if n not in KERNEL_SETS]
    if unknown:
        raise ValueError(f"unknown kernel set {unknown[0]!r}; known: {', '.join(KERNEL_SETS)}")
    jobs = max(1, min(jobs or os.cpu_count() or 1, len(names)))
    done: dict[str, float] = {}
    if jobs == 1:
        for n in names:
            done[n] = _warm_set(n)[1]
            if report is not None:
                report(n, done[n])
        return done
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor, as_completed

    # fresh interpreters: the workers import numba themselves (no fork of a process that has)
    with ProcessPoolExecutor(max_workers=jobs, mp_context=multiprocessing.get_context("spawn")) as pool:
        futures = [pool.submit(_warm_set, n) for n in names]
        for fut in as_completed(futures):
            n, s = fut.result()
            done[n] = s
            if report is not None:
                report(n, s)
    return done
