"""Cross-check of the beam solver against the peer code PyElastica.

Scenes: the built-in ``pendulum`` (flexible rod, hinged at s = 0, self weight
q3 = -0.8475 N/m, released horizontally) and ``cantilever`` (steel, clamped at s = 0,
tip force F3 = -100 N from t = 0); see ``liegroup_int/scenes/builtin/*.toml``.

Ours: RKMK4, p = 4, fixed step. Reference runs: pendulum n_ctrl = 61, dt = 2e-5, T = 1 s;
cantilever n_ctrl = 31, dt = 1e-6, T = 0.05 s. A ladder of our runs (pendulum n_ctrl = 21,
31, 61, 121; cantilever n_ctrl = 21, 31, 61; steps below the RKMK4 stability limits)
measures our own discretization error; the finest is "ours finest".

Peer: PyElastica ``CosseratRod.straight_rod`` with n_elements = 25 ... 400, section
constants overwritten to equal ours (see ``liegroup_int/bench/pyelastica_peer.py``), undamped,
``PositionVerlet``. For every resolution the largest stable step ``dt_max`` is found by
trying steps ``f * dt_est`` (``dt_est = min(dx / sqrt(E/rho), 2 / sqrt(G A / (rho I)))``,
f = 2, 1.5, 1.2, 1, 0.8, 0.6, 0.5, 0.4, each rounded down to divide the output interval)
over the whole time span; the comparison run uses ``dt = dt_max / 2`` (rounded the same
way), and a run at ``dt / 4`` measures PyElastica's time-discretization error.

Model check: PyElastica's rod divides the internal force by the stretch e, the couple by
e^3 and the rotational inertia by e (incompressible section); ours has constant stiffness
and inertia (Simo-Reissner). ``PyElastica-linear`` (``model="linear"`` in the helper)
is PyElastica's discretization with those factors removed, i.e. of our continuum model;
it runs at the same steps.

Robustness (full run, or ``--robustness``): the pendulum with d = 1 mm (everything else
equal, q3 = rho A g) in both codes over 0.6 s, and the largest real part of the eigenvalues of our
linearized operator in the reference state for a few sections.

Timing: ``time.process_time()`` of the time loop only (PyElastica after a numba warm-up
run; ours after two warm-up steps when the numba backend is used, and without the energy
diagnostic evaluated at the output times).

Usage (from the repository root)::

    python benchmarks/pyelastica_compare.py            # full study (~8 min on 2 cores), writes docs/img/pyelastica_*.png
    python benchmarks/pyelastica_compare.py --quick    # n_elements 25..100, shorter spans, ours n_ctrl 21/31 (plots in a temp dir)
    python benchmarks/pyelastica_compare.py --cache DIR  # keep/reuse our runs in DIR

Without PyElastica (the ``[peers]`` extra) only our runs are made and tabulated, with a
note that the peer columns are absent.
"""

from __future__ import annotations

import argparse
import json
import os
import time

import numpy as np

from liegroup_int.bench.table import PEER_ABSENT, figure_dir, markdown, parser, peer_available
from liegroup_int.bench.work_precision import fit_step, peer_dt_max
from liegroup_int.integrators import integrate_fixed, jacobian, resolve_method
from liegroup_int.scenes import load_scene
from liegroup_int.scenes.beam import problem as scene_problem
from liegroup_int.studies import fit_rate

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

IMG = os.path.join(ROOT, "docs", "img")

#: per scene: time span, output interval, our reference run (n_ctrl, dt) and our ladder of
#: runs (n_ctrl, dt) (the reference among them) for our own convergence
SETTINGS = {
    "pendulum": dict(T=1.0, every=1e-3, ref=(61, 2e-5), ladder=((21, 5e-5), (31, 5e-5), (61, 2e-5), (121, 1e-5))),
    "cantilever": dict(T=0.05, every=2.5e-4, ref=(31, 1e-6), ladder=((21, 1e-6), (31, 1e-6), (61, 5e-7))),
}
QUICK = {
    "pendulum": dict(T=0.2, every=1e-3, ref=(31, 5e-5), ladder=((21, 5e-5), (31, 5e-5))),
    "cantilever": dict(T=0.005, every=2.5e-4, ref=(31, 1e-6), ladder=((21, 1e-6), (31, 1e-6))),
}
N_ELEMENTS = (25, 50, 100, 200, 400)
N_ELEMENTS_QUICK = (25, 50, 100)
DT_FACTORS = (2.0, 1.5, 1.2, 1.0, 0.8, 0.6, 0.5, 0.4)


# ----------------------------------------------------------------------------- ours
def _make_problem(name: str, n_ctrl: int, backend: str, overrides: dict | None = None):
    """The built-in scene at ``n_ctrl`` with ``backend`` (plus scene ``overrides``)."""
    return scene_problem(load_scene(name, {"space.n_ctrl": n_ctrl, "integrator.backend": backend,
                                           **(overrides or {})}))


def pick_backend(name: str) -> str:
    """``numba`` if it reproduces the NumPy path on a few steps, else ``numpy``."""
    try:
        tips = []
        for be in ("numpy", "numba"):
            pb = _make_problem(name, 13, be)
            dt = 1e-6 if name == "cantilever" else 5e-5
            _, y, _ = integrate_fixed(pb, resolve_method("rkmk4"), (0.0, 20 * dt), pb.initial_state(), dt)
            tips.append(pb.tip(y))
        ok = np.allclose(tips[0], tips[1], rtol=1e-10, atol=1e-14)
        return "numba" if ok else "numpy"
    except Exception as exc:  # noqa: BLE001 - any failure: fall back
        print(f"  (numba backend not usable: {exc!r}; using numpy)")
        return "numpy"


def run_ours(name: str, n_ctrl: int, dt: float, T: float, every: float, backend: str,
             cache: str | None = None, overrides: dict | None = None, tag: str = "") -> dict:
    """Our RKMK4 run; ``cpu_s`` is the process time of the integration without the
    energy diagnostic evaluated at the output times (the tip is recorded in both codes).
    A run that fails (blow-up) returns what it recorded and ``failed`` = the message."""
    key = f"ours_{name}{tag}_n{n_ctrl}_dt{dt:g}_T{T:g}_every{every:g}.npz"
    if cache and os.path.exists(os.path.join(cache, key)):
        z = np.load(os.path.join(cache, key), allow_pickle=True)
        return {k: z[k].item() if z[k].ndim == 0 else z[k] for k in z.files}
    pb = _make_problem(name, n_ctrl, backend, overrides)
    y0 = pb.initial_state()
    tab = resolve_method("rkmk4")
    if backend != "numpy":  # compile outside the timing
        integrate_fixed(pb, tab, (0.0, 2 * dt), y0, dt)
    n_out = int(round(T / every))
    t_out = every * np.arange(1, n_out + 1)
    rec_t, rec_tip, rec_e = [], [], []
    diag = [0.0, 0.0]  # CPU and wall time spent in the energy diagnostic

    def observer(t, y):
        rec_t.append(t)
        rec_tip.append(pb.tip(y))
        c1, w1 = time.process_time(), time.perf_counter()
        rec_e.append(pb.energy(y))
        diag[0] += time.process_time() - c1
        diag[1] += time.perf_counter() - w1

    failed, steps = "", -1
    c0, w0 = time.process_time(), time.perf_counter()
    try:
        _, _, stats = integrate_fixed(pb, tab, (0.0, T), y0, dt, observer=observer, t_out=t_out)
        steps = stats.steps
    except Exception as exc:  # noqa: BLE001 - StepSizeError / BlowUpError are results here
        failed = f"{type(exc).__name__}: {exc}"
    cpu, wall = time.process_time() - c0 - diag[0], time.perf_counter() - w0 - diag[1]
    out = dict(t=np.array(rec_t), tip=np.array(rec_tip), energy=np.array(rec_e), cpu_s=cpu, wall_s=wall,
               steps=steps, n_ctrl=n_ctrl, dt=dt, backend=backend, failed=failed)
    if cache:
        os.makedirs(cache, exist_ok=True)
        np.savez(os.path.join(cache, key), **out)
    return out


# ----------------------------------------------------------------------------- peer
def diff_metrics(ref: dict, r) -> dict:
    """Tip differences of a run ``r`` (PyElastica result or our run dict) to our run ``ref``."""
    rt, rtip = (r["t"], r["tip"]) if isinstance(r, dict) else (r.t, r.tip)
    m = min(len(ref["t"]), len(rt))
    assert np.allclose(ref["t"][:m], rt[:m], atol=1e-9), "output times differ"
    dz = rtip[:m, 2] - ref["tip"][:m, 2]
    d3 = np.linalg.norm(rtip[:m] - ref["tip"][:m], axis=1)
    return dict(max_dz=float(np.max(np.abs(dz))), final_dz=float(abs(dz[-1])), max_d3=float(np.max(d3)),
                final_z=float(rtip[m - 1, 2]))


def slope(n, e) -> float:
    """:func:`liegroup_int.studies.fit_rate` over the points with a positive error (nan if
    fewer than 3)."""
    n, e = np.asarray(n, float), np.asarray(e, float)
    ok = e > 0
    return fit_rate(n[ok], e[ok]) if ok.sum() >= 3 else float("nan")


def richardson(zs: dict, n_list) -> tuple[np.ndarray | None, float]:
    """Extrapolate the two finest runs with the order observed on the three finest."""
    if len(n_list) < 3:
        return None, float("nan")
    n0, n1, n2 = n_list[-3:]
    e1, e2 = np.max(np.abs(zs[n0] - zs[n1])), np.max(np.abs(zs[n1] - zs[n2]))
    p = float(np.log2(e1 / e2)) if e2 > 0 else float("nan")
    pu = min(max(p, 0.5), 4.0) if np.isfinite(p) else 2.0
    return zs[n2] + (zs[n2] - zs[n1]) / (2.0**pu - 1.0), p


# ----------------------------------------------------------------------------- checks
def cantilever_linear_tip(t, F=-100.0, EI=2.1e11 * 1e-8 / 12, mu=7800 * 1e-4, L=1.0, modes=200):
    """Euler-Bernoulli (linear, small deflection) tip history under a suddenly applied
    constant tip force, modal sum: ``w = sum 4 F / (mu L w_k^2) (1 - cos w_k t)``."""
    from scipy.optimize import brentq

    bl = []
    for k in range(1, modes + 1):
        g = (2 * k - 1) * np.pi / 2
        bl.append(brentq(lambda x: np.cos(x) * np.cosh(x) + 1, g - 0.5, g + 0.5) if k <= 6 else g)
    bl = np.array(bl)
    w = bl**2 * np.sqrt(EI / (mu * L**4))
    t = np.asarray(t, float)[:, None]
    return np.sum(4 * F / (mu * L * w**2) * (1 - np.cos(w * t)), axis=1)


def pendulum_rigid_quarter_period(g=9.8097, L=1.0) -> float:
    """Rigid uniform rod about its end, released horizontally: time to the vertical."""
    from scipy.special import ellipk

    return float(np.sqrt(2 * L / (3 * g)) * ellipk(0.5))


def first_crossing(t, x):
    """First time the tip crosses x1 = 0 (linear interpolation), or nan."""
    i = np.where((x[:-1] > 0) & (x[1:] <= 0))[0]
    if not i.size:
        return float("nan")
    i = i[0]
    return float(t[i] + (t[i + 1] - t[i]) * x[i] / (x[i] - x[i + 1]))


# ----------------------------------------------------------------------------- plots
def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_histories(name, res, path):
    """Left: tip x3 of ours (reference and ladder), PyElastica, (cantilever) linear theory.
    Right: differences to our finest run."""
    plt = _plt()
    ref, fine, ladder, peers = res["ours"][res["ref_n"]], res["ours"][res["fine_n"]], res["ours"], res["peers"]
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(13, 4.8))
    a1.plot(ref["t"], ref["tip"][:, 2], "k-", lw=2.4, label=f"ours n_ctrl={res['ref_n']} (reference)")
    for n, o in ladder.items():
        if n != res["ref_n"]:
            a1.plot(o["t"], o["tip"][:, 2], "--", color="0.45", lw=1.0)
        if n != res["fine_n"]:
            d = np.abs(o["tip"][1:, 2] - fine["tip"][1:, 2]) + 1e-16
            a2.semilogy(o["t"][1:], d, "--", lw=1.2 if n == res["ref_n"] else 0.9,
                        color="k" if n == res["ref_n"] else "0.6",
                        label=f"ours n_ctrl={n}" + (" (reference)" if n == res["ref_n"] else ""))
    cmap = plt.get_cmap("viridis")
    for j, r in enumerate(peers):
        col = cmap(j / max(1, len(peers) - 1))
        a1.plot(r.t, r.tip[:, 2], color=col, lw=1.0, label=f"PyElastica n={r.n_elements}")
        a2.semilogy(r.t[1:], np.abs(r.tip[1:, 2] - fine["tip"][1:, 2]) + 1e-16, color=col, lw=1.0,
                    label=f"PyElastica n={r.n_elements}")
    rl = res["peers_linear"][-1]
    a2.semilogy(rl.t[1:], np.abs(rl.tip[1:, 2] - fine["tip"][1:, 2]) + 1e-16, ":", color="tab:red", lw=1.2,
                label=f"PyElastica-linear n={rl.n_elements}")
    if name == "cantilever":
        a1.plot(ref["t"], cantilever_linear_tip(ref["t"]), ":", color="tab:red", lw=1.4,
                label="linear Euler-Bernoulli (modal sum)")
    a1.plot([], [], "--", color="0.45", label="ours, other n_ctrl")
    a1.set_xlabel("t [s]"), a1.set_ylabel("tip x3 [m]"), a1.grid(alpha=0.3), a1.legend(fontsize=7)
    a1.set_title(f"{name}: tip x3")
    a2.set_xlabel("t [s]"), a2.set_ylabel(f"|tip x3 - ours n_ctrl={res['fine_n']}| [m]")
    a2.set_ylim(bottom=1e-8)
    a2.grid(alpha=0.3, which="both"), a2.legend(fontsize=7, ncol=2)
    a2.set_title(f"difference to our finest run (n_ctrl={res['fine_n']})")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_ours(results, path):
    """Tip x3 of our runs alone (no peer), one panel per scene."""
    plt = _plt()
    fig, axes = plt.subplots(1, len(results), figsize=(6.5 * len(results), 4.2), squeeze=False)
    for ax, (name, res) in zip(axes[0], results.items()):
        for n, o in res["ours"].items():
            ax.plot(o["t"], o["tip"][:, 2], lw=1.0, label=f"ours n_ctrl={n}")
        ax.set_xlabel("t [s]"), ax.set_ylabel("tip x3 [m]"), ax.grid(alpha=0.3), ax.legend(fontsize=8)
        ax.set_title(f"{name} (PyElastica not installed)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_convergence(results, path):
    plt = _plt()
    fig, axes = plt.subplots(1, len(results), figsize=(6.5 * len(results), 5.2), squeeze=False)
    for ax, (name, res) in zip(axes[0], results.items()):
        rows, rowsl = res["rows"], res["rows_linear"]
        nodes = np.array([r["n"] + 1 for r in rows])
        e = np.array([r["max_dz"] for r in rows])
        ef = np.array([r["max_dz_fine"] for r in rows])
        el = np.array([r["max_dz_fine"] for r in rowsl])
        ax.loglog(nodes, e, "o-", color="tab:blue",
                  label=f"PyElastica vs ours n_ctrl={res['ref_n']} (slope {slope(nodes, e):.2f})")
        if res["fine_n"] != res["ref_n"]:
            ax.loglog(nodes, ef, "s-", color="tab:cyan",
                      label=f"PyElastica vs ours n_ctrl={res['fine_n']} (slope {slope(nodes, ef):.2f})")
        ax.loglog(nodes, el, "v-", color="tab:red",
                  label=f"PyElastica-linear vs ours n_ctrl={res['fine_n']} (slope {slope(nodes, el):.2f})")
        sc = res["self_conv"]
        if sc:
            ns, es = np.array([a + 1 for a, _ in sc]), np.array([b for _, b in sc])
            ax.loglog(ns, es, "^-", color="tab:green",
                      label=f"PyElastica self: max|z_n - z_2n| (slope {slope(ns, es):.2f})")
        et = np.array([r["time_err"] for r in rows])
        if np.all(np.isfinite(et)):
            ax.loglog(nodes, et, "x:", color="tab:gray", label="PyElastica time error |z(dt) - z(dt/4)|")
        lad = [(n, d["max_dz_fine"]) for n, d in res["ladder"].items() if n != res["fine_n"]]
        if lad:
            nl, elad = np.array([a for a, _ in lad]), np.array([b for _, b in lad])
            ax.loglog(nl, elad, "D-", color="k",
                      label=f"ours vs ours n_ctrl={res['fine_n']} (slope {slope(nl, elad):.2f})")
        for key, col, lab in (("ext_vs_fine", "tab:blue", "PyElastica"), ("ext_lin_vs_fine", "tab:red",
                                                                           "PyElastica-linear")):
            if np.isfinite(res.get(key, np.nan)):
                ax.axhline(res[key], color=col, ls=":", lw=1.2,
                           label=f"{lab} Richardson-extrapolated vs ours n_ctrl={res['fine_n']}")
        ax.loglog(nodes, e[0] * (nodes / nodes[0]) ** -2.0, color="0.7", lw=0.8, label="slope -2")
        ax.loglog(nodes, e[0] * (nodes / nodes[0]) ** -1.0, color="0.7", lw=0.8, ls="--", label="slope -1")
        ax.set_xlabel("points along the rod (PyElastica nodes n+1; ours control points n_ctrl)")
        ax.set_ylabel(f"max over t in [0, {res['T']:g}] s of |tip x3 difference| [m]")
        ax.set_title(name), ax.grid(alpha=0.3, which="both"), ax.legend(fontsize=6.5)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


# ----------------------------------------------------------------------------- main study
def ours_ladder(name, cfg, backend, cache):
    """Our runs of the ladder: ``({n_ctrl: run}, ref_n, fine_n, {n_ctrl: table row})``."""
    T, every = cfg["T"], cfg["every"]
    ours = {}
    for n_ctrl, dt in cfg["ladder"]:
        o = run_ours(name, n_ctrl, dt, T, every, backend, cache)
        if o["failed"]:
            raise RuntimeError(f"ours {name} n_ctrl={n_ctrl} dt={dt}: {o['failed']}")
        ours[n_ctrl] = o
        print(f"  ours n_ctrl={n_ctrl:4d} dt={dt:.1e}: {o['steps']} steps, CPU {o['cpu_s']:.1f} s "
              f"(wall {o['wall_s']:.1f} s, {o['backend']}), tip_z(T) = {o['tip'][-1, 2]:.6f}, "
              f"energy max-min {np.ptp(o['energy']):.2e} J", flush=True)
    ref_n, fine_n = cfg["ref"][0], max(ours)
    ref, fine = ours[ref_n], ours[fine_n]
    ladder = {n: dict(dt=o["dt"], steps=int(o["steps"]), cpu_s=float(o["cpu_s"]), backend=str(o["backend"]),
                      **diff_metrics(ref, o), max_dz_fine=diff_metrics(fine, o)["max_dz"],
                      final_dz_fine=diff_metrics(fine, o)["final_dz"]) for n, o in ours.items()}
    return ours, ref_n, fine_n, ladder


def study(name, P, cfg, n_list, backend, cache, time_check=True):
    T, every = cfg["T"], cfg["every"]
    print(f"\n=== {name}: T = {T:g} s, output every {every:g} s ===", flush=True)
    ours, ref_n, fine_n, ladder = ours_ladder(name, cfg, backend, cache)
    if P is None:
        return dict(ours=ours, ladder=ladder, ref_n=ref_n, fine_n=fine_n, T=T, peer=False)
    case = P.CASES[name]()
    ref, fine = ours[ref_n], ours[fine_n]
    rows, rows_l, peers, peers_l, zs, zl = [], [], [], [], {}, {}
    for n in n_list:
        dt_max, dt_bad, _ = peer_dt_max(P, case, n, T, every)
        dt = fit_step(dt_max / 2, every)
        r = P.run(case, n, dt, T, every)
        if not r.finite:
            raise RuntimeError(f"{name} n={n} dt={dt}: PyElastica run not finite")
        met = diff_metrics(ref, r)
        time_err = float("nan")
        if time_check:
            r4 = P.run(case, n, dt / 4, T, every)
            time_err = float(np.max(np.abs(r4.tip[:, 2] - r.tip[:, 2])))
        row = dict(n=n, dt_max=dt_max, dt_unstable=dt_bad, dt=dt, steps=r.steps, cpu_s=r.cpu_s, wall_s=r.wall_s,
                   time_err=time_err, **met, max_dz_fine=diff_metrics(fine, r)["max_dz"],
                   final_dz_fine=diff_metrics(fine, r)["final_dz"])
        rows.append(row)
        peers.append(r)
        zs[n] = r.tip[:, 2]
        rl = P.run(case, n, dt, T, every, model="linear")
        if not rl.finite:
            raise RuntimeError(f"{name} n={n} dt={dt}: PyElastica-linear run not finite")
        ml, mlf = diff_metrics(ref, rl), diff_metrics(fine, rl)
        rows_l.append(dict(n=n, dt=dt, steps=rl.steps, cpu_s=rl.cpu_s, **ml, max_dz_fine=mlf["max_dz"],
                           final_dz_fine=mlf["final_dz"]))
        peers_l.append(rl)
        zl[n] = rl.tip[:, 2]
        print(f"  PyElastica n={n:4d} dt_max={dt_max:.3e} (unstable {dt_bad:.3e}) dt={dt:.3e} steps={r.steps:7d} "
              f"CPU={r.cpu_s:6.2f} s max|dz|={met['max_dz']:.3e} |dz(T)|={met['final_dz']:.3e} "
              f"z(T)={met['final_z']:.6f} vs finest ours {row['max_dz_fine']:.3e} time err={time_err:.1e}; "
              f"linear: vs finest ours {mlf['max_dz']:.3e}, z(T)={ml['final_z']:.6f}", flush=True)
    self_conv = [(n, float(np.max(np.abs(zs[n] - zs[2 * n])))) for n in n_list if 2 * n in zs]
    self_conv_l = [(n, float(np.max(np.abs(zl[n] - zl[2 * n])))) for n in n_list if 2 * n in zl]
    out = dict(rows=rows, rows_linear=rows_l, ours=ours, ladder=ladder, peers=peers, peers_linear=peers_l,
               self_conv=self_conv, self_conv_linear=self_conv_l, ref_n=ref_n, fine_n=fine_n,
               constants=peers[0].constants, T=T, peer=True)
    for tag, z in (("", zs), ("_lin", zl)):
        z_ext, p = richardson(z, n_list)
        out[f"p_obs{tag}"] = p
        for which, o in (("ref", ref), ("fine", fine)):
            out[f"ext{tag}_vs_{which}"] = float(np.max(np.abs(z_ext - o["tip"][:, 2]))) if z_ext is not None else np.nan
            out[f"ext{tag}_vs_{which}_T"] = float(abs(z_ext[-1] - o["tip"][-1, 2])) if z_ext is not None else np.nan
    return out


def checks(name, res):
    ref = res["ours"][res["ref_n"]]
    t, z = ref["t"], ref["tip"][:, 2]
    lines = []
    if name == "cantilever":
        zl = cantilever_linear_tip(t)
        lines.append(f"static deflection (linear) F L^3/(3 E I) = {100 / (3 * 175.0):.4f} m; "
                     f"linear Euler-Bernoulli modal tip: max|z_lin| over the span = {np.max(np.abs(zl)):.4f} m, "
                     f"z_lin(T) = {zl[-1]:.6f}")
        early = t <= 0.01
        for n, o in res["ours"].items():
            lines.append(f"  ours n_ctrl={n}: max|z - z_lin| = {np.max(np.abs(o['tip'][:, 2] - zl)):.3e} "
                         f"(t <= 0.01 s: {np.max(np.abs(o['tip'][early, 2] - zl[early])):.2e}), "
                         f"z(T) = {o['tip'][-1, 2]:.6f}, tip x1(T) - 1 = {o['tip'][-1, 0] - 1:.3e}")
        for r in res["peers"]:
            lines.append(f"  PyElastica n={r.n_elements}: max|z - z_lin| = {np.max(np.abs(r.tip[:, 2] - zl)):.3e}, "
                         f"tip x1(T) - 1 = {r.tip[-1, 0] - 1:.3e}")
    else:
        g = 0.8475 / (1100 * np.pi * 0.01**2 / 4)
        early = t <= 0.05
        lines.append(f"free fall (t <= 0.05 s): max|z + g t^2/2| ours = "
                     f"{np.max(np.abs(z[early] + 0.5 * g * t[early] ** 2)):.3e} m")
        lines.append(f"rigid uniform rod, horizontal -> vertical: {pendulum_rigid_quarter_period(g):.4f} s")
        for n, o in res["ours"].items():
            lines.append(f"  ours n_ctrl={n}: tip crosses x1 = 0 at t = {first_crossing(o['t'], o['tip'][:, 0]):.4f} s, "
                         f"min tip z = {o['tip'][:, 2].min():.4f} m at t = {o['t'][np.argmin(o['tip'][:, 2])]:.3f} s")
        for r in res["peers"]:
            lines.append(f"  PyElastica n={r.n_elements}: tip crosses x1 = 0 at t = {first_crossing(r.t, r.tip[:, 0]):.4f} s, "
                         f"min tip z = {r.tip[:, 2].min():.4f} m at t = {r.t[np.argmin(r.tip[:, 2])]:.3f} s")
    for n, o in res["ours"].items():
        lines.append(f"  ours n_ctrl={n}: energy max - min over the span = {np.ptp(o['energy']):.3e} J, "
                     f"E(T) - E(0) = {o['energy'][-1] - o['energy'][0]:.3e} J")
    return lines


# ----------------------------------------------------------------------------- robustness
def max_real_eigenvalue(pb) -> tuple[float, float, float]:
    """Largest real part of the eigenvalues of our linearized operator at the initial
    state (dense finite-difference Jacobian), its imaginary part and max |lambda|."""
    ev = np.linalg.eigvals(jacobian(pb, 0.0, pb.initial_state(), eps=1e-6))
    i = int(np.argmax(ev.real))
    return float(ev[i].real), float(abs(ev[i].imag)), float(np.abs(ev).max())


def robustness(P, backend, cache):
    """Thin pendulum (d = 1 mm) in both codes; eigenvalue real parts of our operator."""
    from math import pi

    print("\n=== robustness: pendulum with d = 1 mm (q3 = rho A g), T = 0.6 s ===", flush=True)
    d, T, every = 0.001, 0.6, 1e-3
    A = pi * d**2 / 4
    q = -1100.0 * A * 9.81
    ov = {"section.d": d, "loads.distributed_force": [0.0, 0.0, q]}
    out = dict(thin=[], eig=[])
    for n_ctrl, dt in ((31, 1e-5), (61, 1e-5), (61, 5e-6), (121, 5e-6), (241, 2.5e-6)):
        o = run_ours("pendulum", n_ctrl, dt, T, every, backend, cache, overrides=ov, tag="_d1mm")
        row = dict(code="ours", n=n_ctrl, dt=dt, cpu_s=float(o["cpu_s"]), failed=str(o["failed"]),
                   t_reached=float(o["t"][-1]), z_04=float(o["tip"][400, 2]) if len(o["t"]) > 400 else np.nan,
                   z_T=float(o["tip"][-1, 2]) if not o["failed"] else np.nan)
        out["thin"].append(row)
        print(f"  ours n_ctrl={n_ctrl} dt={dt:g}: " + (f"FAILED at t ~ {row['t_reached']:.3f} s ({o['failed']})"
              if o["failed"] else f"completed, z(T) = {row['z_T']:.5f}") + f", z(0.4) = {row['z_04']:.5f}", flush=True)
    I = pi * d**4 / 64
    case = P.Case("pendulum_d1mm", E=5e6, G=5e6 / 3, rho=1100.0, A=A, I1=I, I2=I, J=2 * I, bc="pinned",
                  line_load=(0.0, 0.0, q))
    for n in (25, 100, 200):
        r = P.run(case, n, 5e-6, T, every)
        row = dict(code="PyElastica", n=n, dt=5e-6, cpu_s=r.cpu_s, failed="" if r.finite else "not finite",
                   t_reached=float(r.t[-1]), z_04=float(r.tip[400, 2]), z_T=float(r.tip[-1, 2]))
        out["thin"].append(row)
        print(f"  PyElastica n={n} dt=5e-6: finite={r.finite}, z(0.4) = {row['z_04']:.5f}, z(T) = {row['z_T']:.5f}",
              flush=True)
    print("\n=== robustness: largest Re(lambda) of our linearized operator at t = 0 ===", flush=True)
    base = _make_problem("pendulum", 31, backend).constants
    ga10 = {"section.shape": "explicit", "section.EA": base.CN[2], "section.GA": 10 * base.CN[0],
            "section.EI1": base.CM[0], "section.EI2": base.CM[1], "section.GJ": base.CM[2],
            "section.rhoA": base.mu, "section.rhoI1": base.Jm[0], "section.rhoI2": base.Jm[1],
            "section.rhoJ": base.Jm[2]}
    for label, name, ov2 in (("pendulum", "pendulum", {}), ("cantilever", "cantilever", {}),
                             ("pendulum d=1mm", "pendulum", ov),
                             ("pendulum, explicit section with GA x 10", "pendulum", ga10)):
        for n in (31, 61):
            re, im, lam = max_real_eigenvalue(_make_problem(name, n, backend, ov2))
            out["eig"].append(dict(case=label, n=n, max_re=re, im=im, lam_max=lam))
            print(f"  {label}, n_ctrl={n}: max Re = {re:.3e} 1/s (|Im| = {im:.3e}), |lambda|max = {lam:.3e}",
                  flush=True)
    return out


# ----------------------------------------------------------------------------- output
def print_ours(name, res):
    """Our ladder alone (no peer)."""
    print(f"\n## {name}  (T = {res['T']:g} s), ours only\n")
    print(markdown(["run", "dt [s]", "steps", "CPU [s]", f"max_t abs(dz) vs ours n_ctrl={res['ref_n']} [m]",
                    f"max_t abs(dz) vs ours n_ctrl={res['fine_n']} [m]", "tip_z(T) [m]"],
                   [[f"ours RKMK4 p=4 n_ctrl={n}" + (" (reference)" if n == res["ref_n"] else "") + f" [{d['backend']}]",
                     f"{d['dt']:.1e}", d["steps"], f"{d['cpu_s']:.2f}", f"{d['max_dz']:.2e}", f"{d['max_dz_fine']:.2e}",
                     f"{d['final_z']:.6f}"] for n, d in res["ladder"].items()]))


def print_tables(results):
    for name, res in results.items():
        if not res["peer"]:
            print_ours(name, res)
            continue
        print(f"\n## {name}  (T = {res['T']:g} s)")
        print("PyElastica section constants: " + ", ".join(
            f"{k}={v:.6g}" if not isinstance(v, list) else f"{k}=({', '.join(f'{x:.4g}' for x in v)})"
            for k, v in res["constants"].items()))
        print(f"\n| run | dt [s] | steps | CPU [s] | max_t abs(dz) vs ours n_ctrl={res['ref_n']} [m] | "
              f"abs(dz(T)) [m] | max_t abs(dz) vs ours n_ctrl={res['fine_n']} [m] | tip_z(T) [m] | "
              f"time err [m] |")
        print("|---|---|---|---|---|---|---|---|---|")
        for n, d in res["ladder"].items():
            tag = " (reference)" if n == res["ref_n"] else ""
            print(f"| ours RKMK4 p=4 n_ctrl={n}{tag} [{d['backend']}] | {d['dt']:.1e} | {d['steps']} | "
                  f"{d['cpu_s']:.1f} | {d['max_dz']:.2e} | {d['final_dz']:.2e} | {d['max_dz_fine']:.2e} | "
                  f"{d['final_z']:.6f} | - |")
        for r in res["rows"]:
            print(f"| PyElastica n={r['n']} (dt_max {r['dt_max']:.2e}, unstable {r['dt_unstable']:.2e}) | "
                  f"{r['dt']:.2e} | {r['steps']} | {r['cpu_s']:.2f} | {r['max_dz']:.2e} | {r['final_dz']:.2e} | "
                  f"{r['max_dz_fine']:.2e} | {r['final_z']:.6f} | {r['time_err']:.1e} |")
        for r in res["rows_linear"]:
            print(f"| PyElastica-linear n={r['n']} | {r['dt']:.2e} | {r['steps']} | {r['cpu_s']:.2f} | "
                  f"{r['max_dz']:.2e} | {r['final_dz']:.2e} | {r['max_dz_fine']:.2e} | {r['final_z']:.6f} | - |")
        n = [r["n"] for r in res["rows"]]
        print(f"\nPyElastica log-log slope vs n: max|dz| vs ours n_ctrl={res['ref_n']}: "
              f"{slope(n, [r['max_dz'] for r in res['rows']]):.2f}; |dz(T)|: "
              f"{slope(n, [r['final_dz'] for r in res['rows']]):.2f}; max|dz| vs ours n_ctrl={res['fine_n']}: "
              f"{slope(n, [r['max_dz_fine'] for r in res['rows']]):.2f}; PyElastica-linear max|dz| vs ours "
              f"n_ctrl={res['fine_n']}: {slope(n, [r['max_dz_fine'] for r in res['rows_linear']]):.2f}")
        for tag, sc, p in (("PyElastica", res["self_conv"], res["p_obs"]),
                           ("PyElastica-linear", res["self_conv_linear"], res["p_obs_lin"])):
            if sc:
                print(f"{tag} self-convergence max|z_n - z_2n|: " + ", ".join(f"n={a}: {b:.2e}" for a, b in sc)
                      + f"  (slope {slope(*zip(*sc)):.2f}; order from the three finest {p:.2f})")
        for tag, key in (("PyElastica", "ext"), ("PyElastica-linear", "ext_lin")):
            print(f"{tag} Richardson-extrapolated (n={n[-2]},{n[-1]}): max_t|dz| vs ours n_ctrl={res['ref_n']} = "
                  f"{res[key + '_vs_ref']:.2e} (at T {res[key + '_vs_ref_T']:.2e}), vs ours n_ctrl={res['fine_n']} = "
                  f"{res[key + '_vs_fine']:.2e} (at T {res[key + '_vs_fine_T']:.2e})")
        lad = [(k, d["max_dz_fine"]) for k, d in res["ladder"].items() if k != res["fine_n"]]
        if len(lad) >= 2:
            print(f"ours: max|z_n - z_{res['fine_n']}| = " + ", ".join(f"n_ctrl={a}: {b:.2e}" for a, b in lad)
                  + f"  (slope {slope(*zip(*lad)):.2f})")
        for line in checks(name, res):
            print(line)


def print_robustness(rob):
    print("\n## robustness: pendulum with d = 1 mm, T = 0.6 s")
    print("| code | n | dt [s] | CPU [s] | outcome | tip_z(0.4 s) [m] | tip_z(T) [m] |")
    print("|---|---|---|---|---|---|---|")
    for r in rob["thin"]:
        outcome = f"blew up at t = {r['t_reached']:.3f} s" if r["failed"] else "completed"
        print(f"| {r['code']} | {r['n']} | {r['dt']:.1e} | {r['cpu_s']:.1f} | {outcome} | {r['z_04']:.5f} | "
              f"{r['z_T']:.5f} |")
    print("\n| our operator at t = 0 | n_ctrl | max Re(lambda) [1/s] | abs Im there [1/s] | max abs(lambda) [1/s] |")
    print("|---|---|---|---|---|")
    for e in rob["eig"]:
        print(f"| {e['case']} | {e['n']} | {e['max_re']:.2e} | {e['im']:.2e} | {e['lam_max']:.2e} |")


def main(argv=None):
    ap = parser(__doc__, quick_help="n_elements 25..100, shorter spans, ours n_ctrl 21/31; no robustness part; plots in --out")
    ap.add_argument("--cases", nargs="+", default=["pendulum", "cantilever"], choices=list(SETTINGS))
    ap.add_argument("--cache", default=None, help="directory to keep/reuse our runs (npz)")
    ap.add_argument("--backend", default="auto", choices=("auto", "numpy", "numba"),
                    help="our stage kernels (auto: numba if available and consistent)")
    ap.add_argument("--no-plots", action="store_true")
    ap.add_argument("--no-time-check", action="store_true", help="skip the dt/4 PyElastica runs")
    ap.add_argument("--robustness", action=argparse.BooleanOptionalAction, default=None,
                    help="thin-pendulum and eigenvalue checks (default: on, off with --quick)")
    ap.add_argument("--json", default=None, help="write the tables to this JSON file")
    args = ap.parse_args(argv)
    if args.robustness is None:
        args.robustness = not args.quick
    P = None
    if peer_available():
        from liegroup_int.bench import pyelastica_peer as P

        print(f"PyElastica {P.VERSION}; numpy {np.__version__}")
        c0 = time.perf_counter()
        P.warm_up()
        print(f"PyElastica numba warm-up: {time.perf_counter() - c0:.1f} s wall")
    else:
        print(PEER_ABSENT)
    cfgs = QUICK if args.quick else SETTINGS
    n_list = N_ELEMENTS_QUICK if args.quick else N_ELEMENTS
    results = {}
    for name in args.cases:
        backend = pick_backend(name) if args.backend == "auto" else args.backend
        print(f"ours: backend {backend}")
        results[name] = study(name, P, cfgs[name], n_list, backend, args.cache, not args.no_time_check)
    rob = None
    if args.robustness and P is not None:
        backend = pick_backend("pendulum") if args.backend == "auto" else args.backend
        rob = robustness(P, backend, args.cache)

    print("\n" + "=" * 100)
    print_tables(results)
    if rob is not None:
        print_robustness(rob)

    if not args.no_plots:
        img = figure_dir(args, IMG)
        if P is None:
            plot_ours(results, os.path.join(img, "pyelastica_ours_only.png"))
        else:
            for name, res in results.items():
                plot_histories(name, res, os.path.join(img, f"pyelastica_{name}.png"))
            plot_convergence(results, os.path.join(img, "pyelastica_convergence.png"))
        print(f"\nplots: {img}/pyelastica_*.png")
    if args.json:
        keep = ("rows", "rows_linear", "ladder", "self_conv", "self_conv_linear", "ref_n", "fine_n", "constants",
                "T", "p_obs", "p_obs_lin", "ext_vs_ref", "ext_vs_fine", "ext_lin_vs_ref", "ext_lin_vs_fine")
        js = {name: {k: res[k] for k in keep if k in res} for name, res in results.items()}
        if rob is not None:
            js["robustness"] = rob
        with open(args.json, "w") as fh:
            json.dump(js, fh, indent=1, default=lambda x: x.item() if hasattr(x, "item") else str(x))
    return results


if __name__ == "__main__":
    main()
