"""Floating-point operation counts read from the machine code numba compiles.

A flop model derived from the compiled code, not from its source: :func:`kernel_count`
compiles a fresh copy of an engine kernel (``numba.njit`` over its Python function with
the kernel's own options; machine code loaded from numba's cache cannot be inspected),
takes its assembly (the kernel and every callee compiled into its module), splits it into
functions, basic blocks and natural loops (dominators, back edges) and counts the
floating-point arithmetic instructions of x86-64 (``v{add,sub,mul,div,sqrt}{s,p}{d,s}``,
``vf{,n}m{add,sub}*``; a packed instruction weighted by its lanes, an FMA as 2 flops) and
the libm calls.

The counts are static: every basic block of a loop nest counts once, so a branch not
taken is counted (an over-count) and an inner loop's body counts once whatever its trip
count (an under-count). For a kernel whose work is a loop over collocation points, the
sum over the top-level loop nests is the model's flops per point (:attr:`KernelCount.per_point`),
and the code outside loops its fixed cost per call.
"""

from __future__ import annotations

import re
from typing import NamedTuple

FP_RE = re.compile(r"^(v?(?:add|sub|mul|div|sqrt)(?:s|p)(?:d|s)|v?f(?:n?m)(?:add|sub)\d*(?:s|p)(?:d|s))\b")
CALL_RE = re.compile(r"^callq\s+([A-Za-z_][\w.]*)")
LIBM = frozenset({"sin", "cos", "sincos", "tan", "pow", "exp", "log", "atan", "atan2", "fmod"})


class Ops(NamedTuple):
    """Operation counts: ``add`` includes subtractions; ``fma`` instructions count 2 flops;
    ``libm`` calls are listed apart (not flops); ``packed`` counts SIMD instructions."""

    add: int = 0
    mul: int = 0
    fma: int = 0
    div: int = 0
    sqrt: int = 0
    libm: tuple = ()
    packed: int = 0

    def __add__(self, o: Ops) -> Ops:
        return Ops(self.add + o.add, self.mul + o.mul, self.fma + o.fma, self.div + o.div, self.sqrt + o.sqrt,
                   self.libm + o.libm, self.packed + o.packed)

    @property
    def flops(self) -> int:
        return self.add + self.mul + 2 * self.fma + self.div + self.sqrt


class LoopNest(NamedTuple):
    """A top-level loop nest of one function: its flops per outer iteration (every block once)."""

    function: str
    blocks: int
    ops: Ops


class KernelCount(NamedTuple):
    """The counts of one compiled kernel: per call outside loops, and per top-level loop nest."""

    name: str
    straight: Ops
    nests: tuple

    @property
    def per_point(self) -> Ops:
        """Sum of the top-level loop nests (the model's work per collocation point)."""
        total = Ops()
        for n in self.nests:
            total = total + n.ops
        return total


def short_name(symbol: str) -> str:
    """The function's own name in a mangled numba symbol (``_ZN...10rates_intoB2v7...``:
    ``rates_into``), or the symbol itself."""
    if not symbol.startswith("_ZN"):
        return symbol
    i, name = 3, symbol
    while i < len(symbol) and symbol[i].isdigit():
        j = i
        while symbol[j].isdigit():
            j += 1
        length = int(symbol[i:j])
        name, i = symbol[j:j + length], j + length
    return name


def count_ops(instrs: list[str]) -> Ops:
    """Flop counts of a list of instructions (one instruction per string, no indent)."""
    c = {"add": 0, "sub": 0, "mul": 0, "div": 0, "sqrt": 0, "fma": 0}
    libm, packed = [], 0
    for s in instrs:
        m = FP_RE.match(s)
        if m:
            mn = m.group(1)
            lanes = 1
            if re.search(r"p[ds]$", mn):
                packed += 1
                lanes = 8 if "%zmm" in s else (4 if "%ymm" in s else 2)
                lanes *= 1 if mn.endswith("d") else 2
            op = "fma" if mn.lstrip("v").startswith("f") else re.match(r"v?(add|sub|mul|div|sqrt)", mn).group(1)
            c[op] += lanes
            continue
        m = CALL_RE.match(s)
        if m and m.group(1) in LIBM:
            libm.append(m.group(1))
    return Ops(c["add"] + c["sub"], c["mul"], c["fma"], c["div"], c["sqrt"], tuple(libm), packed)


def asm_functions(text: str) -> dict[str, list[str]]:
    """``{symbol: instruction lines}`` of an assembly listing."""
    funcs, cur = {}, None
    for line in text.splitlines():
        m = re.match(r"^([A-Za-z_][\w.$]*):\s*$", line)
        if m:
            cur = funcs.setdefault(m.group(1), [])
        elif line.startswith(".Lfunc_end"):
            cur = None
        elif cur is not None:
            cur.append(line)
    return funcs


def annotate_calls(lines: list[str]) -> list[str]:
    """``callq *%reg`` as ``callq <name>``, from the last ``movabsq $name, %reg``."""
    reg, out = {}, []
    for line in lines:
        m = re.search(r"movabsq\s+\$([A-Za-z_][\w.]*),\s*(%\w+)", line)
        if m:
            reg[m.group(2)] = m.group(1)
        m = re.match(r"^(\s+)callq\s+\*(%\w+)\s*$", line)
        if m and m.group(2) in reg:
            line = f"{m.group(1)}callq {reg[m.group(2)]}"
        out.append(line)
    return out


def basic_blocks(lines: list[str]) -> tuple[list[list[str]], list[set]]:
    """Instruction lists of the basic blocks and each block's successors."""
    blocks, labels, cur, label = [], [], [], "<entry>"
    for line in lines:
        s = line.strip()
        m = re.match(r"^(\.L\w+):", s)
        if m:
            if cur or blocks or label != "<entry>":
                blocks.append(cur)
                labels.append(label)
            cur, label = [], m.group(1)
            continue
        if not s or s.startswith("#") or s.startswith("."):
            continue
        cur.append(s)
        if re.match(r"^(j\w+|ret\w*|ud2)\b", s):
            blocks.append(cur)
            labels.append(label)
            cur, label = [], None
    blocks.append(cur)
    labels.append(label)
    index = {lab: i for i, lab in enumerate(labels) if lab}
    succ = []
    for i, ins in enumerate(blocks):
        last, nxt = (ins[-1] if ins else ""), set()
        m = re.match(r"^j\w+\s+(\.L\w+)", last)
        if m and m.group(1) in index:
            nxt.add(index[m.group(1)])
        if not re.match(r"^(jmp|ret|ud2)", last) and i + 1 < len(blocks):
            nxt.add(i + 1)
        succ.append(nxt)
    return blocks, succ


def dominators(succ: list[set]) -> dict[int, set]:
    """Dominator sets of the blocks reachable from block 0."""
    pred = [set() for _ in succ]
    for a, ss in enumerate(succ):
        for b in ss:
            pred[b].add(a)
    reach, stack = {0}, [0]
    while stack:
        for b in succ[stack.pop()]:
            if b not in reach:
                reach.add(b)
                stack.append(b)
    dom = {a: set(reach) for a in reach}
    dom[0] = {0}
    changed = True
    while changed:
        changed = False
        for a in sorted(reach - {0}):
            new = set.intersection(*[dom[p] for p in pred[a] if p in reach]) | {a}
            if new != dom[a]:
                dom[a], changed = new, True
    return dom


def natural_loops(succ: list[set]) -> list[set]:
    """Block sets of the natural loops (a back edge ``a -> h`` with ``h`` dominating ``a``;
    loops sharing a header merged)."""
    dom = dominators(succ)
    pred = [set() for _ in succ]
    for a, ss in enumerate(succ):
        for b in ss:
            pred[b].add(a)
    loops: dict[int, set] = {}
    for a in dom:
        for h in succ[a]:
            if h in dom[a]:
                body, stack = {h, a}, [a]
                while stack:
                    x = stack.pop()
                    for p in pred[x] if x != h else ():
                        if p in dom and p not in body:
                            body.add(p)
                            stack.append(p)
                loops.setdefault(h, set()).update(body)
    return list(loops.values())


def function_count(name: str, lines: list[str]) -> tuple[Ops, list[LoopNest]]:
    """Flops of one function outside its loops, and of each top-level loop nest."""
    blocks, succ = basic_blocks(annotate_calls(lines))
    loops = natural_loops(succ)
    top = [b for b in loops if not any(b < o for o in loops)]
    inside = set().union(*top) if top else set()
    straight = count_ops([s for i, ins in enumerate(blocks) if i not in inside for s in ins])
    nests = [LoopNest(name, len(b), count_ops([s for i in sorted(b) for s in blocks[i]])) for b in top]
    return straight, [n for n in nests if n.ops.flops or n.ops.libm]


def compile_fresh(kernel, args: tuple):
    """A copy of the numba kernel compiled now for ``args`` (no cache): ``(copy, signature)``."""
    import numba

    options = {k: v for k, v in kernel.targetoptions.items() if k not in ("cache", "nopython")}
    fresh = numba.njit(**options)(kernel.py_func)
    sig = tuple(numba.typeof(a) for a in args)
    fresh.compile(sig)
    return fresh, fresh.signatures[0]


def kernel_count(name: str, kernel, args: tuple) -> KernelCount:
    """:class:`KernelCount` of ``kernel`` compiled for ``args`` (its whole compile unit)."""
    fresh, sig = compile_fresh(kernel, args)
    straight, nests = Ops(), []
    for fname, lines in asm_functions(fresh.inspect_asm(sig)).items():
        if fname.startswith("cfunc.") or fname.startswith("_ZN7cpython"):
            continue  # the Python and C-callable wrappers
        s, n = function_count(fname, lines)
        straight, nests = straight + s, nests + n
    return KernelCount(name, straight, tuple(nests))


def engine_args(cp, y) -> dict[str, tuple]:
    """Arguments of the engine's ``rate`` and ``action`` kernels of a compiled problem
    (:class:`~liegroup_int.integrators.engine.CompiledProblem`) at the state ``y``, zero
    increment."""
    import numpy as np

    from ..integrators.engine import FunctionValue

    k, flat = cp.kernels, cp.pack(y)
    # the functions the loops call through their addresses, as dispatchers: compiled into
    # the kernel, so that its compile unit holds their code
    data = tuple(x.fn if isinstance(x, FunctionValue) else x for x in cp.data)
    m = cp.increment_size(flat)
    # the views and the new state from the kernels' Python functions: compiled for data that
    # hold dispatchers, they would enter numba's disk cache with types that do not pickle
    view = getattr(k.increment_view, "py_func", k.increment_view) or (lambda data, a: a)
    u, out = view(data, np.zeros(m)), view(data, np.zeros(m))
    new_state = getattr(k.new_state, "py_func", k.new_state)
    y_out = new_state(data, flat) if new_state is not None else np.empty_like(flat)
    return {"rate": (data, 0.0, flat, u, out), "action": (data, u, flat, y_out)}
