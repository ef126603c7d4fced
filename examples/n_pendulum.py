"""The N-fold 3D pendulum on (TS^2)^N with SE(3)^N acting (Celledoni, Cokaj, Leone, Murari &
Owren, "Lie group integrators for mechanical systems", Int. J. Comput. Math. 2022): RKMK
with fixed and variable steps, and the symplectic RATTLE splitting over a long run.

    python examples/n_pendulum.py [--quick] [--n 2] [--out DIR]

The model is :class:`liegroup_int.problems.NPendulum` (point masses on massless links, a
fixed pivot, gravity). Prints the energy drift and the constraint error of RKMK4 and of the
adaptive RKMK45 pair over 10 s, then RKMK4 against the splitting methods ``strang`` and
``yoshida4`` over 100 s (their energy error stays bounded, RKMK4's drifts), and plots both.
"""

import argparse
from pathlib import Path

import numpy as np

from liegroup_int import integrate
from liegroup_int.problems import NPendulum


def track(pend, y0, T, **kw):
    """``(history (t, |E - E0|, constraint error), stats)`` of one run with 100 outputs."""
    E0 = pend.energy(y0)
    hist = []
    sol = integrate(pend.problem(), y0, (0.0, T), t_eval=np.linspace(0.0, T, 101)[1:],
                    observer=lambda t, y: hist.append((t, abs(pend.energy(y) - E0), float(pend.space.constraint(y)))),
                    **kw)
    return np.array(hist[1:]), sol.stats


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--n", type=int, default=2)
    ap.add_argument("--out", type=Path, default=Path("examples_out"))
    a = ap.parse_args(argv)
    pend = NPendulum(a.n)
    y0 = pend.initial_state()
    T, T_long = (0.5, 10.0) if a.quick else (10.0, 100.0)
    runs, long = {}, {}
    for label, kw in (("rkmk4, dt = 1e-3", dict(method="rkmk4", dt=1e-3)),
                      ("rkmk45, tol = 1e-8", dict(method="rkmk45", rtol=1e-8, atol=1e-8))):
        runs[label] = track(pend, y0, T, **kw)
    for label, kw in (("rkmk4, dt = 0.02", dict(method="rkmk4", dt=0.02)),
                      ("strang, dt = 0.01", dict(method="strang", dt=0.01)),
                      ("yoshida4, dt = 0.02", dict(method="yoshida4", dt=0.02))):
        long[label] = track(pend, y0, T_long, **kw)
    E0 = pend.energy(y0)
    for label, (h, stats) in {**runs, **long}.items():
        print(f"{label} over {h[-1, 0]:g} s: {stats.steps} steps; energy drift {h[:, 1].max():.2e} J "
              f"(E0 = {E0:.3f} J), constraints {h[:, 2].max():.1e}")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 3.8))
    for ax, group, title in ((axes[0], runs, f"T = {T:g} s"), (axes[1], long, f"T = {T_long:g} s: symplectic")):
        for label, (h, _) in group.items():
            ax.semilogy(h[:, 0], np.maximum(h[:, 1], 1e-17), label=label)
        ax.set_xlabel("t [s]")
        ax.set_ylabel("|E(t) - E(0)| [J]")
        ax.set_title(f"{a.n}-fold 3D pendulum on (TS^2)^{a.n}, {title}", fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    a.out.mkdir(parents=True, exist_ok=True)
    path = a.out / "n_pendulum.png"
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")
    return runs, long


if __name__ == "__main__":
    main()
