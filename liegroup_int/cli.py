"""Command line: ``liegroup-int run|scenes ...``.

Errors in scenes or arguments print one line ``error: ...`` and exit with code 2; a run
that stops early (blow-up) exits with code 3 after saving what it computed.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .scenes import SceneError, builtin_descriptions, load_scene, parse_override


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="liegroup-int", description="Explicit RKMK integration on Lie groups: rigid bodies and beams.")
    p.add_argument("--version", action="version", version=f"%(prog)s {__import__('liegroup_int').__version__}")
    sub = p.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run", help="run a scene (a TOML path or a built-in name)")
    run.add_argument("scene", help="scene file or built-in scene name (see `liegroup-int scenes`)")
    run.add_argument("--out", type=Path, default=None, help="output directory (default: runs/SCENE)")
    run.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                     help="override a scene key, e.g. --set integrator.dt=1e-4 (repeatable)")
    run.add_argument("--quiet", action="store_true", help="no progress bar")
    run.add_argument("--resume", type=Path, default=None, metavar="DIR",
                     help="continue the run stored in DIR from its checkpoint (with --set t_end=T to extend it)")
    val = sub.add_parser("validate", help="check a scene without running it")
    val.add_argument("scene")
    val.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE")
    pl = sub.add_parser("plot", help="plot a run directory (history, deformed shapes) as PNG and PDF")
    pl.add_argument("dir", type=Path, help="output directory of a run")
    pl.add_argument("--times", type=float, nargs="+", default=None, metavar="T",
                    help="times of the deformed shapes (nearest recorded outputs)")
    sc = sub.add_parser("scenes", help="list the built-in scenes")
    sc.add_argument("--reference", action="store_true", help="print the scene key reference (Markdown)")
    return p


class _ArgParser(argparse.ArgumentParser):
    pass


def _load(args):
    overrides = dict(parse_override(s) for s in args.overrides)
    return load_scene(args.scene, overrides)


def main(argv: list[str] | None = None) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    try:
        if args.command == "scenes":
            if args.reference:
                from .scenes.reference import schema_markdown

                print(schema_markdown())
                return 0
            for name, desc in builtin_descriptions().items():
                print(f"{name:24s} {desc}")
            return 0
        if args.command == "plot":
            from .io import plot_run

            try:
                made = plot_run(args.dir, args.times)
            except FileNotFoundError as exc:
                print(f"error: {exc}", file=sys.stderr)
                return 2
            print("\n".join(str(p) for p in made))
            return 0
        if args.command == "validate":
            scene = _load(args)
            print(f"{scene.source}: ok ({scene.kind}, t_end={scene.t_end:g} s, method={scene.integrator.method})")
            return 0
        if args.command == "run":
            from .runner import Interrupted, RunError, resume_run, run_scene

            try:
                if args.resume is not None:
                    overrides = dict(parse_override(s) for s in args.overrides)
                    res = resume_run(args.resume, overrides, quiet=args.quiet)
                    out = args.resume
                    scene_name = res.summary["scene"]
                else:
                    scene = _load(args)
                    out = args.out if args.out is not None else Path("runs") / scene.name
                    scene_name = scene.name
                    res = run_scene(scene, out, quiet=args.quiet)
            except RunError as exc:
                print(f"error: {exc}", file=sys.stderr)
                return 130 if "interrupted" in str(exc) else 3
            s = res.summary
            print(f"{scene_name}: {s['steps']} steps, {s['rhs_evals']} rhs evals, {s['wall_time_s']:.3g} s -> {out}")
            return 0
    except SceneError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    return 0
