"""Command line: ``liegroup-int run|static|modes|buckle|scenes|compile ...``.

Errors in scenes or arguments print one line ``error: ...`` and exit with code 2; a run
that stops early (blow-up) exits with code 3 after saving what it computed.
"""

from __future__ import annotations

import argparse
import time
import sys
from pathlib import Path

from .scenes import SceneError, builtin_descriptions, load_scene, parse_override


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="liegroup-int", description="Explicit RKMK integration on Lie groups: rigid bodies and beams.")
    p.add_argument("--version", action="version", version=f"%(prog)s {__import__('liegroup_int').__version__}")
    sub = p.add_subparsers(dest="command", required=True)
    _add_run_commands(sub)
    _add_study_commands(sub)
    _add_result_commands(sub)
    _add_linear_commands(sub)
    _add_tool_commands(sub)
    return p


def _add_run_commands(sub) -> None:
    """``run`` and ``static``: a scene solved in time or at rest."""
    run = sub.add_parser("run", help="run a scene (a TOML path or a built-in name)")
    run.add_argument("scene", nargs="?", default=None,
                     help="scene file or built-in scene name (see `liegroup-int scenes`); optional with --resume")
    run.add_argument("--out", type=Path, default=None, help="output directory (default: runs/SCENE)")
    run.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                     help="override a scene key, e.g. --set integrator.dt=1e-4 (repeatable)")
    run.add_argument("--quiet", action="store_true", help="no progress bar")
    run.add_argument("--no-plots", action="store_true", help="skip history.png and shapes.png (output.plots=false)")
    run.add_argument("--overwrite", action="store_true", help="replace the run already in the output directory")
    run.add_argument("--resume", type=Path, default=None, metavar="DIR",
                     help="continue the run stored in DIR from its checkpoint (with --set t_end=T to extend it)")
    stt = sub.add_parser("static", help="static equilibrium of a beam scene (Newton-Raphson with load steps)")
    stt.add_argument("scene", help="scene file or built-in scene name (space.formulation = \"galerkin\")")
    stt.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                     help="override a scene key (repeatable)")
    stt.add_argument("--out", type=Path, default=None, help="output directory (default: runs/SCENE-static)")
    stt.add_argument("--arc-length", type=float, default=None, metavar="DS",
                     help="follow the equilibrium path by arc-length continuation with steps DS (norm of (eta / L, "
                          "Theta, load factor)) through limit points, up to load factor 1 or --steps steps")
    stt.add_argument("--steps", type=int, default=10, help="load steps (load factors 1/N, 2/N, ..., 1; default 10)")
    stt.add_argument("--tol", type=float, default=1e-8,
                     help="residual norm relative to the load norm at which a step has converged (default 1e-8)")
    stt.add_argument("--max-iter", type=int, default=30, help="Newton iterations per load step (default 30)")
    stt.add_argument("--time", type=float, default=None, metavar="T",
                     help="time at which the load profiles are evaluated (default: the scene's t_end)")
    stt.add_argument("--quiet", action="store_true", help="no per-step residuals")


def _add_study_commands(sub) -> None:
    """``validate``, ``converge`` and ``sweep``: checks and studies of a scene."""
    val = sub.add_parser("validate", help="check a scene without running it")
    val.add_argument("scene")
    val.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE")
    val.add_argument("--spectrum", action="store_true",
                     help="also compute the linearized spectrum at the initial state: largest |lambda|, largest "
                          "Re lambda (growing modes), stable steps")
    for name, helptext in (("converge", "run a scene over values of one key and fit the convergence rate"),
                           ("sweep", "run a scene over a grid of key values")):
        st = sub.add_parser(name, help=helptext)
        st.add_argument("scene")
        if name == "converge":
            st.add_argument("--param", required=True, metavar="KEY", help="the key to vary, e.g. integrator.dt")
            st.add_argument("--values", required=True, nargs="+", metavar="V", help="its values")
            st.add_argument("--quantity", default="auto",
                            help="final field(s) compared, e.g. tip or R+omega_body (default: by problem)")
            st.add_argument("--finer", choices=("larger", "smaller"), default=None,
                            help="which values of KEY are finer (known for n_ctrl, degree, dt, rtol, atol)")
        else:
            st.add_argument("--grid", required=True, nargs="+", metavar="KEY=V1,V2", help="grid axes")
        st.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE")
        st.add_argument("--out", type=Path, default=None, help="study directory (default: studies/SCENE-<command>)")
        st.add_argument("--scheduler", default=None, metavar="ADDRESS",
                        help="address of a running Dask scheduler (default: a local cluster of processes)")
        st.add_argument("--workers", type=int, default=2, help="local cluster size")
        st.add_argument("--serial", action="store_true", help="run in this process, without Dask")


def _add_result_commands(sub) -> None:
    """``plot`` and ``bench``: pictures of runs, work-precision."""
    pl = sub.add_parser("plot", help="plot a run directory (history, deformed shapes) as PNG and PDF")
    pl.add_argument("dir", type=Path, help="output directory of a run")
    pl.add_argument("--times", type=float, nargs="+", default=None, metavar="T",
                    help="times of the deformed shapes (nearest recorded outputs)")
    be = sub.add_parser("bench", help="work-precision of a beam scene: RKMK methods against PyElastica")
    be.add_argument("scene", help="pendulum, cantilever, spinning_helix (with PyElastica), or any beam scene (ours only)")
    be.add_argument("--quick", action="store_true", help="short span, coarse ladder (about a minute)")
    be.add_argument("--t-end", type=float, default=None, metavar="T", help="span of the compared tip history [s]")
    be.add_argument("--no-peer", action="store_true", help="skip the PyElastica runs")
    be.add_argument("--backend", default="numba", choices=("numba", "numpy"), help="our stage kernels")
    be.add_argument("--budget", type=float, default=None, metavar="S",
                    help="skip our runs predicted to need more CPU seconds than this")
    be.add_argument("--out", type=Path, default=None, help="output directory (default: bench/SCENE)")
    be.add_argument("--fresh", action="store_true", help="recompute instead of reusing cached runs")


def _add_linear_commands(sub) -> None:
    """``modes`` and ``buckle``: linearizations of a beam scene."""
    mo = sub.add_parser("modes", help="natural frequencies, damping ratios and mode shapes at the initial state")
    mo.add_argument("scene")
    mo.add_argument("--n", type=int, default=10, help="number of modes (lowest |lambda| first; default 10)")
    mo.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE")
    mo.add_argument("--out", type=Path, default=None, help="output directory (default: runs/SCENE-modes)")
    mo.add_argument("--no-estimate", action="store_true",
                    help="skip the error estimate (the same modes on the next finer mesh)")
    mo.add_argument("--about", choices=("initial", "static"), default="initial",
                    help="linearize about the initial state (default) or about the static equilibrium under the "
                         "scene's loads at t_end (prestressed modes; beams with space.formulation = \"galerkin\")")
    mo.add_argument("--steps", type=int, default=10, help="load steps of the static solve with --about static "
                                                           "(default 10)")
    bk = sub.add_parser("buckle", help="critical load factors and buckling modes of a beam scene (galerkin)")
    bk.add_argument("scene", help="scene file or built-in scene name (space.formulation = \"galerkin\")")
    bk.add_argument("--n", type=int, default=3, help="number of critical load factors (lowest first; default 3)")
    bk.add_argument("--steps", type=int, default=10,
                    help="load steps per unit load factor: the linear analysis uses the tangent at 1/N, the "
                         "refinement follows the load path in steps of at most 1/N (default 10)")
    bk.add_argument("--no-refine", action="store_true",
                    help="linear buckling only (no refinement of the lowest factor along the load path)")
    bk.add_argument("--time", type=float, default=None, metavar="T",
                    help="time at which the load profiles are evaluated (default: the scene's t_end)")
    bk.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE")
    bk.add_argument("--out", type=Path, default=None, help="output directory (default: runs/SCENE-buckle)")


def _add_tool_commands(sub) -> None:
    """``compile`` and ``scenes``."""
    co = sub.add_parser("compile", help="compile the kernels of the built-in scenes ahead of the first run")
    co.add_argument("sets", nargs="*", metavar="SET",
                    help="kernel sets to compile (default: those of the built-in scenes as shipped; "
                         "`--list` names them all)")
    co.add_argument("--all", action="store_true", help="every kernel set: adaptive pairs and the primal collocation too")
    co.add_argument("--jobs", type=int, default=None, metavar="N", help="processes compiling side by side (default: cores)")
    co.add_argument("--list", action="store_true", help="list the kernel sets")
    sc = sub.add_parser("scenes", help="list the built-in scenes")
    sc.add_argument("--reference", action="store_true", help="print the scene key reference (Markdown)")


def _claim(out: Path, overwrite: bool, scene: str) -> None:
    """Refuse an output directory that holds another run, saying what it holds and what to
    do (:func:`liegroup_int.runner.run_dir_advice`), or clear it with ``--overwrite`` (stale
    VTU files and plots must not sit next to the new ones)."""
    from .runner import run_dir_advice

    advice = run_dir_advice(out, scene)
    if advice is None:
        return
    if not overwrite:
        raise SceneError(advice)
    import shutil

    shutil.rmtree(out)


def _load(args):
    """The scene of ``args``; loading checks it (a large mesh builds its discretization), so a
    load longer than a few seconds says so (``SetupNotice``)."""
    from .runner import SetupNotice

    overrides = dict(parse_override(s) for s in args.overrides)
    with SetupNotice(str(args.scene), enabled=not getattr(args, "quiet", False)):
        return load_scene(args.scene, overrides)


def _study(args) -> int:
    from . import studies

    overrides = dict(parse_override(s) for s in args.overrides)
    name = Path(args.scene).stem
    out = args.out if args.out is not None else Path("studies") / f"{name}-{args.command}"
    if args.command == "converge":
        try:
            studies.finer_direction(args.param, args.finer)
        except ValueError as exc:
            raise SceneError(f"converge: {exc}") from None
        grid = studies.expand_grid({args.param: studies.parse_values(args.param, args.values)})
    else:
        grid = studies.expand_grid(studies.parse_grid(args.grid))
    import time

    clock = time.perf_counter()
    try:
        rows = studies.run_study(args.scene, overrides, grid, out, scheduler=args.scheduler, n_workers=args.workers,
                                 serial=args.serial)
    except ImportError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except studies.StudyInterrupted as exc:
        if exc.rows:
            studies.write_study(out, exc.rows)
        print(f"error: {exc}; the finished runs are in {out}/study.csv; the same command continues the study",
              file=sys.stderr)
        return 130
    workers = 1 if args.serial else (args.workers if args.scheduler is None else 1)
    split = studies.time_split(rows, time.perf_counter() - clock, workers)
    table, no_table = None, None
    if args.command == "converge":
        try:
            table = studies.convergence_table(rows, args.param, quantity=args.quantity, finer=args.finer)
        except ValueError as exc:  # e.g. every run failed: the rows are still written
            no_table = str(exc)
    studies.write_study(out, rows, table, timing=split)
    failed = [r for r in rows if r["status"] != "ok"]
    for r in rows:
        wall = r["wall_time_s"]
        print(f"{r['run']:>4}  {r['overrides']}  {r['status']}  steps={r['steps']}  "
              f"wall={'-' if wall is None else format(wall, '.3g')} s")
    if table is not None:
        _print_table(table, rows)
    print(studies.format_time_split(split))
    if no_table is not None:
        first = next((r.get("error") for r in failed if r.get("error")), None)
        print(f"error: no convergence table: {no_table}" + (f" (run 0: {first})" if first else ""), file=sys.stderr)
    print(f"-> {out}")
    return 3 if failed else 0


def _print_table(table, rows=()) -> None:
    """A convergence table, coarse to fine, and its fitted rate or why there is none (for a
    step-size study, and a rate that is not the method's order, a note saying so)."""
    from . import studies

    if table:
        print(f"errors, coarse to fine, against the finest run (run {table[0]['reference_run']}; "
              f"{table[0]['finer']} {table[0]['param']} is finer):")
    for e in table:
        if e["error"] is not None:
            flag = "  (within 100x of round-off: not fitted)" if e.get("round_off") else ""
            print(f"  {e['param']} = {e['value']!r}: error {e['error']:.3e}{flag}")
        else:
            print(f"  {e['param']} = {e['value']!r}: {e['status']}")
    try:
        fit = studies.fit_table(table)
    except ValueError as exc:
        print(f"no rate fitted: {exc}")
        return
    print(studies.format_fit(fit, table[0]["param"], table[0]["finer"]))
    methods = {r.get("method") for r in rows if r.get("status") == "ok"}
    if table[0]["param"] == "integrator.dt" and len(methods) == 1:
        note = studies.order_note(fit, methods.pop())
        if note:
            print(note)


def _spectrum(scene) -> int:
    """``validate --spectrum``: dense linearized spectrum at the initial state."""
    from .integrators import growth_check, resolve_method, stable_step
    from .scenes import KINDS

    sim = KINDS[scene.kind].build(scene)
    try:
        rep = growth_check(sim.problem, 0.0, sim.y0, scene.t_end)
    except ValueError as exc:
        print(f"error: {scene.source}: {exc}", file=sys.stderr)
        return 2
    kv = sim.info.get("kelvin_voigt_auto")
    if isinstance(kv, str):
        print(f"kelvin_voigt = auto: {kv}")
    elif kv is not None:
        print(f"kelvin_voigt = auto: tau = {kv['tau']:.3g} s (undamped max Re lambda = {kv['max_real_undamped']:.3g} "
              f"1/s at |Im| = {kv['at_imag']:.4g} 1/s; damping ratio on mode 1: {kv['zeta1']:.2g})")
    print(f"spectrum at t=0 ({rep.size} unknowns): |lambda|max = {rep.lam_max:.4g} 1/s, "
          f"max Re lambda = {rep.max_real:.3g} 1/s (at |Im| = {rep.at_imag:.4g} 1/s)")
    if rep.lam_max > 0:
        for m in ("rkmk3", "rkmk4", "rkmk6", "rkmk65"):
            st = stable_step(resolve_method(m), rep.lam_max, scene.t_end)
            print(f"  stable dt {m:7s} {st.dt:.3g} s ({st.rule})")
    if rep.growing:
        print(f"warning: {scene.source}: a linearized mode grows like exp({rep.max_real:.3g} t) "
              f"({rep.max_real * scene.t_end:.3g} e-folds over t_end = {scene.t_end:g} s). About a state at rest an "
              "undamped structure has a purely imaginary spectrum, so such a mode is a spurious instability of the "
              "discretization and the run will blow up whatever dt (docs/verification.md, 'Stability maps'; for "
              "beams try material.kelvin_voigt = \"auto\" or another n_ctrl); about a moving state it may be the "
              "physical divergence of nearby trajectories", file=sys.stderr)
    return 0


def _bench(args) -> int:
    from dataclasses import replace

    from . import bench

    if args.t_end is not None and not args.t_end > 0:
        print(f"error: --t-end must be positive, got {args.t_end}", file=sys.stderr)
        return 2
    if args.budget is not None and not args.budget > 0:
        print(f"error: --budget must be positive, got {args.budget}", file=sys.stderr)
        return 2
    try:
        plan = bench.plan_for(args.scene, quick=args.quick, t_end=args.t_end)
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if args.budget is not None:
        plan = replace(plan, budget_s=args.budget)
    out = args.out if args.out is not None else Path("bench") / (Path(args.scene).stem + ("-quick" if args.quick else ""))
    print(f"work-precision of {args.scene}: T = {plan.t_end:g} s -> {out}")
    try:
        result = bench.work_precision(plan, out, backend=args.backend, peer=not args.no_peer, fresh=args.fresh)
    except KeyboardInterrupt:
        print(f"error: interrupted; finished runs are kept in {out / 'runs'} and reused by the next call",
              file=sys.stderr)
        return 130
    except RuntimeError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 3
    made = bench.write(result, out)
    print()
    print(bench.markdown(result))
    print("\n".join(str(p) for p in made))
    return 0


#: Relative change of a frequency on the next finer mesh above which ``modes`` calls it
#: unconverged.
MODES_UNCONVERGED = 1e-3
#: Modes with ``|lambda|`` below this fraction of ``|lambda|max`` are rigid-body motion up
#: to the finite differences' noise: no error estimate.
NEAR_ZERO = 1e-6


def _linearization(args, scene, n: int, duration: float | None = None):
    """The modal analysis of ``modes``: ``(sim, report, state, words)``, about the initial
    state at t = 0 or (``--about static``) about the static equilibrium under the loads at
    ``t_end`` (:func:`~liegroup_int.problems.beam.buckling.prestressed_modes`); ``words``
    say which, for the header."""
    from .integrators import modal_analysis
    from .scenes import KINDS

    if args.about == "static":
        from .static_run import check_scene

        check_scene(scene, "modes --about static")
    sim = KINDS[scene.kind].build(scene)
    if args.about == "initial":
        return sim, modal_analysis(sim.problem, 0.0, sim.y0, n, duration=duration), sim.y0, "at t = 0"
    from .problems.beam.buckling import prestressed_modes

    pm = prestressed_modes(sim.problem, n, t=scene.t_end, load_steps=args.steps, duration=duration)
    return sim, pm.report, pm.static.state, (f"about the static equilibrium (load factor 1, "
                                             f"{sum(pm.static.iterations)} Newton iterations; loads at t = "
                                             f"{scene.t_end:g})")


def _finer_frequencies(args, scene, n: int, floor: float):
    """The lowest frequencies of the scene on the next finer mesh of its kind (about that
    mesh's own equilibrium with ``--about static``), modes with ``|lambda| <= floor`` left
    out (the near-zero modes of the coarse mesh, :data:`NEAR_ZERO`, by the coarse mesh's
    ``|lambda|max``: the finer mesh's is larger, and a low physical mode, e.g. a column's
    bending mode near its buckling load, would fall below its own threshold and shift the
    pairing): ``(freq_hz or None, what was refined or why not)``."""
    from .problems.beam.statics import StaticDivergence
    from .scenes import KINDS

    kind = KINDS[scene.kind]
    if kind.refine is None:
        return None, f"no finer mesh for a {scene.kind} problem"
    extra, why = kind.refine(scene)
    if extra is None:
        return None, why
    fine = load_scene(args.scene, {**dict(parse_override(s) for s in args.overrides), **extra})
    try:
        _, rep, _, _ = _linearization(args, fine, n + 12)  # room for near-zero modes
    except (ValueError, StaticDivergence) as exc:
        return None, f"finer mesh: {exc}"
    return [m.freq_hz for m in rep.modes if abs(m.lam) > floor], \
        ", ".join(f"{k} = {v}" for k, v in extra.items())


def _zero_modes_text(kind, sim, rep) -> str:
    """The header's account of the zero eigenvalues: constraints apart from rigid-body modes
    (two zero eigenvalues per held degree of freedom or rigid-body mode)."""
    held = kind.constrained(sim.problem) if kind.constrained is not None else None
    free = None if held is None else rep.zero_modes - 2 * held
    if free is None or free < 0 or free % 2:
        return f"{rep.zero_modes} zero eigenvalues: constraints and rigid-body modes"
    return (f"{rep.zero_modes} zero eigenvalues: {2 * held} from the {held} degrees of freedom held by supports "
            f"and joints, {free} from free rigid-body motion")


def _modes_table(rows: list[dict], estimate: str) -> None:
    print(f"{'mode':>4}  {'f [Hz]':>12}  {'damping ratio':>13}  {'finer mesh':>10}  dominant")
    for r in rows:
        flag = ("  (near zero: rigid-body motion)" if r["near_zero"] else "") + (
            "  (non-oscillatory)" if r["im_lambda"] == 0.0 or abs(r["damping_ratio"]) >= 1.0 else "") + (
            "  GROWING" if r["growing"] else "") + (
            "  UNCONVERGED" if r["rel_change_finer"] != "" and r["rel_change_finer"] > MODES_UNCONVERGED else "")
        change = f"{r['rel_change_finer']:10.2g}" if r["rel_change_finer"] != "" else f"{'-':>10}"
        print(f"{r['mode']:>4}  {r['freq_hz']:12.6g}  {r['damping_ratio']:13.3g}  {change}  {r['dominant']}{flag}")
    changes = [r["rel_change_finer"] for r in rows if r["rel_change_finer"] != ""]
    if not changes:
        print(f"discretization error: not estimated ({estimate})")
        return
    bad = [r["mode"] for r in rows if r["rel_change_finer"] != "" and r["rel_change_finer"] > MODES_UNCONVERGED]
    print(f"discretization error: relative change on the next finer mesh ({estimate}) at most {max(changes):.2g} "
          "(about 1e-7 is the finite-difference Jacobian's noise)"
          + (f"; modes {', '.join(map(str, bad))} change by more than {MODES_UNCONVERGED:g}: unconverged, refine "
             "the mesh" if bad else ""))


def _modes(args) -> int:
    """``modes``: the linearized increment map at the initial state (or about the static
    equilibrium), its lowest modes, and how much they move on the next finer mesh."""
    import numpy as np

    from .problems.beam.statics import StaticDivergence
    from .scenes import KINDS

    if args.n < 1:
        raise SceneError(f"modes: --n {args.n}: expected at least one mode")
    if args.steps < 1:
        raise SceneError(f"modes: --steps {args.steps}: expected a positive number of load steps")
    scene = _load(args)
    try:
        sim, rep, state, about = _linearization(args, scene, args.n, duration=scene.t_end)
    except SceneError:
        raise
    except ValueError as exc:
        raise SceneError(f"{scene.source}: {exc}") from None
    except StaticDivergence as exc:
        print(f"error: {scene.source}: {exc}", file=sys.stderr)
        return 3
    floor = NEAR_ZERO * rep.lam_max
    finer, estimate = (None, "--no-estimate") if args.no_estimate else _finer_frequencies(args, scene, args.n, floor)
    out = args.out if args.out is not None else Path("runs") / f"{scene.name}-modes"
    from .io.modes import dominant, plot_modes, real_shapes, write_mode_shapes, write_modes_csv

    rows = [{"mode": k, "freq_hz": m.freq_hz, "damping_ratio": m.damping_ratio, "re_lambda": m.lam.real,
             "im_lambda": m.lam.imag, "growing": m.growing, "dominant": "", "rel_change_finer": "",
             "near_zero": bool(abs(m.lam) <= floor)} for k, m in enumerate(rep.modes, start=1)]
    # the modes above the noise, paired in order with those of the finer mesh
    paired = [r for r in rows if not r["near_zero"]]
    for r, f in zip(paired, finer or []):
        r["rel_change_finer"] = abs(r["freq_hz"] / f - 1.0)
    shapes = []
    shape_of = sim.mode_shape if args.about == "initial" else _equilibrium_shape(sim.problem, state)
    if shape_of is not None:
        shapes = real_shapes([shape_of(m.vector) for m in rep.modes], [m.freq_hz for m in rep.modes])
        for row, (points, disp, rot) in zip(rows, shapes):
            row["dominant"] = dominant(disp, rot, float(np.max(np.ptp(points, axis=0))) or 1.0)
    out.mkdir(parents=True, exist_ok=True)
    made = [write_modes_csv(out / "modes.csv", rows)]
    if shapes:
        made += write_mode_shapes(out, shapes)
        labels = [f"mode {r['mode']}: {r['freq_hz']:.4g} Hz ({r['dominant']})" for r in rows]
        made.append(plot_modes(out / "modes.png", shapes, labels, title=f"{scene.name}: mode shapes "
                               + ("at t = 0" if args.about == "initial" else "about the static equilibrium")))
    print(f"{scene.name}: {len(rows)} lowest modes of the linearization {about} ({rep.size} unknowns; "
          f"{_zero_modes_text(KINDS[scene.kind], sim, rep)}; |lambda|max = {rep.lam_max:.4g} 1/s)")
    _modes_table(rows, estimate)
    if args.about == "initial" and scene.kind == "beam" and _off_equilibrium(sim.problem, state, rep, floor):
        print(f"note: {scene.source}: the state at t = 0 is at rest but not in equilibrium under the loads there "
              "(the reference, unstressed), so these modes leave out what the loads do to the stiffness and, under "
              "gravity, to hanging bodies; modes --about static gives those of the loaded structure", file=sys.stderr)
    grow = [r for r in rows if r["growing"]]
    if grow:
        print(f"warning: {scene.source}: {len(grow)} growing mode(s) {about.split(' (')[0]} (Re lambda > 0, growth by "
              f"more than e over t_end), the fastest {max(r['re_lambda'] for r in grow):.3g} 1/s", file=sys.stderr)
    listed = [made[0].name] + ([made[-1].name, "mode_XX.vtu", "modes.pvd"] if shapes else [])
    print(f"-> {out} ({', '.join(listed)})")
    return 0


def _off_equilibrium(problem, y, rep, floor: float) -> bool:
    """Whether a beam state at rest accelerates under its loads by more than round-off: the
    largest acceleration over the lowest mode's ``omega^2`` (the displacement it would cause
    in that mode) above 1e-6 of the structure's size."""
    import numpy as np

    if np.any(y.v) or np.any(y.w):
        return False
    omega = [abs(m.lam) for m in rep.modes if abs(m.lam) > floor]
    acc = float(np.max(np.abs(problem.vector_field(0.0, y)[2:])))
    size = float(np.max(np.ptp(np.asarray(y.c), axis=0))) or 1.0
    return bool(omega) and acc / min(omega) ** 2 > 1e-6 * size


def _equilibrium_shape(problem, state):
    """Mode shapes on the centreline of an equilibrium ``state`` (beams)."""
    from .scenes.beam import mode_shape

    return mode_shape(problem, state)


def _compile(args) -> int:
    import time

    from .precompile import DEFAULT_SETS, KERNEL_SETS, compile_sets, write_bytecode

    if args.list:
        for name, ks in KERNEL_SETS.items():
            print(f"{name:22s} {ks.description}")
        return 0
    names = list(KERNEL_SETS) if args.all else (args.sets or list(DEFAULT_SETS))
    unknown = [n for n in names if n not in KERNEL_SETS]
    if unknown:
        import difflib

        close = difflib.get_close_matches(unknown[0], list(KERNEL_SETS), n=1)
        hint = f" (did you mean {close[0]!r}?)" if close else f"; known: {', '.join(KERNEL_SETS)}"
        raise SceneError(f"compile: unknown kernel set {unknown[0]!r}{hint}")
    if args.jobs is not None and args.jobs < 1:
        raise SceneError(f"compile: --jobs {args.jobs}: expected a positive number of processes")
    print(f"compiling {len(names)} kernel set(s): {', '.join(names)} (cached for later runs)", file=sys.stderr)
    c = time.perf_counter()
    write_bytecode()  # first: the worker processes then import the package from it
    compile_sets(names, args.jobs, report=lambda n, s: print(f"  {n}: {s:.1f} s", file=sys.stderr))
    print(f"compiled in {time.perf_counter() - c:.1f} s", file=sys.stderr)
    return 0


def _scenes(args) -> int:
    if args.reference:
        from .scenes.reference import schema_markdown

        print(schema_markdown())
        return 0
    for name, desc in builtin_descriptions().items():
        print(f"{name:24s} {desc}")
    return 0


def _static(args) -> int:
    from .static_run import main_static

    return main_static(args)


def _buckle(args) -> int:
    from .buckle_run import main_buckle

    return main_buckle(args)


def _plot(args) -> int:
    from .io import plot_run

    try:
        made = plot_run(args.dir, args.times)
    except FileNotFoundError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print("\n".join(str(p) for p in made))
    return 0


def _validate(args) -> int:
    scene = _load(args)
    print(f"{scene.source}: ok ({scene.kind}, t_end={scene.t_end:g} s, method={scene.integrator.method})")
    return _spectrum(scene) if args.spectrum else 0


def _run(args) -> int:
    """``run``: a new run into ``--out`` or the continuation of ``--resume DIR``."""
    from .runner import RunError, format_outputs, resume_run, run_scene

    if args.no_plots:
        args.overrides.append("output.plots=false")
    if args.resume is None and args.scene is None:
        raise SceneError("run: give a SCENE (or --resume DIR)")
    try:
        if args.resume is not None:
            overrides = dict(parse_override(s) for s in args.overrides)
            res = resume_run(args.resume, overrides, quiet=args.quiet, scene=args.scene)
            out = args.resume
            scene_name = res.summary["scene"]
        else:
            c0 = time.perf_counter()
            scene = _load(args)
            out = args.out if args.out is not None else Path("runs") / scene.name
            scene_name = scene.name
            res = run_scene(scene, out, quiet=args.quiet, claim=lambda d: _claim(d, args.overwrite, args.scene),
                            load_s=time.perf_counter() - c0)
    except RunError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 130 if "interrupted" in str(exc) else 3
    except OSError as exc:  # an output directory or file that cannot be written
        where = exc.filename if exc.filename else (args.resume or args.out)
        print(f"error: cannot write {where}: {exc.strerror or exc}", file=sys.stderr)
        return 2
    s = res.summary
    resumed = s.get("resumed_from")
    took = f"{s['wall_time_s']:.3g} s" if resumed is None else f"{s['wall_time_s']:.3g} s since the resume at t = {resumed:.6g} s"
    print(f"{scene_name}: {s['steps']} steps, {s['rhs_evals']} rhs evals, {took} -> {out}")
    print(format_outputs(s))
    return 0


#: What each subcommand runs.
COMMANDS = {"scenes": _scenes, "converge": _study, "sweep": _study, "compile": _compile, "static": _static,
            "modes": _modes, "buckle": _buckle, "bench": _bench, "plot": _plot, "validate": _validate, "run": _run}


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    try:
        return COMMANDS[args.command](args)
    except SceneError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
