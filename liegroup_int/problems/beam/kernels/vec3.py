"""Inline 3-vector and 3x3 helpers of the beam kernels: vectors are 3-tuples of floats.

Each helper is compiled once, as a small function that LLVM inlines into the calling
kernel (their machine code is linked into the kernel's module), so it costs no call. They
are not inlined earlier, in numba's IR (``inline="always"``): that made every kernel
compile each use anew, 5 s more for the Galerkin stage rate, at the same step cost
(``benchmarks/formulation_cost.py``). Their arithmetic is strict IEEE (no fast-math flags),
whatever the caller's flags.
"""

from __future__ import annotations

import math

from numba import njit


@njit(cache=True)
def cross(a, b):
    """``a x b``."""
    return a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]


@njit(cache=True)
def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(cache=True)
def add(a, b):
    return a[0] + b[0], a[1] + b[1], a[2] + b[2]


@njit(cache=True)
def sub(a, b):
    return a[0] - b[0], a[1] - b[1], a[2] - b[2]


@njit(cache=True)
def neg(a):
    return -a[0], -a[1], -a[2]


@njit(cache=True)
def scale(s, a):
    """``s a`` for a scalar ``s``."""
    return s * a[0], s * a[1], s * a[2]


@njit(cache=True)
def axpy(s, a, b):
    """``b + s a``."""
    return b[0] + s * a[0], b[1] + s * a[1], b[2] + s * a[2]


@njit(cache=True)
def mul(a, b):
    """Componentwise ``a * b`` (a diagonal matrix times a vector)."""
    return a[0] * b[0], a[1] * b[1], a[2] * b[2]


@njit(cache=True)
def div(a, b):
    """Componentwise ``a / b``."""
    return a[0] / b[0], a[1] / b[1], a[2] / b[2]


@njit(cache=True)
def wdot(c, a):
    """``a . diag(c) a``."""
    return c[0] * a[0] * a[0] + c[1] * a[1] * a[1] + c[2] * a[2] * a[2]


@njit(cache=True)
def row(A, i):
    """``A[i, 0:3]`` of an ``(n, 3)`` array."""
    return A[i, 0], A[i, 1], A[i, 2]


@njit(cache=True)
def put(A, i, a):
    """``A[i, 0:3] = a``."""
    A[i, 0], A[i, 1], A[i, 2] = a[0], a[1], a[2]


@njit(cache=True)
def put_at(A, i, q, a):
    """``A[i, q:q+3] = a``."""
    A[i, q], A[i, q + 1], A[i, q + 2] = a[0], a[1], a[2]


@njit(cache=True)
def col(A, q, i):
    """``A[q:q+3, i]`` of a ``(rows, m)`` array of per-point values stored by rows."""
    return A[q, i], A[q + 1, i], A[q + 2, i]


@njit(cache=True)
def put_col(A, q, i, a):
    """``A[q:q+3, i] = a``."""
    A[q, i], A[q + 1, i], A[q + 2, i] = a[0], a[1], a[2]


@njit(cache=True)
def rot(R, i, a):
    """``R[i] a`` of an ``(n, 3, 3)`` array of rotations."""
    return (R[i, 0, 0] * a[0] + R[i, 0, 1] * a[1] + R[i, 0, 2] * a[2],
            R[i, 1, 0] * a[0] + R[i, 1, 1] * a[1] + R[i, 1, 2] * a[2],
            R[i, 2, 0] * a[0] + R[i, 2, 1] * a[1] + R[i, 2, 2] * a[2])


@njit(cache=True)
def rot_T(R, i, a):
    """``R[i]^T a``."""
    return (R[i, 0, 0] * a[0] + R[i, 1, 0] * a[1] + R[i, 2, 0] * a[2],
            R[i, 0, 1] * a[0] + R[i, 1, 1] * a[1] + R[i, 2, 1] * a[2],
            R[i, 0, 2] * a[0] + R[i, 1, 2] * a[1] + R[i, 2, 2] * a[2])


@njit(cache=True)
def norm(a):
    return math.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])


# symmetric 3x3 matrices as 6-tuples (s00, s01, s02, s11, s12, s22)
@njit(cache=True)
def inertia(R, i, J):
    """The spatial inertia ``R[i] diag(J) R[i]^T`` (symmetric); its rows taken here, so no
    helper is called with constant indices (numba compiles a copy per constant)."""
    r0, r1, r2 = (R[i, 0, 0], R[i, 0, 1], R[i, 0, 2]), (R[i, 1, 0], R[i, 1, 1], R[i, 1, 2]), \
        (R[i, 2, 0], R[i, 2, 1], R[i, 2, 2])
    j0, j1, j2 = mul(J, r0), mul(J, r1), mul(J, r2)
    return dot(j0, r0), dot(j0, r1), dot(j0, r2), dot(j1, r1), dot(j1, r2), dot(j2, r2)


@njit(cache=True)
def sym_times(S, a):
    return (S[0] * a[0] + S[1] * a[1] + S[2] * a[2], S[1] * a[0] + S[3] * a[1] + S[4] * a[2],
            S[2] * a[0] + S[4] * a[1] + S[5] * a[2])


@njit(cache=True)
def sym_add(S, T):
    return S[0] + T[0], S[1] + T[1], S[2] + T[2], S[3] + T[3], S[4] + T[4], S[5] + T[5]


@njit(cache=True)
def sym_solve(S, b):
    """``S^-1 b`` by cofactors."""
    s00, s01, s02, s11, s12, s22 = S
    c00, c01, c02 = s11 * s22 - s12 * s12, s02 * s12 - s01 * s22, s01 * s12 - s02 * s11
    c11, c12, c22 = s00 * s22 - s02 * s02, s01 * s02 - s00 * s12, s00 * s11 - s01 * s01
    det = s00 * c00 + s01 * c01 + s02 * c02
    return scale(1.0 / det, sym_times((c00, c01, c02, c11, c12, c22), b))
