"""Flops, ns and flop-bound ratio of one RKMK stage of the beam (numba backend).

Scene: the built-in ``cantilever`` (p = 4, clamped-free, tip force), RKMK4, numba backend,
started (as :mod:`beam_backends`) from a smooth deformed moving state so that nothing
underflows to subnormal numbers.

What one step costs on the public path. ``integrate_fixed`` without a per-step monitor
runs all steps between two output times in one compiled call,
``integrate_fixed`` -> the compiled engine (``BeamProblem.compiled_kernels``) ->
the engine's fixed-step loop (called ``advance_kernel`` in the tables): per step 4 ``rates_into`` + 4 ``action_kernel`` + the 4 increment
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

from liegroup_int.integrators import MAX_INCREMENT_ANGLE as MAX_ANGLE  # noqa: E402
from liegroup_int.integrators import integrate_fixed, resolve_method  # noqa: E402
from liegroup_int.integrators.combine_numba import combine_into  # noqa: E402
from liegroup_int.integrators.engine import compiled_stepper  # noqa: E402
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
    """Smooth deformed, moving state: ``beam_backends.start_state``."""
    from beam_backends import start_state as deformed

    return deformed(pb)


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


def fused_args(pb, y):
    """``(stepper, args)``: the compiled engine's stepper of the timed run (with ``sf``,
    ``si`` of its data as attributes) and the argument tuple its ``advance`` passes to the
    engine's fixed-step loop (one step from ``y``)."""
    st = compiled_stepper(pb, TAB)
    st.sf, st.si = st.cp.data[0], st.cp.data[1]
    packed = st.cp.pack(y)
    dt = 1e-9
    args = (st.cp.data, st.cp.increment_size(packed), st.A, st.b, st.c, st.fsal, packed, 0.0, dt, dt, 1,
            float(MAX_ANGLE))
    return st, args


def asm_crosscheck(nb, y, rows):
    """Compare static per-section counts with the code the fused step runs (the
    ``advance_kernel`` compile unit and its callees). Returns Markdown lines."""
    k = nb._nb
    W = k.bandwidth
    st, args = fused_args(nb, y)
    loop = st.engine.advance_fixed
    loop(*args)
    text = kernel_asm(loop, args)
    model = {}
    for kern, sec, ops, ex, kind in rows:
        if kind:
            model.setdefault((kern, kind), Ops())
            model[(kern, kind)] = model[(kern, kind)] + ops
    res = {}
    engine_lines = []  # the engine's step loop and its step function: "advance_kernel" below
    for fname, flines in asm_functions(text).items():
        if fname.startswith("_ZN7cpython") or fname.startswith("cfunc."):
            continue
        if "14_advance_fixed" in fname or "5_step" in fname:
            engine_lines += flines
            continue
        m = re.search(r"kernels_numba(\d+)", fname) or re.search(r"combine_numba(\d+)", fname)
        if m is None:  # not one of the beam kernels or the shared combination
            continue
        name = fname[m.end():m.end() + int(m.group(1))]  # Itanium mangling: <length><name>
        res["_combine" if name == "combine_into" else name] = loop_report(flines)
    res["advance_kernel"] = loop_report(engine_lines)

    def fmt(o):
        s = f"{o.mul} mul, {o.add} add/sub"
        if o.fma:
            s += f", {o.fma} FMA"
        if o.div or o.sqrt:
            s += f", {o.div} div, {o.sqrt} sqrt"
        if o.libm:
            s += ", " + "+".join(sorted(o.libm))
        return s

    def eq(o):  # (mul, add, div, sqrt) with each FMA counted as one mul and one add
        return (o.mul + o.fma, o.add + o.fma, o.div, o.sqrt)

    def point_loop(rep):
        # outermost loop that contains a sqrt (|theta| per collocation point)
        cands = [r for r in rep if any(kk.endswith("sqrtsd") for kk in r["incl"])]
        return max(cands, key=lambda r: (sum(r["incl"].values()), -r["depth"])) if cands else None

    def sub_ops(x, y):
        return Ops(x.add - y.add, x.mul - y.mul, x.fma - y.fma, x.div - y.div, x.sqrt - y.sqrt,
                   tuple((collections.Counter(x.libm) - collections.Counter(y.libm)).elements()))

    def unroll(asm, body):
        """Integer k with asm == k * body (FMA = mul + add), else None."""
        a, b = eq(asm), eq(body)
        ref = b[0] or b[1]
        val = a[0] if b[0] else a[1]
        if not ref or val % ref or val == 0:
            return None
        kk = val // ref
        return kk if a == tuple(kk * x for x in b) else None

    def remainder(asm, static, body, kmax=8):
        """Remainder iterations ``r`` of an unrolled loop found in straight-line code:
        the ``r`` (0 <= r < kmax) for which ``static + r * body`` comes closest to
        ``asm`` in flops (within 2 flops; LLVM may fold a multiply)."""
        d = asm.flops - static.flops
        r = round(d / body.flops) if body.flops else 0
        return r if 0 < r < kmax and abs(d - r * body.flops) <= 2 else 0

    def negated(c):  # x -= m * y contracts to vfnmadd
        f = [kk for kk in c if re.match(r"v?f(n?m)", kk)]
        return bool(f) and all(re.match(r"v?fnm", kk) for kk in f)

    table = []  # (region, analytic static, asm, note)
    # ---- action_kernel (+ inlined _coef_ABCB1C1, _n_terms, _cross)
    rep, whole = res["action_kernel"]
    pl = point_loop(rep)
    if pl:
        hk = None
        for r in (r for r in rep if r["header"] in pl["inner"]):
            ao = asm_ops(r["incl"])
            for kind, label in (("band", "band matvec"), ("horner5", "Horner step of A,B,C,B1,C1")):
                kk = unroll(ao, model[("action", kind)])
                if kk:
                    hk = kk if kind == "horner5" else hk
                    table.append((f"action_kernel: inner loop ({label}), per asm iteration", model[("action", kind)],
                                  ao, f"unrolled x{kk}" + (f", runs W = {W} times" if kind == "band" else
                                                           "; trip count _n_terms - 1 (4, 6 or 11)")))
                    break
            else:
                table.append(("action_kernel: inner loop (unmatched)", None, ao, ""))
        line = asm_ops(pl["excl"])
        static = model[("action", "line")] + model[("action", "coef")]
        r = remainder(line, static, model[("action", "horner5")])
        note = f"calls: {', '.join(kk[5:] for kk in pl['excl'] if kk.startswith('call ')) or '-'}; " \
               "both coefficient branches static (closed form with libm calls)"
        if r:
            static = static + model[("action", "horner5")].scale(r)
            note += f"; includes {r} remainder Horner step{'s' if r > 1 else ''} of the x{hk} unrolled loop " \
                    "(runs when the step count is odd: 11 steps, not 4 or 6)"
        table.append(("action_kernel: per-point straight-line code (+ inlined _coef_ABCB1C1: t^2, closed form)",
                      static, line, note))
    # ---- rates_into (+ inlined _coef_D, _forward_row, _finish_solve)
    rep, whole = res["rates_into"]
    pl = point_loop(rep)
    if pl:
        extra, notes = Ops(), []
        for r in (r for r in rep if r["header"] in pl["inner"]):
            ao = asm_ops(r["incl"])
            for kind, label in (("band", "band matvec"), ("kvband", "Kelvin-Voigt band matvec (tau != 0 only)"),
                                ("sweep", "forward sweep entry (12 rhs)"), ("horner1", "Horner step of D")):
                if kind in ("kvband", "sweep") and negated(r["incl"]) != (kind == "sweep"):
                    continue
                kk = unroll(ao, model[("rates", kind)])
                if kk:
                    table.append((f"rates_into: inner loop ({label}), per asm iteration", model[("rates", kind)],
                                  ao, f"unrolled x{kk}"))
                    break
            else:
                if any(r["header"] in x["inner"] for x in rep if x["header"] in pl["inner"]):
                    continue
                extra = extra + ao
                notes.append(f"{fmt(ao)} in the loop over the ends")
        table.append(("rates_into: per-point straight-line code + loop over the ends (all branches: Kelvin-Voigt, "
                      "Neumann terms, loads, D closed form)", model[("rates", "line")], asm_ops(pl["excl"]) + extra,
                      "; ".join(notes) + "; LICM hoists R N out of the ends loop"))
        others = [r for r in rep if r["depth"] == 0 and r["header"] != pl["header"] and sum(r["incl"].values())]
        for r in others:
            ao = asm_ops(r["incl"])
            if eq(ao) == eq(model[("rates", "sweep_b")] + model[("rates", "pivot")]):
                table.append(("rates_into: backward sweep row (U entry 12 mul+sub, pivot 12 mul)",
                              model[("rates", "sweep_b")] + model[("rates", "pivot")], ao, "_finish_solve"))
            elif ao.mul + ao.fma > 50:
                table.append(("rates_into: dense M_c^-1 fallback (not used: banded)", None, ao,
                              "12 rhs x unrolled dot products"))
    # ---- the step work of advance_kernel
    forms = (("m = 1 form h (w0 K0)", Ops(mul=2)),
             ("m >= 2 form: first difference, total K0, h (outer part for m >= 3)", Ops(add=2, mul=3)),
             ("m >= 3: one more term w_l (K_l - K0)", Ops(add=2, mul=1)))
    if "_combine" in res:
        rep, whole = res["_combine"]
        for r in sorted(rep, key=lambda r: r["header"]):
            ao = asm_ops(r["excl"])
            if not (ao.mul or ao.add or ao.fma):
                continue
            for label, body in forms:
                kk = unroll(ao, body)
                if kk:
                    vec = packed_count(r["excl"])
                    table.append((f"_combine: loop ({label}; per increment component), per asm iteration", body, ao,
                                  f"unrolled x{kk}" + (f" ({vec} packed instructions: x{kk} = lanes x unroll)"
                                                       if vec else " (scalar)")))
                    break
            else:
                table.append(("_combine: loop (unmatched)", None, ao, ""))
    if "_newton_schulz" in res:
        rep, whole = res["_newton_schulz"]
        ao = asm_ops(whole)
        table.append(("_newton_schulz: per point (whole function)", model[("step", "ns")], ao,
                      "fastmath=False: no FMA"))
    if "rotation_angle_kernel" in res:
        rep, whole = res["rotation_angle_kernel"]
        pl = point_loop(rep)
        if pl:
            for r in (r for r in rep if r["header"] in pl["inner"]):
                ao = asm_ops(r["incl"])
                kk = unroll(ao, model[("step", "aband")])
                table.append(("rotation_angle_kernel: inner loop (band matvec), per asm iteration",
                              model[("step", "aband")], ao, f"unrolled x{kk}, runs W = {W} times" if kk else "unmatched"))
            line = asm_ops(pl["excl"])
            static = model[("step", "anorm")]
            r = remainder(line, static, model[("step", "aband")])
            note = "max as vmaxsd (not counted)"
            if r:
                static = static + model[("step", "aband")].scale(r)
                note += f"; includes {r} remainder iteration of the unrolled band loop"
            table.append(("rotation_angle_kernel: per-point rest (|.|, sqrt)", static, line, note))
    rep, whole = res["advance_kernel"]
    fin = [r for r in rep if r["depth"] > 0 and not any(kk.startswith("call ") for kk in r["incl"])
           and eq(asm_ops(r["incl"])) == eq(Ops(add=1))]
    for r in fin:
        table.append(("advance_kernel: inlined _all_finite loop, per entry", Ops(add=1), asm_ops(r["incl"]),
                      "isfinite(x) as x - x, vucomisd (12 entries per control point)"))
    own = asm_ops(whole)
    own = sub_ops(own, Ops(add=len(fin)))
    table.append(("advance_kernel: own code outside the callees (per step, not per point)", None, own,
                  "grid times t_start + (i + 1) dt, h = t_next - t, t + c_r h; h_min/h_max as vminsd/vmaxsd"))

    lines = ["| code region | analytic (static, one copy of the source) | asm (static count) | note |",
             "|---|---|---|---|"]
    for name, mo, ao, note in table:
        agree = ""
        kk = re.search(r"unrolled x(\d+)", note)
        if kk and mo is not None:
            mo = mo.scale(int(kk.group(1)))
            name = name.replace("per asm iteration", f"per asm iteration (= {kk.group(1)} source iterations)")
        if mo is not None and ao is not None:
            d = ao.flops - mo.flops
            if d:
                agree = f"; asm - analytic = {d:+d} flops" + (" (LLVM folds a multiply)" if d == -1 else "")
            elif eq(ao) == eq(mo) and ao.fma:
                agree = f"; identical ({ao.fma} mul+add pairs contracted into FMAs)"
            elif eq(ao) == eq(mo):
                agree = "; identical"
            else:
                agree = "; same flops, different mul/add split"
        lines.append(f"| {name} | {fmt(mo) if mo is not None else ''} | {fmt(ao) if ao is not None else ''} | "
                     f"{note}{agree} |")
    calls = collections.Counter()
    per_fn = []
    for s, (rep, whole) in res.items():
        per_fn.append(f"{s} {fma_count(whole)}/{packed_count(whole)}")
        for key, v in whole.items():
            if key.startswith("call "):
                calls[f"{s}: {key[5:]}"] += v
    nfma = sum(fma_count(w) for _, w in res.values())
    npk = sum(packed_count(w) for _, w in res.values())
    lines.append("")
    lines.append(f"FMA instructions (static) in the compile unit: **{nfma}**; packed (SIMD) FP arithmetic "
                 f"instructions: **{npk}**. Per function (FMA/packed): {', '.join(per_fn)}. "
                 "action_kernel and rates_into are compiled with fastmath={'contract'} (FMA, no reassociation, so "
                 "no vectorized reductions); the step functions keep fastmath=False (no FMA), but LLVM may still "
                 "vectorize loops without reassociation (elementwise _combine forms).")
    lines.append("Calls found (movabsq targets): " + ", ".join(f"{k} x{v}" for k, v in sorted(calls.items())))
    lines.append("Not cross-checked: dirichlet_rows (integer work, once per call), _set_loads / profile_value / "
                 "_interp (no time-dependent loads in this scene: 0 per stage), work-array allocation and the state "
                 "copies at the start of advance_kernel (no FP arithmetic).")
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


def noop_monitor(t, y, stats):
    """A per-step monitor that does nothing: ``integrate_fixed`` then takes its generic loop."""


def steps_for(pb, y, dt, batch_s):
    """Steps per timed batch of the fused run (>= ``batch_s`` CPU seconds, estimated)."""
    integrate_fixed(pb, TAB, (0.0, 2 * dt), y, dt)  # warm-up: compile / cache load
    integrate_fixed(pb, TAB, (0.0, 2 * dt), y, dt, monitor=noop_monitor)
    t0, k = CLOCK(), 0
    while CLOCK() - t0 < 0.03:
        integrate_fixed(pb, TAB, (0.0, 50 * dt), y, dt)
        k += 50
    return max(5, int(np.ceil(batch_s / max((CLOCK() - t0) / k, 1e-7))))


def time_step(pb, y, dt, N, repeats, monitor=None):
    """Best CPU seconds per step of ``integrate_fixed`` over ``N`` steps from ``y`` (one
    output time: the fused loop takes all ``N`` steps in one call unless ``monitor``)."""
    integrate_fixed(pb, TAB, (0.0, 2 * dt), y, dt, monitor=monitor)  # warm-up
    best, y_end = np.inf, None
    for _ in range(repeats):
        t0 = CLOCK()
        _, y_end, _ = integrate_fixed(pb, TAB, (0.0, N * dt), y, dt, monitor=monitor)
        best = min(best, (CLOCK() - t0) / N)
    return best, y_end


def stage_increment(pb, y, dt, variant="taylor"):
    """A stage increment ``u = h k``: ``taylor`` the realistic one (angles ~1e-7 rad: 5
    Horner terms); ``mid`` with collocation angles 0.4-0.5 rad (12 terms); ``closed``
    with angles 1.3-1.4 rad > ``TAYLOR_THRESHOLD`` (closed forms, libm calls)."""
    u = dt * pb.increment_rate(0.0, y, pb.zero_increment(y))
    if variant != "taylor":
        s = np.asarray(pb.space.curve.greville())
        s = s / s.max()
        u[1, :, 0] += (0.4 if variant == "mid" else 1.3) + 0.1 * s  # N0 is a partition of unity
    return np.ascontiguousarray(u)


_LOOPS = {}


def compiled_loops():
    """njit loops that call each piece of the fused step ``reps`` times from compiled code
    (no Python dispatch, no allocation): what ``advance_kernel`` pays per call."""
    if _LOOPS:
        return _LOOPS
    from numba import njit

    @njit(cache=False)
    def action(reps, u, c, v, w, R, K, Ks, c2, v2, w2, R2, K2, Ks2, sf, si):
        for _ in range(reps):
            kn.action_kernel(u, c, v, w, R, K, Ks, c2, v2, w2, R2, K2, Ks2, sf, si)

    @njit(cache=False)
    def rates(reps, c, v, w, R, K, Ks, u, sf, si, fixp, fixr, x, out, pw):
        for _ in range(reps):
            kn.rates_into(c, v, w, R, K, Ks, u, sf, si, fixp, fixr, x, out, pw)

    @njit(cache=False)
    def combine(reps, A, b, cc, Kf, h, uf):
        s = b.shape[0]
        for _ in range(reps):
            for r in range(1, s):
                combine_into(A[r], r, cc[r], Kf, h, uf)
            combine_into(b, s, 1.0, Kf, h, uf)

    @njit(cache=False)
    def newton_schulz(reps, R):
        for _ in range(reps):
            kn._newton_schulz(R)

    @njit(cache=False)
    def finite(reps, uf):
        k = 0
        for _ in range(reps):
            k += kn._all_finite(uf)
        return k

    @njit(cache=False)
    def angle(reps, u, sf, si):
        a = 0.0
        for _ in range(reps):
            a = max(a, kn.rotation_angle_kernel(u, sf, si))
        return a

    _LOOPS.update(action=action, rates=rates, combine=combine, newton_schulz=newton_schulz, finite=finite,
                  angle=angle)
    return _LOOPS


def time_kernels(pb, y, dt, batch_s, repeats, variant="taylor"):
    """Seconds per call of the compiled pieces (from compiled loops) for one stage
    increment ``variant``; with ``taylor`` also the step pieces, the separate
    ``solve_kernel`` and the Python wrappers of the generic loop."""
    L = compiled_loops()
    k = pb._nb
    n = k.n
    reps = max(8, 20000 // n)
    st, _ = fused_args(pb, y)
    sf, si = st.sf, st.si
    u = stage_increment(pb, y, dt, variant)
    ys = [np.ascontiguousarray(a, dtype=float) for a in (y.c, y.v, y.w, y.R, y.K, y.K_s)]
    outs = [np.empty_like(a) for a in ys]
    fixp, fixr = kn.dirichlet_rows(pb)
    x = np.empty((n, 12))
    out = np.empty((4, n, 3))
    zero = np.zeros((4, n, 3))

    def per_call(fn, *a):
        return best_of(lambda: fn(reps, *a), batch_s / 3, repeats) / reps

    res = {"action_kernel": per_call(L["action"], u, *ys, *outs, sf, si),
           "rates_into": per_call(L["rates"], *ys, u, sf, si, fixp, fixr, x, out, np.zeros(1))}
    if variant != "taylor":
        return res
    S = TAB.stages
    rng = np.random.default_rng(0)
    Kst = np.ascontiguousarray(1e-3 * rng.standard_normal((S, 4, n, 3)))
    Kf = Kst.reshape(S, 12 * n)
    uf = np.ascontiguousarray(u).reshape(12 * n)
    R = ys[3].copy()
    xs, x0 = np.array(u), np.array(u)
    res.update({
        "rates_into, u = 0": per_call(L["rates"], *ys, zero, sf, si, fixp, fixr, x, out, np.zeros(1)),
        "4 x _combine": per_call(L["combine"], st.A, st.b, st.c, Kf, dt, np.empty(12 * n)),
        "_newton_schulz": per_call(L["newton_schulz"], R),
        "_all_finite": per_call(L["finite"], uf),
        "rotation_angle_kernel": per_call(L["angle"], u, sf, si),
    })
    f = {
        "copy (for solve)": lambda: np.copyto(xs, x0),
        "copy + solve_kernel": lambda: (np.copyto(xs, x0), kn.solve_kernel(xs, k.sf, k.si)),
        "wrapper nb.action": lambda: pb.action(u, y),
        "wrapper nb.increment_rate": lambda: pb.increment_rate(dt, y, u),
    }
    res.update({name: best_of(fn, batch_s / 3, repeats) for name, fn in f.items()})
    res["solve_kernel"] = res["copy + solve_kernel"] - res["copy (for solve)"]
    return res


def time_call_cost(pb, y, dt, batch_s, repeats):
    """CPU seconds of one ``integrate_fixed`` call of a single fused step (driver, stepper
    construction, ``advance`` dispatch, work arrays and state copies, ``Advance``)."""
    return best_of(lambda: integrate_fixed(pb, TAB, (0.0, dt), y, dt), batch_s / 3, repeats)


def time_driver_pieces(pb, y, dt, batch_s, repeats):
    """Per-step cost of the NumPy/Python pieces of one generic-loop RKMK4 step (outside
    the kernels; not run by the fused loop)."""
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
    """Measured FP throughput of one core, GFLOP/s: scalar (fastmath=False, 16 independent
    mul+add chains), scalar FMA (fastmath={"contract"}, the same 16 chains contracted into
    scalar FMAs, as in the per-point kernels) and vector (fastmath=True, contracted into
    FMAs and vectorized)."""
    from numba import njit

    def chains(n, m, c):
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

    scalar = njit(cache=False, fastmath=False)(chains)
    scalar_fma = njit(cache=False, fastmath={"contract"})(chains)

    @njit(cache=False, fastmath=True)
    def vector(x, reps, m, c):
        # x: 256 doubles (L1); each pass is 256 independent FMAs
        for _ in range(reps):
            for j in range(x.shape[0]):
                x[j] = x[j] * m + c
        return x[0]

    N = 2_000_000
    out = []
    for f in (scalar, scalar_fma):
        f(10, 0.999, 1e-3)
        out.append(32 * N / best_of(lambda f=f: f(N, 0.999, 1e-3), 0.05, repeats, inner=3) / 1e9)
    x = np.ones(256)
    vector(x, 2, 0.999, 1e-3)
    reps = 20000
    tv = best_of(lambda: vector(x, reps, 0.999, 1e-3), 0.05, repeats, inner=3)
    return out[0], out[1], 2 * 256 * reps / tv / 1e9


# ====================================================================== 4. profile
def cprofile_fused(pb, y, dt, steps, calls):
    """cProfile of ``calls`` fused ``integrate_fixed`` calls of ``steps`` steps each:
    ``(total s, rows (own s, ncalls, name))``. The compiled loop is one entry
    (``advance_kernel``); everything else is per-call Python/NumPy overhead."""
    import cProfile
    import pstats

    integrate_fixed(pb, TAB, (0.0, 2 * dt), y, dt)
    prof = cProfile.Profile()
    prof.enable()
    for _ in range(calls):
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
    """Run whole fused steps for ``seconds`` (the py-spy sampling target)."""
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
    # attribute each sample: last Python frame + native leaf; JIT code has no symbols (0x...),
    # so everything compiled under FusedBeamStepper.advance is one group
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
        if pyfn.endswith("advance") and native and leaf.startswith("0x"):
            cat = "JIT code under FusedBeamStepper.advance (advance_kernel and its callees)"
            coarse["compiled fused step loop (JIT code)"] += cnt
        elif pyfn.endswith("advance") and native and leaf.startswith(("numba_", "NRT_")):
            cat = f"advance -> {leaf}"
            coarse["numba C helpers called from the compiled loop (array reshapes of the sf/si views that "
                   "_views builds in every kernel call, NRT allocation)"] += cnt
        elif pyfn.endswith("advance") and native:
            cat = f"advance -> {leaf}"
            coarse["advance: dispatch, unboxing, boxing of the result (native, not JIT)"] += cnt
        else:
            cat = f"{pyfn} -> {leaf}" if native else f"{pyfn} (Python)"
            coarse["Python driver per call (integrate_fixed, stepper construction, Advance, BeamState)"] += cnt
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
        print(f"py-spy record --native -r 997, n_ctrl {n}, fused steps (integrate_fixed of 200 steps per call): "
              f"{total} samples in the timed loop (JIT code has no symbols: a 0x... leaf under "
              "FusedBeamStepper.advance is compiled code of the fused loop)\n")
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
    S = TAB.stages
    print("# RKMK stage: flops, ns per point, flop-bound ratio (cantilever p=4, RKMK4, numba backend)")
    print(f"# python {platform.python_version()}, numpy {np.__version__}, numba {numba.__version__}, "
          f"llvm host cpu {numba.config.CPU_NAME or __import__('llvmlite.binding', fromlist=['x']).get_host_cpu_name()}, "
          f"{os.cpu_count()} cpus, BLAS threads {os.environ.get('OPENBLAS_NUM_THREADS', 'default')}, "
          f"load average {os.getloadavg()[0]:.2f}")
    print(f"# process CPU time, best of {repeats} batches >= {args.batch} s; clock for bounds {ghz} GHz; "
          "whole step = integrate_fixed, fused compiled loop (advance_kernel) unless stated")
    print()

    # ---------------------------------------------------------------- set-up + 1. flop model
    models = {}
    for n in sorted(set(sizes) | {31, 1001}):
        pb = make_problem(n)
        y = start_state(pb)
        dt = dt_of(n)
        N = steps_for(pb, y, dt, args.batch)  # steps of one timed batch (section 3)
        sv = angle_survey(pb, y, dt, N)
        models[n] = dict(pb=pb, y=y, dt=dt, N=N, survey=sv, rows=flop_model(pb, sv))
    print("## 1. Flop count of one stage per collocation point (analytic, from kernels_numba.py)\n")
    print("Angles met by the SO(3) coefficients in the timed run (replayed: same start state, dt and number of "
          "steps as one timed batch of section 3; every collocation point of every call; term count by "
          "kernels_numba._n_terms):\n")
    trs = []
    for n in sorted(models):
        m = models[n]
        for key, label in (("action", "action_kernel (A,B,C,B1,C1)"), ("rates", "rates_into (D)")):
            sv = m["survey"][key]
            trs.append([n, m["N"], f"{m['dt']:.3g}", label, sv["calls"], sv["points"], f"{sv['max']:.3g}"] +
                       [f"{100 * f:.3g}%" for f in sv["share"]] + [f"{sv['steps']:.3g}"])
    print(md_table(["n_ctrl", "steps", "dt", "kernel", "calls", "points", "max angle rad"] +
                   [f"{b}" for b in BRANCHES] + ["Horner steps / point"], trs))
    print()
    n_show = [n for n in (31, 1001) if n in models]
    head = ["kernel", "section", "ops per execution", "executions / point / stage"] + \
           [f"flops / point (n={n})" for n in n_show]
    trs = []
    rows0 = models[n_show[0]]["rows"]
    for i, (kern, sec, ops, ex, _) in enumerate(rows0):
        o = f"{ops.mul} mul + {ops.add} add" + (f" + {ops.div} div" if ops.div else "") + \
            (f" + {ops.sqrt} sqrt" if ops.sqrt else "") + (f" + {'/'.join(ops.libm)}" if ops.libm else "")
        exs = [models[n]["rows"][i][3] for n in n_show]
        exs = "; ".join(f"{e:.3g}" for e in exs) if len(set(exs)) > 1 else f"{ex:.3g}"
        trs.append([kern, sec, o, exs] +
                   [f"{models[n]['rows'][i][2].scale(models[n]['rows'][i][3]).flops:.1f}" for n in n_show])
    print(md_table(head, trs))
    print()
    summ = {}
    for n in sorted(models):
        per = summarize_model(models[n]["rows"])
        tot = Ops()
        for v in per.values():
            tot = tot + v
        sv = models[n]["survey"]
        libm = sv["action"]["share"][3] * len(CLOSED_ABCB1C1.libm) + sv["rates"]["share"][3] * len(CLOSED_D.libm)
        summ[n] = (per, tot, libm)
    head = ["n_ctrl"] + [f"{k} flops" for k in summ[n_show[0]][0]] + ["total flops / stage / point",
                                                                      "of which div+sqrt", "libm calls / point"]
    trs = []
    for n in sorted(summ):
        per, tot, libm = summ[n]
        trs.append([n] + [f"{v.flops:.1f}" for v in per.values()] +
                   [f"**{tot.flops:.1f}**", f"{tot.div + tot.sqrt:.2f}", f"{libm:.3g}"])
    print(md_table(head, trs))
    print("\nConventions: add/sub/mul/div/sqrt = 1 flop, FMA = 2 flops, so contraction does not change the count "
          "(section 2: each FMA LLVM forms in action_kernel and rates_into replaces one mul and one add); libm calls "
          "listed, not counted; comparisons (_n_terms, max, isfinite's vucomisd) not counted; common subexpressions "
          "counted once (as the compiler does); 'step' = work per control point per step inside the fused "
          "advance_kernel (compiled, fastmath=False), divided by the 4 stages. Horner rows: executions = mean Horner "
          "steps per point measured above (5 terms = 4 steps, 7 = 6, 12 = 11, closed form = 0).\n")

    # ---------------------------------------------------------------- 2. asm cross-check
    n0 = sizes[0]
    if not args.no_asm:
        m0 = models[n0]
        print(f"## 2. Cross-check against numba's generated assembly (advance_kernel compile unit, n_ctrl = {n0} "
              "specialization)\n")
        for line in asm_crosscheck(m0["pb"], m0["y"], m0["rows"]):
            print(line)
        print()

    # ---------------------------------------------------------------- 3. timing
    gs, gf, gv = calibrate(ghz, repeats)
    d15, d10 = dispatch_cost(args.batch, repeats)
    results = []
    for n in sizes:
        m = models[n]
        pb, y, dt, N = m["pb"], m["y"], m["dt"], m["N"]
        per, tot, _ = summ[n]
        kt = time_kernels(pb, y, dt, args.batch, repeats)
        km = time_kernels(pb, y, dt, args.batch, repeats, variant="mid")
        kb = time_kernels(pb, y, dt, args.batch, repeats, variant="closed")
        t_step, y_end = time_step(pb, y, dt, N, repeats)
        t_gen, y_gen = time_step(pb, y, dt, N, repeats, monitor=noop_monitor)
        t_call = time_call_cost(pb, y, dt, args.batch, repeats)
        dp = time_driver_pieces(pb, y, dt, args.batch, repeats)
        results.append(dict(n=n, N=N, per=per, tot=tot, kt=kt, km=km, kb=kb, dp=dp, step=t_step, gen=t_gen,
                            call=t_call, sub=subnormals(y_end) + subnormals(y_gen),
                            finite=bool(pb.is_finite(y_end) and pb.is_finite(y_gen)),
                            diff=max(float(np.max(np.abs(a - b)) / max(np.max(np.abs(a)), 1e-300)) for a, b in
                                     zip(y_end.arrays().values(), y_gen.arrays().values()))))
        print(f"#   n={n}: timed (load average {os.getloadavg()[0]:.2f})", flush=True)

    def pieces(kt):  # compiled step work besides the 4 actions and 4 rates, per step
        return kt["4 x _combine"] + kt["_newton_schulz"] + kt["_all_finite"] + kt["rotation_angle_kernel"]

    print("\n## 3. Time per stage per collocation point and flop rate\n")
    head = ["n_ctrl", "steps / timed call", "action_kernel ns/pt", "rates_into ns/pt", "  solve alone (solve_kernel) ns/pt",
            "step pieces ns/stage/pt (combine, Newton-Schulz, checks)", "**fused step** ns/stage/pt",
            "generic loop ns/stage/pt", "flops/stage/pt", "GFLOP/s (fused step)", "% of 4 flop/cyc (scalar FMA)",
            "% of 16 flop/cyc (AVX2 FMA)", "% of 2 flop/cyc (scalar, no FMA)", "GFLOP/s (generic loop)"]
    trs = []
    for r in results:
        n, kt, tot = r["n"], r["kt"], r["tot"]
        ns = r["step"] / (S * n) * 1e9
        gfl = tot.flops / ns
        trs.append([n, r["N"], f"{kt['action_kernel'] / n * 1e9:.1f}", f"{kt['rates_into'] / n * 1e9:.1f}",
                    f"{kt['solve_kernel'] / n * 1e9:.1f}", f"{pieces(kt) / (S * n) * 1e9:.1f}",
                    f"**{ns:.1f}**", f"{r['gen'] / (S * n) * 1e9:.1f}", f"{tot.flops:.0f}", f"{gfl:.2f}",
                    f"{100 * gfl / (4 * ghz):.1f}", f"{100 * gfl / (16 * ghz):.1f}", f"{100 * gfl / (2 * ghz):.1f}",
                    f"{tot.flops / (r['gen'] / (S * n) * 1e9):.2f}"])
    print(md_table(head, trs))
    print()
    head = ["n_ctrl", "action flops/pt", "action GFLOP/s", "rates flops/pt (incl. solve)", "rates GFLOP/s",
            "kernels-only ns/stage/pt", "kernels-only GFLOP/s", "% scalar-FMA peak", "% AVX2 peak",
            "% of measured scalar-FMA rate"]
    trs = []
    for r in results:
        n, kt, per = r["n"], r["kt"], r["per"]
        ta, tr = kt["action_kernel"] / n * 1e9, kt["rates_into"] / n * 1e9
        tk = ta + tr
        fk = per["action"].flops + per["rates"].flops
        trs.append([n, f"{per['action'].flops:.0f}", f"{per['action'].flops / ta:.2f}", f"{per['rates'].flops:.0f}",
                    f"{per['rates'].flops / tr:.2f}", f"{tk:.1f}", f"{fk / tk:.2f}", f"{100 * fk / tk / (4 * ghz):.1f}",
                    f"{100 * fk / tk / (16 * ghz):.1f}", f"{100 * fk / tk / gf:.1f}"])
    print(md_table(head, trs))
    print("\nKernel times: each piece called max(8, 20000 // n_ctrl) times per call of a compiled loop (no Python "
          "dispatch), same specialization as inside advance_kernel, inputs and outputs preallocated (cache-hot). "
          "'% of 2 flop/cyc' can exceed 100 % now that FMAs are generated.")
    print(f"Measured FP throughput of this core (micro-kernels, 16 independent chains): scalar mul+add without FMA "
          f"(fastmath=False) **{gs:.2f} GFLOP/s** = {gs / ghz:.2f} flop/cycle at {ghz} GHz; scalar FMA "
          f"(fastmath={{'contract'}}) **{gf:.2f} GFLOP/s** = {gf / ghz:.2f} flop/cycle (if the core retires 2 scalar "
          f"FMAs per cycle, its clock is {gf / 4:.2f} GHz, above the nominal {ghz} GHz); vectorized FMA "
          f"(fastmath=True, L1-resident) **{gv:.2f} GFLOP/s** = {gv / ghz:.2f} flop/cycle. "
          f"Theoretical at {ghz} GHz: scalar FMA {4 * ghz:.1f}, AVX2 FMA {16 * ghz:.1f} GFLOP/s.")
    print(f"All runs finite: {all(r['finite'] for r in results)}; subnormal entries in end states: "
          f"{sum(r['sub'] for r in results)}; largest |fused - generic| in the end states: "
          f"{max(r['diff'] for r in results):.2g} relative to the largest entry of each field (FMA round-off, "
          "grown over the steps).\n")

    # ---------------------------------------------------------------- 4. where the time goes
    print("## 4. Where the time goes\n")
    print("Fused step (integrate_fixed -> advance_kernel), us per step; pieces timed from compiled loops; "
          "'per-call set-up' = (one-step call - per-step time) / (1 - 1/N), spread over the N steps of a call.\n")
    head = ["n_ctrl", "fused step us", "4 x action_kernel", "4 x rates_into", "4 x _combine", "_newton_schulz",
            "_all_finite", "rotation angle", "compiled pieces total", "rest", "  of which per-call set-up / N",
            "  in-situ rest", "action + rates share", "pieces share"]
    trs = []
    for r in results:
        kt, N = r["kt"], r["N"]
        ker = S * (kt["action_kernel"] + kt["rates_into"])
        tot = ker + pieces(kt)
        rest = r["step"] - tot
        setup = (r["call"] - r["step"]) / (1 - 1 / N)
        r["setup"] = setup
        trs.append([r["n"], f"{r['step'] * 1e6:.1f}", f"{S * kt['action_kernel'] * 1e6:.1f}",
                    f"{S * kt['rates_into'] * 1e6:.1f}", f"{kt['4 x _combine'] * 1e6:.2f}",
                    f"{kt['_newton_schulz'] * 1e6:.2f}", f"{kt['_all_finite'] * 1e6:.2f}",
                    f"{kt['rotation_angle_kernel'] * 1e6:.2f}", f"{tot * 1e6:.1f}", f"{rest * 1e6:.1f}",
                    f"{setup / N * 1e6:.2f}", f"{(rest - setup / N) * 1e6:.1f}", f"{100 * ker / r['step']:.0f}%",
                    f"{100 * tot / r['step']:.0f}%"])
    print(md_table(head, trs))
    print()
    print("Per integrate_fixed call (fused): " + "; ".join(
        f"n_ctrl {r['n']}: one-step call {r['call'] * 1e6:.1f} us, set-up {r['setup'] * 1e6:.1f} us "
        f"(= {r['setup'] / r['step']:.2g} steps)" for r in results) +
        ". The set-up is the Python driver, compiled_stepper (FusedBeamStepper: copy of sf, tableau arrays), "
        "the advance_kernel dispatch (19 arguments), its work arrays and state copies, Advance and BeamState.\n")
    print("Generic loop (same driver with a no-op monitor: Python step loop, NumPy combinations and end step), "
          "us per step:\n")
    keys = list(results[0]["dp"])
    head = ["n_ctrl", "generic step us", "fused step us", "generic / fused",
            "kernels (4 action + 4 rates + angle, compiled)", "wrappers over kernels (alloc + state + dispatch)"] + \
           [f"{k} us" for k in keys] + ["Python rest"]
    trs = []
    for r in results:
        kt = r["kt"]
        ker = S * (kt["action_kernel"] + kt["rates_into"]) + kt["rotation_angle_kernel"]
        wrap = S * (kt["wrapper nb.action"] - kt["action_kernel"] + kt["wrapper nb.increment_rate"] - kt["rates_into"])
        rest = r["gen"] - ker - wrap - sum(r["dp"].values())
        trs.append([r["n"], f"{r['gen'] * 1e6:.1f}", f"{r['step'] * 1e6:.1f}", f"{r['gen'] / r['step']:.2f}",
                    f"{ker * 1e6:.1f}", f"{wrap * 1e6:.1f}"] + [f"{r['dp'][k] * 1e6:.1f}" for k in keys] +
                   [f"{rest * 1e6:.1f}"])
    print(md_table(head, trs))
    print(f"\nEmpty numba call with 15 / 10 array arguments (dispatch + unboxing): {d15 * 1e6:.2f} / {d10 * 1e6:.2f} us "
          "(generic loop: per action / stage-rate call; fused loop: once per integrate_fixed call, advance_kernel "
          "takes 19 arguments).\n")
    head = ["n_ctrl", "action 5 terms ns/pt", "action 12 terms ns/pt", "action closed form ns/pt",
            "rates 5 terms ns/pt", "rates 12 terms ns/pt", "rates closed form ns/pt", "rates with u = 0 ns/pt",
            "copy+solve us", "copy us"]
    trs = []
    for r in results:
        n, kt, km, kb = r["n"], r["kt"], r["km"], r["kb"]
        trs.append([n] + [f"{d[k] / n * 1e9:.1f}" for k in ("action_kernel", "rates_into") for d in (kt, km, kb)] +
                   [f"{kt['rates_into, u = 0'] / n * 1e9:.1f}", f"{kt['copy + solve_kernel'] * 1e6:.2f}",
                    f"{kt['copy (for solve)'] * 1e6:.2f}"])
    print(md_table(head, trs))
    print("\n(5 terms: the angles of the run; 12 terms: every collocation angle 0.4-0.5 rad, 35 more FMAs per point "
          "in the action's 5 chains and 7 in D, 7 more dependent steps each; closed form: 1.3-1.4 rad, libm calls.)")
    if len(results) >= 2:
        ns_ = np.array([r["n"] for r in results], float)
        print()
        for key in ("action_kernel", "rates_into", "solve_kernel", "rotation_angle_kernel", "4 x _combine",
                    "_newton_schulz"):
            t = np.array([r["kt"][key] for r in results])
            b, a = np.polyfit(ns_, t, 1)
            print(f"- {key}: fixed cost per call {a * 1e6:.2f} us + {b * 1e9:.1f} ns per point (linear fit over n_ctrl)")
        fixed = 0.0
        for key, k in (("action_kernel", S), ("rates_into", S), ("rotation_angle_kernel", 1)):
            fixed += k * np.polyfit(ns_, np.array([r["kt"][key] for r in results]), 1)[1]
        print(f"- fixed per-call costs of the kernel calls of one step (4 action, 4 rates, 1 angle; each call "
              f"unpacks sf/si in _views, with array reshapes): {fixed * 1e6:.1f} us per step")
        for key, label in (("step", "fused step"), ("gen", "generic-loop step")):
            t = np.array([r[key] for r in results])
            b, a = np.polyfit(ns_, t, 1)
            print(f"- {label}: {a * 1e6:.1f} us fixed + {b * 1e9:.0f} ns per point per step "
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
        # advance_kernel: 3 states (24 each), stage rates K (12 S), u, zero, x (12 each), band, LU, geo
        ws = 8 * n * (3 * 24 + 12 * (S + 3) + 3 * W + 7 + 9)
        print(f"- n_ctrl {n}: working set of the fused loop ~{ws / 1024:.0f} KiB -> "
              f"{'L1d (48 KiB)' if ws < 44 * 1024 else ('L2 (2 MiB)' if ws < 1.8 * 2**20 else 'L3')}; "
              f"{(act + rat) / ((r['kt']['action_kernel'] + r['kt']['rates_into']) / n * 1e9):.1f} GB/s "
              "while in the kernels")
    print()
    for n in ([31, 1001] if not args.quick else [31]):
        m = models[n]
        calls = 10
        total, prow = cprofile_fused(m["pb"], m["y"], m["dt"], m["N"], calls)
        print(f"cProfile, n_ctrl {n}, {calls} fused integrate_fixed calls of {m['N']} steps (own time per function "
              f"per call, share of the profiled total; cProfile inflates Python-call costs):\n")
        print(md_table(["function", "calls per integrate_fixed call", "own us per call", "share"],
                       [[name, f"{nc / calls:.3g}", f"{tt / calls * 1e6:.1f}", f"{100 * tt / total:.1f}%"]
                        for tt, nc, name in prow[:8]]))
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
