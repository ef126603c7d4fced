"""Flexible pendulum over 10 s: our Galerkin beam (RKMK4) against PyElastica.

Scene: the built-in ``pendulum`` (rod of length 1 m hinged at the origin, along +x1 at
t = 0, released from rest under its self weight q3 = -0.8475 N/m; it swings in the
x1-x3 plane, tip x3 negative). Both codes run undamped.

Ours: ``space.formulation = "galerkin"`` (weak form), p = 4 (the scene default),
n_ctrl = 21, 31, 61, numba backend, RKMK4 at the fixed step ``dt = 2 / |lambda|max``
(RKMK4 is stable for |lambda| h < 2.83; ``|lambda|max`` by power iteration at t = 0,
:func:`liegroup_int.integrators.spectral_radius`), plus n_ctrl = 31 at ``dt = 1 / |lambda|max``.
The driver lands on every output time (the last step of an output interval is shortened).
The finest run (n_ctrl = 61) is the reference of the tip-distance columns.

Peer: PyElastica ``CosseratRod`` with our section constants
(``liegroup_int/bench/pyelastica_peer.py``), ``PositionVerlet``, undamped, 50 / 100 / 200
elements. Step as in ``benchmarks/pyelastica_compare.py``: the largest stable step
``dt_max`` of its ladder ``f * dt_est`` is searched over the first ``min(T, 1)`` s
(``liegroup_int.bench.work_precision.peer_dt_max``), then the run uses ``dt = dt_max / 2`` (rounded down to divide the output
interval) over the whole span; should that run not stay finite (|tip| < 2 L) the step is
halved again (reported). The helper records the tip only, so PyElastica's energy is n/a.

Output every 0.01 s. Printed table per run: resolution, dt, CPU, tip (x1, x3) at
t = 1, 2, 5, 10 s, energy drift max|E - E0| over [0, 2] and [0, 10] s (E = kinetic + strain
+ load potential, ``pb.energy``), and the largest tip distance |x_tip - x_tip,ref| to our
n_ctrl = 61 run over [0, 1], [0, 2], [0, 5], [0, 10] s. CPU: ``time.process_time()`` of the
time loop; ours after a short warm-up integration (numba compilation not timed) and without
the energy diagnostics evaluated at the output times (PyElastica records only the tip;
their cost is printed separately). Plot: ``docs/img/galerkin_pendulum_10s.png``.

Usage (from the repository root)::

    python benchmarks/galerkin_pendulum_10s.py           # full run (a few minutes of CPU), writes the plot
    python benchmarks/galerkin_pendulum_10s.py --quick   # T = 0.2 s, ours n_ctrl 11 at two steps, PyElastica 50
    python benchmarks/galerkin_pendulum_10s.py --save runs.npz   # also keep the histories (t, tip, E, KE)

Without PyElastica (the ``[peers]`` extra) only our runs are made and tabulated, with a
note that the peer rows are absent.
"""

from __future__ import annotations

import os
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402  (after the thread count is set)

from liegroup_int.bench.table import PEER_ABSENT, figure_dir, parser, peer_available  # noqa: E402
from liegroup_int.bench.work_precision import fit_step, peer_dt_max  # noqa: E402
from liegroup_int.integrators import integrate_fixed, resolve_method, spectral_radius  # noqa: E402
from liegroup_int.scenes import load_scene  # noqa: E402
from liegroup_int.scenes.beam import problem  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
IMG = os.path.join(ROOT, "docs", "img")
EVERY = 0.01
TIP_TIMES = (1.0, 2.0, 5.0, 10.0)
WINDOWS = (1.0, 2.0, 5.0, 10.0)
DRIFT_WINDOWS = (2.0, 10.0)
THRESHOLDS = (1e-4, 1e-3, 1e-2)   # first time the tip distance to the reference exceeds these

FULL = dict(T=10.0, ours=((21, 2.0), (31, 2.0), (61, 2.0), (31, 1.0)), peers=(50, 100, 200))
QUICK = dict(T=0.2, ours=((11, 2.0), (11, 1.0)), peers=(50,), tip_times=(0.1, 0.2), windows=(0.1, 0.2),
             drift_windows=(0.2,))


# ----------------------------------------------------------------------------- ours
def run_ours(n_ctrl: int, c_dt: float, T: float) -> dict:
    """RKMK4 on the Galerkin pendulum at ``dt = c_dt / |lambda|max``."""
    pb = problem(load_scene("pendulum", {"space.formulation": "galerkin", "space.n_ctrl": n_ctrl,
                                         "integrator.backend": "numba"}))
    y0 = pb.initial_state()
    lam = spectral_radius(pb, 0.0, y0)
    dt = c_dt / lam
    tab = resolve_method("rkmk4")
    integrate_fixed(pb, tab, (0.0, 10 * dt), y0, dt)  # warm-up: numba compilation is not timed
    t_out = EVERY * np.arange(1, int(round(T / EVERY)) + 1)
    rec = {"t": [], "tip": [], "E": [], "KE": []}
    diag = [0.0]

    def observer(t, y):
        rec["t"].append(t)
        rec["tip"].append(pb.tip(y))
        c1 = time.process_time()
        rec["E"].append(pb.energy(y, t))
        rec["KE"].append(pb.energy_parts(y, t)["kinetic"])
        diag[0] += time.process_time() - c1

    failed, steps = "", -1
    c0 = time.process_time()
    try:
        _, _, stats = integrate_fixed(pb, tab, (0.0, T), y0, dt, observer=observer, t_out=t_out)
        steps = stats.steps
    except Exception as exc:  # noqa: BLE001 - a blow-up is a result here
        failed = f"{type(exc).__name__}: {exc}"
    cpu_total = time.process_time() - c0
    return dict(label=f"ours Galerkin p=4 n_ctrl={n_ctrl}, dt={c_dt:g}/lam", short=f"ours n={n_ctrl} ({c_dt:g}/lam)",
                kind="ours", n=n_ctrl, res=f"n_ctrl={n_ctrl}", lam=lam, c_dt=c_dt, dt=dt, steps=steps,
                cpu_s=cpu_total - diag[0], diag_s=diag[0], t=np.array(rec["t"]), tip=np.array(rec["tip"]),
                E=np.array(rec["E"]), KE=np.array(rec["KE"]), failed=failed)


# ----------------------------------------------------------------------------- PyElastica
def run_peer(P, case, n: int, T: float) -> dict:
    """PyElastica at ``dt_max / 2`` (``dt_max`` searched over ``min(T, 1)`` s)."""
    T_probe = min(T, 1.0)
    dt_max, dt_bad, _ = peer_dt_max(P, case, n, T_probe, EVERY)
    dt = fit_step(dt_max / 2, EVERY)
    notes = []
    for _ in range(4):
        r = P.run(case, n, dt, T, EVERY)
        ok = r.finite and np.all(np.abs(r.tip) < 2 * case.length) and len(r.t) == int(round(T / EVERY)) + 1
        if ok:
            break
        notes.append(f"dt={dt:.3e} not stable over {T:g} s (finite={r.finite}, {len(r.t)} outputs)")
        dt = fit_step(dt / 2, EVERY)
    return dict(label=f"PyElastica {n} el (dt_max {dt_max:.2e} over {T_probe:g} s, unstable {dt_bad:.2e})",
                short=f"PyElastica {n} el", kind="peer", n=n, res=f"{n} elements", dt=r.dt, dt_max=dt_max,
                dt_bad=dt_bad, steps=r.steps, cpu_s=r.cpu_s, diag_s=0.0, t=r.t, tip=r.tip, E=None, KE=None,
                failed="" if ok else "; ".join(notes), notes=notes)


# ----------------------------------------------------------------------------- metrics
def idx(t_end: float) -> int:
    return int(round(t_end / EVERY))


def metrics(run: dict, ref: dict, T: float) -> dict:
    t, tip = run["t"], run["tip"]
    m = dict(tips={}, drift={}, dist={}, first={})
    for tt in TIP_TIMES:
        k = idx(tt)
        if tt <= T + 1e-12 and k < len(t):
            assert abs(t[k] - tt) < 1e-8, (run["label"], t[k], tt)
            m["tips"][tt] = tip[k]
    if run["E"] is not None:
        dE = np.abs(run["E"] - run["E"][0])
        for w in DRIFT_WINDOWS:
            if w <= T + 1e-12 and idx(w) < len(dE):
                m["drift"][w] = float(dE[: idx(w) + 1].max())
        m["drift_T"] = float(dE.max())
        m["KE_max"] = float(run["KE"].max())
    k_all = min(len(t), len(ref["t"]))
    assert np.allclose(t[:k_all], ref["t"][:k_all], atol=1e-8), "output times differ"
    d = np.linalg.norm(tip[:k_all] - ref["tip"][:k_all], axis=1)
    m["d"] = d
    if run is not ref:
        for w in WINDOWS:
            if w <= T + 1e-12 and idx(w) < k_all:
                m["dist"][w] = float(d[: idx(w) + 1].max())
        for thr in THRESHOLDS:
            over = np.nonzero(d > thr)[0]
            m["first"][thr] = float(t[over[0]]) if over.size else None
    m["max_abs_x2"] = float(np.max(np.abs(tip[:, 1])))
    return m


# ----------------------------------------------------------------------------- output
def fmt_tip(x) -> str:
    return f"({x[0]:+.5f}, {x[2]:+.5f})" if x is not None else "-"


def fmt(x, spec=".2e") -> str:
    return "-" if x is None else format(x, spec)


def print_table(runs, mets, ref, T):
    print(f"\n## Flexible pendulum, T = {T:g} s, output every {EVERY:g} s; reference: {ref['label']}\n")
    head = (["run", "resolution", "dt [s]", "steps", "CPU [s]"]
            + [f"tip (x1, x3) t={tt:g} s [m]" for tt in TIP_TIMES]
            + [f"max abs(E-E0) [0,{w:g}] s [J]" for w in DRIFT_WINDOWS]
            + [f"max tip dist to ref [0,{w:g}] s [m]" for w in WINDOWS])
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for r, m in zip(runs, mets):
        name = r["short"] + (" (ref)" if r is ref else "") + (" FAILED" if r["failed"] else "")
        row = [name, r["res"], f"{r['dt']:.3e}", str(r["steps"]), f"{r['cpu_s']:.2f}"]
        row += [fmt_tip(m["tips"].get(tt)) for tt in TIP_TIMES]
        if r["E"] is None:
            row += ["n/a"] * len(DRIFT_WINDOWS)
        else:
            row += [fmt(m["drift"].get(w)) for w in DRIFT_WINDOWS]
        if r is ref:
            row += ["0 (ref)" if w <= T + 1e-12 else "-" for w in WINDOWS]
        else:
            row += [fmt(m["dist"].get(w)) for w in WINDOWS]
        print("| " + " | ".join(row) + " |")

    print("\n| run | first t with tip dist to ref > " + " | > ".join(f"{x:g} m" for x in THRESHOLDS)
          + " | max abs(E-E0) over run / max KE | max abs(tip x2) [m] | notes |")
    print("|" + "---|" * (len(THRESHOLDS) + 4))
    for r, m in zip(runs, mets):
        firsts = ["(ref)" if r is ref else ("never" if m["first"][thr] is None else f"{m['first'][thr]:.2f} s")
                  for thr in THRESHOLDS]
        rel = "n/a" if r["E"] is None else f"{m['drift_T'] / m['KE_max']:.2e} (KE max {m['KE_max']:.4e} J)"
        if r["kind"] == "ours":
            note = f"lam={r['lam']:.4e} 1/s; energy diagnostics {r['diag_s']:.2f} s CPU (not in CPU column)"
        else:
            tried = (f"next tried {r['dt_bad']:.3e} unstable" if np.isfinite(r["dt_bad"])
                     else "the largest step of the ladder")
            note = (f"dt = dt_max/2, dt_max={r['dt_max']:.3e} ({tried}) over "
                    f"{min(T, 1.0):g} s" + ("; " + "; ".join(r["notes"]) if r["notes"] else ""))
        if r["failed"]:
            note += f"; FAILED: {r['failed']}"
        print(f"| {r['short']} | " + " | ".join(firsts) + f" | {rel} | {m['max_abs_x2']:.1e} | {note} |")

    # time-step check: our runs on the same mesh at different steps
    ours = [r for r in runs if r["kind"] == "ours" and not r["failed"]]
    pairs = [(a, b) for i, a in enumerate(ours) for b in ours[i + 1:] if a["n"] == b["n"]]
    if pairs:
        print("\n| time-step check (same n_ctrl) | " + " | ".join(f"max tip dist [0,{w:g}] s [m]" for w in WINDOWS)
              + " |")
        print("|" + "---|" * (len(WINDOWS) + 1))
        for a, b in pairs:
            k = min(len(a["t"]), len(b["t"]))
            d = np.linalg.norm(a["tip"][:k] - b["tip"][:k], axis=1)
            cells = [fmt(float(d[: idx(w) + 1].max())) if w <= T + 1e-12 and idx(w) < k else "-" for w in WINDOWS]
            print(f"| {a['short']} vs {b['short']} | " + " | ".join(cells) + " |")


def plot(runs, mets, ref, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    show = [("ours", 31, 2.0), ("ours", 61, 2.0), ("peer", 100, None), ("peer", 200, None)]
    styles = {("ours", 31): dict(color="tab:blue", ls="--", lw=1.4), ("ours", 61): dict(color="k", ls="-", lw=1.0),
              ("peer", 100): dict(color="tab:orange", ls="-", lw=0.9), ("peer", 200): dict(color="tab:red", ls=":", lw=1.4)}
    fig, (a1, a2, a3) = plt.subplots(3, 1, figsize=(11, 10), sharex=True,
                                     gridspec_kw=dict(height_ratios=(1.3, 1.0, 1.0)))
    for kind, n, c in show:
        for r, m in zip(runs, mets):
            if r["kind"] == kind and r["n"] == n and (c is None or r["c_dt"] == c):
                a1.plot(r["t"], r["tip"][:, 2], label=r["short"], **styles[(kind, n)])
    a1.set_ylim(-1.08, 0.38)
    a1.set_ylabel("tip x3 [m]"), a1.grid(alpha=0.3), a1.legend(fontsize=8, ncol=4, loc="upper center")
    a1.set_title("Flexible pendulum: tip x3 (ours: Galerkin p=4, RKMK4; PyElastica: PositionVerlet)")
    cmap = plt.get_cmap("tab10")
    for j, (r, m) in enumerate(zip(runs, mets)):
        if r is ref:
            continue
        a2.semilogy(r["t"][1:], m["d"][1:] + 1e-16, color=cmap(j), lw=0.9, label=r["short"])
    a2.set_ylabel(f"|tip - tip {ref['short']}| [m]"), a2.set_ylim(bottom=1e-9)
    a2.grid(alpha=0.3, which="both"), a2.legend(fontsize=8, ncol=3)
    drifts = [np.abs(r["E"] - r["E"][0]).max() for r in runs if r["E"] is not None]
    lin = max(1e-13, 1e-8 * max(drifts)) if drifts else 1e-10   # show the onset of the drift too
    for j, r in enumerate(runs):
        if r["E"] is not None:
            a3.plot(r["t"], r["E"] - r["E"][0], color=cmap(j), lw=0.9, label=r["short"])
    a3.set_yscale("symlog", linthresh=lin, linscale=2.0)
    a3.set_ylabel("ours: E(t) - E0 [J]"), a3.set_xlabel("t [s]")
    a3.grid(alpha=0.3, which="both"), a3.legend(fontsize=8, ncol=2)
    a3.set_title(f"energy drift (symlog, linear below {lin:.0e} J); PyElastica: not recorded by the helper",
                 fontsize=9)
    fig.tight_layout()
    os.makedirs(os.path.dirname(path), exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


# ----------------------------------------------------------------------------- main
def peer_runs(cfg, T) -> list[dict]:
    """PyElastica's runs, or none (with a note) without PyElastica."""
    if not peer_available():
        print(PEER_ABSENT, flush=True)
        return []
    from liegroup_int.bench import pyelastica_peer as P

    print(f"PyElastica {P.VERSION}; numpy {np.__version__}", flush=True)
    w0 = time.perf_counter()
    P.warm_up()
    print(f"PyElastica numba warm-up: {time.perf_counter() - w0:.1f} s wall", flush=True)
    runs, case = [], P.pendulum_case()
    for n in cfg["peers"]:
        r = run_peer(P, case, n, T)
        runs.append(r)
        print(f"  {r['label']}: dt={r['dt']:.3e}, {r['steps']} steps, CPU {r['cpu_s']:.2f} s, "
              f"tip(T)={np.round(r['tip'][-1], 6)}" + (f"  FAILED: {r['failed']}" if r["failed"] else ""),
              flush=True)
    return runs


def main(argv=None):
    ap = parser(__doc__, quick_help="T = 0.2 s, ours n_ctrl 11 at two steps, PyElastica 50 elements")
    ap.add_argument("--save", default=None, metavar="FILE.npz", help="also save the recorded histories")
    args = ap.parse_args(argv)
    cfg = QUICK if args.quick else FULL
    T = cfg["T"]
    global TIP_TIMES, WINDOWS, DRIFT_WINDOWS
    TIP_TIMES, WINDOWS = cfg.get("tip_times", TIP_TIMES), cfg.get("windows", WINDOWS)
    DRIFT_WINDOWS = cfg.get("drift_windows", DRIFT_WINDOWS)
    runs = []
    for n_ctrl, c_dt in cfg["ours"]:
        r = run_ours(n_ctrl, c_dt, T)
        runs.append(r)
        print(f"  {r['label']}: lam={r['lam']:.4e}, dt={r['dt']:.3e}, {r['steps']} steps, CPU {r['cpu_s']:.2f} s "
              f"(+{r['diag_s']:.2f} s energy diag), tip(T)={np.round(r['tip'][-1], 6)}"
              + (f"  FAILED: {r['failed']}" if r["failed"] else ""), flush=True)
    runs += peer_runs(cfg, T)
    ours_ok = [r for r in runs if r["kind"] == "ours" and not r["failed"]]
    ref = max(ours_ok, key=lambda r: (r["n"], -r["dt"]))
    mets = [metrics(r, ref, T) for r in runs]
    print_table(runs, mets, ref, T)
    if args.save:
        np.savez(args.save, **{f"{r['short']}|{key}": r[key] for r in runs for key in ("t", "tip", "E", "KE")
                               if r[key] is not None})
        print(f"\nhistories: {args.save}")
    path = os.path.join(figure_dir(args, IMG), "galerkin_pendulum_10s.png")
    plot(runs, mets, ref, path)
    print(f"\nplot: {path}")
    return runs, mets


if __name__ == "__main__":
    main()
