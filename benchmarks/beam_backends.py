"""Per-step cost of the beam plugin: NumPy backend vs compiled (numba) backend.

Scene: the built-in ``cantilever`` (p = 4), ``n_ctrl`` in 31, 61, 121, 251, 501, 1001,
integrated with fixed-step RKMK4 through the public driver
(:func:`liegroup_int.integrators.integrate_fixed`, i.e. what a user gets: 4 actions,
4 stage rates, 4 increment combinations, one rotation-angle check and one finiteness
check per step). Three paths:

* ``numpy``: ``backend="numpy"``, the generic driver loop;
* ``numba generic``: ``backend="numba"`` through the generic driver loop (one compiled
  call per action, stage rate and angle check; combinations and checks in NumPy). The
  driver takes this path whenever a per-step ``monitor`` is given, so it is timed with
  a no-op monitor (one Python call per step, ~0.1 us);
* ``numba fused``: ``backend="numba"`` without a monitor: the driver hands all steps
  between output times to the problem's compiled stepper
  (the compiled engine with ``BeamProblem.compiled_kernels``, one compiled call for the whole batch here).

Start state. Not the state at rest: with the tiny steps these sizes need, the far field of
a from-rest run underflows to subnormal numbers during the first hundreds of steps and
subnormal arithmetic slows *both* backends by ~2x on x86. The timed runs start from a
smooth deformed and moving state, ``Lambda(u, y0)`` with control values
``eta ~ 1e-3 s^2, theta ~ 1e-2 s^2, dv, dw ~ 1e-2 s^2`` (zero at the clamp), and use
``dt = 0.3e-6 (31 / n)^2`` (below the stability limit at every size; finiteness and the
absence of subnormals are checked and printed).

Timing. CPU time of this process (``time.process_time``; ``--wall`` for
``time.perf_counter``) around ``integrate_fixed`` of ``N`` steps after a warm-up (JIT
compilation, caches); ``N`` is chosen so that a batch lasts >= ``--batch`` seconds; best of
``--repeats`` batches. With one BLAS thread both backends are single-threaded, so CPU time
equals wall time on an idle machine and is far less disturbed by other processes on a
shared one. BLAS threads default to 1 (``--threads``), set before NumPy
is imported, for both backends alike. "driver only" times the same driver on a null
problem with the beam's increment shape (action returns its input, rates return zeros):
the floor no problem backend can go below.

Columns: per-step time of each path, speed-ups ``t_numpy / t_fused`` and
``t_numpy / t_generic``, fused cost per stage per collocation point in ns, the
driver-only time of the generic loop. Fitted exponents: least squares
of ``log t_step`` against ``log n_ctrl`` over all sizes.

Usage (from the repository root)::

    python benchmarks/beam_backends.py                  # table + docs/img/beam_backends.png
    python benchmarks/beam_backends.py --quick          # n_ctrl 31 and 41, one short batch; figure in a temp dir
"""

from __future__ import annotations

import os
import platform
import time

from liegroup_int.bench.table import figure_dir, markdown, parser


def _parse():
    ap = parser(__doc__, quick_help="n_ctrl 31 and 41, one batch of >= 0.002 s, figure in a temporary directory")
    ap.add_argument("--sizes", type=int, nargs="*", default=[31, 61, 121, 251, 501, 1001])
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--batch", type=float, default=0.15, help="minimum seconds per timed batch")
    ap.add_argument("--threads", default="1", help="BLAS threads (OPENBLAS/OMP/MKL_NUM_THREADS)")
    ap.add_argument("--wall", action="store_true", help="wall-clock time instead of process CPU time")
    ap.add_argument("--figure", default=None, help="figure path (default: OUT/beam_backends.png)")
    return ap.parse_args()


ARGS = _parse() if __name__ == "__main__" else None
if ARGS is not None and ARGS.threads:
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[var] = str(ARGS.threads)

import numpy as np  # noqa: E402  (after the BLAS thread count is set)

from liegroup_int.bench.beam_step import TAB, NullProblem, cantilever, no_monitor, start_state, step_dt  # noqa: E402
from liegroup_int.bench.beam_step import time_steps as _time_steps  # noqa: E402
from liegroup_int.bench.timing import best_of  # noqa: E402
from liegroup_int.integrators import integrate_fixed  # noqa: E402

CLOCK = time.process_time
STAGES = TAB.stages


def problems(n):
    """The cantilever at ``n_ctrl = n`` with the NumPy and the numba backend."""
    return cantilever(n, "numpy"), cantilever(n, "numba")


def time_steps(prob, y, dt, batch_s, repeats, monitor=None):
    """:func:`liegroup_int.bench.beam_step.time_steps` on this script's clock."""
    return _time_steps(prob, y, dt, batch_s, repeats, monitor, CLOCK)


def rel_diff(a, b, y0):
    """``max |a.c - b.c|`` relative to the largest displacement ``max |b.c - y0.c|``."""
    scale = np.max(np.abs(b.c - y0.c))
    return float(np.max(np.abs(a.c - b.c)) / scale) if scale > 0 else 0.0


def time_calls(nb, y, dt, batch_s, repeats):
    """Best CPU time of one call of each problem method the driver uses (numba backend)."""
    u = 1e-3 * dt * nb.increment_rate(0.0, y, nb.zero_increment(y))
    calls = {"action": lambda: nb.action(u, y), "rate": lambda: nb.increment_rate(dt, y, u),
             "angle": lambda: nb.rotation_angle(u)}
    return {name: best_of(f, repeats, batch_s / 3, clock=CLOCK).seconds for name, f in calls.items()}


def subnormals(y):
    return int(sum(np.sum((a != 0) & (np.abs(a) < np.finfo(float).tiny)) for a in y.arrays().values()))


def fit_exponent(n, t):
    return float(np.polyfit(np.log(n), np.log(t), 1)[0])


def measure(n, args):
    """One size: per-step times of the four paths, per-call times and the checks."""
    pb, nb = problems(n)
    if pb.compiled_kernels() is not None or nb.compiled_kernels() is None:
        raise RuntimeError("beam_backends: expected compiled kernels with backend numba only")
    y = start_state(pb)
    dt = step_dt(n)
    t_np, N_np, y_np = time_steps(pb, y, dt, args.batch, args.repeats)
    t_nb, N_nb, y_nb = time_steps(nb, y, dt, args.batch, args.repeats, monitor=no_monitor)
    t_fu, N_fu, y_fu = time_steps(nb, y, dt, args.batch, args.repeats)
    t_dr, _, _ = time_steps(NullProblem(n), None, dt, args.batch, args.repeats)
    row = dict(n=n, numpy=t_np, numba=t_nb, fused=t_fu, driver=t_dr, N_np=N_np, N_nb=N_nb, N_fu=N_fu,
               calls=time_calls(nb, y, dt, args.batch, args.repeats),
               finite=bool(pb.is_finite(y_np) and nb.is_finite(y_nb) and nb.is_finite(y_fu)),
               subnormal=subnormals(y_np) + subnormals(y_nb) + subnormals(y_fu))
    # same trajectory? (c after the fused batch vs generic numba and NumPy runs of the same length)
    _, y_np, _ = integrate_fixed(pb, TAB, (0.0, N_fu * dt), y, dt)
    _, y_nb, _ = integrate_fixed(nb, TAB, (0.0, N_fu * dt), y, dt, monitor=no_monitor)
    row["tip_diff"] = rel_diff(y_np, y_nb, y)
    row["fused_diff"] = rel_diff(y_fu, y_nb, y)
    print(f"#   n={n}: done (steps/batch: numpy {N_np}, numba generic {N_nb}, fused {N_fu})", flush=True)
    return row


def tables(rows) -> None:
    print(markdown(["n_ctrl", "numpy us/step", "numba generic us/step", "numba fused us/step", "speed-up numpy/fused",
                    "numpy/generic", "fused ns/stage/pt", "driver-only us/step"],
                   [[r["n"], f"{r['numpy'] * 1e6:.1f}", f"{r['numba'] * 1e6:.1f}", f"{r['fused'] * 1e6:.1f}",
                     f"{r['numpy'] / r['fused']:.1f}x", f"{r['numpy'] / r['numba']:.1f}x",
                     f"{r['fused'] / (STAGES * r['n']) * 1e9:.0f}", f"{r['driver'] * 1e6:.1f}"] for r in rows]))
    print(f"\nwhere the generic numba step goes (us; per call, then per step = {STAGES} actions + {STAGES} rates "
          f"+ 1 angle):\n")
    out = []
    for r in rows:
        c = r["calls"]
        prob = STAGES * (c["action"] + c["rate"]) + c["angle"]
        out.append([r["n"], f"{c['action'] * 1e6:.2f}", f"{c['rate'] * 1e6:.2f}", f"{c['angle'] * 1e6:.2f}",
                    f"{prob * 1e6:.1f}", f"{r['driver'] * 1e6:.1f}", f"{(prob + r['driver']) * 1e6:.1f}",
                    f"{r['numba'] * 1e6:.1f}"])
    print(markdown(["n_ctrl", "action", "rate", "angle", "problem/step", "driver-only", "sum", "measured"], out))


def exponents(rows) -> None:
    n = np.array([r["n"] for r in rows], float)
    e_nb = fit_exponent(n, [r["numba"] for r in rows])
    e_fu = fit_exponent(n, [r["fused"] for r in rows])
    e_np = fit_exponent(n, [r["numpy"] for r in rows])
    e_net = fit_exponent(n, [r["numba"] - r["driver"] for r in rows])
    print(f"\nfitted exponent of step cost vs n_ctrl ({int(n[0])}..{int(n[-1])}): numba fused {e_fu:.3f}, "
          f"numba generic {e_nb:.3f}, generic minus driver-only {e_net:.3f}, numpy {e_np:.3f}")
    if len(rows) > 2:
        loc = fit_exponent(n[-2:], [r["fused"] for r in rows[-2:]])
        print(f"local exponent of the fused step cost, n_ctrl {int(n[-2])} -> {int(n[-1])}: {loc:.3f}")


def main(args):
    import numba

    global CLOCK
    CLOCK = time.perf_counter if args.wall else time.process_time
    sizes, out = args.sizes, figure_dir(args, "docs/img")
    if args.quick:
        sizes, args.repeats, args.batch = [31, 41], 1, 0.002
    print("# beam backends: cantilever p=4, RKMK4, fixed dt = 0.3e-6 (31/n)^2, smooth deformed start")
    print(f"# python {platform.python_version()}, numpy {np.__version__}, numba {numba.__version__}, "
          f"{platform.machine()}, {os.cpu_count()} cpus, BLAS threads {os.environ.get('OPENBLAS_NUM_THREADS', 'default')}")
    print(f"# load average at start: {os.getloadavg()[0]:.2f} (timings: {'wall' if args.wall else 'process CPU'} "
          f"time, best of {args.repeats} batches >= {args.batch} s)")
    rows = [measure(n, args) for n in sizes]
    print()
    tables(rows)
    if len(rows) > 1:
        exponents(rows)
    print(f"all runs finite: {all(r['finite'] for r in rows)}; subnormal entries in end states: "
          f"{sum(r['subnormal'] for r in rows)}; max difference of c after the fused batch length, relative to the "
          f"displacement: numpy vs numba generic {max(r['tip_diff'] for r in rows):.1e}, "
          f"fused vs generic {max(r['fused_diff'] for r in rows):.1e}")
    print(f"load average at end: {os.getloadavg()[0]:.2f}")
    path = args.figure or str(out / "beam_backends.png")
    figure(rows, path)
    print(f"figure: {path}")
    return rows


def figure(rows, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = np.array([r["n"] for r in rows], float)
    t_np = np.array([r["numpy"] for r in rows]) * 1e6
    t_nb = np.array([r["numba"] for r in rows]) * 1e6
    t_fu = np.array([r["fused"] for r in rows]) * 1e6
    t_dr = np.array([r["driver"] for r in rows]) * 1e6
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(10, 4))
    ax.loglog(n, t_np, "o-", label=f"numpy (slope {fit_exponent(n, t_np):.2f})")
    ax.loglog(n, t_nb, "s-", label=f"numba generic (slope {fit_exponent(n, t_nb):.2f})")
    ax.loglog(n, t_fu, "D-", label=f"numba fused (slope {fit_exponent(n, t_fu):.2f})")
    ax.loglog(n, t_dr, "^--", color="gray", label="driver only (null problem)")
    ax.loglog(n, t_fu[0] * n / n[0], ":", color="k", lw=0.8, label="slope 1")
    ax.set_xlabel("n_ctrl")
    ax.set_ylabel("time per RKMK4 step [us]")
    ax.set_title("cantilever p=4, RKMK4")
    ax.legend(fontsize=8)
    ax2.semilogx(n, t_np / t_fu, "D-", label="numpy / numba fused")
    ax2.semilogx(n, t_np / t_nb, "s-", label="numpy / numba generic")
    ax2.legend(fontsize=8)
    ax2.axhline(20, color="gray", ls=":", lw=0.8)
    ax2.set_xlabel("n_ctrl")
    ax2.set_ylabel("speed-up")
    ax2.set_ylim(bottom=0)
    fig.tight_layout()
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    fig.savefig(path, dpi=120)


if __name__ == "__main__":
    main(ARGS)
