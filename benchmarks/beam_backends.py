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
    python benchmarks/beam_backends.py --quick          # 31 and 121 only, no figure
    python benchmarks/beam_backends.py --what-if-combine
        # also time numba with the driver's increment combination done by ``@``
        # instead of np.tensordot (used only if bitwise identical), to show how much
        # of the step the generic driver costs; the library itself is not changed

"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time


def _parse():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="*", default=[31, 61, 121, 251, 501, 1001])
    ap.add_argument("--quick", action="store_true", help="sizes 31 and 121, no figure")
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--batch", type=float, default=0.15, help="minimum seconds per timed batch")
    ap.add_argument("--threads", default="1", help="BLAS threads (OPENBLAS/OMP/MKL_NUM_THREADS)")
    ap.add_argument("--what-if-combine", action="store_true")
    ap.add_argument("--wall", action="store_true", help="wall-clock time instead of process CPU time")
    ap.add_argument("--figure", default="docs/img/beam_backends.png")
    return ap.parse_args()


ARGS = _parse() if __name__ == "__main__" else None
if ARGS is not None and ARGS.threads:
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[var] = str(ARGS.threads)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
if ROOT not in sys.path:
    sys.path.insert(0, ROOT)

import numpy as np  # noqa: E402

from liegroup_int.integrators import integrate_fixed, resolve_method  # noqa: E402
from liegroup_int.integrators.engine import compiled_stepper  # noqa: E402
from liegroup_int.problems.beam import BeamProblem  # noqa: E402
from liegroup_int.scenes import load_scene  # noqa: E402
from liegroup_int.scenes.beam import problem as scene_problem  # noqa: E402

TAB = resolve_method("rkmk4")
CLOCK = time.process_time
STAGES = TAB.stages


class NullProblem:
    """The driver's own cost: increments of the beam's shape, no work."""

    def __init__(self, n):
        self.n = n

    def action(self, u, y):
        return y

    def end_step(self, y):
        return y

    def increment_rate(self, t, y, u):
        return np.zeros((4, self.n, 3))

    def zero_increment(self, y):
        return np.zeros((4, self.n, 3))

    def rotation_angle(self, u):
        return 0.0


def problems(n):
    # the scene default is backend="numba": ask for NumPy explicitly
    pb = scene_problem(load_scene("cantilever", {"space.n_ctrl": n, "space.degree": 4,
                                                 "integrator.backend": "numpy"}))
    nb = BeamProblem(pb.space, pb.constants, pb.bcs, pb.loads, pb.initial, backend="numba")
    return pb, nb


def start_state(pb):
    """Smooth deformed, moving state (see the module docstring)."""
    s = np.asarray(pb.space.curve.greville())
    u = np.zeros((4, pb.n, 3))
    u[0, :, 1], u[0, :, 2] = 5e-4 * s**3, 1e-3 * s**2
    u[1, :, 1], u[1, :, 2] = 1e-2 * s**2, 5e-3 * s**3
    u[2, :, 2] = 1e-2 * s**2
    u[3, :, 1] = 1e-2 * s**2
    return pb.action(u, pb.initial_state())


def no_monitor(t, y, stats):
    """A per-step monitor that does nothing: keeps the driver on its generic loop."""


def time_steps(prob, y, dt, batch_s, repeats, monitor=None):
    """Best per-step seconds over ``repeats`` batches of ``N`` steps, and the end state."""
    integrate_fixed(prob, TAB, (0.0, 2 * dt), y, dt, monitor=monitor)  # warm-up (JIT, caches)
    t0 = CLOCK()
    integrate_fixed(prob, TAB, (0.0, 10 * dt), y, dt, monitor=monitor)
    est = max((CLOCK() - t0) / 10, 1e-7)
    N = max(3, int(np.ceil(batch_s / est)))
    best, y_end = np.inf, None
    for _ in range(repeats):
        t0 = CLOCK()
        _, y_end, _ = integrate_fixed(prob, TAB, (0.0, N * dt), y, dt, monitor=monitor)
        best = min(best, (CLOCK() - t0) / N)
    return best, N, y_end


def rel_diff(a, b, y0):
    """``max |a.c - b.c|`` relative to the largest displacement ``max |b.c - y0.c|``."""
    scale = np.max(np.abs(b.c - y0.c))
    return float(np.max(np.abs(a.c - b.c)) / scale) if scale > 0 else 0.0


def time_calls(nb, y, dt, batch_s, repeats):
    """Best CPU time of one call of each problem method the driver uses (numba backend)."""
    u = 1e-3 * dt * nb.increment_rate(0.0, y, nb.zero_increment(y))
    calls = {"action": lambda: nb.action(u, y), "rate": lambda: nb.increment_rate(dt, y, u),
             "angle": lambda: nb.rotation_angle(u)}
    out = {}
    for name, f in calls.items():
        f()
        t0 = CLOCK()
        for _ in range(20):
            f()
        est = max((CLOCK() - t0) / 20, 1e-8)
        N = max(5, int(np.ceil(batch_s / 3 / est)))
        best = np.inf
        for _ in range(repeats):
            t0 = CLOCK()
            for _ in range(N):
                f()
            best = min(best, (CLOCK() - t0) / N)
        out[name] = best
    return out


def subnormals(y):
    return int(sum(np.sum((a != 0) & (np.abs(a) < np.finfo(float).tiny)) for a in y.arrays().values()))


def fit_exponent(n, t):
    return float(np.polyfit(np.log(n), np.log(t), 1)[0])


def main(args):
    import numba

    global CLOCK
    CLOCK = time.perf_counter if args.wall else time.process_time
    sizes = [31, 121] if args.quick else args.sizes
    print("# beam backends: cantilever p=4, RKMK4, fixed dt = 0.3e-6 (31/n)^2, smooth deformed start")
    print(f"# python {platform.python_version()}, numpy {np.__version__}, numba {numba.__version__}, "
          f"{platform.machine()}, {os.cpu_count()} cpus, BLAS threads {os.environ.get('OPENBLAS_NUM_THREADS', 'default')}")
    print(f"# load average at start: {os.getloadavg()[0]:.2f} (timings: {'wall' if args.wall else 'process CPU'} "
          f"time, best of {args.repeats} batches >= {args.batch} s)")
    rows = []
    for n in sizes:
        pb, nb = problems(n)
        y = start_state(pb)
        dt = 0.3e-6 * (31.0 / n) ** 2
        assert compiled_stepper(nb, TAB) is not None and compiled_stepper(pb, TAB) is None
        t_np, N_np, y_np = time_steps(pb, y, dt, args.batch, args.repeats)
        t_nb, N_nb, y_nb = time_steps(nb, y, dt, args.batch, args.repeats, monitor=no_monitor)
        t_fu, N_fu, y_fu = time_steps(nb, y, dt, args.batch, args.repeats)
        t_dr, _, _ = time_steps(NullProblem(n), None, dt, args.batch, args.repeats)
        calls = time_calls(nb, y, dt, args.batch, args.repeats)
        row = dict(n=n, numpy=t_np, numba=t_nb, fused=t_fu, driver=t_dr, N_np=N_np, N_nb=N_nb, N_fu=N_fu,
                   calls=calls, solver=nb._nb.solver,
                   finite=bool(pb.is_finite(y_np) and nb.is_finite(y_nb) and nb.is_finite(y_fu)),
                   subnormal=subnormals(y_np) + subnormals(y_nb) + subnormals(y_fu))
        # same trajectory? (c after the fused batch vs generic numba and NumPy runs of the same length)
        _, y_np, _ = integrate_fixed(pb, TAB, (0.0, N_fu * dt), y, dt)
        _, y_nb, _ = integrate_fixed(nb, TAB, (0.0, N_fu * dt), y, dt, monitor=no_monitor)
        row["tip_diff"] = rel_diff(y_np, y_nb, y)
        row["fused_diff"] = rel_diff(y_fu, y_nb, y)
        if args.what_if_combine:
            row["numba_mm"] = time_with_matmul_combine(nb, y, dt, args)
        rows.append(row)
        print(f"#   n={n}: done (steps/batch: numpy {N_np}, numba generic {N_nb}, fused {N_fu})", flush=True)

    head = (f"{'n_ctrl':>6} | {'numpy us/step':>13} | {'numba generic us/step':>21} | "
            f"{'numba fused us/step':>19} | {'speed-up numpy/fused':>20} | {'numpy/generic':>13} | "
            f"{'fused ns/stage/pt':>17} | {'driver-only us/step':>19}")
    if args.what_if_combine:
        head += f" | {'numba, matmul combine':>21} | {'speed-up':>8}"
    print()
    print(head)
    print("-" * len(head))
    for r in rows:
        line = (f"{r['n']:>6} | {r['numpy'] * 1e6:>13.1f} | {r['numba'] * 1e6:>21.1f} | "
                f"{r['fused'] * 1e6:>19.1f} | {r['numpy'] / r['fused']:>19.1f}x | "
                f"{r['numpy'] / r['numba']:>12.1f}x | {r['fused'] / (STAGES * r['n']) * 1e9:>17.0f} | "
                f"{r['driver'] * 1e6:>19.1f}")
        if args.what_if_combine:
            line += f" | {r['numba_mm'] * 1e6:>21.1f} | {r['numpy'] / r['numba_mm']:>7.1f}x"
        print(line)
    print(f"\nwhere the generic numba step goes (us; per call, then per step = {STAGES} actions + {STAGES} rates + 1 angle):")
    head2 = (f"{'n_ctrl':>6} | {'action':>7} | {'rate':>7} | {'angle':>6} | {'problem/step':>12} | "
             f"{'driver-only':>11} | {'sum':>7} | {'measured':>8}")
    print(head2)
    print("-" * len(head2))
    for r in rows:
        c = r["calls"]
        prob = STAGES * (c["action"] + c["rate"]) + c["angle"]
        print(f"{r['n']:>6} | {c['action'] * 1e6:>7.2f} | {c['rate'] * 1e6:>7.2f} | {c['angle'] * 1e6:>6.2f} | "
              f"{prob * 1e6:>12.1f} | {r['driver'] * 1e6:>11.1f} | {(prob + r['driver']) * 1e6:>7.1f} | "
              f"{r['numba'] * 1e6:>8.1f}")
    n = np.array([r["n"] for r in rows], float)
    if len(rows) > 1:
        e_nb = fit_exponent(n, [r["numba"] for r in rows])
        e_fu = fit_exponent(n, [r["fused"] for r in rows])
        e_np = fit_exponent(n, [r["numpy"] for r in rows])
        e_net = fit_exponent(n, [r["numba"] - r["driver"] for r in rows])
        print(f"\nfitted exponent of step cost vs n_ctrl ({int(n[0])}..{int(n[-1])}): numba fused {e_fu:.3f}, "
              f"numba generic {e_nb:.3f}, generic minus driver-only {e_net:.3f}, numpy {e_np:.3f}")
        if len(rows) > 2:
            loc = fit_exponent(n[-2:], [r["fused"] for r in rows[-2:]])
            print(f"local exponent of the fused step cost, n_ctrl {int(n[-2])} -> {int(n[-1])}: {loc:.3f}")
    print(f"M_c solver: {', '.join(sorted({r['solver'] for r in rows}))}; all runs finite: "
          f"{all(r['finite'] for r in rows)}; subnormal entries in end states: {sum(r['subnormal'] for r in rows)}; "
          f"max difference of c after the fused batch length, relative to the displacement: "
          f"numpy vs numba generic {max(r['tip_diff'] for r in rows):.1e}, "
          f"fused vs generic {max(r['fused_diff'] for r in rows):.1e}")
    print(f"load average at end: {os.getloadavg()[0]:.2f}")
    if not args.quick and args.figure:
        figure(rows, args.figure)
        print(f"figure: {args.figure}")
    return rows


def _matmul_combine(weights, K, h, total=None):
    """``rkmk.combine`` with ``np.tensordot`` replaced by ``@`` on 2-D views."""
    m = weights.shape[0]
    if total is None or m == 1:
        return (h * (weights @ K[:m].reshape(m, -1))).reshape(K.shape[1:])
    d = (K[1:m] - K[0]).reshape(m - 1, -1)
    return h * (total * K[0] + (weights[1:] @ d).reshape(K.shape[1:]))


def time_with_matmul_combine(nb, y, dt, args):
    """What-if: the driver's ``combine`` computed with ``@`` instead of ``np.tensordot``.

    Used only if it reproduces the library's ``combine`` bit for bit on every call the
    RKMK4 step makes (checked here); the library is restored afterwards. NaN otherwise.
    """
    import liegroup_int.integrators.rkmk as rkmk

    rng = np.random.default_rng(0)
    K = rng.standard_normal((TAB.stages, 4, nb.n, 3))
    calls = [(TAB.A_f[r, :r], TAB.c_f[r]) for r in range(1, TAB.stages)] + [(TAB.b_f, 1.0), (TAB.b_f, None)]
    for w, tot in calls:
        if not np.array_equal(_matmul_combine(w, K, 1e-3, tot), rkmk.combine(w, K, 1e-3, tot)):
            print("#   what-if combine differs from rkmk.combine: skipped")
            return float("nan")
    original = rkmk.combine
    rkmk.combine = _matmul_combine
    try:
        return time_steps(nb, y, dt, args.batch, args.repeats, monitor=no_monitor)[0]
    finally:
        rkmk.combine = original


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
    os.makedirs(os.path.dirname(os.path.join(ROOT, path)), exist_ok=True)
    fig.savefig(os.path.join(ROOT, path), dpi=120)


if __name__ == "__main__":
    main(ARGS)
