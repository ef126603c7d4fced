"""Flops, ns and flop-bound ratio of one RKMK stage of the beam (numba backend).

Scene: the built-in ``cantilever`` (p = 4, clamped-free, tip force), RKMK4, numba backend,
started (as :mod:`beam_backends`) from a smooth deformed moving state so that nothing
underflows to subnormal numbers.

What one step costs on the public path. ``integrate_fixed`` without a per-step monitor
runs all steps between two output times in one compiled call,
``BeamProblem.compiled_stepper(tab)`` -> ``FusedBeamStepper.advance`` ->
``advance_kernel``: per step 4 ``rates_into`` + 4 ``action_kernel`` + the 4 increment
combinations (``_combine``), the Newton-Schulz end step (``_newton_schulz``), the
finiteness check (``_all_finite``) and the rotation-angle check
(``rotation_angle_kernel``), all compiled, on work arrays allocated once per call. With a
monitor, the generic Python/NumPy step loop runs instead (kept here as the "generic loop"
row, with a no-op monitor).

What it prints (Markdown):

1. **Flop count** of one stage per collocation point, analytic, per kernel section (a
   table of adds/subs, muls, divisions, sqrt and libm calls, derived from the source of
   ``kernels_numba.py``). The per-point kernels (``action_kernel``, ``rates_into`` and
   their inlined helpers) are compiled with ``fastmath={"contract"}``: LLVM fuses
   mul-add pairs into FMAs, which count 2 flops, so the flop count is that of the
   source (section 2 checks that each FMA replaces exactly one mul and one add). The
   Taylor series of the SO(3) coefficients use an angle-dependent number of terms
   (``_n_terms``: 5 below 0.05 rad, 7 below 0.25 rad, else all 12; closed forms at and
   above ``TAYLOR_THRESHOLD``): the script replays the timed run (same start state, dt
   and number of steps) through the generic loop, records the angle at every
   collocation point of every action and stage-rate call, and counts the Horner steps
   actually taken (branch shares and the largest stage angle are printed). The
   per-control-point work of the fused step loop (combinations, Newton-Schulz end step,
   finiteness check, rotation-angle check; all compiled, plain IEEE) is counted too and
   spread over the stages of one step. The banded ``M_c`` solve is counted from the
   actual non-zero multipliers of the LU factors (the kernel skips zeros).
2. **Assembly cross-check** of the code the fused step runs: ``advance_kernel`` is
   recompiled into a private numba cache directory (cached code cannot be inspected);
   its ``inspect_asm`` contains ``advance_kernel`` itself and every callee compiled into
   it (``action_kernel``, ``rates_into``, ``_combine``, ``_newton_schulz``,
   ``rotation_angle_kernel``, ...; ``_all_finite`` is inlined). The text is split into
   functions and basic blocks, natural loops are found (dominators, back edges), and
   scalar / packed FP arithmetic instructions (``v{add,sub,mul,div,sqrt}{s,p}{d,s}``,
   ``vf{,n}m{add,sub}*``; packed ones weighted by their lanes) and libm calls are counted
   in the straight-line part of each per-point loop and per iteration of the inner
   loops; the analytic static counts (every branch once) are printed next to them.
3. **Timing** (process CPU time, BLAS on one thread, warm-up excluded, best of
   ``--repeats`` batches of >= ``--batch`` s): each compiled piece of the fused step
   called ``reps`` times from a compiled loop (no Python dispatch; the same specialization
   ``advance_kernel`` calls), with the Taylor branch at the angles of the run, with 12
   Horner terms, and with the closed forms; a whole step through the public driver
   ``integrate_fixed`` (fused) and through the generic loop (no-op monitor); ns per stage
   per collocation point; achieved GFLOP/s and ratio to the flop bounds of one core at
   ``--ghz`` (default 2.6): vector AVX2+FMA peak 16 DP flop/cycle, scalar FMA peak 4 DP
   flop/cycle (2 FMA ports), scalar without FMA 2 DP flop/cycle; plus measured scalar
   (fastmath=False), scalar FMA (contract) and vector (fastmath=True) FP throughput of
   this machine (micro-kernels).
4. **Where the time goes**: in the fused step, the compiled pieces vs the rest (per-call
   set-up of ``integrate_fixed``/``advance`` amortized over the steps, and the in-situ
   difference); the generic loop for comparison (NumPy pieces, wrappers); the Horner
   term count and closed-form branch; fixed per-call cost vs per-point slope; bytes
   touched per point vs L1/L2; cProfile of the fused driver call; and (with ``--pyspy``)
   a ``py-spy record --native`` sample breakdown of fused steps (JIT code has no symbols,
   so it separates compiled code from Python and runtime, not kernels from each other).

Usage (from the repository root)::

    python benchmarks/stage_flops.py                   # n_ctrl 31, 121, 1001
    python benchmarks/stage_flops.py --quick           # 31 only, fewer repeats
    python benchmarks/stage_flops.py --pyspy           # + py-spy --native sampling (31, 1001)
    python benchmarks/stage_flops.py --spy-target 1001 --seconds 5   # (what --pyspy runs)

Hardware counters are not used (``perf`` is not supported on the VM it was written on).
"""

from __future__ import annotations

import argparse
import atexit
import collections
import os
import platform
import re
import shutil
import subprocess
import sys
import tempfile
import time


def _parse(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="*", default=[31, 121, 1001])
    ap.add_argument("--quick", action="store_true", help="n_ctrl 31 only, 3 repeats")
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--batch", type=float, default=0.15, help="minimum seconds per timed batch")
    ap.add_argument("--threads", default="1", help="BLAS threads (set before NumPy is imported)")
    ap.add_argument("--ghz", type=float, default=2.6, help="core clock for the flop bounds")
    ap.add_argument("--no-asm", action="store_true", help="skip the assembly cross-check")
    ap.add_argument("--pyspy", action="store_true", help="also sample whole steps with py-spy --native")
    ap.add_argument("--only-pyspy", action="store_true", help="only the py-spy part")
    ap.add_argument("--spy-target", type=int, default=0, help=argparse.SUPPRESS)
    ap.add_argument("--seconds", type=float, default=4.0, help=argparse.SUPPRESS)
    return ap.parse_args(argv)


ARGS = _parse() if __name__ == "__main__" else None
if ARGS is not None:
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[var] = str(ARGS.threads)
    if not ARGS.no_asm and not ARGS.spy_target:
        # cached machine code cannot be inspected: compile into a private, throw-away cache
        _CACHE = tempfile.mkdtemp(prefix="stage_flops_numba_")
        os.environ["NUMBA_CACHE_DIR"] = _CACHE
        atexit.register(shutil.rmtree, _CACHE, True)

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
for p in (ROOT, HERE):
    if p not in sys.path:
        sys.path.insert(0, p)

import numpy as np  # noqa: E402

from liegroup_int.integrators import integrate_fixed, resolve_method  # noqa: E402
from liegroup_int.problems.beam import BeamProblem  # noqa: E402
from liegroup_int.problems.beam import kernels_numba as kn  # noqa: E402
from liegroup_int.scenes import load_scene  # noqa: E402
from liegroup_int.scenes.beam import problem as scene_problem  # noqa: E402

TAB = resolve_method("rkmk4")
CLOCK = time.process_time


# ====================================================================== set-up
def make_problem(n):
    """Cantilever p = 4 with ``n`` control points, numba backend."""
    pb = scene_problem(load_scene("cantilever", {"space.n_ctrl": n, "space.degree": 4}))
    return BeamProblem(pb.space, pb.constants, pb.bcs, pb.loads, pb.initial, backend="numba")


def start_state(pb):
    """Smooth deformed, moving state (same as ``beam_backends.start_state``)."""
    s = np.asarray(pb.space.curve.greville())
    u = np.zeros((4, pb.n, 3))
    u[0, :, 1], u[0, :, 2] = 5e-4 * s**3, 1e-3 * s**2
    u[1, :, 1], u[1, :, 2] = 1e-2 * s**2, 5e-3 * s**3
    u[2, :, 2] = 1e-2 * s**2
    u[3, :, 1] = 1e-2 * s**2
    return pb.action(u, pb.initial_state())


def dt_of(n):
    return 0.3e-6 * (31.0 / n) ** 2


def subnormals(y):
    return int(sum(np.sum((a != 0) & (np.abs(a) < np.finfo(float).tiny)) for a in y.arrays().values()))


# ====================================================================== 1. analytic flop count
class Ops(collections.namedtuple("Ops", "add mul fma div sqrt libm")):
    """Operation counts; ``add`` includes subtractions; ``libm`` is a tuple of call names."""

    def __new__(cls, add=0, mul=0, fma=0, div=0, sqrt=0, libm=()):
        return super().__new__(cls, add, mul, fma, div, sqrt, tuple(libm))

    def __add__(self, o):
        return Ops(self.add + o.add, self.mul + o.mul, self.fma + o.fma, self.div + o.div,
                   self.sqrt + o.sqrt, self.libm + o.libm)

    def scale(self, k):
        return Ops(self.add * k, self.mul * k, self.fma * k, self.div * k, self.sqrt * k, self.libm)

    @property
    def flops(self):
        """adds + muls + 2 FMA + div + sqrt (libm calls not counted as flops)."""
        return self.add + self.mul + 2 * self.fma + self.div + self.sqrt


def cross_ops():
    return Ops(add=3, mul=6)


def mat3vec_ops(k=1):  # k products R v or R^T v
    return Ops(add=6 * k, mul=9 * k)


#: Closed forms of the SO(3) coefficients (``TAYLOR_THRESHOLD`` <= angle): counted from
#: ``_coef_ABCB1C1`` / ``_coef_D`` (t**2.0 becomes t*t; t**3.0, t**4.0, t**5.0 stay ``pow``
#: calls; LLVM writes the three ``2.0 * x`` as ``x + x``, so 3 of the 8 muls appear as adds).
CLOSED_ABCB1C1 = Ops(add=5, mul=8, div=5, libm=("sin", "cos", "sin", "pow", "pow", "pow"))
CLOSED_D = Ops(add=1, mul=2, div=2, libm=("tan",))
#: Branches of the SO(3) coefficients, in the order of :func:`angle_survey`.
BRANCHES = ("Taylor, 5 terms", "Taylor, 7 terms", "Taylor, 12 terms", "closed form")


def lu_nonzeros(nb):
    """Non-zero multipliers per row of the ``L`` and off-diagonal ``U`` factors (the
    sweeps skip exact zeros), and ``(lower, upper)``."""
    k = nb._nb
    si, sf, n = k.si, k.sf, k.n
    lo, up = int(si[kn._H_L]), int(si[kn._H_U])
    lu = sf[si[kn._H_LU]:si[kn._H_LU] + n * (lo + up + 1)].reshape(n, lo + up + 1)
    return int(np.count_nonzero(lu[:, :lo])), int(np.count_nonzero(lu[:, lo + 1:])), lo, up


def angle_survey(pb, y, dt, steps):
    """Angles met by the SO(3) coefficients in ``steps`` steps from ``y`` (the timed run).

    Replays the run through the generic step loop (a no-op monitor disables the fused
    loop; same arithmetic up to FMA round-off) with ``action`` and ``increment_rate``
    wrapped to record ``|N0 u_theta|`` at every collocation point of every call: the
    angle ``action_kernel`` feeds ``_coef_ABCB1C1`` and ``rates_into`` feeds ``_coef_D``
    (stage 1 passes ``u = 0``). Each angle is classified with the kernel's own rule
    (``kernels_numba._n_terms``, run as Python, and ``TAYLOR_THRESHOLD``).

    Returns ``{"action" | "rates": dict(max=, calls=, points=, share=(4 fractions in
    BRANCHES order), steps=mean Horner steps per point on the Taylor branch)}``.
    """
    nt = int(pb._nb.si[kn._H_NT])
    thr = float(kn.TAYLOR_THRESHOLD)
    N0 = np.asarray(pb.N0, dtype=float)
    rec = {"action": [], "rates": []}
    act, rate = pb.action, pb.increment_rate

    def action(u, yy):
        rec["action"].append(np.linalg.norm(N0 @ u[1], axis=1))
        return act(u, yy)

    def increment_rate(t, yy, u):
        rec["rates"].append(np.linalg.norm(N0 @ u[1], axis=1))
        return rate(t, yy, u)

    pb.action, pb.increment_rate = action, increment_rate  # instance attributes shadow the methods
    try:
        integrate_fixed(pb, TAB, (0.0, steps * dt), y, dt, monitor=lambda t, yy, st: None)
    finally:
        del pb.action, pb.increment_rate
    terms = np.vectorize(lambda t2: kn._n_terms.py_func(t2, nt), otypes=[int])
    out = {}
    for key, angs in rec.items():
        a = np.concatenate(angs)
        m = terms(a * a)
        closed = a >= thr
        share = tuple(float(np.mean((m == k) & ~closed)) for k in (min(5, nt), min(7, nt), nt)) + \
            (float(np.mean(closed)),)
        if nt <= 7:  # short tables: 5, 7 and 12 terms may coincide
            share = (float(np.mean(~closed)), 0.0, 0.0, float(np.mean(closed)))
        out[key] = dict(max=float(a.max()), calls=len(angs), points=a.size, share=share,
                        steps=float(np.mean(np.where(closed, 0, m - 1))))
    return out


def horner_label(sv):
    """``5 terms 100%`` style summary of one :func:`angle_survey` entry."""
    return ", ".join(f"{b} {100 * f:.3g}%" for b, f in zip(BRANCHES, sv["share"]) if f)


def flop_model(nb, survey, tab=TAB):
    """Per-point operation counts of one stage, section by section.

    ``survey`` is :func:`angle_survey` of the timed run: it sets how many Horner steps
    (``_n_terms`` - 1) and how many closed forms are executed per point on average.

    Returns a list of rows ``(kernel, section, ops_per_exec, execs_per_point, kind)``
    where ``execs_per_point`` is how often the section runs per collocation point and
    stage (loop trip counts, 1/n for once-per-call work, 1/stages for once-per-step
    work, 0 for branches not taken in this scene) and ``kind`` names the asm region
    the section's static code belongs to (section 2).
    """
    k = nb._nb
    n, W = k.n, k.bandwidth
    nL, nU, lo, up = lu_nonzeros(nb)
    pb = nb
    ends = pb.ends
    nforce = sum(e.force_neumann for e in ends)
    nmom = sum(e.moment_neumann for e in ends)
    kv = W if pb.tau != 0.0 else 0
    S = tab.stages
    sa, sr = survey["action"], survey["rates"]
    taylor_a, taylor_r = 1.0 - sa["share"][3], 1.0 - sr["share"][3]
    rows = []
    A, R_ = "action", "rates"
    # ---- action_kernel (per collocation point)
    rows += [
        (A, "c, v, w += eta, dv, dw", Ops(add=9), 1, "line"),
        (A, "band matvecs theta, theta_s, theta_ss (N0,N1,N2; W iters)", Ops(add=9, mul=9), W, "band"),
        (A, "|theta| (sqrt)", Ops(add=2, mul=3, sqrt=1), 1, "line"),
        (A, f"A,B,C,B1,C1: Horner, 5 chains x {sa['steps']:.3g} steps per point ({horner_label(sa)}; "
            f"max angle {sa['max']:.2g} rad)", Ops(add=5, mul=5), sa["steps"], "horner5"),
        (A, "  t^2 for Horner", Ops(mul=1), taylor_a, "coef"),
        (A, "  [closed form if |theta| >= 1]" + ("" if sa["share"][3] else ": not taken"),
         CLOSED_ABCB1C1, sa["share"][3], "coef"),
        (A, "exp(hat theta) = I + A X + B X^2 (9 entries)", Ops(add=12, mul=15), 1, "line"),
        (A, "R' = exp(hat theta) R (3x3 . 3x3)", Ops(add=18, mul=27), 1, "line"),
        (A, "g = J_r theta_s, g_s (5 crosses, theta.theta_s, combos)", Ops(add=38, mul=53), 1, "line"),
        (A, "R^T g, R^T g_s", mat3vec_ops(2), 1, "line"),
        (A, "K' = K + x, K_s' = K_s - K x x + x_s", Ops(add=12, mul=6), 1, "line"),
    ]
    # ---- rates_into (per collocation point)
    rows += [
        (R_, "band matvecs c_s, c_ss, v_c, w_c, theta_c (W iters)", Ops(add=15, mul=15), W, "band"),
        (R_, "strains Gamma, Gamma_s (R^T c_s, R^T c_ss, K x)", Ops(add=21, mul=24), 1, "line"),
        (R_, "K - K0, K_s - K0_s", Ops(add=6), 1, "line"),
        (R_, "  [Kelvin-Voigt band matvecs v_s, v_ss, w_s, w_ss (W iters)]" + ("" if kv else ": tau = 0"),
         Ops(add=12, mul=12), kv, "kvband"),
        (R_, "  [Kelvin-Voigt strain rates, tau x rates]" + ("" if kv else ": tau = 0"),
         Ops(add=66, mul=78), 1 if kv else 0, "line"),
        (R_, "resultants N = CN Gamma, M = CM (K - K0)", Ops(mul=6), 1, "line"),
        (R_, "n_s = R (K x N + CN Gamma_s)", Ops(add=12, mul=18), 1, "line"),
        (R_, "torque: -Om x J Om + K x M + CM K_s + (R^T c_s) x N", Ops(add=24, mul=33), 1, "line"),
        (R_, "  [distributed force / couple: none in this scene]", Ops(add=12, mul=9), 0, "line"),
        (R_, "Neumann end force (once per free end)", Ops(add=12, mul=15), nforce / n, "line"),
        (R_, "Neumann end couple (once per end)", Ops(add=12, mul=15), nmom / n, "line"),
        (R_, "|theta_c| (sqrt)", Ops(add=2, mul=3, sqrt=1), 1, "line"),
        (R_, f"D (dexpinv): Horner, 1 chain x {sr['steps']:.3g} steps per point ({horner_label(sr)}; "
             f"max angle {sr['max']:.2g} rad; stage 1 has u = 0)", Ops(add=1, mul=1), sr["steps"], "horner1"),
        (R_, "  t^2 for Horner", Ops(mul=1), taylor_r, "line"),
        (R_, "  [closed form of D if |theta_c| >= 1]" + ("" if sr["share"][3] else ": not taken"),
         CLOSED_D, sr["share"][3], "line"),
        (R_, "dexpinv rows: w - theta x w / 2 + D theta x (theta x w)", Ops(add=12, mul=18), 1, "line"),
        (R_, "n_s / mu, tq / J (6 div), R J^-1 tq", Ops(add=6, mul=9, div=6), 1, "line"),
        (R_, f"M_c forward sweep L (12 rhs x {nL / n:.2f} nnz/row)", Ops(add=12, mul=12), nL / n, "sweep"),
        (R_, f"M_c backward sweep U (12 rhs x {nU / n:.2f} nnz/row)", Ops(add=12, mul=12), nU / n, "sweep_b"),
        (R_, "M_c reciprocal pivots (12 rhs)", Ops(mul=12), 1, "pivot"),
    ]
    # ---- step work per control point, compiled in advance_kernel, spread over the stages
    comb = Ops()
    for r in range(1, S):
        comb = comb + combine_ops(int(r))
    comb = comb + combine_ops(S)
    D = "step"
    rows += [
        (D, f"increment combinations h sum a_rl k_l ({S - 1} stages + b), _combine", comb, 1 / S, "comb"),
        (D, "end step Newton-Schulz R <- (R/2)(3I - R^T R), _newton_schulz", Ops(add=36, mul=54), 1 / S, "ns"),
        (D, "finiteness check of the increment, _all_finite (x - x per entry)", Ops(add=12), 1 / S, "finite"),
        (D, "rotation angle check: band matvec N0 u_theta (W iters)", Ops(add=3, mul=3), W / S, "aband"),
        (D, "rotation angle check: |.| (sqrt), max", Ops(add=2, mul=3, sqrt=1), 1 / S, "anorm"),
    ]
    return rows


def combine_ops(m):
    """``_combine`` (= ``rkmk.combine``) with ``m`` weights and a known total, per control
    point (12 increment components): differences, weighted sum, ``total K0`` and ``*h``."""
    if m == 1:  # h * (w0 * K0): 2 muls per component
        return Ops(mul=24)
    return Ops(add=12 * (m - 1) + 12 * (m - 2) + 12, mul=12 * (m - 1) + 24)


def summarize_model(rows):
    per = collections.OrderedDict()
    for kern, _, ops, ex, _ in rows:
        per.setdefault(kern, Ops())
        per[kern] = per[kern] + ops.scale(ex) if ex else per[kern]
    return per


# ====================================================================== 2. assembly
FP_RE = re.compile(r"^\s+(v?(?:add|sub|mul|div|sqrt|min|max)(?:s|p)(?:d|s)|v?f(?:n?m)(?:add|sub)\d*(?:s|p)(?:d|s))\b")
CALL_RE = re.compile(r"movabsq\s+\$([A-Za-z_][\w\.]*)")
LIBM = {"sin", "cos", "sincos", "tan", "pow", "exp", "log", "atan", "atan2", "fmod"}


def asm_functions(text):
    funcs, cur = {}, None
    for line in text.splitlines():
        m = re.match(r"^([A-Za-z_][\w\.\$]*):\s*$", line)
        if m:
            cur = funcs.setdefault(m.group(1), [])
            continue
        if cur is not None:
            if line.startswith(".Lfunc_end"):
                cur = None
                continue
            cur.append(line)
    return funcs


def basic_blocks(lines):
    """Split into blocks; return (blocks: list of (label, [instr]), succ: list of sets)."""
    blocks, cur_label, cur = [], "<entry>", []
    for l in lines:
        s = l.strip()
        if not s or s.startswith("#") or (s.startswith(".") and not s.endswith(":")):
            continue
        m = re.match(r"^(\.L\w+):", l)
        if m:
            if cur or cur_label != "<entry>" or blocks:
                blocks.append((cur_label, cur))
            cur_label, cur = m.group(1), []
            continue
        cur.append(s)
        if re.match(r"^(j\w+|ret\w*|ud2)\b", s):
            blocks.append((cur_label, cur))
            cur_label, cur = None, []
    blocks.append((cur_label, cur))
    blocks = [(lab, ins) for lab, ins in blocks if ins or lab]
    index = {lab: i for i, (lab, _) in enumerate(blocks) if lab}
    succ = []
    for i, (_, ins) in enumerate(blocks):
        s, last = set(), ins[-1] if ins else ""
        m = re.match(r"^(j\w+)\s+(\.L\w+)", last)
        if m and m.group(2) in index:
            s.add(index[m.group(2)])
        if not (last.startswith("jmp") or last.startswith("ret") or last.startswith("ud2")) and i + 1 < len(blocks):
            s.add(i + 1)
        succ.append(s)
    return blocks, succ


def natural_loops(succ):
    """``{header: body set}`` of natural loops (back edge ``a -> h`` with ``h dom a``)."""
    nb = len(succ)
    pred = [set() for _ in range(nb)]
    for a, ss in enumerate(succ):
        for b in ss:
            pred[b].add(a)
    reach, stack = {0}, [0]
    while stack:
        a = stack.pop()
        for b in succ[a]:
            if b not in reach:
                reach.add(b)
                stack.append(b)
    dom = {a: set(reach) for a in reach}
    dom[0] = {0}
    changed = True
    while changed:
        changed = False
        for a in sorted(reach):
            if a == 0:
                continue
            ps = [dom[p] for p in pred[a] if p in reach]
            new = set.intersection(*ps) | {a} if ps else {a}
            if new != dom[a]:
                dom[a], changed = new, True
    loops = {}
    for a in reach:
        for h in succ[a]:
            if h in dom[a]:
                body, st = {h, a}, [a]
                while st:
                    x = st.pop()
                    if x == h:
                        continue
                    for p in pred[x]:
                        if p in reach and p not in body:
                            body.add(p)
                            st.append(p)
                loops.setdefault(h, set()).update(body)
    return loops


def annotate_calls(lines):
    """Rewrite ``callq *%reg`` as ``callq <name>`` using the last ``movabsq $name, %reg``."""
    reg, out = {}, []
    for line in lines:
        m = re.search(r"movabsq\s+\$([A-Za-z_][\w\.]*),\s*(%\w+)", line)
        if m:
            reg[m.group(2)] = m.group(1)
        m = re.match(r"^(\s+)callq\s+\*(%\w+)\s*$", line)
        if m and m.group(2) in reg:
            line = f"{m.group(1)}callq {reg[m.group(2)]}"
        out.append(line)
    return out


def count_fp(instrs):
    """Counter of FP arithmetic mnemonics and calls; a packed instruction is keyed
    ``mnemonic/lanes`` (xmm 2, ymm 4, zmm 8 doubles)."""
    c = collections.Counter()
    for s in instrs:
        m = FP_RE.match("\t" + s)
        if m:
            mn = m.group(1)
            if re.search(r"p[ds]$", mn):
                lanes = 8 if "%zmm" in s else (4 if "%ymm" in s else 2)
                mn = f"{mn}/{lanes if mn.endswith('d') else 2 * lanes}"
            c[mn] += 1
        m = re.match(r"^\s*callq\s+([A-Za-z_][\w\.]*)", s)
        if m:
            name = m.group(1)
            if name in LIBM:
                c["call " + name] += 1
            elif "kernels_numba" in name:
                mm = re.search(r"kernels_numba(\d+)", name)
                c["call " + name[mm.end():mm.end() + int(mm.group(1))]] += 1
    return c


def asm_ops(c):
    """Counter of mnemonics -> Ops in flops (packed instructions weighted by lanes)."""
    tot = collections.Counter()
    for k, v in c.items():
        m = re.match(r"^v?(f(?:n?m)(?:add|sub)\d*|add|sub|mul|div|sqrt)(sd|pd/(\d+))$", k)
        if not m:
            continue
        op = "fma" if m.group(1).startswith("f") else {"sub": "add"}.get(m.group(1), m.group(1))
        tot[op] += v * (int(m.group(3)) if m.group(3) else 1)
    libm = tuple(sorted(k[5:] for k, v in c.items() if k.startswith("call ") and k[5:] in LIBM for _ in range(v)))
    return Ops(tot["add"], tot["mul"], tot["fma"], tot["div"], tot["sqrt"], libm)


def packed_count(c):
    return sum(v for k, v in c.items() if "/" in k)


def fma_count(c):
    return sum(v for k, v in c.items() if re.match(r"v?f(n?m)(add|sub)", k))


def kernel_asm(kernel, args):
    """Assembly of the specialization ``kernel`` uses for ``args``."""
    import numba

    sig = tuple(numba.typeof(a) for a in args)
    for s in kernel.signatures:
        if tuple(s) == sig:
            return kernel.inspect_asm(s)
    raise KeyError(f"{kernel.__name__}: no specialization for {sig}")


def loop_report(lines):
    """Per-loop FP counts of one function: list of dicts (header, depth, excl, incl, blocks)."""
    blocks, succ = basic_blocks(annotate_calls(lines))
    loops = natural_loops(succ)
    hs = sorted(loops, key=lambda h: len(loops[h]))
    out = []
    for h in hs:
        body = loops[h]
        inner = [g for g in hs if g != h and loops[g] < body]
        inner_blocks = set().union(*[loops[g] for g in inner]) if inner else set()
        outer = [g for g in hs if g != h and body < loops[g]]
        excl = count_fp([s for b in sorted(body - inner_blocks) for s in blocks[b][1]])
        incl = count_fp([s for b in sorted(body) for s in blocks[b][1]])
        direct_inner = [g for g in inner if not any(loops[g] < loops[x] for x in inner if x != g)]
        out.append(dict(header=h, depth=len(outer), excl=excl, incl=incl, nblocks=len(body),
                        inner=direct_inner))
    whole = count_fp([s for _, ins in blocks for s in ins])
    return out, whole


def asm_crosscheck(nb, y, u, rows):
    """Compare static per-section counts with the compiled code. Returns Markdown lines."""
    k = nb._nb
    n = k.n
    outs = [np.empty((n, 3)) for _ in range(3)] + [np.empty((n, 3, 3))] + [np.empty((n, 3)) for _ in range(2)]
    a_args = (u, y.c, y.v, y.w, y.R, y.K, y.K_s, outs[0], outs[1], outs[2], outs[3], outs[4], outs[5], k.sf, k.si)
    r_args = (y.c, y.v, y.w, y.R, y.K, y.K_s, u, k.sf, k.si, np.empty((4, n, 3)))
    kn.action_kernel(*a_args)
    kn.rates_kernel(*r_args)
    xs = np.array(u)
    kn.solve_kernel(xs, k.sf, k.si)
    lines = []
    vec_total = 0
    W = k.bandwidth
    model = {}
    for kern, sec, ops, ex, kind in rows:
        if kind:
            model.setdefault((kern, kind), Ops())
            model[(kern, kind)] = model[(kern, kind)] + ops
    res = {}
    for name, kernel, args in (("action", kn.action_kernel, a_args), ("rates", kn.rates_kernel, r_args),
                               ("solve", kn.solve_kernel, (xs, k.sf, k.si))):
        text = kernel_asm(kernel, args)
        funcs = asm_functions(text)
        for fname, flines in funcs.items():
            if fname.startswith("_ZN7cpython") or fname.startswith("cfunc."):
                continue
            rep, whole = loop_report(flines)
            vec_total += packed_count(whole)
            m = re.search(r"kernels_numba(\d+)", fname)  # Itanium mangling: <length><name>
            short = fname[m.end():m.end() + int(m.group(1))] if m else fname[:30]
            res[(name, short)] = (rep, whole)
    # --- rows of the comparison
    def fmt(o):
        s = f"{o.mul} mul, {o.add} add/sub, {o.div} div, {o.sqrt} sqrt"
        if o.fma:
            s += f", {o.fma} FMA"
        if o.libm:
            s += ", " + "+".join(sorted(o.libm))
        return s

    def point_loop(rep):
        # outermost loop that contains the sqrt of |theta|
        cands = [r for r in rep if any(kk.endswith("sqrtsd") for kk in r["incl"])]
        return max(cands, key=lambda r: (sum(r["incl"].values()), -r["depth"])) if cands else None

    def sub_ops(x, y):
        return Ops(x.add - y.add, x.mul - y.mul, x.fma - y.fma, x.div - y.div, x.sqrt - y.sqrt,
                   tuple((collections.Counter(x.libm) - collections.Counter(y.libm)).elements()))

    def unroll(asm, body):
        """Integer k with asm == k * body (mul and add), else None."""
        if body.mul == 0 or asm.mul % body.mul or asm.add != asm.mul // body.mul * body.add:
            return None
        return asm.mul // body.mul

    table = []  # (region, analytic, asm, note)
    # ---- action_kernel + _coef_ABCB1C1
    rep, whole = res[("action", "action_kernel")]
    pl = point_loop(rep)
    if pl:
        line = asm_ops(pl["excl"])
        table.append(("action_kernel: per-point straight-line code", model[("action", "line")], line,
                      f"calls: {', '.join(k[5:] for k in pl['excl'] if k.startswith('call ')) or '-'}"))
        for r in (r for r in rep if r["header"] in pl["inner"]):
            ao = asm_ops(r["excl"])
            k = unroll(ao, model[("action", "band")])
            table.append(("action_kernel: inner loop (band matvec), per asm iteration", model[("action", "band")], ao,
                          f"unrolled x{k}, runs W = {W} times" if k else "unmatched"))
    coef = [v for (kk, s_), v in res.items() if kk == "action" and s_.startswith("_coef_ABCB1C1")]
    if coef:
        rep_c, whole_c = coef[0]
        in_loops = Ops()
        for r in (r for r in rep_c if r["depth"] == 0):
            ao = asm_ops(r["incl"])
            in_loops = in_loops + ao
            k = unroll(ao, model[("action", "horner5")])
            table.append(("_coef_ABCB1C1: Horner loop, per asm iteration", model[("action", "horner5")], ao,
                          f"unrolled x{k} (5 chains per source step)" if k else "unmatched"))
        rest = sub_ops(asm_ops(whole_c), in_loops)
        k2 = [unroll(asm_ops(r["incl"]), model[("action", "horner5")]) for r in rep_c if r["depth"] == 0]
        nt = int(nb._nb.si[kn._H_NT])
        peeled = model[("action", "horner5")].scale((nt - 1) % k2[0] if k2 and k2[0] else 0)
        table.append(("_coef_ABCB1C1: outside the loop = t^2 + closed form (+ 1 peeled Horner step)",
                      model[("action", "coef")] + peeled, rest, "both branches static; closed form not executed here"))
    # ---- rates_kernel
    rep, whole = res[("rates", "rates_kernel")]
    pl = point_loop(rep)
    if pl:
        line = asm_ops(pl["excl"])
        extra, notes = Ops(), []
        for r in (r for r in rep if r["header"] in pl["inner"]):
            ao = asm_ops(r["incl"])
            for kind, label in (("band", "band matvec"), ("sweep", "forward sweep entry (12 rhs)"),
                                ("horner1", "Horner step of D")):
                k = unroll(ao, model[("rates", kind)])
                if k:
                    table.append((f"rates_kernel: inner loop ({label}), per asm iteration", model[("rates", kind)],
                                  ao, f"unrolled x{k}"))
                    break
            else:
                if any(r["header"] in x["inner"] for x in rep if x["header"] in pl["inner"]):
                    continue
                extra = extra + ao
                notes.append(f"{ao.mul} mul + {ao.add} add in the loop over the ends")
        table.append(("rates_kernel: per-point straight-line code + loop over the ends (all branches: "
                      "Neumann terms, loads, D closed form)", model[("rates", "line")], line + extra,
                      "; ".join(notes) + "; LICM hoists R N out of the ends loop"))
        others = [r for r in rep if r["depth"] == 0 and r["header"] != pl["header"] and sum(r["incl"].values())]
        for r in others:
            ao = asm_ops(r["incl"])
            if ao.mul == 24 and ao.add == 12:
                table.append(("rates_kernel: backward sweep row (U entry 12 mul+sub, pivot 12 mul)",
                              Ops(add=12, mul=12) + Ops(mul=12), ao, "_finish_solve"))
            elif ao.mul == ao.add and ao.mul > 50:
                table.append(("rates_kernel: dense M_c^-1 fallback (not used: banded)", None, ao,
                              "12 rhs x 8-way unrolled dot products"))
    lines.append("| code region | analytic (static, one copy of the source) | asm (static count) | note |")
    lines.append("|---|---|---|---|")
    for name, mo, ao, note in table:
        agree = ""
        k = re.search(r"unrolled x(\d+)", note)
        if k and mo is not None:
            mo = mo.scale(int(k.group(1)))
            name = name.replace("per asm iteration", f"per asm iteration (= {k.group(1)} source iterations)")
        if mo is not None and ao is not None:
            d = ao.flops - mo.flops
            agree = f"; asm - analytic = {d:+d} flops" if d else "; identical"
        lines.append(f"| {name} | {fmt(mo) if mo is not None else ''} | {fmt(ao) if ao is not None else ''} | "
                     f"{note}{agree} |")
    calls = collections.Counter()
    for (kk, s), (rep, whole) in res.items():
        for key, v in whole.items():
            if key.startswith("call "):
                calls[f"{s}: {key[5:]}"] += v
    lines.append("")
    lines.append(f"Packed (SIMD) FP arithmetic instructions in the three kernels: **{vec_total}**; "
                 f"FMA instructions: **{sum(v for (_, _), (_, w) in res.items() for kk, v in w.items() if 'fm' in kk)}** "
                 "(fastmath=False: no contraction, no reassociation, so no vectorized reductions).")
    lines.append("Calls found (movabsq targets): " + ", ".join(f"{k} x{v}" for k, v in sorted(calls.items())))
    return lines


# ====================================================================== 3. timing
def best_of(f, batch_s, repeats, inner=None):
    """Best CPU seconds per call of ``f`` over ``repeats`` batches lasting >= ``batch_s``."""
    f()
    if inner is None:
        t0 = CLOCK()
        k = 0
        while CLOCK() - t0 < 0.02 or k < 3:
            f()
            k += 1
        est = max((CLOCK() - t0) / k, 1e-8)
        inner = max(3, int(np.ceil(batch_s / est)))
    best = np.inf
    for _ in range(repeats):
        t0 = CLOCK()
        for _ in range(inner):
            f()
        best = min(best, (CLOCK() - t0) / inner)
    return best


def time_step(pb, y, dt, batch_s, repeats):
    integrate_fixed(pb, TAB, (0.0, 2 * dt), y, dt)  # warm-up
    t0 = CLOCK()
    integrate_fixed(pb, TAB, (0.0, 20 * dt), y, dt)
    est = max((CLOCK() - t0) / 20, 1e-7)
    N = max(5, int(np.ceil(batch_s / est)))
    best, y_end = np.inf, None
    for _ in range(repeats):
        t0 = CLOCK()
        _, y_end, _ = integrate_fixed(pb, TAB, (0.0, N * dt), y, dt)
        best = min(best, (CLOCK() - t0) / N)
    return best, y_end


def stage_increment(pb, y, dt, big=False):
    """A realistic stage increment ``u = h k`` (or one with |theta_c| ~ 1.3 rad: closed forms)."""
    u = dt * pb.increment_rate(0.0, y, pb.zero_increment(y))
    if big:
        s = np.asarray(pb.space.curve.greville())
        u[1, :, 0] += 1.3 + 0.1 * s  # every collocation angle > 1 rad (TAYLOR_THRESHOLD)
    return np.ascontiguousarray(u)


def time_kernels(pb, y, dt, batch_s, repeats, big=False):
    k = pb._nb
    n = k.n
    u = stage_increment(pb, y, dt, big)
    outs = [np.empty((n, 3)) for _ in range(3)] + [np.empty((n, 3, 3))] + [np.empty((n, 3)) for _ in range(2)]
    out = np.empty((4, n, 3))
    x0 = np.array(u)
    xs = np.array(u)
    sf, si = k.sf, k.si
    zero = np.zeros((4, n, 3))
    f = {
        "action_kernel": lambda: kn.action_kernel(u, y.c, y.v, y.w, y.R, y.K, y.K_s, *outs, sf, si),
        "rates_kernel": lambda: kn.rates_kernel(y.c, y.v, y.w, y.R, y.K, y.K_s, u, sf, si, out),
        "copy (for solve)": lambda: np.copyto(xs, x0),
        "copy + solve_kernel": lambda: (np.copyto(xs, x0), kn.solve_kernel(xs, sf, si)),
        "rotation_angle_kernel": lambda: kn.rotation_angle_kernel(u, sf, si),
        "wrapper nb.action": lambda: pb.action(u, y),
        "wrapper nb.increment_rate": lambda: pb.increment_rate(dt, y, u),
        "rates_kernel, u = 0": lambda: kn.rates_kernel(y.c, y.v, y.w, y.R, y.K, y.K_s, zero, sf, si, out),
    }
    res = {name: best_of(fn, batch_s / 3, repeats) for name, fn in f.items()}
    res["solve_kernel"] = res["copy + solve_kernel"] - res["copy (for solve)"]
    return res


def time_driver_pieces(pb, y, dt, batch_s, repeats):
    """Per-step cost of the NumPy/Python pieces of one RKMK4 step (outside the kernels)."""
    from liegroup_int.integrators import drivers, rkmk

    n = pb.n
    rng = np.random.default_rng(0)
    K = 1e-3 * rng.standard_normal((TAB.stages, 4, n, 3))
    A, c, b = TAB.A_f, TAB.c_f, TAB.b_f
    u = dt * K[0]

    def combines():
        for r in range(1, TAB.stages):
            rkmk.combine(A[r, :r], K, dt, c[r])
        rkmk.combine(b, K, dt, 1.0)

    ys = y.copy()
    f = {"4 x combine": combines,
         "end_step (Newton-Schulz, NumPy)": lambda: pb.end_step(ys),
         "_check_finite": lambda: drivers._check_finite(u, 0.0, 1),
         "zeros_like (u of stage 1)": lambda: np.zeros_like(K[0])}
    return {k: best_of(fn, batch_s / 3, repeats) for k, fn in f.items()}


def dispatch_cost(batch_s, repeats):
    """Cost of calling a trivial numba function with 15 / 10 array arguments."""
    from numba import njit

    @njit(cache=False)
    def nop15(a, b, c, d, e, f, g, h, i, j, k, l, m, o, p):
        return 0

    @njit(cache=False)
    def nop10(a, b, c, d, e, f, g, h, i, j):
        return 0

    a = np.zeros((3, 3))
    return (best_of(lambda: nop15(*([a] * 15)), batch_s / 3, repeats),
            best_of(lambda: nop10(*([a] * 10)), batch_s / 3, repeats))


def calibrate(ghz, repeats):
    """Measured FP throughput of one core: scalar (fastmath=False, 16 independent mul+add
    chains) and vector (fastmath=True, contracted into FMAs and vectorized), GFLOP/s."""
    from numba import njit

    @njit(cache=False, fastmath=False)
    def scalar(n, m, c):
        a0 = a1 = a2 = a3 = a4 = a5 = a6 = a7 = 0.0
        b0 = b1 = b2 = b3 = b4 = b5 = b6 = b7 = 0.5
        for _ in range(n):
            a0 = a0 * m + c
            a1 = a1 * m + c
            a2 = a2 * m + c
            a3 = a3 * m + c
            a4 = a4 * m + c
            a5 = a5 * m + c
            a6 = a6 * m + c
            a7 = a7 * m + c
            b0 = b0 * m + c
            b1 = b1 * m + c
            b2 = b2 * m + c
            b3 = b3 * m + c
            b4 = b4 * m + c
            b5 = b5 * m + c
            b6 = b6 * m + c
            b7 = b7 * m + c
        return a0 + a1 + a2 + a3 + a4 + a5 + a6 + a7 + b0 + b1 + b2 + b3 + b4 + b5 + b6 + b7

    @njit(cache=False, fastmath=True)
    def vector(x, reps, m, c):
        # x: 256 doubles (L1); each pass is 256 independent FMAs
        for _ in range(reps):
            for j in range(x.shape[0]):
                x[j] = x[j] * m + c
        return x[0]

    N = 2_000_000
    scalar(10, 0.999, 1e-3)
    ts = best_of(lambda: scalar(N, 0.999, 1e-3), 0.05, repeats, inner=3)
    x = np.ones(256)
    vector(x, 2, 0.999, 1e-3)
    reps = 20000
    tv = best_of(lambda: vector(x, reps, 0.999, 1e-3), 0.05, repeats, inner=3)
    return 32 * N / ts / 1e9, 2 * 256 * reps / tv / 1e9


# ====================================================================== 4. profile
def cprofile_step(pb, y, dt, steps):
    import cProfile
    import pstats

    integrate_fixed(pb, TAB, (0.0, 2 * dt), y, dt)
    prof = cProfile.Profile()
    prof.enable()
    integrate_fixed(pb, TAB, (0.0, steps * dt), y, dt)
    prof.disable()
    st = pstats.Stats(prof)
    total = sum(v[2] for v in st.stats.values())
    rows = []
    for (fn, line, name), (cc, nc, tt, ct, callers) in st.stats.items():
        rows.append((tt, nc, f"{os.path.basename(fn)}:{name}" if fn != "~" else name))
    rows.sort(reverse=True)
    return total, rows


def spy_target(n, seconds):
    """Run whole steps for ``seconds`` (the py-spy sampling target)."""
    pb = make_problem(n)
    y = start_state(pb)
    dt = dt_of(n)
    integrate_fixed(pb, TAB, (0.0, 2 * dt), y, dt)  # JIT compile / cache load: not sampled below
    _spy_timed_loop(pb, y, dt, seconds)


def _spy_timed_loop(pb, y, dt, seconds):
    t0 = time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        integrate_fixed(pb, TAB, (0.0, 200 * dt), y, dt)


def run_pyspy(n, seconds):
    """``py-spy record --native`` of :func:`spy_target`; sample shares by category."""
    exe = shutil.which("py-spy") or os.path.join(os.path.dirname(sys.executable), "py-spy")
    if not os.path.exists(exe):
        return None
    with tempfile.TemporaryDirectory() as td:
        out = os.path.join(td, "spy.txt")
        cmd = [exe, "record", "--native", "-r", "997", "-f", "raw", "-o", out, "--",
               sys.executable, os.path.abspath(__file__), "--spy-target", str(n), "--seconds", str(seconds),
               "--threads", "1"]
        p = subprocess.run(cmd, capture_output=True, text=True)
        if p.returncode != 0 or not os.path.exists(out):
            return ("py-spy failed: " + (p.stderr or p.stdout)[-300:],)
        stacks = collections.Counter()
        for line in open(out):
            line = line.rstrip()
            if not line:
                continue
            st, _, cnt = line.rpartition(" ")
            stacks[st] += int(cnt)
    # attribute each sample: last Python frame + native leaf; JIT code has no symbols (0x...)
    wrappers = {"NumbaBeamKernels.action": "action_kernel", "NumbaBeamKernels.increment_rate": "rates_kernel",
                "NumbaBeamKernels.rotation_angle": "rotation_angle_kernel"}
    cats, coarse = collections.Counter(), collections.Counter()
    total = 0
    for st, cnt in stacks.items():
        frames = st.split(";")
        if not any(f.startswith("_spy_timed_loop") for f in frames):
            continue
        total += cnt
        names = [f.rsplit(" (", 1)[0] for f in frames]
        files = [f.rsplit(" (", 1)[1] if " (" in f else "" for f in frames]
        py = [i for i, fl in enumerate(files) if ".py:" in fl]
        ip = py[-1] if py else 0
        pyfn, leaf = names[ip], names[-1]
        native = len(names) - 1 > ip
        if pyfn in wrappers and native and leaf.startswith("0x"):
            cat = f"JIT code of {wrappers[pyfn]}"
            coarse["compiled kernels (JIT code)"] += cnt
        elif pyfn in wrappers:
            cat = f"{pyfn}: {'numba dispatch / alloc: ' + leaf if native else 'Python'}"
            coarse["kernel wrappers: dispatch, unboxing, allocation, state object"] += cnt
        else:
            cat = f"{pyfn} -> {leaf}" if native else f"{pyfn} (Python)"
            grp = {"combine": "increment combinations (NumPy)", "BeamProblem.end_step": "end_step (NumPy matmul)"}
            coarse[grp.get(pyfn, "other Python driver code (interpreter, checks, numpy calls)")] += cnt
        cats[cat] += cnt
    cats = collections.Counter({**{f"**{k}**": v for k, v in coarse.items()}, **cats})
    return total, cats


# ====================================================================== main
def md_table(head, rows):
    out = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    out += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(out)


def pyspy_section(args):
    """py-spy record --native of whole steps at n_ctrl 31 and 1001 (Markdown)."""
    for n in (31, 1001):
        res = run_pyspy(n, args.seconds)
        if res is None:
            print("py-spy not found")
            return
        if len(res) == 1:
            print(res[0])
            return
        total, cats = res
        print(f"py-spy record --native -r 997, n_ctrl {n}: {total} samples in the timed loop "
              "(JIT code has no symbols: a 0x... leaf under a kernel wrapper is the compiled kernel)\n")
        print(md_table(["group (bold) / last Python frame -> native leaf", "share"],
                       [[c, f"{100 * v / total:.1f}%"] for c, v in cats.most_common(18)]))
        print()


def main(args):
    import numba

    if args.only_pyspy:
        return pyspy_section(args)
    sizes = [31] if args.quick else args.sizes
    repeats = 3 if args.quick else args.repeats
    ghz = args.ghz
    print("# RKMK stage: flops, ns per point, flop-bound ratio (cantilever p=4, RKMK4, numba backend)")
    print(f"# python {platform.python_version()}, numpy {np.__version__}, numba {numba.__version__}, "
          f"llvm host cpu {numba.config.CPU_NAME or __import__('llvmlite.binding', fromlist=['x']).get_host_cpu_name()}, "
          f"{os.cpu_count()} cpus, BLAS threads {os.environ.get('OPENBLAS_NUM_THREADS', 'default')}, "
          f"load average {os.getloadavg()[0]:.2f}")
    print(f"# process CPU time, best of {repeats} batches >= {args.batch} s; clock for bounds {ghz} GHz")
    print()

    # ---------------------------------------------------------------- 1. flop model
    models = {}
    for n in sorted(set(sizes) | {31, 1001}):
        pb = make_problem(n)
        rows = flop_model(pb)
        models[n] = (pb, rows)
    print("## 1. Flop count of one stage per collocation point (analytic, from kernels_numba.py)\n")
    n_show = [n for n in (31, 1001) if n in models]
    head = ["kernel", "section", "ops per execution", "executions / point / stage"] + \
           [f"flops / point (n={n})" for n in n_show]
    trs = []
    rows31 = models[n_show[0]][1]
    for i, (kern, sec, ops, ex, _) in enumerate(rows31):
        o = f"{ops.mul} mul + {ops.add} add" + (f" + {ops.div} div" if ops.div else "") + \
            (f" + {ops.sqrt} sqrt" if ops.sqrt else "") + (f" + {'/'.join(ops.libm)}" if ops.libm else "")
        exs = "; ".join(f"{models[n][1][i][3]:.3g}" for n in n_show) if len(set(models[n][1][i][3] for n in n_show)) > 1 \
            else f"{ex:.3g}"
        trs.append([kern, sec, o, exs] + [f"{models[n][1][i][2].scale(models[n][1][i][3]).flops:.1f}" for n in n_show])
    print(md_table(head, trs))
    print()
    summ = {}
    for n in sorted(models):
        per = summarize_model(models[n][1])
        tot = Ops()
        for v in per.values():
            tot = tot + v
        summ[n] = (per, tot)
    head = ["n_ctrl"] + [f"{k} flops" for k in summ[n_show[0]][0]] + ["total flops / stage / point", "of which div+sqrt",
                                                                      "libm calls / point (Taylor branch)"]
    trs = []
    for n in sorted(summ):
        per, tot = summ[n]
        trs.append([n] + [f"{v.flops:.1f}" for v in per.values()] + [f"**{tot.flops:.1f}**", f"{tot.div + tot.sqrt:.2f}", "0"])
    print(md_table(head, trs))
    print("\nConventions: add/sub/mul/div/sqrt = 1 flop, FMA = 2 (none generated), libm calls listed, not counted; "
          "common subexpressions counted once (as the compiler does); 'driver' = NumPy work per control point per step "
          "divided by the 4 stages. Angles here are << 1 rad, so every point takes the Taylor (Horner) branch.\n")

    # ---------------------------------------------------------------- 2. asm cross-check
    n0 = sizes[0]
    if not args.no_asm:
        pb = models[n0][0] if n0 in models else make_problem(n0)
        y = start_state(pb)
        u = stage_increment(pb, y, dt_of(n0))
        print(f"## 2. Cross-check against numba's generated assembly (n_ctrl = {n0} specialization)\n")
        for line in asm_crosscheck(pb, y, u, models[n0][1] if n0 in models else flop_model(pb)):
            print(line)
        print()

    # ---------------------------------------------------------------- 3. timing
    gs, gv = calibrate(ghz, repeats)
    d15, d10 = dispatch_cost(args.batch, repeats)
    results = []
    for n in sizes:
        pb = models[n][0] if n in models else make_problem(n)
        rows = models[n][1] if n in models else flop_model(pb)
        per, tot = summ[n] if n in summ else (summarize_model(rows), None)
        if tot is None:
            tot = Ops()
            for v in per.values():
                tot = tot + v
        y = start_state(pb)
        dt = dt_of(n)
        kt = time_kernels(pb, y, dt, args.batch, repeats)
        kb = time_kernels(pb, y, dt, args.batch, repeats, big=True)
        t_step, y_end = time_step(pb, y, dt, args.batch, repeats)
        dp = time_driver_pieces(pb, y, dt, args.batch, repeats)
        results.append(dict(n=n, per=per, tot=tot, kt=kt, kb=kb, dp=dp, step=t_step, sub=subnormals(y_end),
                            finite=bool(pb.is_finite(y_end))))
        print(f"#   n={n}: timed", flush=True)

    print("\n## 3. Time per stage per collocation point and flop rate\n")
    S = TAB.stages
    head = ["n_ctrl", "action_kernel ns/pt", "rates_kernel ns/pt", "  of which solve_kernel ns/pt",
            "angle kernel ns/pt", "whole step ns/stage/pt", "flops/stage/pt", "GFLOP/s (step)",
            "% of 4 flop/cyc (scalar FMA)", "% of 16 flop/cyc (AVX2 FMA)", "% of 2 flop/cyc (scalar, no FMA)"]
    trs = []
    for r in results:
        n, kt, tot = r["n"], r["kt"], r["tot"]
        ns = r["step"] / (S * n) * 1e9
        gf = tot.flops / ns
        trs.append([n, f"{kt['action_kernel'] / n * 1e9:.1f}", f"{kt['rates_kernel'] / n * 1e9:.1f}",
                    f"{kt['solve_kernel'] / n * 1e9:.1f}", f"{kt['rotation_angle_kernel'] / n * 1e9:.1f}",
                    f"**{ns:.1f}**", f"{tot.flops:.0f}", f"{gf:.2f}", f"{100 * gf / (4 * ghz):.1f}",
                    f"{100 * gf / (16 * ghz):.1f}", f"{100 * gf / (2 * ghz):.1f}"])
    print(md_table(head, trs))
    print()
    head = ["n_ctrl", "action flops/pt", "action GFLOP/s", "rates flops/pt (incl. solve)", "rates GFLOP/s",
            "kernels-only ns/stage/pt", "kernels-only GFLOP/s", "% scalar-FMA peak"]
    trs = []
    for r in results:
        n, kt, per = r["n"], r["kt"], r["per"]
        ta, tr = kt["action_kernel"] / n * 1e9, kt["rates_kernel"] / n * 1e9
        tk = ta + tr
        fk = per["action"].flops + per["rates"].flops
        trs.append([n, f"{per['action'].flops:.0f}", f"{per['action'].flops / ta:.2f}", f"{per['rates'].flops:.0f}",
                    f"{per['rates'].flops / tr:.2f}", f"{tk:.1f}", f"{fk / tk:.2f}", f"{100 * fk / tk / (4 * ghz):.1f}"])
    print(md_table(head, trs))
    print(f"\nMeasured FP throughput of this core (micro-kernels, same clock): scalar mul+add without FMA "
          f"(fastmath=False) **{gs:.2f} GFLOP/s** = {gs / ghz:.2f} flop/cycle at {ghz} GHz; vectorized FMA "
          f"(fastmath=True, L1-resident) **{gv:.2f} GFLOP/s** = {gv / ghz:.2f} flop/cycle. "
          f"Theoretical at {ghz} GHz: scalar FMA {4 * ghz:.1f}, AVX2 FMA {16 * ghz:.1f} GFLOP/s.")
    print(f"All runs finite: {all(r['finite'] for r in results)}; subnormal entries in end states: "
          f"{sum(r['sub'] for r in results)}.\n")

    # ---------------------------------------------------------------- 4. where the time goes
    print("## 4. Where the time goes\n")
    head = ["n_ctrl", "step us", "4 x action_kernel", "4 x rates_kernel", "angle kernel", "kernels total",
            "wrappers (alloc + state object + dispatch) over kernels", "Python driver rest", "kernel share"]
    trs = []
    for r in results:
        kt = r["kt"]
        ker = S * (kt["action_kernel"] + kt["rates_kernel"]) + kt["rotation_angle_kernel"]
        wrap = S * (kt["wrapper nb.action"] - kt["action_kernel"] + kt["wrapper nb.increment_rate"] - kt["rates_kernel"])
        rest = r["step"] - ker - wrap
        trs.append([r["n"], f"{r['step'] * 1e6:.1f}", f"{S * kt['action_kernel'] * 1e6:.1f}",
                    f"{S * kt['rates_kernel'] * 1e6:.1f}", f"{kt['rotation_angle_kernel'] * 1e6:.1f}",
                    f"{ker * 1e6:.1f}", f"{wrap * 1e6:.1f}", f"{rest * 1e6:.1f}", f"{100 * ker / r['step']:.0f}%"])
    print(md_table(head, trs))
    print()
    keys = list(results[0]["dp"])
    print(md_table(["n_ctrl"] + [f"{k} us/step" for k in keys] + ["sum", "unexplained Python driver rest"],
                   [[r["n"]] + [f"{r['dp'][k] * 1e6:.1f}" for k in keys] + [f"{sum(r['dp'].values()) * 1e6:.1f}",
                    f"{(r['step'] - S * (r['kt']['wrapper nb.action'] + r['kt']['wrapper nb.increment_rate']) - r['kt']['rotation_angle_kernel'] - sum(r['dp'].values())) * 1e6:.1f}"]
                    for r in results]))
    print(f"\nEmpty numba call with 15 / 10 array arguments (dispatch + unboxing): {d15 * 1e6:.2f} / {d10 * 1e6:.2f} us "
          f"(action_kernel takes 15, rates_kernel 10).\n")
    head = ["n_ctrl", "action Taylor ns/pt", "action closed form ns/pt", "rates Taylor ns/pt",
            "rates closed form ns/pt", "rates with u = 0 ns/pt", "copy+solve us", "copy us"]
    trs = []
    for r in results:
        n, kt, kb = r["n"], r["kt"], r["kb"]
        trs.append([n, f"{kt['action_kernel'] / n * 1e9:.1f}", f"{kb['action_kernel'] / n * 1e9:.1f}",
                    f"{kt['rates_kernel'] / n * 1e9:.1f}", f"{kb['rates_kernel'] / n * 1e9:.1f}",
                    f"{kt['rates_kernel, u = 0'] / n * 1e9:.1f}", f"{kt['copy + solve_kernel'] * 1e6:.2f}",
                    f"{kt['copy (for solve)'] * 1e6:.2f}"])
    print(md_table(head, trs))
    if len(results) >= 2:
        ns_ = np.array([r["n"] for r in results], float)
        print()
        for key in ("action_kernel", "rates_kernel", "solve_kernel", "rotation_angle_kernel"):
            t = np.array([r["kt"][key] for r in results])
            b, a = np.polyfit(ns_, t, 1)
            print(f"- {key}: fixed cost per call {a * 1e6:.2f} us + {b * 1e9:.1f} ns per point (linear fit over n_ctrl)")
        t = np.array([r["step"] for r in results])
        b, a = np.polyfit(ns_, t, 1)
        print(f"- whole step: {a * 1e6:.1f} us fixed + {b * 1e9:.0f} ns per point per step "
              f"(= {b * 1e9 / S:.0f} ns per point per stage)")
    # bytes per point (float64): action reads u (12), c v w (9), R (9), K K_s (6), 3 W band values,
    # writes 24; rates reads c v w (9), R (9), K K_s (6), u[1] (3), 3 W band, geo (9), LU row (7),
    # writes x (12) and out (12)
    W = 5
    act = 8 * (12 + 9 + 9 + 6 + 3 * W + 24)
    rat = 8 * (9 + 9 + 6 + 3 + 3 * W + 9 + 7 + 12 + 12)
    print(f"Bytes touched per point and stage: ~{act} B (action) + ~{rat} B (rates) = ~{act + rat} B "
          f"(~{(act + rat) / results[0]['tot'].flops:.2f} B/flop).")
    for r in results:
        n = r["n"]
        ws = 8 * n * (24 + 24 + 12 * (S + 2) + 3 * W + 7 + 9)  # y, y_r, K, u, out, band, LU, geo
        print(f"- n_ctrl {n}: working set of one step ~{ws / 1024:.0f} KiB -> "
              f"{'L1d (48 KiB)' if ws < 44 * 1024 else ('L2 (2 MiB)' if ws < 1.8 * 2**20 else 'L3')}; "
              f"{(act + rat) / ((r['kt']['action_kernel'] + r['kt']['rates_kernel']) / n * 1e9):.1f} GB/s "
              "while in the kernels")
    print()
    for n in ([31, 1001] if not args.quick else [31]):
        pb = make_problem(n)
        y = start_state(pb)
        steps = max(20, int(20000 / n))
        total, prow = cprofile_step(pb, y, dt_of(n), steps)
        print(f"cProfile, n_ctrl {n}, {steps} steps (own time per function, share of the profiled total; "
              f"cProfile inflates Python-call costs):\n")
        print(md_table(["function", "calls/step", "own us/step", "share"],
                       [[name, f"{nc / steps:.0f}", f"{tt / steps * 1e6:.1f}", f"{100 * tt / total:.0f}%"]
                        for tt, nc, name in prow[:12]]))
        print()
    if args.pyspy:
        pyspy_section(args)
    print(f"load average at end: {os.getloadavg()[0]:.2f}")
    return results


if __name__ == "__main__":
    if ARGS.spy_target:
        spy_target(ARGS.spy_target, ARGS.seconds)
    else:
        main(ARGS)
