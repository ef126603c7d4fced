"""Verification studies of the beam plugin (docs/verification.md).

Five studies, all on the built-in scenes of ``liegroup_int/scenes/builtin``:

1. **Time convergence** (paper Fig. 4(a)/5(a)). Pendulum (T = 0.1 s) and cantilever
   (T = 2 ms), p = 4, n_ctrl = 31, RKMK2/3/4/6 against RKMK6 at ``|lambda|max h = 0.05``. Errors at the
   final time: ``e_c`` = max |c - c_ref| over the position control values, ``e_v`` = the
   same on the velocity control values, and the paper's ``err_L2 = |u_r - u_h| / |u_r|``
   of the displacement ``u = c(s) - c0(s)`` on 101 equally spaced points along the beam.
   The round-off floor of each measure is the difference between two RKMK6 runs at
   ``|lambda| h = 0.05`` and ``0.1`` (their time errors are far below it); points within 10x
   of a floor are left out of that measure's fit. Step sizes are given as
   ``y = |lambda|max h`` (a load switched on at t = 0 excites the top of the spectrum, so
   orders are only visible for y <~ 0.3; RKMK2 grows those modes by y^4/8 per step and is
   kept to N y^4 << 1).
2. **Space convergence** (paper Fig. 4(c)/5(c)). p = 2, 3, 4, 6, 8 (and 5, 7 for the smooth
   loads) against n_ctrl = 11..81
   at ``y = 0.3`` of each discretization (RKMK6 for the loads switched on at t = 0, whose
   top modes carry a large time error; RKMK4 for the smoothly ramped loads; a y vs y/2
   check is printed), against p = 8, n_ctrl = 121; err_L2 on 201 points, rates fitted
   against the mesh size ``h = L / (n_ctrl - p)`` over the finest four meshes.
   Each discretization is also probed for linear instability of its semi-discrete
   operator: a load-free run from rest plus a 1e-12 rad/s random angular velocity
   (RKMK4, y = 0.3, over 1/5 of the span); a growth of max |w| by more than 10x marks the
   discretization "unstable" and it is left out of the fits.
3. **First natural frequencies of the cantilever** (n_ctrl = 11, 21, 31, p = 4): free
   vibration from an initial velocity field made of the first three Euler-Bernoulli
   clamped-free modes (tip velocities 1e-3, 3e-4, 1e-4 m/s, no load), 0.5 s of RKMK4; the
   three strongest sinusoids of the tip deflection history are identified one by one
   (Hann-windowed spectral peak of the residual) and refitted together by least squares.
   Compared with Euler-Bernoulli (8.382, 52.53, 147.08 Hz) and with the linear Timoshenko
   beam of the same constants (shear factor 1, rotary inertia), solved here in 50-digit
   arithmetic. Also (3b) the frequencies of the linearized semi-discrete operator at rest
   (dense eigenvalues) for p = 2, 3, 4, 6 and n_ctrl = 11, 21, 31, 61.
4. **Energy and invariants** of the four paper scenes over their full spans with the scene
   settings (RKMK4 and the scene's dt): max |E(t) - E(t_ref)| over the kinetic-energy scale
   max_t KE(t), the orthogonality error of R, and for the spinning helix the axial angular
   momentum about x3 (through the hinge). The arch's end couple does work until it is
   removed at t = 0.25 s, so its drift is measured from t_ref = 0.25 s. To tell time from
   space error: pendulum, cantilever and helix are repeated with twice the control points
   (at dt/2), and every scene is run over a short span both with the scene's RKMK4 step and
   with RKMK6 at |lambda| dt = 0.3 (the arch with a 2 ms couple pulse, drift over 2-10 ms,
   also at n_ctrl = 61).
5. **Histories** (paper Fig. 7 and 10): arch tip x1, x2 and the x3 component of the tip
   curvature vector ``k = R K`` vs t; spinning helix tip displacement and velocity components
   vs t (from the runs of study 4).

Usage (from the repository root)::

    python benchmarks/beam_convergence.py            # all studies, PNGs in docs/img
    python benchmarks/beam_convergence.py --quick    # smoke version (seconds), PNGs in a temp dir or --out
    python benchmarks/beam_convergence.py --studies 1 3
    python benchmarks/beam_convergence.py --stability-scan cantilever
        # dense eigenvalues of the linearized semi-discrete operator at rest for
        # p = 2..8 and n_ctrl = 11..121 (slow: ~30 min per scene); prints max Re(lambda)

CPU time is ``time.process_time`` (BLAS threads default to 1). Tables are printed as
markdown; ``--markdown FILE`` also writes them to FILE.
"""

from __future__ import annotations

import os
import platform
import time

from liegroup_int.bench.table import figure_dir, parser


def _parse():
    ap = parser(__doc__, quick_help="smoke version (tiny meshes and spans); figures in a temporary directory")
    ap.add_argument("--studies", type=int, nargs="*", default=[1, 2, 3, 4, 5])
    ap.add_argument("--figdir", default=None, help="where to write the PNGs (same as --out)")
    ap.add_argument("--markdown", default=None, help="also write the printed tables to this file")
    ap.add_argument("--threads", default="1", help="BLAS threads")
    ap.add_argument("--stability-scan", default=None, metavar="SCENE",
                    help="only run the (slow) eigenvalue scan of SCENE over p and n_ctrl")
    ap.add_argument("--formulation", default="primal", choices=("primal", "galerkin"),
                    help="beam formulation of the studied discretizations (references stay primal p=8)")
    ap.add_argument("--degrees", type=int, nargs="*", default=None, help="space study: only these degrees")
    ap.add_argument("--smooth-only", action="store_true", help="space study: only the smoothly ramped loads")
    return ap.parse_args()


ARGS = _parse() if __name__ == "__main__" else None
if ARGS is not None and ARGS.threads:
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[var] = str(ARGS.threads)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

import numpy as np  # noqa: E402  (after the BLAS thread count is set)
import scipy.optimize  # noqa: E402

from liegroup_int.integrators import (  # noqa: E402
    BlowUpError,
    StepSizeError,
    eigenvalues,
    integrate_fixed,
    resolve_method,
    spectral_radius,
)
from liegroup_int.scenes import load_scene  # noqa: E402
from liegroup_int.scenes.beam import problem  # noqa: E402
from liegroup_int.studies import fit_rate  # noqa: E402

CLOCK = time.process_time
OUT: list[str] = []
FORMULATION = ARGS.formulation if ARGS is not None else "primal"


def emit(line: str = "") -> None:
    print(line, flush=True)
    OUT.append(line)


def make(scene: str, overrides: dict | None = None):
    pb = problem(load_scene(scene, {"space.formulation": FORMULATION, **dict(overrides or {})}))
    y0 = pb.initial_state()
    return pb, y0, spectral_radius(pb, 0.0, y0)


def steps_for(T: float, lam: float, y: float) -> tuple[int, float]:
    """Number of equal steps over T with |lambda| h <= y, and h."""
    N = int(np.ceil(T * lam / y - 1e-9))
    return N, T / N


def run(pb, y0, method: str, T: float, h: float, t_out=None, observer=None, t0: float = 0.0):
    start = CLOCK()
    _, y, stats = integrate_fixed(pb, resolve_method(method), (t0, T), y0, h, observer=observer, t_out=t_out)
    return y, CLOCK() - start, stats.steps


def slope(x, e) -> float:
    """:func:`liegroup_int.studies.fit_rate` (nan below 3 points)."""
    return fit_rate(x, e) if len(x) >= 3 else float("nan")


def fmt(x: float, d: int = 3) -> str:
    return "-" if x is None or not np.isfinite(x) else f"{x:.{d}e}"


def table(head: list[str], rows: list[list[str]]) -> None:
    emit("| " + " | ".join(head) + " |")
    emit("|" + "|".join("---" for _ in head) + "|")
    for r in rows:
        emit("| " + " | ".join(r) + " |")
    emit()


# ---------------------------------------------------------------------------------------
# Study 1: time convergence
# ---------------------------------------------------------------------------------------
TIME_CASES = {
    # scene: (span, reference y, {method: [y values]})
    "pendulum": (0.1, 0.05, {
        "rkmk2": [0.15, 0.105, 0.075, 0.0525, 0.0375],
        "rkmk3": [0.21, 0.15, 0.105, 0.075, 0.0525],
        "rkmk4": [0.3, 0.21, 0.15, 0.105, 0.075],
        "rkmk6": [0.6, 0.42, 0.3, 0.21],
    }),
    "cantilever": (2e-3, 0.05, {
        "rkmk2": [0.0525, 0.0375, 0.02625, 0.018375],
        "rkmk3": [0.21, 0.15, 0.105, 0.075, 0.0525],
        "rkmk4": [0.21, 0.15, 0.105, 0.075, 0.0525],
        "rkmk6": [0.6, 0.42, 0.3, 0.21],
    }),
}
TIME_CASES_QUICK = {
    "pendulum": (0.005, 0.1, {"rkmk2": [0.3, 0.21, 0.15], "rkmk4": [0.42, 0.3, 0.21]}),
}
TIME_N_CTRL, TIME_N_CTRL_QUICK = 31, 11
ORDER = {"rkmk2": 2, "rkmk3": 3, "rkmk4": 4, "rkmk6": 6}
MEASURES = ("e_c", "e_v", "err_L2")


def fit_cells(pts: list, floor: dict) -> tuple[list, dict]:
    """Fitted slopes of each measure over the points above 10x its floor: table cells and
    ``{measure: slope}`` (nan below 3 points)."""
    cells, fitted = [], {}
    for k in MEASURES:
        ok = [p for p in pts if np.isfinite(p[k]) and p[k] > 10 * floor[k]]
        if len(ok) >= 3:
            s = slope([p["h"] for p in ok], [p[k] for p in ok])
            y_lo, y_hi = min(p["y"] for p in ok), max(p["y"] for p in ok)
            cells.append(f"**{s:.2f}** ({len(ok)} pts, y {y_lo:.3g}-{y_hi:.3g})")
        else:
            s = np.nan
            cells.append(f"below floor ({len(ok)} pts)")
        fitted[k] = s
    return cells, fitted


def time_study(quick: bool) -> dict:
    cases = TIME_CASES_QUICK if quick else TIME_CASES
    ug = np.linspace(0.0, 1.0, 101)
    results = {}
    fit_rows = []
    for scene, (T, y_ref, windows) in cases.items():
        n_ctrl = TIME_N_CTRL_QUICK if quick else TIME_N_CTRL
        pb, y0, lam = make(scene, {"space.degree": 4, "space.n_ctrl": n_ctrl})
        C0 = pb.centreline(y0, ug)
        N, h = steps_for(T, lam, y_ref)
        ref, cpu_ref, _ = run(pb, y0, "rkmk6", T, h)
        N2, h2 = steps_for(T, lam, 2 * y_ref)
        ref2, cpu_ref2, _ = run(pb, y0, "rkmk6", T, h2)
        u_r = pb.centreline(ref, ug) - C0

        def errors(y):
            return {"e_c": float(np.abs(y.c - ref.c).max()), "e_v": float(np.abs(y.v - ref.v).max()),
                    "err_L2": float(np.linalg.norm(pb.centreline(y, ug) - C0 - u_r) / np.linalg.norm(u_r))}

        floor = errors(ref2)
        emit(f"### {scene}: p = 4, n_ctrl = {n_ctrl}, T = {T:g} s, |lambda|max = {lam:.4g} 1/s")
        emit()
        emit(f"Reference: RKMK6, |lambda| h = {lam * h:.3f} (h = {h:.4g} s, {N} steps, {cpu_ref:.1f} s CPU); "
             f"|u_r| = {np.linalg.norm(u_r):.4g} m over 101 points. Round-off floors (reference vs RKMK6 at "
             f"|lambda| h = {lam * h2:.3f}): e_c {floor['e_c']:.2e} m, e_v {floor['e_v']:.2e} m/s, "
             f"err_L2 {floor['err_L2']:.2e}.")
        emit()
        rows, per = [], {}
        for m, ys in windows.items():
            per[m] = []
            for yv in ys:
                Nm, hm = steps_for(T, lam, yv)
                try:
                    ym, cpu, _ = run(pb, y0, m, T, hm)
                    e = errors(ym)
                except (BlowUpError, StepSizeError) as exc:
                    e, cpu = {k: np.nan for k in MEASURES}, np.nan
                    emit(f"  ({m} at y={yv}: {type(exc).__name__})")
                per[m].append(dict(y=lam * hm, h=hm, N=Nm, cpu=cpu, **e))
                prev = per[m][-2] if len(per[m]) > 1 else None
                loc = (lambda k: f"{np.log(prev[k] / e[k]) / np.log(prev['h'] / hm):.2f}") if prev else (lambda k: "")
                rows.append([m, f"{lam * hm:.4f}", f"{hm:.4g}", str(Nm), f"{cpu:.2f}",
                             *[f"{fmt(e[k], 2)}" + (f" ({loc(k)})" if prev else "") for k in MEASURES]])
        table(["method", "\\|lambda\\| h", "h [s]", "steps", "CPU s", "e_c [m] (local slope)",
               "e_v [m/s] (local slope)", "err_L2 (local slope)"], rows)
        for m, pts in per.items():
            cells, fitted = fit_cells(pts, floor)
            results.setdefault(scene, {})[m] = fitted
            fit_rows.append([scene, m, str(ORDER[m]), f"{pts[-1]['y']:.3g}-{pts[0]['y']:.3g}", *cells])
        results[scene]["_runs"] = per
        results[scene]["_floor"] = floor
        results[scene]["_meta"] = dict(T=T, lam=lam, ref_y=lam * h)
    emit("### Fitted orders (least squares of log e against log h over the points above 10x floor)")
    emit()
    table(["problem", "method", "order", "\\|lambda\\| h window", "slope e_c", "slope e_v", "slope err_L2"], fit_rows)
    return results


def _clean_log_ticks(ax) -> None:
    """No labels on minor ticks of log axes (they overlap)."""
    from matplotlib.ticker import NullFormatter

    ax.xaxis.set_minor_formatter(NullFormatter())


def plot_time(results: dict, path: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    colors = {"rkmk2": "C3", "rkmk3": "C1", "rkmk4": "C0", "rkmk6": "C2"}
    scenes = [s for s in ("pendulum", "cantilever") if s in results]
    fig, axes = plt.subplots(len(scenes), 3, figsize=(15, 4.6 * len(scenes)), squeeze=False)
    for row, scene in enumerate(scenes):
        res = results[scene]
        runs, floor, meta = res["_runs"], res["_floor"], res["_meta"]
        ax1, ax2, ax3 = axes[row]
        for m, pts in runs.items():
            h = np.array([p["h"] for p in pts])
            lab = f"{m.upper()} (slope {res[m]['err_L2']:.2f})" if np.isfinite(res[m]["err_L2"]) else m.upper()
            ax1.loglog(h, [p["err_L2"] for p in pts], "o-", color=colors[m], label=lab)
            def lab2(k, m=m):
                return f"{m.upper()} {k} ({res[m][k]:.2f})" if np.isfinite(res[m][k]) else f"{m.upper()} {k}"

            ax2.loglog(h, [p["e_c"] for p in pts], "o-", color=colors[m], label=lab2("e_c"))
            ax2.loglog(h, [p["e_v"] for p in pts], "s--", color=colors[m], mfc="none", label=lab2("e_v"))
            ax3.loglog([p["cpu"] for p in pts], [p["err_L2"] for p in pts], "o-", color=colors[m], label=m.upper())
            # reference slope triangle through the first point
            h0, e0 = h[0], pts[0]["err_L2"]
            ax1.loglog([h0, h0 / 2], [e0 * 3, e0 * 3 / 2 ** ORDER[m]], ":", color=colors[m], lw=1)
        ax1.axhline(floor["err_L2"], color="grey", lw=0.8, ls="--")
        ax2.axhline(floor["e_c"], color="grey", lw=0.8, ls="--")
        ax2.axhline(floor["e_v"], color="grey", lw=0.8, ls="-.")
        ax3.axhline(floor["err_L2"], color="grey", lw=0.8, ls="--")
        ax1.set_title(f"{scene}: paper's err_L2 at T = {meta['T']:g} s")
        ax2.set_title(f"{scene}: control-value errors (floors dashed)")
        ax3.set_title(f"{scene}: err_L2 vs CPU time")
        for ax in (ax1, ax2):
            ax.set_xlabel("h [s]")
            ax.grid(True, which="both", alpha=0.3)
            sec = ax.secondary_xaxis("top", functions=(lambda x, l=meta["lam"]: x * l, lambda x, l=meta["lam"]: x / l))
            sec.set_xlabel("|lambda|max h")
            _clean_log_ticks(ax)
            _clean_log_ticks(sec)
        ax1.set_ylabel("err_L2")
        ax2.set_ylabel("e_c [m] (o), e_v [m/s] (s)")
        ax3.set_xlabel("CPU s")
        ax3.grid(True, which="both", alpha=0.3)
        _clean_log_ticks(ax3)
        ax1.legend(fontsize=8)
        ax2.legend(fontsize=7, ncol=2)
        ax3.legend(fontsize=8)
    fig.suptitle("Time convergence, p = 4, n_ctrl = 31 (dotted: reference slopes 2, 3, 4, 6)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


# ---------------------------------------------------------------------------------------
# Study 2: space convergence
# ---------------------------------------------------------------------------------------
SPACE_CASES = [
    # scene, load case, overrides, span, method (RKMK6 where the top modes are excited), degrees
    ("pendulum", "gravity switched on at t = 0 (paper)", {}, 0.1, "rkmk6", [2, 3, 4, 6, 8]),
    ("pendulum", "gravity ramped smoothly over the span", {"loads.profile": "smooth", "loads.ramp": 0.1}, 0.1,
     "rkmk4", [2, 3, 4, 5, 6, 7, 8]),
    ("cantilever", "tip force switched on at t = 0 (paper)", {}, 1e-3, "rkmk6", [2, 3, 4, 6, 8]),
    ("cantilever", "tip force ramped smoothly over the span",
     {"loads.end.profile": "smooth", "loads.end.ramp": 1e-3}, 1e-3, "rkmk4", [2, 3, 4, 5, 6, 7, 8]),
]
SPACE_NS, SPACE_REF = [11, 21, 31, 41, 61, 81], (8, 121)
SPACE_PS_QUICK, SPACE_NS_QUICK, SPACE_REF_QUICK = [2], [11, 15, 21], (4, 31)
SPACE_T_QUICK = 0.01  # the first case (pendulum) only
SPACE_Y = 0.3
GROWTH_LIMIT = 10.0  # growth probe: max|w| growth over T/5 above this marks "unstable"


def growth_probe(scene: str, overrides: dict, T: float) -> float:
    """max|w| growth factor of a load-free run from a 1e-12 rad/s random angular velocity."""
    ov = dict(overrides)
    if scene == "pendulum":
        ov["loads.distributed_force"] = [0.0, 0.0, 0.0]
    else:
        ov["loads.end.force"] = [0.0, 0.0, 0.0]
    pb, y0, lam = make(scene, ov)
    y1 = y0.copy()
    rng = np.random.default_rng(0)
    y1.w = y1.w + 1e-12 * rng.standard_normal(y1.w.shape)
    for e in pb.ends:
        if e.fix_rotation:
            y1.w[e.index] = 0.0
    a0 = np.abs(y1.w).max()
    N, h = steps_for(T, lam, SPACE_Y)
    try:
        y, _, _ = run(pb, y1, "rkmk4", T, h)
        return float(np.abs(y.w).max() / a0) if pb.is_finite(y) else np.inf
    except (BlowUpError, StepSizeError):
        return np.inf


def space_tables(res: dict, ps, ns) -> dict:
    """Emits the error table and the fitted rates of one space study; returns ``{p: rate}``."""
    rows = []
    for p in ps:
        cells = []
        for n in ns:
            r = res.get((p, n))
            if r is None:
                cells.append("")
                continue
            cells.append(fmt(r["e"], 2) + (" (unstable)" if r["growth"] > GROWTH_LIMIT else ""))
        rows.append([str(p), *cells])
    emit("err_L2 by degree p (rows) and n_ctrl (columns):")
    emit()
    table(["p \\ n_ctrl", *map(str, ns)], rows)
    rate_rows = []
    rates = {}
    for p in ps:
        pts = [(n, res[(p, n)]) for n in ns if (p, n) in res]
        good = [(n, r) for n, r in pts if r["growth"] <= GROWTH_LIMIT][-4:]
        bad = [n for n, r in pts if r["growth"] > GROWTH_LIMIT]
        if len(good) >= 3:
            hs = [r["h"] for _, r in good]
            s2 = slope(hs, [r["e"] for _, r in good])
            sm = slope(hs, [r["emax"] for _, r in good])
            loc = [np.log(a["e"] / b["e"]) / np.log(a["h"] / b["h"]) for (_, a), (_, b) in zip(good[:-1], good[1:])]
        else:
            s2 = sm = np.nan
            loc = []
        rates[p] = s2
        expected = p if p % 2 == 0 else p - 1
        rate_rows.append([str(p), str(expected), ", ".join(str(n) for n, _ in good), f"**{s2:.2f}**",
                          f"{sm:.2f}", ", ".join(f"{x:.2f}" for x in loc),
                          ", ".join(f"{n} (x{res[(p, n)]['growth']:.2g})" for n in bad) or "-"])
    emit("Fitted rates against h = 1/(n_ctrl - p) (finest four stable meshes):")
    emit()
    table(["p", "Greville rate (p even: p, odd: p-1)", "n_ctrl used", "rate err_L2", "rate max-norm",
           "local rates err_L2", "unstable (growth over T/5)"], rate_rows)
    return rates


def space_study(quick: bool) -> list:
    ns, ref_pn = (SPACE_NS_QUICK, SPACE_REF_QUICK) if quick else (SPACE_NS, SPACE_REF)
    cases = [(*SPACE_CASES[0][:3], SPACE_T_QUICK, *SPACE_CASES[0][4:])] if quick else SPACE_CASES
    if ARGS is not None and ARGS.smooth_only:
        cases = [c for c in cases if "smooth" in c[1]]
    ug = np.linspace(0.0, 1.0, 201)
    out = []
    for scene, label, ov, T, method, ps in cases:
        ps = SPACE_PS_QUICK if quick else (ARGS.degrees if ARGS is not None and ARGS.degrees else ps)
        def solve(p, n, y=SPACE_Y, formulation=None):
            extra = {} if formulation is None else {"space.formulation": formulation}
            pb, y0, lam = make(scene, {**ov, "space.degree": p, "space.n_ctrl": n, **extra})
            N, h = steps_for(T, lam, y)
            yT, cpu, _ = run(pb, y0, method, T, h)
            return pb.centreline(yT, ug) - pb.centreline(y0, ug), cpu, lam, N

        u_r, cpu_ref, lam_ref, N_ref = solve(*ref_pn, formulation="primal")
        nr = np.linalg.norm(u_r)
        # time-error check (step y vs y/2) on the highest degree at n_ctrl = 41
        pc, nc = max(ps), (41 if 41 in ns else ns[-1])
        u_a, _, _, _ = solve(pc, nc)
        u_b, cpu_b, _, _ = solve(pc, nc, SPACE_Y / 2)
        terr = np.linalg.norm(u_a - u_b) / nr
        emit(f"### {scene}, {label}: T = {T:g} s ({FORMULATION if FORMULATION == 'galerkin' else FORMULATION + ' collocation'})")
        emit()
        emit(f"{method.upper()} at |lambda|max h = {SPACE_Y} of each discretization. Reference p = {ref_pn[0]}, "
             f"n_ctrl = {ref_pn[1]} (|lambda|max = {lam_ref:.3g} 1/s, {N_ref} steps, {cpu_ref:.1f} s CPU), "
             f"|u_r| = {nr:.4g} m over 201 points. Time-error check: p = {pc}, n_ctrl = {nc} at |lambda| h = "
             f"{SPACE_Y} vs {SPACE_Y / 2}: err_L2 difference {terr:.1e}.")
        emit()
        res = {}
        for p in ps:
            for n in ns:
                if n < p + 2:
                    continue
                u, cpu, lam, N = solve(p, n)
                g = growth_probe(scene, {**ov, "space.degree": p, "space.n_ctrl": n}, T / 5)
                res[(p, n)] = dict(e=float(np.linalg.norm(u - u_r) / nr), emax=float(np.abs(u - u_r).max()),
                                   cpu=cpu, lam=lam, N=N, growth=g, h=1.0 / (n - p))
        rates = space_tables(res, ps, ns)
        cpu_all = sum(r["cpu"] for r in res.values())
        emit(f"(CPU of the {len(res)} runs: {cpu_all:.1f} s; largest growth factor among the stable ones: "
             f"{max(r['growth'] for r in res.values() if r['growth'] <= GROWTH_LIMIT):.2g})")
        emit()
        out.append(dict(scene=scene, label=label, T=T, res=res, rates=rates, ps=ps, ns=ns, ref=ref_pn, method=method))
    return out


def plot_space(cases: list, path: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    nc = 2
    nr = (len(cases) + 1) // 2
    fig, axes = plt.subplots(nr, nc, figsize=(12, 4.6 * nr), squeeze=False)
    for ax, c in zip(axes.ravel(), cases):
        for i, p in enumerate(c["ps"]):
            pts = [(r["h"], r["e"], r["growth"]) for (pp, n), r in sorted(c["res"].items()) if pp == p]
            pts.sort()
            h = np.array([a for a, _, _ in pts])
            e = np.array([b for _, b, _ in pts])
            g = np.array([x for _, _, x in pts])
            lab = f"p = {p} (rate {c['rates'][p]:.2f})"
            ok = g <= GROWTH_LIMIT
            ax.loglog(h[ok], e[ok], "o-", color=f"C{i}", label=lab)
            if np.any(~ok):
                ax.loglog(h[~ok], np.minimum(e[~ok], 3.0), "x", color=f"C{i}", ms=11, mew=2.5)
        ax.set_xlabel("h = 1/(n_ctrl - p)")
        ax.set_ylabel("err_L2")
        _clean_log_ticks(ax)
        ax.set_title(f"{c['scene']}: {c['label']}\nT = {c['T']:g} s, {c['method'].upper()}, ref p = {c['ref'][0]}, "
                     f"n_ctrl = {c['ref'][1]}",
                     fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    for ax in axes.ravel()[len(cases):]:
        ax.axis("off")
    fig.suptitle("Space convergence at |lambda|max h = 0.3 (x: semi-discretization unstable, left out of the "
                 "fits; values above 3 drawn at 3)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


# ---------------------------------------------------------------------------------------
# Study 3: natural frequencies of the cantilever
# ---------------------------------------------------------------------------------------
BETA_L = np.array([1.875104068711961, 4.694091132974175, 7.854757438237613, 10.995540734875467])


def eb_mode(x, k, L=1.0):
    b = BETA_L[k] / L
    sig = (np.cosh(b * L) + np.cos(b * L)) / (np.sinh(b * L) + np.sin(b * L))
    phi = np.cosh(b * x) - np.cos(b * x) - sig * (np.sinh(b * x) - np.sin(b * x))
    dphi = b * (np.sinh(b * x) + np.sin(b * x) - sig * (np.cosh(b * x) - np.cos(b * x)))
    tip = np.cosh(b * L) - np.cos(b * L) - sig * (np.sinh(b * L) - np.sin(b * L))
    return phi / tip, dphi / tip


def timoshenko_frequencies(EI, GA, rhoA, rhoI, L, guesses, grid: int = 41):
    """Clamped-free linear Timoshenko beam (Hz): roots of the 2x2 end determinant of the
    transfer matrix ``expm(A L)``, in 50-digit arithmetic (mpmath). In double precision
    the transfer matrix has entries ~exp(L sqrt(GA/EI)) ~ 1e97 and the roots come out
    ~2e-6 off. Each root is bracketed on ``grid`` points below the guess, then refined."""
    import mpmath as mp

    mp.mp.dps = 50
    EI, GA, rhoA, rhoI, L = (mp.mpf(repr(float(x))) for x in (EI, GA, rhoA, rhoI, L))

    def det(f):
        w2 = (2 * mp.pi * f) ** 2
        # y = (w, w', psi, psi'): GA (w'' - psi') + rhoA w2 w = 0; EI psi'' + GA (w' - psi) + rhoI w2 psi = 0
        A = mp.matrix([[0, 1, 0, 0], [-rhoA * w2 / GA, 0, 0, 1], [0, 0, 0, 1], [0, -GA / EI, (GA - rhoI * w2) / EI, 0]])
        E = mp.expm(A * L)
        # w(0) = psi(0) = 0, unknowns w'(0), psi'(0); ends: psi'(L) = 0, w'(L) - psi(L) = 0
        return E[3, 1] * (E[1, 3] - E[2, 3]) - E[3, 3] * (E[1, 1] - E[2, 1])

    out = []
    for g in guesses:
        # bracket the root just below the Euler-Bernoulli value (shear and rotary inertia lower it)
        fs = np.linspace(0.97 * g, 1.001 * g, grid)
        d = [float(mp.sign(det(mp.mpf(f)))) for f in fs]
        i = [k for k in range(len(d) - 1) if d[k] != d[k + 1]][-1]
        out.append(float(mp.findroot(det, (mp.mpf(fs[i]), mp.mpf(fs[i + 1])), solver="anderson")))
    return np.array(out)


def fit_frequencies(t, z, f_guess):
    """Variable-projection least squares: z ~ a0 + sum_k (a_k sin w_k t + b_k cos w_k t).
    Returns frequencies, amplitudes and the residual."""

    def design(f):
        cols = [np.ones_like(t)]
        for fk in f:
            cols += [np.sin(2 * np.pi * fk * t), np.cos(2 * np.pi * fk * t)]
        return np.array(cols).T

    def resid(f):
        D = design(f)
        coef = np.linalg.lstsq(D, z, rcond=None)[0]
        return D @ coef - z

    sol = scipy.optimize.least_squares(resid, f_guess, x_scale=np.asarray(f_guess) * 1e-3, xtol=1e-15, ftol=1e-15,
                                       gtol=1e-15, max_nfev=2000)
    D = design(sol.x)
    coef = np.linalg.lstsq(D, z, rcond=None)[0]
    amps = np.hypot(coef[1::2], coef[2::2])
    return sol.x, amps, z - D @ coef


def hann_peak(t, z, f_lo, f_hi):
    """Frequency of the largest Hann-windowed spectral peak in [f_lo, f_hi] (parabolic on log |X|)."""
    dt = t[1] - t[0]
    x = (z - z.mean()) * np.hanning(len(z))
    nfft = 64 * len(z)
    X = np.abs(np.fft.rfft(x, nfft))
    f = np.fft.rfftfreq(nfft, dt)
    sel = np.where((f >= f_lo) & (f <= f_hi))[0]
    i = sel[np.argmax(X[sel])]
    a, b, c = np.log(X[i - 1 : i + 2])
    return f[i] + 0.5 * (a - c) / (a - 2 * b + c) * (f[1] - f[0])


def identify_modes(t, z, k):
    """k sinusoids, found one at a time: the largest Hann-windowed peak of the current
    residual is added, then all frequencies are refitted together (least squares)."""
    freqs, res = [], z - z.mean()
    for _ in range(k):
        freqs.append(hann_peak(t, res, 1.0, 0.45 / (t[1] - t[0])))
        f, amps, res = fit_frequencies(t, z, freqs)
        freqs = list(f)
    order = np.argsort(f)
    return f[order], amps[order], float(np.sqrt(np.mean(res**2)))


def operator_frequencies(grid, f_ti) -> None:
    """Study 3b: the first three frequencies of the linearized semi-discrete operator at
    rest over ``grid = (degrees, n_ctrl values)``, against Timoshenko's ``f_ti``."""
    ps3, ns3 = grid
    rows = []
    for p in ps3:
        for n in ns3:
            pb, y0, lam = make("cantilever", {"space.degree": p, "space.n_ctrl": n, "loads.end.force": [0.0, 0.0, 0.0]})
            ev = eigenvalues(pb, 0.0, y0)
            f = np.sort(np.abs(ev.imag[ev.imag > 1e-6])) / (2 * np.pi)
            uniq = []  # bending modes come in pairs (two planes of a square section)
            for x in f:
                if not uniq or x - uniq[-1] > 1e-7 * x:
                    uniq.append(x)
            f = np.array(uniq[:3])
            rows.append([str(p), str(n), *[f"{f[k]:.6f} ({(f[k] - f_ti[k]) / f_ti[k]:+.2e})" for k in range(3)],
                         f"{ev.real.max():.1e}"])
    emit("3b. Frequencies of the linearized semi-discrete operator at rest, Hz (relative error vs Timoshenko):")
    emit()
    table(["p", "n_ctrl", "f1", "f2", "f3", "max Re(lambda) 1/s"], rows)


def frequency_study(quick: bool) -> dict:
    T = 0.025 if quick else 0.5
    n_list = [11] if quick else [11, 21, 31]
    y_step = 2.0
    dt_out = 2.5e-4
    pb0, _, _ = make("cantilever", {"loads.end.force": [0.0, 0.0, 0.0]})
    C = pb0.constants
    EI, GA, rhoA, rhoI = C.CM[0], C.CN[0], C.mu, C.Jm[0]
    f_eb = BETA_L**2 / (2 * np.pi) * np.sqrt(EI / rhoA)
    f_ti = timoshenko_frequencies(EI, GA, rhoA, rhoI, 1.0, f_eb[:3], grid=3 if quick else 41)
    emit(f"Section constants of the scene: EI = {EI:.6g} N m^2, GA = {GA:.6g} N (shear factor 1), "
         f"rhoA = {rhoA:.6g} kg/m, rhoI = {rhoI:.6g} kg m.")
    emit(f"Euler-Bernoulli f1..f3 = {', '.join(f'{f:.6f}' for f in f_eb[:3])} Hz; linear Timoshenko (same constants) "
         f"= {', '.join(f'{f:.6f}' for f in f_ti)} Hz (relative shift "
         f"{', '.join(f'{(a - b) / b:.2e}' for a, b in zip(f_ti, f_eb))}).")
    emit()
    V = np.array([1e-3, 3e-4, 1e-4])
    rows, hist = [], {}
    for n in n_list:
        pb, y0, lam = make("cantilever", {"space.degree": 4, "space.n_ctrl": n, "loads.end.force": [0.0, 0.0, 0.0]})
        s = pb.space.s_c
        v3 = sum(Vk * eb_mode(s, k)[0] for k, Vk in enumerate(V))
        w2 = -sum(Vk * eb_mode(s, k)[1] for k, Vk in enumerate(V))  # rotation about x2: theta2 = -dw/dx
        vc = np.zeros((pb.n, 3))
        wc = np.zeros((pb.n, 3))
        vc[:, 2], wc[:, 1] = v3, w2
        y0.v = pb.space.solve(vc)
        y0.w = pb.space.solve(wc)
        y0.v[0] = 0.0
        y0.w[0] = 0.0
        n_sub, _ = steps_for(dt_out, lam, y_step)
        h = dt_out / n_sub
        t_out = np.arange(1, int(round(T / dt_out)) + 1) * dt_out
        ts, zs = [], []

        def obs(t, y):
            ts.append(t)
            zs.append(y.c[-1, 2])

        _, cpu, steps = run(pb, y0, "rkmk4", t_out[-1], h, t_out=t_out, observer=obs)
        t, z = np.array(ts), np.array(zs)
        f, amps, rms = identify_modes(t, z, 3)
        f_fft = hann_peak(t, z, 0.5 * f_eb[0], 1.5 * f_eb[0])
        hist[n] = (t, z)
        rows.append([str(n), f"{lam:.3g}", f"{lam * h:.2f}", str(steps), f"{cpu:.1f}",
                     f"{f[0]:.6f}", f"{(f[0] - f_eb[0]) / f_eb[0]:+.2e}", f"{(f[0] - f_ti[0]) / f_ti[0]:+.2e}",
                     f"{f_fft:.4f}",
                     f"{f[1]:.5f}", f"{(f[1] - f_eb[1]) / f_eb[1]:+.2e}", f"{(f[1] - f_ti[1]) / f_ti[1]:+.2e}",
                     f"{f[2]:.4f}", f"{(f[2] - f_eb[2]) / f_eb[2]:+.2e}", f"{(f[2] - f_ti[2]) / f_ti[2]:+.2e}",
                     f"{rms / amps.max():.1e}"])
    emit(f"Free vibration over {T:g} s, RKMK4 at |lambda|max h <= {y_step}, tip x3 sampled every {dt_out:g} s, "
         f"fitted with 3 sinusoids + constant, found one by one from the Hann-windowed spectrum of the residual "
         f"and refitted together (least squares); f1 Hann-FFT: the windowed spectral peak alone:")
    emit()
    table(["n_ctrl", "\\|lambda\\|max", "\\|lambda\\| h", "steps", "CPU s", "f1 [Hz]", "vs EB", "vs Timo.",
           "f1 Hann-FFT", "f2 [Hz]", "vs EB", "vs Timo.", "f3 [Hz]", "vs EB", "vs Timo.", "fit rms / amp1"], rows)
    operator_frequencies(([4], [11]) if quick else ([2, 3, 4, 6], [11, 21, 31, 61]), f_ti)
    return dict(hist=hist, f_eb=f_eb, f_ti=f_ti)


# ---------------------------------------------------------------------------------------
# Studies 4 and 5: energy, invariants and histories of the paper's scenes
# ---------------------------------------------------------------------------------------
SCENE_RUNS = {
    # scene: (span, output every, t_ref for the drift)
    "pendulum": (1.0, 0.005, 0.0),
    "cantilever": (0.05, 2.5e-4, 0.0),
    "arch": (1.0, 1e-3, 0.25),
    "spinning_helix": (1.0, 0.005, 0.0),
}
SCENE_RUNS_QUICK = {"pendulum": (0.01, 0.002, 0.0), "cantilever": (5e-4, 1e-4, 0.0)}
SCENE_N_CTRL_QUICK = 11  # quick: every scene run on this mesh (and the doubled one), at the scene's dt


class Recorder:
    def __init__(self, pb):
        self.pb = pb
        self.rows = []

    def __call__(self, t, y):
        pb = self.pb
        parts = pb.energy_parts(y)
        p, h = pb.momentum(y)
        k = y.R[-1] @ y.K[-1]  # spatial curvature vector at the tip
        m = pb.n // 2
        km = y.R[m] @ y.K[m]  # and at the middle collocation point
        self.rows.append((t, parts["kinetic"] + parts["strain"] + parts["potential"], parts["kinetic"],
                          pb.orth_error(y), *pb.tip(y), *y.v[-1], *k, *h, *km))

    def arrays(self):
        a = np.array(self.rows)
        return dict(t=a[:, 0], E=a[:, 1], KE=a[:, 2], orth=a[:, 3], tip=a[:, 4:7], vtip=a[:, 7:10],
                    ktip=a[:, 10:13], h=a[:, 13:16], kmid=a[:, 16:19])


def _scene_run(scene, overrides, T, every, dt, method, t_ref):
    pb, y0, lam = make(scene, overrides)
    rec = Recorder(pb)
    t_out = np.arange(1, int(round(T / every)) + 1) * every
    _, cpu, steps = run(pb, y0, method, t_out[-1], dt, t_out=t_out, observer=rec)
    a = rec.arrays()
    sel = a["t"] >= t_ref - 1e-12
    ke = a["KE"].max()
    drift = np.abs(a["E"][sel] - a["E"][sel][0]).max()
    h3 = a["h"][:, 2]
    hrel = np.abs(h3 - h3[0]).max() / abs(h3[0]) if abs(h3[0]) > 0 else np.nan
    return a, dict(lam=lam, cpu=cpu, steps=steps, ke=ke, drift=drift / ke, orth=a["orth"].max(), hrel=hrel)


CHECK_SPANS = {"pendulum": 0.2, "cantilever": 0.005, "arch": 0.01, "spinning_helix": 0.1}


def scene_summaries(out: dict, quick: bool) -> None:
    """Emits the arch's and the helix's figures from their runs (when run)."""
    if "arch" in out:
        a = out["arch"]
        t_off = 0.01 if quick else 0.25
        on = a["t"] < t_off
        x1 = a["tip"][:, 0]
        emit(f"Arch tip x1 while the couple acts (t < {t_off:g} s): min {x1[on].min():.4f} m, max {x1[on].max():.4f} m "
             f"(3/(2 pi) = {3 / (2 * np.pi):.4f}); after removal: min {x1[~on].min():.4f}, max {x1[~on].max():.4f} m; "
             f"tip x2 range [{a['tip'][:, 1].min():.4f}, {a['tip'][:, 1].max():.4f}] m. Tip curvature k3 = (R K)_3: "
             f"initial {a['ktip'][0, 2]:.4f} 1/m (-pi/3 = {-np.pi / 3:.4f}), range "
             f"[{a['ktip'][1:, 2][on[1:]].min():.4f}, {a['ktip'][1:, 2][on[1:]].max():.4f}] while on (t > 0), "
             f"[{a['ktip'][~on, 2].min():.4f}, {a['ktip'][~on, 2].max():.4f}] after; at the middle collocation "
             f"point [{a['kmid'][on, 2].min():.4f}, {a['kmid'][on, 2].max():.4f}] while on, "
             f"[{a['kmid'][~on, 2].min():.4f}, {a['kmid'][~on, 2].max():.4f}] after.")
        emit()
    if "spinning_helix" in out:
        a = out["spinning_helix"]
        u = a["tip"] - a["tip"][0]
        emit(f"Spinning helix tip displacement range over the span: u1 [{u[:, 0].min():.4f}, {u[:, 0].max():.4f}], "
             f"u2 [{u[:, 1].min():.4f}, {u[:, 1].max():.4f}], u3 [{u[:, 2].min():.4f}, {u[:, 2].max():.4f}] m; "
             f"h3(0) = {a['h'][0, 2]:.6g} kg m^2/s.")
        emit()


def scene_study(quick: bool) -> dict:
    runs = SCENE_RUNS_QUICK if quick else SCENE_RUNS
    out = {}
    rows = []

    def add(scene, label, T, method, dti, t_ref, r):
        rows.append([scene, label, f"{T:g}", method, f"{dti:.3g}", f"{r['lam'] * dti:.2f}", str(r["steps"]),
                     f"{r['cpu']:.1f}", f"{t_ref:g}", f"{r['ke']:.4g}", f"{r['drift']:.2e}", f"{r['orth']:.1e}",
                     fmt(r["hrel"], 2) if scene == "spinning_helix" else "-"])

    mesh = {"space.n_ctrl": SCENE_N_CTRL_QUICK} if quick else {}
    for scene, (T, every, t_ref) in runs.items():
        sc = load_scene(scene)
        dt, method = sc.integrator.dt, sc.integrator.method
        n0 = mesh.get("space.n_ctrl", sc["space.n_ctrl"])
        n2 = 2 * n0 - 1 if scene != "spinning_helix" else 2 * n0 - 2
        ov0 = {**mesh, **({"loads.end.t_off": 0.01} if (quick and scene == "arch") else {})}
        a, r = _scene_run(scene, ov0, T, every, dt, method, t_ref)
        out[scene] = a
        add(scene, "scene settings" + (f", n_ctrl = {n0}" if mesh else ""), T, method, dt, t_ref, r)
        if scene != "arch":
            _, r = _scene_run(scene, {"space.n_ctrl": n2}, T, every, dt / 2, method, t_ref)
            add(scene, f"n_ctrl = {n2}, dt/2", T, method, dt / 2, t_ref, r)
        # time integrator vs space: the same short span with the scene's RKMK4 step and with
        # RKMK6 at |lambda| dt = 0.3 (the arch: a 2 ms couple pulse, drift over 2-10 ms)
        Tc = CHECK_SPANS[scene] if not quick else T / 2
        ev_c = min(every, Tc / 20)
        ov_c = {"loads.end.t_off": 0.002} if scene == "arch" else {}
        tr_c = 0.002 if scene == "arch" else t_ref
        if scene == "arch" and quick:
            ov_c, tr_c = {"loads.end.t_off": 0.0005}, 0.0005
        ov_c = {**mesh, **ov_c}
        pre = ("short pulse, " if quick else "2 ms pulse, ") if scene == "arch" else "short span, "
        _, r = _scene_run(scene, ov_c, Tc, ev_c, dt, method, tr_c)
        add(scene, pre + "RKMK4 at the scene dt", Tc, method, dt, tr_c, r)
        lam = r["lam"]
        _, r = _scene_run(scene, ov_c, Tc, ev_c, 0.3 / lam, "rkmk6", tr_c)
        add(scene, pre + "RKMK6 at \\|lambda\\| dt = 0.3", Tc, "rkmk6", 0.3 / lam, tr_c, r)
        if scene == "arch":
            _, r = _scene_run(scene, {**ov_c, "space.n_ctrl": n2}, Tc, ev_c, dt / 2, method, tr_c)
            add(scene, pre + f"n_ctrl = {n2}, dt/2", Tc, method, dt / 2, tr_c, r)
    emit("Energy = kinetic + strain + potential of the distributed loads - work of constant end forces, by the "
         "library's collocation quadrature (end couples are not included, hence t_ref = 0.25 s for the arch); "
         "drift = max over t >= t_ref of |E(t) - E(t_ref)| / max_t KE(t):")
    emit()
    table(["scene", "variant", "span s", "method", "dt s", "\\|lambda\\| dt", "steps", "CPU s", "t_ref s",
           "KE scale J", "energy drift / KE scale", "max orth. err.", "axial ang. mom. drift (rel.)"], rows)
    scene_summaries(out, quick)
    return out


def plot_energy(out: dict, path: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(out), figsize=(4.2 * len(out), 3.8), squeeze=False)
    for ax, (scene, a) in zip(axes[0], out.items()):
        t_ref = SCENE_RUNS[scene][2] if a["t"][-1] >= SCENE_RUNS[scene][2] + 0.01 else SCENE_RUNS_QUICK[scene][2]
        sel = a["t"] >= t_ref - 1e-12
        ke = a["KE"].max()
        ax.plot(a["t"][sel], (a["E"][sel] - a["E"][sel][0]) / ke, label="(E - E_ref) / KE scale")
        if scene == "spinning_helix":
            h3 = a["h"][:, 2]
            ax.plot(a["t"], (h3 - h3[0]) / abs(h3[0]), label="(h3 - h3(0)) / |h3(0)|")
        ax.set_title(scene + (f" (t >= {t_ref:g} s)" if t_ref else ""), fontsize=10)
        ax.set_xlabel("t [s]")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
        ax.ticklabel_format(axis="y", style="sci", scilimits=(0, 0))
    fig.suptitle("Energy and axial angular momentum, scene settings (RKMK4, scene dt)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_histories(out: dict, dirpath: str) -> list[str]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    written = []
    if "arch" in out:
        a = out["arch"]
        fig, (ax1, ax2, ax3) = plt.subplots(1, 3, figsize=(15, 4))
        ax1.plot(a["t"], a["tip"][:, 0], label="tip x1")
        ax1.axhline(3 / (2 * np.pi), color="grey", ls=":", lw=1)
        ax1.axhline(-3 / (2 * np.pi), color="grey", ls=":", lw=1)
        ax1.axvline(0.25, color="r", lw=0.8)
        ax1.set_title("arch: tip x1 (dotted: +-3/(2 pi); red: couple removed)", fontsize=10)
        ax2.plot(a["t"], a["tip"][:, 1], color="C1", label="tip x2")
        ax2.axvline(0.25, color="r", lw=0.8)
        ax2.set_title("arch: tip x2", fontsize=10)
        ax3.plot(a["t"], a["kmid"][:, 2], color="C4", lw=1, label="mid-span collocation point")
        ax3.plot(a["t"], a["ktip"][:, 2], color="C2", label="tip")
        ax3.axhline(-np.pi / 3, color="r", lw=1, label="initial k3 = -pi/3")
        ax3.axvline(0.25, color="r", lw=0.8, ls="--")
        ax3.set_title("arch: curvature k3 = (R K)_3 (spatial x3 component)", fontsize=10)
        ax3.legend(fontsize=8)
        for ax in (ax1, ax2, ax3):
            ax.set_xlabel("t [s]")
            ax.grid(True, alpha=0.3)
        ax1.set_ylabel("m")
        ax3.set_ylabel("1/m")
        fig.tight_layout()
        p = os.path.join(dirpath, "verification_arch.png")
        fig.savefig(p, dpi=110)
        plt.close(fig)
        written.append(p)
    if "spinning_helix" in out:
        a = out["spinning_helix"]
        u = a["tip"] - a["tip"][0]
        fig, axes = plt.subplots(2, 3, figsize=(15, 7), sharex=True)
        for k in range(3):
            axes[0, k].plot(a["t"], u[:, k], color=f"C{k}")
            axes[0, k].set_title(f"helix: tip displacement u{k + 1} [m]", fontsize=10)
            axes[1, k].plot(a["t"], a["vtip"][:, k], color=f"C{k}")
            axes[1, k].set_title(f"helix: tip velocity v{k + 1} [m/s]", fontsize=10)
            axes[1, k].set_xlabel("t [s]")
            for ax in axes[:, k]:
                ax.grid(True, alpha=0.3)
        fig.suptitle("Spinning helix, p = 6, n_ctrl = 62, RKMK4, dt = 2.5e-5 s")
        fig.tight_layout()
        p = os.path.join(dirpath, "verification_helix.png")
        fig.savefig(p, dpi=110)
        plt.close(fig)
        written.append(p)
    return written


def plot_frequency(fr: dict, path: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(9, 3.6))
    for n, (t, z) in fr["hist"].items():
        ax.plot(t, z * 1e6, lw=1, label=f"n_ctrl = {n}")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("tip x3 [um]")
    ax.set_title(f"Cantilever free vibration (modes 1-3 initial velocity); EB f1 = {fr['f_eb'][0]:.4f} Hz")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


# ---------------------------------------------------------------------------------------
def stability_scan(scene: str) -> None:
    ns = [11, 16, 21, 31, 41, 51, 61, 71, 81, 91, 101, 121]
    emit(f"max Re(lambda) [1/s] of the linearized increment map at rest, {scene} (dense, central differences)")
    emit()
    rows = []
    for p in range(2, 9):
        cells = []
        for n in ns:
            pb, y0, lam = make(scene, {"space.degree": p, "space.n_ctrl": n})
            ev = eigenvalues(pb, 0.0, y0)
            cells.append(f"{ev.real.max():.2g}")
        rows.append([str(p), *cells])
        print(f"#  p={p} done", flush=True)
    table(["p \\ n_ctrl", *map(str, ns)], rows)


def main(args) -> None:
    import matplotlib
    import numba

    if args.figdir:
        args.out = args.figdir
    figdir = str(figure_dir(args, os.path.join(ROOT, "docs", "img")))
    t_start = CLOCK()
    w_start = time.perf_counter()
    emit(f"<!-- beam_convergence.py {'--quick ' if args.quick else ''}studies {args.studies}: python "
         f"{platform.python_version()}, numpy {np.__version__}, numba {numba.__version__}, matplotlib "
         f"{matplotlib.__version__}; {platform.machine()}, {os.cpu_count()} CPUs, load average at start "
         f"{os.getloadavg()[0]:.2f} -->")
    emit()
    if args.stability_scan:
        stability_scan(args.stability_scan)
    else:
        cpu = {}
        if 1 in args.studies:
            emit("## Study 1: time convergence")
            emit()
            c0 = CLOCK()
            res = time_study(args.quick)
            plot_time(res, os.path.join(figdir, "verification_time.png"))
            cpu[1] = CLOCK() - c0
        if 2 in args.studies:
            emit("## Study 2: space convergence")
            emit()
            c0 = CLOCK()
            cases = space_study(args.quick)
            plot_space(cases, os.path.join(figdir, "verification_space.png"))
            cpu[2] = CLOCK() - c0
        if 3 in args.studies:
            emit("## Study 3: cantilever natural frequencies")
            emit()
            c0 = CLOCK()
            fr = frequency_study(args.quick)
            plot_frequency(fr, os.path.join(figdir, "verification_frequency.png"))
            cpu[3] = CLOCK() - c0
        if 4 in args.studies or 5 in args.studies:
            emit("## Studies 4 and 5: energy, invariants, histories")
            emit()
            c0 = CLOCK()
            out = scene_study(args.quick)
            if 4 in args.studies:
                plot_energy(out, os.path.join(figdir, "verification_energy.png"))
            if 5 in args.studies:
                plot_histories(out, figdir)
            cpu[4] = CLOCK() - c0
        emit("CPU time per study [s]: " + ", ".join(f"{k}: {v:.0f}" for k, v in cpu.items()))
    emit(f"Total: {CLOCK() - t_start:.0f} s CPU (process_time), {time.perf_counter() - w_start:.0f} s wall; "
         f"figures in {figdir}")
    if args.markdown:
        with open(args.markdown, "w") as fh:
            fh.write("\n".join(OUT) + "\n")


if __name__ == "__main__":
    main(ARGS)
