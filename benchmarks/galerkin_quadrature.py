"""Quadrature rules of the Galerkin beam's stiffness: rank, spectrum, accuracy, energy, cost.

    python benchmarks/galerkin_quadrature.py [--quick] [--rules gauss greville ...]

For each rule of ``space.quadrature`` (liegroup_int.iga.quadrature.RULES):

1. **Rank and spectrum at rest** (``cantilever``, unloaded, undamped, p = 4, 3 and 2,
   n_ctrl = 11, 21, 41): the number of points ``m``; the null space of the strain-energy
   Hessian over all ``(eta, Theta)`` control values (``problems.beam.galerkin_linear``; a free beam has 6 rigid modes, more are zero-energy
   "hourglass" modes); the largest ``Re lambda / |lambda|max`` and ``|lambda|max`` of the
   dense spectrum of the linearized increment map (central differences of the stage rate).
2. **Accuracy.** Relative errors of the first four distinct natural frequencies (the
   generalized eigenproblem of that Hessian and the consistent masses) against the
   ``gauss`` rule at p = 6, n_ctrl = 61 (whose own error is printed against p = 6,
   n_ctrl = 81), and their log-log slope against the knot span.
3. **Energy.** The ``pendulum`` (p = 4, n_ctrl = 31, undamped) over 0.2 s, RKMK4 at
   ``|lambda| h = 2``: largest energy drift, and the tip position at 0.2 s against the
   ``gauss`` rule at n_ctrl = 61 and ``|lambda| h = 0.5``. Then the tip at 0.2 s at
   ``|lambda| h = 0.5`` for n_ctrl = 11, 21, 41 against the gauss rule at n_ctrl = 81
   (space convergence), and the in-plane spectrum of the ``rollup`` beam in its static
   half and full circle (n_ctrl = 21): zero eigenvalues (compare with ``gauss``: the
   clamp's) and the largest real part.
4. **Cost.** CPU per RKMK4 step in the compiled engine (numba, pendulum, p = 4), median of
   three runs, for primal collocation and every rule in the same run; and CPU per
   simulated second at ``|lambda| h = 2.26`` (the stable step follows ``|lambda|max``).
   A straight-line fit of the Galerkin CPU per step against the number of points splits
   it into the point loop and the rest (banded solves, per control value work).
"""

from __future__ import annotations

import statistics
import time

import numpy as np

from liegroup_int.integrators import eigenvalues, integrate_fixed, jacobian, resolve_method, spectral_radius
from liegroup_int.bench.table import parser
from liegroup_int.iga.quadrature import RULES
from liegroup_int.problems.beam.galerkin_linear import distinct_frequencies, energy_nullity, natural_frequencies
from liegroup_int.scenes import load_scene
from liegroup_int.scenes.beam import problem
from liegroup_int.scenes.schema import SceneError

AT_REST = {"material.kelvin_voigt": 0.0, "loads.end.force": [0.0, 0.0, 0.0]}


def galerkin(scene: str, rule: str, p: int, n: int, backend: str = "numba", **extra):
    return problem(load_scene(scene, {"space.formulation": "galerkin", "space.quadrature": rule,
                                      "space.degree": p, "space.n_ctrl": n, "integrator.backend": backend,
                                      **extra}))


def spectrum_table(rules, degrees, sizes, ref: np.ndarray) -> None:
    print("| rule | p | n_ctrl | points m | energy nullity (6 rigid) | sigma_min/sigma_max | max Re/abs(lambda)max "
          "| abs(lambda)max [1/s] | ratio to gauss | rel. error of omega_1..4 |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    slopes = {}
    for p in degrees:
        lam_gauss = {}
        for rule in rules:
            errs = []
            for n in sizes:
                try:
                    pb = galerkin("cantilever", rule, p, n, **AT_REST)
                except SceneError as exc:
                    print(f"| {rule} | {p} | {n} | rejected: {str(exc).split(': ', 1)[1]} |||||||")
                    errs.append([np.nan] * 4)
                    continue
                null, smin = energy_nullity(pb)
                ev = eigenvalues(pb, 0.0, pb.initial_state())
                lam = float(np.max(np.abs(ev)))
                if rule == "gauss":
                    lam_gauss[n] = lam
                err = np.abs(distinct_frequencies(natural_frequencies(pb), 4) / ref - 1.0)
                errs.append(err)
                ratio = f"{lam / lam_gauss[n]:.3f}" if n in lam_gauss else "-"  # gauss not run
                print(f"| {rule} | {p} | {n} | {pb.m} | {null} | {smin:.1e} | {ev.real.max() / lam:.1e} | {lam:.4g} "
                      f"| {ratio} | {' '.join(f'{e:.1e}' for e in err)} |", flush=True)
            h = np.log(1.0 / (np.array(sizes) - p))
            if np.all(np.isfinite(errs)):
                slopes[(rule, p)] = [np.polyfit(h, np.log(np.array(errs)[:, j]), 1)[0] for j in range(4)]
    print("\n| rule | p | log-log slope of omega_1..4 errors vs knot span (n_ctrl " + ", ".join(map(str, sizes)) + ") |")
    print("|---|---|---|")
    for (rule, p), s in slopes.items():
        print(f"| {rule} | {p} | {' '.join(f'{x:.2f}' for x in s)} |")


def reference_frequencies(refs=(61, 81)) -> np.ndarray:
    ref = distinct_frequencies(natural_frequencies(galerkin("cantilever", "gauss", 6, refs[0], **AT_REST)), 4)
    fine = distinct_frequencies(natural_frequencies(galerkin("cantilever", "gauss", 6, refs[1], **AT_REST)), 4)
    print(f"reference omega_1..4 (gauss, p = 6, n_ctrl = {refs[0]}): {' '.join(f'{w:.7g}' for w in ref)} rad/s; "
          f"relative change to n_ctrl = {refs[1]}: {' '.join(f'{e:.1e}' for e in np.abs(fine / ref - 1))}\n")
    return ref


def run_pendulum(pb, y0, lam: float, gamma: float, t_end: float = 0.2):
    rec = []
    y = integrate_fixed(pb, resolve_method("rkmk4"), (0.0, t_end), y0, gamma / lam,
                        observer=lambda t, y: rec.append((pb.energy(y, t), pb.energy_parts(y, t)["kinetic"])),
                        t_out=np.linspace(0.0, t_end, 21)[1:])[1]
    rec = np.array(rec)
    return y, float(np.max(np.abs(rec[:, 0] - pb.energy(y0)))), float(rec[:, 1].max())


def energy_table(rules, refs=(61, 81), t_end=0.2, n=31) -> None:
    ref_pb = galerkin("pendulum", "gauss", 4, refs[0], **{"material.kelvin_voigt": 0.0})
    y0 = ref_pb.initial_state()
    yr = run_pendulum(ref_pb, y0, spectral_radius(ref_pb, 0.0, y0), 0.5, t_end)[0]
    ref_pb2 = galerkin("pendulum", "gauss", 4, refs[1], **{"material.kelvin_voigt": 0.0})
    y02 = ref_pb2.initial_state()
    yr2 = run_pendulum(ref_pb2, y02, spectral_radius(ref_pb2, 0.0, y02), 0.5, t_end)[0]
    tip_ref = ref_pb.tip(yr)
    print(f"pendulum tip at {t_end:g} s (gauss, n_ctrl = {refs[0]}, |lambda| h = 0.5): {tip_ref}; "
          f"change to n_ctrl = {refs[1]}: {np.linalg.norm(ref_pb2.tip(yr2) - tip_ref):.1e} m\n")
    print(f"| rule | n_ctrl | energy drift over {t_end:g} s [J] | largest kinetic energy [J] | tip error at {t_end:g} s [m] |")
    print("|---|---|---|---|---|")
    for rule in rules:
        pb = galerkin("pendulum", rule, 4, n, **{"material.kelvin_voigt": 0.0})
        y0 = pb.initial_state()
        y, drift, kin = run_pendulum(pb, y0, spectral_radius(pb, 0.0, y0), 2.0, t_end)
        print(f"| {rule} | {n} | {drift:.1e} | {kin:.4g} | {np.linalg.norm(pb.tip(y) - tip_ref):.1e} |",
              flush=True)


def tip_table(rules, sizes, refs=(81, 61), t_end=0.2) -> None:
    """Pendulum (p = 4, undamped) tip at 0.2 s, RKMK4 at |lambda| h = 0.5, against the gauss
    rule at n_ctrl = 81: space convergence."""
    def tip(rule, n):
        pb = galerkin("pendulum", rule, 4, n, **{"material.kelvin_voigt": 0.0})
        y0 = pb.initial_state()
        return pb.tip(run_pendulum(pb, y0, spectral_radius(pb, 0.0, y0), 0.5, t_end)[0])

    ref = tip("gauss", refs[0])
    print(f"pendulum tip at {t_end:g} s, reference (gauss, n_ctrl = {refs[0]}, |lambda| h = 0.5): {ref}; "
          f"difference to n_ctrl = {refs[1]}: {np.linalg.norm(tip('gauss', refs[1]) - ref):.1e} m\n")
    print(f"| rule | tip error at {t_end:g} s [m], n_ctrl " + ", ".join(map(str, sizes)) + " | log-log slope |")
    print("|---|---|---|")
    for rule in rules:
        err = [np.linalg.norm(tip(rule, n) - ref) for n in sizes]
        slope = np.polyfit(np.log(1.0 / (np.array(sizes) - 4)), np.log(err), 1)[0]
        print(f"| {rule} | {' '.join(f'{e:.1e}' for e in err)} | {slope:.2f} |", flush=True)


def rolled(rule: str, k: float, n: int):
    """The roll-up (p = 4) under the end couple ``k pi EI / L`` in its static state (the
    exact arc, positions projected), as benchmarks/galerkin_spectra.py."""
    from liegroup_int.groups.so3 import exp_so3

    base = galerkin("rollup", rule, 4, n)
    kap = k * np.pi / base.space.length
    pb = galerkin("rollup", rule, 4, n, **{"material.kelvin_voigt": 0.0,
                                            "loads.end.couple": [0.0, 0.0, kap * float(base.CM[0, 0])]})
    y, s_pts = pb.initial_state(), pb.gs.s
    y.c = pb.gs.project(np.stack([np.sin(kap * s_pts) / kap, (1.0 - np.cos(kap * s_pts)) / kap, 0.0 * s_pts], axis=1))
    y.R = exp_so3(np.outer(kap * s_pts, [0.0, 0.0, 1.0])) @ pb.gs.R0
    y.K = pb.gs.K0 + kap * np.einsum("qji,j->qi", pb.gs.R0, [0.0, 0.0, 1.0])
    return pb, y, 20.0


def rollup_table(rules, n: int = 21) -> None:
    """In-plane spectrum of the rolled-up beam (conservative): zero eigenvalues and the
    largest real part, per rule."""
    print(f"| rule | couple | n_ctrl | residual max abs(v') | in-plane abs(lambda) < 1e-6 max | "
          f"in-plane max Re / abs(lambda)max | abs(lambda)max |")
    print("|---|---|---|---|---|---|---|")
    for rule in rules:
        for k in (1.0, 2.0):
            pb, y, t = rolled(rule, k, n)
            J = jacobian(pb, t, y)
            idx = np.arange(J.shape[0]).reshape(4, pb.n, 3)
            inplane = np.concatenate([idx[0, :, :2].ravel(), idx[1, :, 1], idx[2, :, :2].ravel(), idx[3, :, 1]])
            ei = np.linalg.eigvals(J[np.ix_(inplane, inplane)])
            lam = float(np.max(np.abs(ei)))
            print(f"| {rule} | {k:g} pi EI/L | {n} | {np.max(np.abs(pb.vector_field(t, y)[2])):.1e} "
                  f"| {int(np.sum(np.abs(ei) < 1e-6 * lam))} | {ei.real.max() / lam:.1e} | {lam:.4g} |", flush=True)


def step_cost(pb, steps: int) -> tuple[float, float]:
    """CPU per RKMK4 step [us] (median of three) and ``|lambda|max``."""
    y0 = pb.initial_state()
    lam = spectral_radius(pb, 0.0, y0)
    tab, dt = resolve_method("rkmk4"), 1.0 / lam
    integrate_fixed(pb, tab, (0.0, 3 * dt), y0, dt)
    cpu = []
    for _ in range(3):
        c0 = time.process_time()
        integrate_fixed(pb, tab, (0.0, steps * dt), y0, dt)
        cpu.append((time.process_time() - c0) / steps)
    return 1e6 * statistics.median(cpu), lam


def cost_table(rules, sizes, steps: int) -> None:
    print("| n_ctrl | formulation / rule | points | CPU per step [us] | ratio to primal | abs(lambda)max [1/s] "
          "| CPU per simulated s, ratio to primal |")
    print("|---|---|---|---|---|---|---|")
    for n in sizes:
        over = {"space.n_ctrl": n, "material.kelvin_voigt": 0.0, "integrator.backend": "numba"}
        prim = problem(load_scene("pendulum", {**over, "space.formulation": "primal"}))
        us0, lam0 = step_cost(prim, steps)
        print(f"| {n} | primal | {n} | {us0:.1f} | 1.00 | {lam0:.4g} | 1.00 |", flush=True)
        fit = []
        for rule in rules:
            pb = galerkin("pendulum", rule, 4, n, **{"material.kelvin_voigt": 0.0})
            us, lam = step_cost(pb, steps)
            fit.append((pb.m, us))
            print(f"| {n} | galerkin {rule} | {pb.m} | {us:.1f} | {us / us0:.2f} | {lam:.4g} "
                  f"| {us * lam / (us0 * lam0):.2f} |", flush=True)
        if len(fit) > 1:
            b, a = np.polyfit(*np.array(fit).T, 1)
            print(f"| {n} | fit over the rules: {a:.1f} us + {1e3 * b:.0f} ns per point "
                  f"(the points' share of the step, {rules[0]}: {b * fit[0][0] / fit[0][1]:.0%}) ||||||", flush=True)


def main(argv=None) -> None:
    ap = parser(__doc__, "p = 4 only, rules gauss and gauss-spline, n_ctrl 11 21 against coarser references, "
                         "pendulum over 0.02 s, roll-up at n_ctrl 11 (cost: 21, 200 steps)")
    ap.add_argument("--rules", nargs="+", default=None, choices=list(RULES),
                    help="rules to compare (default: all but auto; --quick: gauss and gauss-spline)")
    ap.add_argument("--skip", nargs="*", default=[], choices=["spectrum", "energy", "tip", "rollup", "cost"])
    ap.add_argument("--degrees", nargs="+", type=int, default=None,
                    help="degrees of the spectrum table (default 4 3 2; --quick: 4)")
    args = ap.parse_args(argv)
    degrees, sizes = ((4,), (11, 21)) if args.quick else ((4, 3, 2), (11, 21, 41))
    degrees = tuple(args.degrees) if args.degrees else degrees
    cost_sizes, steps = ((21,), 200) if args.quick else ((21, 41, 61, 121), 2000)
    if args.rules is None:
        args.rules = ["gauss", "gauss-spline"] if args.quick else [r for r in RULES if r != "auto"]
    if "spectrum" not in args.skip:
        spectrum_table(args.rules, degrees, sizes, reference_frequencies(*(((31, 41),) if args.quick else ())))
        print()
    if "energy" not in args.skip:
        energy_table(args.rules, *(((21, 31), 0.02, 11) if args.quick else ()))
        print()
    if "tip" not in args.skip:
        tip_table(args.rules, sizes, *(((31, 21), 0.02) if args.quick else ()))
        print()
    if "rollup" not in args.skip:
        rollup_table(args.rules, *((11,) if args.quick else ()))
        print()
    if "cost" not in args.skip:
        cost_table(args.rules, cost_sizes, steps)


if __name__ == "__main__":
    main()
