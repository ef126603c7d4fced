"""The assembly flop counter of ``liegroup_int.bench.asm_flops`` on small listings."""

import numpy as np
from numba import njit

from liegroup_int.bench.asm_flops import basic_blocks, count_ops, kernel_count, natural_loops, short_name


def test_count_ops_weights_fma_and_packed_lanes():
    ops = count_ops(["vfmadd231sd %xmm1, %xmm2, %xmm3", "vmulpd %ymm0, %ymm1, %ymm2", "vsubsd %xmm0, %xmm1, %xmm2",
                     "vaddpd %xmm0, %xmm1, %xmm2", "vdivsd %xmm0, %xmm1, %xmm2", "vsqrtsd %xmm0, %xmm0, %xmm0",
                     "callq sin", "movq %rax, %rbx"])
    # one FMA (2 flops), a 4-lane multiply, one sub plus a 2-lane add, a division, a root
    assert (ops.fma, ops.mul, ops.add, ops.div, ops.sqrt, ops.libm, ops.packed) == (1, 4, 3, 1, 1, ("sin",), 2)
    assert ops.flops == 2 + 4 + 3 + 1 + 1


def test_natural_loops_of_a_nested_loop():
    asm = """
    movq $0, %rax
.LBB0_1:
    vaddsd %xmm0, %xmm1, %xmm1
.LBB0_2:
    vmulsd %xmm0, %xmm1, %xmm1
    cmpq %rax, %rbx
    jne .LBB0_2
    incq %rax
    cmpq %rax, %rcx
    jne .LBB0_1
    retq
"""
    blocks, succ = basic_blocks(asm.splitlines())
    loops = sorted(natural_loops(succ), key=len)
    assert len(loops) == 2 and loops[0] < loops[1]
    inner = count_ops([s for i in loops[0] for s in blocks[i]])
    outer = count_ops([s for i in loops[1] for s in blocks[i]])
    assert (inner.mul, inner.add, outer.mul, outer.add) == (1, 0, 1, 1)


def test_kernel_count_of_a_compiled_loop():
    @njit(fastmath={"contract"})
    def axpy(a, x, y):
        for i in range(x.shape[0]):
            y[i] = a * x[i] + y[i]

    x = np.ones(8)
    kc = kernel_count("axpy", axpy, (2.0, x, x.copy()))
    # a multiply-add per element: one contracted FMA or a mul and an add, possibly
    # vectorized (lanes counted) and unrolled; at least 2 flops per iteration either way
    assert kc.per_point.flops >= 2 and kc.per_point.libm == ()


def test_short_name_reads_the_last_mangled_component():
    assert short_name("_ZN12liegroup_int8problems4beam13kernels_numba10rates_intoB2v7B70c8tJTI") == "rates_into"
    assert short_name("cfunc.xyz") == "cfunc.xyz"
