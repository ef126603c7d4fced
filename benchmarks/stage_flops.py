"""Flops, ns and flop-bound ratio of one RKMK stage of the beam (numba backend).

Scene: the built-in ``cantilever`` (p = 4), RKMK4, numba backend, in the formulation of
``--formulation`` (default: the default, Galerkin), started from the smooth deformed moving
state of :mod:`liegroup_int.bench.beam_step` (nothing underflows to subnormal numbers).
"Points" are the collocation points (``n_ctrl``) of collocation and the quadrature points
of the Galerkin form (its stage loops run over them).

1. **Flop model, read from the compiled code** (:mod:`liegroup_int.bench.asm_flops`):
   the engine's ``rate`` and ``action`` kernels (``problem.compiled_kernels()``, the
   kernels the compiled step loop runs per stage) are compiled afresh and their assembly
   counted: adds/subs, muls, FMAs (2 flops), divisions, square roots, libm calls and
   packed (SIMD) instructions, per top-level loop nest of every function in the compile
   unit, every basic block once. Their sum is the model's flops per collocation point per
   stage: a static count, not the work one stage does. It over-counts (both branches of
   the SO(3) coefficients, Taylor and closed form; nests that run once per call, such as
   the joint rows, counted as if per point) and under-counts (an inner loop's body once,
   whatever its trip count); the first over-counts dominate for these kernels, so rates
   and bound ratios derived from it are upper estimates.
2. **Timing** (process CPU time, BLAS on one thread, warm-up excluded, best of
   ``--repeats`` batches of >= ``--batch`` s): a whole RKMK4 step through the public driver
   ``integrate_fixed`` (fused: the compiled engine; generic: the Python loop, kept there
   by a no-op monitor), and one call of ``problem.action`` / ``problem.increment_rate``.
   From these: ns per stage per collocation point, GFLOP/s at the model's static count,
   and its ratio to the flop bounds of one core at ``--ghz``: scalar FMA 4 flop/cycle
   (2 FMA ports), AVX2+FMA 16 flop/cycle (upper estimates, see 1).

Usage (from the repository root)::

    python benchmarks/stage_flops.py                   # n_ctrl 31, 121, 1001
    python benchmarks/stage_flops.py --quick           # n_ctrl 31, one short batch, the action's count only
"""

from __future__ import annotations

import os
import platform
import time

from liegroup_int.bench.table import markdown, parser


def _parse():
    ap = parser(__doc__, quick_help="n_ctrl 31 only, one batch of >= 0.02 s, the flop model of the action only "
                                    "(the stage rate's fresh compile alone takes about 15 s)")
    ap.add_argument("--sizes", type=int, nargs="*", default=[31, 121, 1001])
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--batch", type=float, default=0.15, help="minimum seconds per timed batch")
    ap.add_argument("--threads", default="1", help="BLAS threads (set before NumPy is imported)")
    ap.add_argument("--ghz", type=float, default=2.6, help="core clock for the flop bounds")
    ap.add_argument("--formulation", default="galerkin", choices=("primal", "galerkin"))
    return ap.parse_args()


ARGS = _parse() if __name__ == "__main__" else None
if ARGS is not None:
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[var] = str(ARGS.threads)

import numpy as np  # noqa: E402  (after the BLAS thread count is set)

from liegroup_int.bench.asm_flops import engine_args, kernel_count, short_name  # noqa: E402
from liegroup_int.bench.beam_step import TAB, cantilever, no_monitor, start_state, step_dt, time_steps  # noqa: E402
from liegroup_int.bench.timing import best_of  # noqa: E402

STAGES = TAB.stages
OP_HEAD = ["add/sub", "mul", "FMA", "div", "sqrt", "libm calls", "packed instr.", "flops"]


def op_cells(ops) -> list:
    libm = ", ".join(f"{n} {ops.libm.count(n)}" for n in sorted(set(ops.libm))) or "-"
    return [ops.add, ops.mul, ops.fma, ops.div, ops.sqrt, libm, ops.packed, ops.flops]


def points(pb) -> int:
    """The points a stage loops over: quadrature points (Galerkin) or collocation points."""
    return int(pb.m) if pb.formulation == "galerkin" else int(pb.n)


def flop_model(n: int, formulation: str, names=("rate", "action")):
    """Kernel counts of the engine's kernels ``names`` (static: independent of n)."""
    pb = cantilever(n, formulation=formulation)
    args = engine_args(pb.compiled_kernels(), start_state(pb))
    kernels = pb.compiled_kernels().kernels
    return [kernel_count(name, getattr(kernels, name), args[name]) for name in names]


def print_model(counts) -> int:
    """Prints the loop-nest table and the per-point totals; returns flops per point per stage."""
    rows = []
    for kc in counts:
        for nest in kc.nests:
            rows.append([kc.name, short_name(nest.function), nest.blocks, *op_cells(nest.ops)])
    print("### Flop model: top-level loop nests of the compiled kernels (static: every block once)\n")
    print(markdown(["kernel", "function", "blocks", *OP_HEAD], rows))
    total = sum(kc.per_point.flops for kc in counts)
    print()
    print(markdown(["kernel", "per call, outside loops: flops", "per point: flops", "per point: FMA instr.",
                    "per point: packed instr."],
                   [[kc.name, kc.straight.flops, kc.per_point.flops, kc.per_point.fma, kc.per_point.packed]
                    for kc in counts] + [[f"stage ({' + '.join(kc.name for kc in counts)})", "", total, "", ""]]))
    return total


def measure(n: int, args, flops: int) -> list:
    """One table row: step and call timings at ``n_ctrl = n`` and the derived rates."""
    pb = cantilever(n, formulation=args.formulation)
    y, dt, npt = start_state(pb), step_dt(n), points(pb)
    fused, _, _ = time_steps(pb, y, dt, args.batch, args.repeats)
    generic, _, _ = time_steps(pb, y, dt, args.batch, args.repeats, monitor=no_monitor)
    u = 1e-3 * dt * pb.increment_rate(0.0, y, pb.zero_increment(y))
    t_act = best_of(lambda: pb.action(u, y), args.repeats, args.batch / 3).seconds
    t_rate = best_of(lambda: pb.increment_rate(dt, y, u), args.repeats, args.batch / 3).seconds
    ns = fused / (STAGES * npt) * 1e9
    gflops = flops / ns
    return [n, npt, f"{fused * 1e6:.1f}", f"{ns:.1f}", f"{gflops:.2f}", f"{100 * gflops / (4 * args.ghz):.0f}",
            f"{100 * gflops / (16 * args.ghz):.0f}", f"{generic / (STAGES * npt) * 1e9:.0f}",
            f"{t_act / npt * 1e9:.1f}", f"{t_rate / npt * 1e9:.1f}"]


def main(args) -> None:
    import numba

    sizes = [31] if args.quick else args.sizes
    if args.quick:
        args.repeats, args.batch = 1, 0.02
    print(f"# stage flops: cantilever p=4, RKMK4, {args.formulation}, numba backend; python {platform.python_version()}, numpy "
          f"{np.__version__}, numba {numba.__version__}, {platform.machine()}, {os.cpu_count()} cpus, "
          f"load average {os.getloadavg()[0]:.2f}\n")
    c0 = time.process_time()
    flops = print_model(flop_model(sizes[0], args.formulation, ("action",) if args.quick else ("rate", "action")))
    print(f"\n(model: {time.process_time() - c0:.1f} s CPU to compile and count)\n")
    print(f"### Timing (process CPU, best of {args.repeats} batches >= {args.batch} s; bounds at {args.ghz} GHz)\n")
    print(markdown(["n_ctrl", "points", "fused step [us]", "fused ns/stage/point", "GFLOP/s (static count)",
                    "% scalar-FMA bound (static count)", "% AVX2 bound (static count)", "generic ns/stage/point",
                    "action call ns/point", "rate call ns/point"], [measure(n, args, flops) for n in sizes]))


if __name__ == "__main__":
    main(ARGS)
