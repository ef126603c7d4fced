"""Per-step cost of adaptive runs: generic Python loop vs fused compiled loop.

Built-in scenes (numba backend, scene discretization), embedded pair and tolerance as
given, ``atol = 1e-3 rtol``, steps capped by the method's stable step (spectral radius
at the initial state, ``stable_step``). Process CPU time of the whole
``integrate_adaptive`` call after a warm-up run, best of ``--repeats``; the generic loop
is forced by a no-op monitor.

    python benchmarks/adaptive_fused.py --scenes cantilever pendulum --method rkmk65 --rtol 1e-7
    python benchmarks/adaptive_fused.py --quick
"""

from liegroup_int.bench.table import markdown, parser
from liegroup_int.bench.timing import best_of
from liegroup_int.integrators import integrate_adaptive, resolve_method, spectral_radius, stable_step
from liegroup_int.scenes import load_scene
from liegroup_int.scenes.beam import problem


def noop(t, y, stats):
    pass


def timed(pb, tab, y0, T, rtol, h_max, fused, repeats):
    """Best CPU seconds of one adaptive run over ``[0, T]`` and its statistics."""
    t = best_of(lambda: integrate_adaptive(pb, tab, (0.0, T), y0, rtol=rtol, atol=1e-3 * rtol, h_max=h_max,
                                           monitor=None if fused else noop), repeats)
    return t.seconds, t.result[2]


def row(name, tab, rtol, steps, repeats, overrides):
    pb = problem(load_scene(name, {"integrator.backend": "numba", **overrides}))
    y0 = pb.initial_state()
    h_max = stable_step(tab, spectral_radius(pb, 0.0, y0), 1.0).dt
    T = steps * h_max
    tg, sg = timed(pb, tab, y0, T, rtol, h_max, False, repeats)
    tf, sf = timed(pb, tab, y0, T, rtol, h_max, True, repeats)
    return [name, pb.n, f"{h_max:.3g}", f"{T:.3g}", f"{sf.steps} ({sg.steps})", f"{sf.rejected} ({sg.rejected})",
            f"{1e6 * tg / sg.steps:.1f}", f"{1e6 * tf / sf.steps:.1f}", f"{tg / sg.steps / (tf / sf.steps):.2f}x"]


def main(argv=None):
    ap = parser(__doc__)
    ap.add_argument("--scenes", nargs="+", default=["cantilever", "pendulum"])
    ap.add_argument("--method", default="rkmk65")
    ap.add_argument("--rtol", type=float, default=1e-7)
    ap.add_argument("--steps", type=int, default=2000, help="nominal steps of h_max in the span")
    ap.add_argument("--repeats", type=int, default=3)
    a = ap.parse_args(argv)
    steps, repeats, overrides = (a.steps, a.repeats, {}) if not a.quick else (50, 1, {"space.n_ctrl": 11})
    tab = resolve_method(a.method)
    rows = [row(name, tab, a.rtol, steps, repeats, overrides) for name in a.scenes]
    print(markdown(["scene", "n_ctrl", "h_max (stable)", "span", "steps", "rejected", "generic us/step",
                    "fused us/step", "speed-up"], rows))


if __name__ == "__main__":
    main()
