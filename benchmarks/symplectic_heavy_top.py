"""Symplectic splittings against RKMK and DOP853 on the heavy top: long-time energy and work-precision.

    python benchmarks/symplectic_heavy_top.py [--quick] [--out DIR]

The heavy top of ``examples/heavy_top.py`` (I = (1, 1, 0.5), m = 1, chi = (0, 0, 0.5), g =
9.81), tilted by 0.3 rad, spinning at 10 rad/s. Two tables and a figure:

* long run (10^4 s, about 16,000 spin periods, dt = 0.02): CPU, largest energy error, its
  fitted drift over the run, and the drift of the vertical angular momentum, for the
  splittings ``strang``, ``yoshida4``, ``yoshida6`` and RKMK4 / RKMK6 at the same step;
* work-precision at t = 10 s: the error of the state against RKMK6 at dt = 1e-4 over CPU
  time, every method on a ladder of steps, with scipy's DOP853 on the flattened ODE
  (rtol 1e-4 ... 1e-12) for comparison;
* long-time work-precision over 10^3 s (about 1,600 spin periods): the largest energy error
  over the run (200 outputs) against CPU time, the same ladders.

``symplectic_heavy_top.png``: the energy error over the long run, and both work-precisions.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from liegroup_int import integrate
from liegroup_int.bench.table import figure_dir, markdown, parser
from liegroup_int.groups import SO3
from liegroup_int.problems import RigidBody

TOP = RigidBody(inertia=(1.0, 1.0, 0.5), mass=1.0, com=(0.0, 0.0, 0.5))
Y0 = TOP.state(SO3.exp(np.array([0.3, 0.0, 0.0])), np.array([0.0, 0.5, 10.0]))
METHODS = ("strang", "yoshida4", "yoshida6", "rkmk4", "rkmk6")


def long_run(method: str, T: float, dt: float, outputs: int) -> dict:
    pb = TOP.problem()
    integrate(pb, Y0, (0.0, 10 * dt), method=method, dt=dt)  # compile
    c = time.process_time()
    sol = integrate(pb, Y0, (0.0, T), method=method, dt=dt, t_eval=np.linspace(0.0, T, outputs + 1))
    cpu = time.process_time() - c
    e = np.array([TOP.energy(y) for y in sol.y]) - TOP.energy(Y0)
    h = np.array([TOP.casimir(y) for y in sol.y])
    return {"t": sol.t, "e": e, "cpu": cpu, "max": np.max(np.abs(e)), "drift": np.polyfit(sol.t, e, 1)[0] * T,
            "casimir": np.max(np.abs(h - h[0]))}


def _dop853(rtol: float, T: float, t_eval=None) -> tuple[float, np.ndarray]:
    """CPU and the states (``(12,)`` at ``T``, or ``(12, k)`` at ``t_eval``) of DOP853."""
    from scipy.integrate import solve_ivp

    def f(t, x):
        R, W = x[:9].reshape(3, 3), x[9:]
        xi = TOP.vector_field(t, np.concatenate([R.ravel(), W]))
        return np.concatenate([(SO3.hat(xi[:3]) @ R).ravel(), xi[3:]])

    c = time.process_time()
    y = solve_ivp(f, (0.0, T), Y0, method="DOP853", rtol=rtol, atol=1e-3 * rtol, t_eval=t_eval).y
    return time.process_time() - c, (y[:, -1] if t_eval is None else y)


def long_work_precision(T: float, dts, rtols, outputs: int = 200) -> list[tuple[str, float, float, float]]:
    """``(method, dt or rtol, CPU, max |dE| over the run)`` over ``[0, T]``."""
    out = [(m, dt, r["cpu"], r["max"]) for m in METHODS for dt in dts
           for r in (long_run(m, T, dt, outputs),)]
    t_eval = np.linspace(0.0, T, outputs + 1)
    for rtol in rtols:
        cpu, ys = _dop853(rtol, T, t_eval)
        e = np.array([TOP.energy(y) for y in ys.T]) - TOP.energy(Y0)
        out.append(("DOP853", rtol, cpu, float(np.max(np.abs(e)))))
    return out


def work_precision(T: float, dts, rtols) -> list[tuple[str, float, float]]:
    pb = TOP.problem()
    ref = integrate(pb, Y0, (0.0, T), method="rkmk6", dt=1e-4).y_final
    out = []
    for m in METHODS:
        for dt in dts:
            integrate(pb, Y0, (0.0, 2 * dt), method=m, dt=dt)
            c = time.process_time()
            y = integrate(pb, Y0, (0.0, T), method=m, dt=dt).y_final
            out.append((m, time.process_time() - c, float(np.max(np.abs(y - ref)))))
    for rtol in rtols:
        cpu, y = _dop853(rtol, T)
        out.append(("DOP853", cpu, float(np.max(np.abs(y - ref)))))
    return out


def _plot(runs: dict, wp, lwp, T_long: float, path: Path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax, bx, cx) = plt.subplots(1, 3, figsize=(16, 4.2))
    for m, r in runs.items():
        ax.semilogy(r["t"], np.maximum(np.abs(r["e"]), 1e-17), lw=0.8, label=m)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("|E(t) - E(0)| [J]")
    ax.set_title("heavy top, dt = 0.02: energy error", fontsize=9)
    ax.legend(fontsize=7)
    for m in (*METHODS, "DOP853"):
        pts = sorted((c, e) for name, c, e in wp if name == m)
        if pts:
            bx.loglog([p[0] for p in pts], [p[1] for p in pts], marker="o", label=m)
    bx.set_xlabel("CPU [s]")
    bx.set_ylabel("max |y(10) - y_ref(10)|")
    bx.set_title("work-precision at t = 10 s", fontsize=9)
    bx.legend(fontsize=7)
    for m in (*METHODS, "DOP853"):
        pts = sorted((c, e) for name, _, c, e in lwp if name == m)
        if pts:
            cx.loglog([p[0] for p in pts], [p[1] for p in pts], marker="o", label=m)
    cx.set_xlabel("CPU [s]")
    cx.set_ylabel("max |E(t) - E(0)| over the run [J]")
    cx.set_title(f"long-time work-precision over {T_long:g} s", fontsize=9)
    cx.legend(fontsize=7)
    for a in (ax, bx, cx):
        a.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def main(argv=None) -> None:
    ap = parser(__doc__)
    args = ap.parse_args(argv)
    T, dts, rtols, T_wp = (1e4, (0.04, 0.02, 0.01, 0.005), (1e-4, 1e-6, 1e-8, 1e-10, 1e-12), 10.0)
    T_long, long_rtols, long_outputs = 1e3, (1e-6, 1e-8, 1e-10), 200  # outputs 5 s apart: whole steps
    if args.quick:
        T, dts, rtols, T_wp = 50.0, (0.04, 0.02), (1e-6, 1e-9), 1.0
        T_long, long_rtols, long_outputs = 5.0, (1e-6,), 25
    runs = {m: long_run(m, T, 0.02, 400 if T % 50.0 == 0 and T >= 1e3 else 250) for m in METHODS}
    print(f"Long run: heavy top over {T:g} s at dt = 0.02 ({int(T / 0.02)} steps)\n")
    print(markdown(["method", "CPU [s]", "max |dE| [J]", "fitted drift over the run [J]", "drift / max",
                    "vertical angular momentum drift"],
                   [[m, f"{r['cpu']:.3g}", f"{r['max']:.2e}", f"{r['drift']:.2e}", f"{abs(r['drift']) / r['max']:.3f}",
                     f"{r['casimir']:.1e}"] for m, r in runs.items()]))
    wp = work_precision(T_wp, dts, rtols)
    print(f"\nWork-precision at t = {T_wp:g} s (error against RKMK6 at dt = 1e-4)\n")
    print(markdown(["method", "CPU [s]", "max error"], [[m, f"{c:.3g}", f"{e:.2e}"] for m, c, e in wp]))
    lwp = long_work_precision(T_long, dts, long_rtols, long_outputs)
    print(f"\nLong-time work-precision over {T_long:g} s (largest energy error over the run, {long_outputs} "
          "outputs)\n")
    print(markdown(["method", "dt / rtol", "CPU [s]", "max |dE| [J]"],
                   [[m, f"{p:g}", f"{c:.3g}", f"{e:.2e}"] for m, p, c, e in lwp]))
    out = figure_dir(args, Path("docs/img"))
    print(f"\n-> {_plot(runs, wp, lwp, T_long, out / 'symplectic_heavy_top.png')}")


if __name__ == "__main__":
    main()
