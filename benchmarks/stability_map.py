"""Stability maps of the beam discretizations: largest Re(lambda) over (p, n_ctrl).

    python benchmarks/stability_map.py [--scenes cantilever pendulum arch]
        [--states rest half_circle full_circle t=2] [--formulations primal galerkin]
        [--damping none auto] [--degrees 2 3 4 5 6 7 8] [--n 11 21 31 41 61 81 121]

Each entry is the dense spectrum of the linearized increment map at one state
(liegroup_int/bench/stability.py): at rest (the scene's initial state), about the static
half and full circle of the roll-up beam, or at the state a run reaches at time T.
Prints one table per (scene, state, formulation, damping) with max Re(lambda) [1/s]
(``.`` for at most 1e-2 1/s, the growth threshold), and with ``--damping auto`` the
Kelvin-Voigt time sized per discretization and its damping ratio on the first mode.
Entries are cached in bench/stability_map.json (delete it to recompute); the tables go
to docs/img/stability_map_*.png as heat maps. ``--quick``: the cantilever at rest, primal,
p = 3, n_ctrl = 11, cache and heat map in a temporary directory (or ``--out``).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from liegroup_int.bench.stability import map_entry
from liegroup_int.bench.table import figure_dir, parser

ROOT = Path(__file__).resolve().parents[1]
CACHE = ROOT / "bench" / "stability_map.json"
IMG = ROOT / "docs" / "img"


def _key(scene, state, formulation, damping, p, n):
    return f"{scene}|{state}|{formulation}|{damping}|{p}|{n}"


def _load(path: Path):
    return json.loads(path.read_text()) if path.exists() else {}


def _save(cache, path: Path):
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(cache, indent=1))
    tmp.replace(path)


def _cell(e: dict) -> str:
    if e.get("note", "").startswith("refused"):
        return "refused"
    if e.get("note"):
        return "fail"
    r = e["max_real"]
    return "." if r <= 1e-2 else f"{r:.2g}"


def table(entries: list[dict], degrees, ns, damping: str) -> str:
    head = "| p \\ n_ctrl | " + " | ".join(str(n) for n in ns) + " |"
    lines = [head, "|" + "---|" * (len(ns) + 1)]
    by = {(e["degree"], e["n_ctrl"]): e for e in entries}
    for p in degrees:
        row = []
        for n in ns:
            e = by.get((p, n))
            if e is None:
                row.append("")
                continue
            cell = _cell(e)
            if damping == "auto" and e["tau"] > 0:
                cell += f" (tau {e['tau']:.1g}, zeta1 {e['zeta1']:.1g})"
            row.append(cell)
        lines.append(f"| {p} | " + " | ".join(row) + " |")
    return "\n".join(lines)


def heatmap(entries, degrees, ns, title, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    by = {(e["degree"], e["n_ctrl"]): e for e in entries}
    z = np.full((len(degrees), len(ns)), np.nan)
    for i, p in enumerate(degrees):
        for j, n in enumerate(ns):
            e = by.get((p, n))
            if e is not None and not e.get("note"):
                z[i, j] = np.log10(max(e["max_real"], 1e-3))
    fig, ax = plt.subplots(figsize=(6.4, 3.6))
    im = ax.imshow(z, origin="lower", cmap="magma_r", vmin=-3, vmax=5, aspect="auto")
    ax.set_xticks(range(len(ns)), [str(n) for n in ns])
    ax.set_yticks(range(len(degrees)), [str(p) for p in degrees])
    ax.set_xlabel("n_ctrl")
    ax.set_ylabel("degree p")
    for i in range(len(degrees)):
        for j in range(len(ns)):
            e = by.get((degrees[i], ns[j]))
            if e is not None:
                ax.text(j, i, _cell(e), ha="center", va="center", fontsize=7,
                        color="white" if np.isfinite(z[i, j]) and z[i, j] > 2 else "black")
    fig.colorbar(im, ax=ax, label="log10 max(Re lambda, 1e-3) [1/s]")
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None):
    ap = parser(__doc__, quick_help="cantilever at rest, primal, p = 3, n_ctrl = 11")
    ap.add_argument("--scenes", nargs="+", default=["cantilever", "pendulum", "arch"])
    ap.add_argument("--states", nargs="+", default=["rest"])
    ap.add_argument("--formulations", nargs="+", default=["primal"])
    ap.add_argument("--damping", nargs="+", default=["none"])
    ap.add_argument("--degrees", nargs="+", type=int, default=list(range(2, 9)))
    ap.add_argument("--n", nargs="+", type=int, default=[11, 21, 31, 41, 61, 81, 121])
    ap.add_argument("--no-plots", action="store_true")
    args = ap.parse_args(argv)
    img = figure_dir(args, IMG)
    if args.quick:
        args.scenes, args.states, args.formulations, args.damping = ["cantilever"], ["rest"], ["primal"], ["none"]
        args.degrees, args.n = [3], [11]
    cache_path = img / "stability_map.json" if args.quick or args.out is not None else CACHE
    cache = _load(cache_path)
    for scene in args.scenes:
        for state in args.states:
            for form in args.formulations:
                for damping in args.damping:
                    entries = []
                    for p in args.degrees:
                        for n in args.n:
                            if n < p + 1:
                                continue
                            key = _key(scene, state, form, damping, p, n)
                            if key not in cache:
                                cache[key] = map_entry(scene, state, form, damping, p, n).as_dict()
                                _save(cache, cache_path)
                            entries.append(cache[key])
                    grow = sum(1 for e in entries if not e.get("note") and e["max_real"] > 1e-2)
                    refused = sum(1 for e in entries if e.get("note", "").startswith("refused"))
                    fails = sum(1 for e in entries if e.get("note")) - refused
                    title = f"{scene}, {state}, {form}, damping {damping}"
                    print(f"\n### {title}: {grow} of {len(entries)} growing (max Re lambda > 1e-2 1/s)"
                          + (f", {refused} refused by the damping sizing" if refused else "")
                          + (f", {fails} not reached" if fails else ""))
                    print(table(entries, args.degrees, args.n, damping))
                    if not args.no_plots:
                        name = f"stability_map_{scene}_{state.replace('=', '')}_{form}_{damping}.png"
                        heatmap(entries, args.degrees, args.n, title, img / name)


if __name__ == "__main__":
    main()
