"""Right-angle cantilever (Simo & Vu-Quoc 1988, example 5.2) against the published curves.

    python benchmarks/right_angle_cantilever.py [--runs DIR] [--n-ctrl 11 21] [--t-end 30]
        [--formulation galerkin] [--kelvin-voigt 0]

Runs the built-in scene ``right_angle_cantilever`` at each ``space.n_ctrl`` (control points
per leg; a run is reused when ``DIR/n<N>/history.csv`` exists), prints the extrema of the
out-of-plane displacement of the elbow (s = 0.5) and the tip (s = 1) with their times next to
the published ones, and saves ``docs/img/right_angle_cantilever.png``: both histories, with
the published extrema marked.

Published values: extrema of the curves of the paper's figure as digitized in AeroBeams.jl
(github.com/luizpancini/AeroBeams.jl, test/referenceData/elbowFrame/u3_elbow.txt and
u3_tip.txt, commit b9ed84ce, labelled "Simo & Vu-Quoc (1987)"; hand-digitized, about 0.2
either way); the digitized points themselves are not copied here.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from liegroup_int.bench.table import figure_dir, markdown, parser
from liegroup_int.io import read_history
from liegroup_int.runner import run_scene
from liegroup_int.scenes import load_scene

#: (curve, sign, window [s], published (value, time [s]))
EXTREMA = [
    ("elbow", +1, (0.0, 6.0), (5.50, 3.05)),
    ("tip", +1, (5.0, 10.0), (8.29, 7.67)),
    ("elbow", -1, (8.0, 13.0), (-3.87, 10.82)),
    ("tip", -1, (13.0, 18.0), (-9.67, 15.99)),
    ("elbow", +1, (22.0, 28.0), (6.11, 25.16)),
]


def histories(out: Path, n_ctrl: int, t_end: float, overrides: dict | None = None):
    if not (out / "history.csv").exists():
        run_scene(load_scene("right_angle_cantilever", {"space.n_ctrl": n_ctrl, "t_end": t_end,
                                                         "output.plots": False, "output.paraview": False,
                                                         **(overrides or {})}), out)
    h = read_history(out / "history.csv")
    return h["t"], {"elbow": h["s0p5_z"], "tip": h["s1_z"]}


def extremum(t, y, window, sign):
    m = (t >= window[0]) & (t <= window[1])
    if not np.any(m):
        return float("nan"), float("nan")
    i = int(np.argmax(sign * y[m]))
    return float(y[m][i]), float(t[m][i])


def main(argv=None) -> None:
    ap = parser(__doc__, quick_help="n_ctrl = 11 over 0.5 s, runs and figure in --out")
    ap.add_argument("--runs", type=Path, default=Path("runs/right_angle_cantilever"))
    ap.add_argument("--n-ctrl", type=int, nargs="+", default=[11])
    ap.add_argument("--t-end", type=float, default=30.0)
    ap.add_argument("--plot", type=Path, default=None, help="figure (default: OUT/right_angle_cantilever.png)")
    ap.add_argument("--formulation", choices=("primal", "galerkin"), default=None,
                    help="space.formulation (default: the scene's, galerkin)")
    ap.add_argument("--kelvin-voigt", type=float, default=None,
                    help="material.kelvin_voigt [s] (default: the scene's, 3e-4)")
    args = ap.parse_args(argv)
    out = figure_dir(args, Path("docs/img"))
    if args.quick:
        args.n_ctrl, args.t_end, args.runs = [11], 0.5, out / "runs"
    args.plot = args.plot or out / "right_angle_cantilever.png"
    over = {**({"space.formulation": args.formulation} if args.formulation else {}),
            **({"material.kelvin_voigt": args.kelvin_voigt} if args.kelvin_voigt is not None else {})}
    tag = "".join(f"_{v}" for v in over.values())
    runs = {n: histories(args.runs / f"n{n}{tag}", n, args.t_end, over) for n in args.n_ctrl}
    rows = [[f"{curve} {'max' if sign > 0 else 'min'}", f"{value:+.2f} ({time:.2f} s)",
             *[f"{v:+.3f} ({tt:.2f} s)" for v, tt in (extremum(t, y[curve], window, sign) for t, y in runs.values())]]
            for curve, sign, window, (value, time) in EXTREMA if window[0] <= args.t_end]
    print(markdown(["extremum", "published (t)", *[f"n_ctrl = {n} per leg (t)" for n in args.n_ctrl]], rows))

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 4.2))
    for n, (t, y) in runs.items():
        ax.plot(t, y["elbow"], label=f"elbow, n_ctrl = {n}")
        ax.plot(t, y["tip"], label=f"tip, n_ctrl = {n}")
    for k, (curve, _, window, (value, time)) in enumerate(EXTREMA):
        if window[0] <= args.t_end:
            ax.errorbar(time, value, xerr=0.2, yerr=0.2, fmt="o" if curve == "tip" else "s", color="k", ms=4,
                        label="published extrema (digitized, +-0.2)" if k == 0 else None)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("out-of-plane displacement u3 [m]")
    ax.set_title("Right-angle cantilever (Simo & Vu-Quoc 1988): elbow and tip"
                 + (f" ({', '.join(f'{k.split(chr(46))[1]} = {v}' for k, v in over.items())})" if over else ""))
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower left")
    fig.tight_layout()
    args.plot.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.plot, dpi=110)
    print(f"wrote {args.plot}")


if __name__ == "__main__":
    main()
