"""Per-step cost of adaptive runs: generic Python loop vs fused compiled loop.

Built-in scenes (numba backend, scene discretization), embedded pair and tolerance as
given, ``atol = 1e-3 rtol``, steps capped by the method's stable step (spectral radius
at the initial state, ``stable_step``). Process CPU time of the whole
``integrate_adaptive`` call after a warm-up run, best of ``--repeats``; the generic loop
is forced by a no-op monitor.

    PYTHONPATH=. python benchmarks/adaptive_fused.py --scenes cantilever pendulum --method rkmk65 --rtol 1e-7
"""

import argparse
import time

from liegroup_int.integrators import integrate_adaptive, resolve_method, spectral_radius, stable_step
from liegroup_int.scenes import load_scene
from liegroup_int.scenes.beam import problem


def noop(t, y, stats):
    pass


def timed(pb, tab, y0, T, rtol, h_max, fused, repeats):
    best, stats = float("inf"), None
    for _ in range(repeats):
        c0 = time.process_time()
        _, _, stats = integrate_adaptive(pb, tab, (0.0, T), y0, rtol=rtol, atol=1e-3 * rtol, h_max=h_max,
                                         monitor=None if fused else noop)
        best = min(best, time.process_time() - c0)
    return best, stats


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--scenes", nargs="+", default=["cantilever", "pendulum"])
    ap.add_argument("--method", default="rkmk65")
    ap.add_argument("--rtol", type=float, default=1e-7)
    ap.add_argument("--steps", type=int, default=2000, help="nominal steps of h_max in the span")
    ap.add_argument("--repeats", type=int, default=3)
    a = ap.parse_args()
    tab = resolve_method(a.method)
    print("| scene | n_ctrl | h_max (stable) | span | steps | rejected | generic us/step | fused us/step | speed-up |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name in a.scenes:
        pb = problem(load_scene(name, {"integrator.backend": "numba"}))
        y0 = pb.initial_state()
        h_max = stable_step(tab, spectral_radius(pb, 0.0, y0), 1.0).dt
        T = a.steps * h_max
        for fused in (True, False):  # warm-up (compile / cache load)
            integrate_adaptive(pb, tab, (0.0, 5 * h_max), y0, rtol=a.rtol, atol=1e-3 * a.rtol, h_max=h_max,
                               monitor=None if fused else noop)
        tg, sg = timed(pb, tab, y0, T, a.rtol, h_max, False, a.repeats)
        tf, sf = timed(pb, tab, y0, T, a.rtol, h_max, True, a.repeats)
        print(f"| {name} | {pb.n} | {h_max:.3g} | {T:.3g} | {sf.steps} ({sg.steps}) | {sf.rejected} ({sg.rejected}) "
              f"| {1e6 * tg / sg.steps:.1f} | {1e6 * tf / sf.steps:.1f} | {tg / sg.steps / (tf / sf.steps):.2f}x |",
              flush=True)


if __name__ == "__main__":
    main()
