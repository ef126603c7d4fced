"""Compiled (numba) single-point kernels of the built-in groups, twins of the NumPy API.

For one point (no batch axes) of ``Rn``, ``SO3``, ``SE3`` and products and powers of them,
the RKMK contract needs ``retract(u, y) = exp(u) y``, ``dexpinv_u(w)``, the rotation angle
of an increment and the error-norm magnitude of a point. Through NumPy each costs tens of
microseconds of array machinery for a handful of flops; these kernels work on the flat
point (``y.reshape(-1)``) and algebra vectors in one call each.

A space is described by a factor table (:func:`factor_table`): one row ``(kind, point
offset, algebra offset, size)`` per factor, ``kind`` one of :data:`KIND_RN`,
:data:`KIND_SO3`, :data:`KIND_SE3`. Points are stored like the NumPy API stores them
(``SO3``: the 9 entries of ``R`` row by row; ``SE3``: the 16 entries of the 4x4 matrix).

The SO(3) coefficients use the branch logic of :mod:`.so3_coefficients`: its 12-term Taylor
polynomials (passed at run time as ``ser``, :func:`series_table`, so numba's cache never
freezes them) below ``TAYLOR_THRESHOLD``, the closed forms above. The polynomials stop at
the first term below ``1e-20`` relative (:func:`_n_terms`). These are the compiled SO(3)
coefficients of the package: every compiled kernel that needs them (the beam's too) calls
:func:`coefficients`, :func:`coef_ABC`, :func:`coef_ABCB1C1` or :func:`coef_D`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .so3_coefficients import TAYLOR, TAYLOR_THRESHOLD

KIND_RN, KIND_SO3, KIND_SE3 = 0, 1, 2
_KEYS = ("A", "B", "C", "D", "E", "F", "B1", "C1")
_IA, _IB, _IC, _ID, _IB1, _IC1 = 0, 1, 2, 3, 6, 7


def series_table() -> np.ndarray:
    """Float Taylor coefficients ``(8, N_TERMS)`` of A, B, C, D, E, F, B1, C1 (in that order)."""
    return np.array([[float(c) for c in TAYLOR[k]] for k in _KEYS])


def factor_table(space) -> np.ndarray | None:
    """``(n_factors, 4)`` int64 rows ``(kind, point offset, algebra offset, size)``, or
    ``None`` when ``space`` holds a group without compiled kernels."""
    from .product import Power, Product
    from .rn import Rn
    from .se3 import SE3
    from .so3 import SO3

    rows: list[tuple[int, int, int, int]] = []

    def add(g, p, a) -> tuple[int, int] | None:
        if isinstance(g, Rn):
            rows.append((KIND_RN, p, a, g.dim))
            return p + g.dim, a + g.dim
        if g is SO3:
            rows.append((KIND_SO3, p, a, 3))
            return p + 9, a + 3
        if g is SE3:
            rows.append((KIND_SE3, p, a, 6))
            return p + 16, a + 6
        if isinstance(g, Product):
            for f in g.factors:
                nxt = add(f, p, a)
                if nxt is None:
                    return None
                p, a = nxt
            return p, a
        if isinstance(g, Power):
            for _ in range(g.n):
                nxt = add(g.group, p, a)
                if nxt is None:
                    return None
                p, a = nxt
            return p, a
        return None

    if add(space, 0, 0) is None:
        return None
    return np.array(rows, dtype=np.int64).reshape(-1, 4)


# ====================================================================== scalar helpers
@njit(cache=True, inline="always")
def _n_terms(t2, m):
    """Series terms needed below 1e-20 relative truncation: 5 for t < 0.05 rad, 7 for
    t < 0.25 rad (largest dropped term ~t^(2k) / (2k + 1)!), all ``m`` otherwise."""
    if t2 < 2.5e-3:
        return min(5, m)
    if t2 < 6.25e-2:
        return min(7, m)
    return m


@njit(cache=True, inline="always")
def _series(ser, k, t2):
    m = _n_terms(t2, ser.shape[1])
    out = ser[k, m - 1]
    for j in range(m - 2, -1, -1):
        out = out * t2 + ser[k, j]
    return out


@njit(cache=True, inline="always")
def _coef_AB(t, ser, thr):
    """``(A, B)`` alone (the SO(3) exponential), same branches and formulas as
    :func:`coefficients`."""
    if t < thr:
        t2 = t * t
        return _series(ser, _IA, t2), _series(ser, _IB, t2)
    sh = math.sin(0.5 * t) / t
    return math.sin(t) / t, 2.0 * sh * sh


@njit(cache=True, inline="always")
def coef_ABC(t, ser, thr):
    """``(A, B, C)``: the SO(3) exponential and ``J_r``. The Horner recurrences run in one
    loop (independent chains, same arithmetic per chain as :func:`_series`), which hides
    their latency."""
    if t < thr:
        t2 = t * t
        m = _n_terms(t2, ser.shape[1])
        a, b, c = ser[_IA, m - 1], ser[_IB, m - 1], ser[_IC, m - 1]
        for j in range(m - 2, -1, -1):
            a = a * t2 + ser[_IA, j]
            b = b * t2 + ser[_IB, j]
            c = c * t2 + ser[_IC, j]
        return a, b, c
    s = math.sin(t)
    sh = math.sin(0.5 * t) / t
    return s / t, 2.0 * sh * sh, (t - s) / (t * t * t)


@njit(cache=True, inline="always")
def coef_ABCB1C1(t, ser, thr):
    """``(A, B, C, B1, C1)`` with ``B1 = B'/t``, ``C1 = C'/t`` (the s-derivative of
    ``J_r(theta) theta_s``); one loop of five chains, as :func:`coef_ABC`."""
    if t < thr:
        t2 = t * t
        m = _n_terms(t2, ser.shape[1])
        a, b, c, b1, c1 = ser[_IA, m - 1], ser[_IB, m - 1], ser[_IC, m - 1], ser[_IB1, m - 1], ser[_IC1, m - 1]
        for j in range(m - 2, -1, -1):
            a = a * t2 + ser[_IA, j]
            b = b * t2 + ser[_IB, j]
            c = c * t2 + ser[_IC, j]
            b1 = b1 * t2 + ser[_IB1, j]
            c1 = c1 * t2 + ser[_IC1, j]
        return a, b, c, b1, c1
    s, co = math.sin(t), math.cos(t)
    sh = math.sin(0.5 * t) / t
    t2 = t * t
    return (s / t, 2.0 * sh * sh, (t - s) / (t2 * t), (t * s + 2.0 * co - 2.0) / (t2 * t2),
            (3.0 * s - 2.0 * t - t * co) / (t2 * t2 * t))


@njit(cache=True, inline="always")
def coef_D(t, ser, thr):
    """``D = (1 - (t/2) cot(t/2)) / t^2`` alone (the SO(3) dexpinv), same branches and
    formula as :func:`coefficients`."""
    if t < thr:
        return _series(ser, _ID, t * t)
    return (1.0 - 0.5 * t / math.tan(0.5 * t)) / (t * t)


@njit(cache=True)
def coefficients(t, ser, thr):
    """``(A, B, C, D, E, F)`` of :mod:`.so3_coefficients` at the angle ``t``."""
    if t < thr:
        t2 = t * t
        return (_series(ser, 0, t2), _series(ser, 1, t2), _series(ser, 2, t2), _series(ser, 3, t2),
                _series(ser, 4, t2), _series(ser, 5, t2))
    s, c = math.sin(t), math.cos(t)
    sh = math.sin(0.5 * t) / t
    t2 = t * t
    return (s / t, 2.0 * sh * sh, (t - s) / (t2 * t), (1.0 - 0.5 * t / math.tan(0.5 * t)) / t2,
            (t2 + 2.0 * c - 2.0) / (2.0 * t2 * t2), (2.0 * t - 3.0 * s + t * c) / (2.0 * t2 * t2 * t))


@njit(cache=True, inline="always")
def _cross(a0, a1, a2, b0, b1, b2):
    return a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0


@njit(cache=True, inline="always")
def _exp_rot(cA, cB, x, y, z):
    """Rows of ``I + A X + B X X``, ``X = hat(x, y, z)``."""
    return (1.0 + cB * (-z * z - y * y), cA * -z + cB * (x * y), cA * y + cB * (x * z),
            cA * z + cB * (x * y), 1.0 + cB * (-z * z - x * x), cA * -x + cB * (y * z),
            cA * -y + cB * (x * z), cA * x + cB * (y * z), 1.0 + cB * (-y * y - x * x))


@njit(cache=True, inline="always")
def _rotate(e, src, so, dst, do, stride):
    """``dst[3x3 at do] = E @ src[3x3 at so]``, rows ``stride`` apart (3: SO3, 4: SE3)."""
    for c in range(3):
        s0, s1, s2 = src[so + c], src[so + stride + c], src[so + 2 * stride + c]
        dst[do + c] = e[0] * s0 + e[1] * s1 + e[2] * s2
        dst[do + stride + c] = e[3] * s0 + e[4] * s1 + e[5] * s2
        dst[do + 2 * stride + c] = e[6] * s0 + e[7] * s1 + e[8] * s2


@njit(cache=True, inline="always")
def _dexpinv3(cD, t0, t1, t2, v0, v1, v2):
    """``v - t x v / 2 + D t x (t x v)``."""
    a0, a1, a2 = _cross(t0, t1, t2, v0, v1, v2)
    b0, b1, b2 = _cross(t0, t1, t2, a0, a1, a2)
    return v0 - 0.5 * a0 + cD * b0, v1 - 0.5 * a1 + cD * b1, v2 - 0.5 * a2 + cD * b2


@njit(cache=True, inline="always")
def _q_times(cC, cE, cF, r0, r1, r2, t0, t1, t2, w0, w1, w2):
    """``Q(rho, theta) w`` of the SE(3) left Jacobian (se3.q_block) by cross products:
    ``Q w = rho x w / 2 + C (T P + P T + T P T) w + E (T T P + P T T - 3 T P T) w
    + F (T P T T + T T P T) w``, ``P = hat(rho)``, ``T = hat(theta)``."""
    pw = _cross(r0, r1, r2, w0, w1, w2)
    tw = _cross(t0, t1, t2, w0, w1, w2)
    tpw = _cross(t0, t1, t2, pw[0], pw[1], pw[2])
    ptw = _cross(r0, r1, r2, tw[0], tw[1], tw[2])
    tptw = _cross(t0, t1, t2, ptw[0], ptw[1], ptw[2])
    ttpw = _cross(t0, t1, t2, tpw[0], tpw[1], tpw[2])
    ttw = _cross(t0, t1, t2, tw[0], tw[1], tw[2])
    pttw = _cross(r0, r1, r2, ttw[0], ttw[1], ttw[2])
    tpttw = _cross(t0, t1, t2, pttw[0], pttw[1], pttw[2])
    ttptw = _cross(t0, t1, t2, tptw[0], tptw[1], tptw[2])
    return (0.5 * pw[0] + cC * (tpw[0] + ptw[0] + tptw[0]) + cE * (ttpw[0] + pttw[0] - 3.0 * tptw[0])
            + cF * (tpttw[0] + ttptw[0]),
            0.5 * pw[1] + cC * (tpw[1] + ptw[1] + tptw[1]) + cE * (ttpw[1] + pttw[1] - 3.0 * tptw[1])
            + cF * (tpttw[1] + ttptw[1]),
            0.5 * pw[2] + cC * (tpw[2] + ptw[2] + tptw[2]) + cE * (ttpw[2] + pttw[2] - 3.0 * tptw[2])
            + cF * (tpttw[2] + ttptw[2]))


# ====================================================================== kernels
@njit(cache=True, fastmath=False)
def normalize_rotations(R):
    """``R <- (R / 2) (3 I - R^T R)`` for each ``R[i]`` of ``(n, 3, 3)``, in place: the
    compiled twin of :meth:`SO3.normalize <liegroup_int.groups.so3.SO3.normalize>` (one
    Newton-Schulz step, the beam's end step)."""
    for i in range(R.shape[0]):
        r00, r01, r02 = R[i, 0, 0], R[i, 0, 1], R[i, 0, 2]
        r10, r11, r12 = R[i, 1, 0], R[i, 1, 1], R[i, 1, 2]
        r20, r21, r22 = R[i, 2, 0], R[i, 2, 1], R[i, 2, 2]
        # A = 3 I - R^T R (symmetric)
        a00 = 3.0 - (r00 * r00 + r10 * r10 + r20 * r20)
        a11 = 3.0 - (r01 * r01 + r11 * r11 + r21 * r21)
        a22 = 3.0 - (r02 * r02 + r12 * r12 + r22 * r22)
        a01 = 0.0 - (r00 * r01 + r10 * r11 + r20 * r21)
        a02 = 0.0 - (r00 * r02 + r10 * r12 + r20 * r22)
        a12 = 0.0 - (r01 * r02 + r11 * r12 + r21 * r22)
        for a in range(3):
            h0, h1, h2 = 0.5 * R[i, a, 0], 0.5 * R[i, a, 1], 0.5 * R[i, a, 2]
            R[i, a, 0] = h0 * a00 + h1 * a01 + h2 * a02
            R[i, a, 1] = h0 * a01 + h1 * a11 + h2 * a12
            R[i, a, 2] = h0 * a02 + h1 * a12 + h2 * a22


@njit(cache=True, inline="always")
def se3_exp_parts(u, a, ser, thr):
    """``exp(u)`` of SE(3) for ``u[a:a+6] = (rho, theta)``: the rotation's rows ``E`` (9-tuple)
    and the translation ``J_l(theta) rho = rho + B theta x rho + C theta x (theta x rho)``."""
    r0, r1, r2 = u[a], u[a + 1], u[a + 2]
    x0, x1, x2 = u[a + 3], u[a + 4], u[a + 5]
    cA, cB, cC, cD, cE, cF = coefficients(math.sqrt(x0 * x0 + x1 * x1 + x2 * x2), ser, thr)
    e = _exp_rot(cA, cB, x0, x1, x2)
    c0, c1, c2 = _cross(x0, x1, x2, r0, r1, r2)
    d0, d1, d2 = _cross(x0, x1, x2, c0, c1, c2)
    return e, r0 + cB * c0 + cC * d0, r1 + cB * c1 + cC * d1, r2 + cB * c2 + cC * d2


@njit(cache=True, inline="always")
def retract_so3(ser, thr, u, a, y, p, out):
    """``out[p:p+9] = exp(u[a:a+3]) y[p:p+9]`` for a rotation stored row by row."""
    x0, x1, x2 = u[a], u[a + 1], u[a + 2]
    cA, cB = _coef_AB(math.sqrt(x0 * x0 + x1 * x1 + x2 * x2), ser, thr)
    _rotate(_exp_rot(cA, cB, x0, x1, x2), y, p, out, p, 3)


@njit(cache=True, inline="always")
def dexpinv_so3(ser, thr, u, w, out, a):
    """``out[a:a+3] = dexpinv_t(w[a:a+3])`` with ``t = u[a:a+3]`` (``w`` may be ``out``)."""
    t0, t1, t2 = u[a], u[a + 1], u[a + 2]
    cD = coef_D(math.sqrt(t0 * t0 + t1 * t1 + t2 * t2), ser, thr)
    out[a], out[a + 1], out[a + 2] = _dexpinv3(cD, t0, t1, t2, w[a], w[a + 1], w[a + 2])


@njit(cache=True)
def retract_flat(ft, ser, thr, u, y, out, po, ao):
    """``out = exp(u) y`` factor by factor for the point at offset ``po`` of ``y``/``out``
    and the algebra vector at offset ``ao`` of ``u``."""
    for r in range(ft.shape[0]):
        kind, p, a, n = ft[r, 0], ft[r, 1] + po, ft[r, 2] + ao, ft[r, 3]
        if kind == KIND_RN:
            for k in range(n):
                out[p + k] = y[p + k] + u[a + k]
        elif kind == KIND_SO3:
            retract_so3(ser, thr, u, a, y, p, out)
        else:  # SE3: exp(u) = [[E, J rho], [0, 1]], u = (rho, theta)
            e, j0, j1, j2 = se3_exp_parts(u, a, ser, thr)
            _rotate(e, y, p, out, p, 4)
            g0, g1, g2 = y[p + 3], y[p + 7], y[p + 11]
            out[p + 3] = e[0] * g0 + e[1] * g1 + e[2] * g2 + j0
            out[p + 7] = e[3] * g0 + e[4] * g1 + e[5] * g2 + j1
            out[p + 11] = e[6] * g0 + e[7] * g1 + e[8] * g2 + j2
            for k in range(12, 16):
                out[p + k] = y[p + k]


@njit(cache=True)
def dexpinv_flat(ft, ser, thr, u, w, out, ao):
    """``out = dexpinv_u(w)`` factor by factor at offset ``ao`` of ``u``, ``w``, ``out``
    (``SO3``: ``J_l^-1``; ``SE3``: the block inverse ``[[J^-1, -J^-1 Q J^-1], [0, J^-1]]``;
    ``w`` may be ``out``)."""
    for r in range(ft.shape[0]):
        kind, a, n = ft[r, 0], ft[r, 2] + ao, ft[r, 3]
        if kind == KIND_RN:
            for k in range(n):
                out[a + k] = w[a + k]
        elif kind == KIND_SO3:
            dexpinv_so3(ser, thr, u, w, out, a)
        else:
            r0, r1, r2 = u[a], u[a + 1], u[a + 2]
            t0, t1, t2 = u[a + 3], u[a + 4], u[a + 5]
            cA, cB, cC, cD, cE, cF = coefficients(math.sqrt(t0 * t0 + t1 * t1 + t2 * t2), ser, thr)
            v0, v1, v2 = _dexpinv3(cD, t0, t1, t2, w[a + 3], w[a + 4], w[a + 5])
            q0, q1, q2 = _q_times(cC, cE, cF, r0, r1, r2, t0, t1, t2, v0, v1, v2)
            s0, s1, s2 = _dexpinv3(cD, t0, t1, t2, w[a] - q0, w[a + 1] - q1, w[a + 2] - q2)
            out[a], out[a + 1], out[a + 2] = s0, s1, s2
            out[a + 3], out[a + 4], out[a + 5] = v0, v1, v2


@njit(cache=True)
def rotation_angle_flat(ft, u, ao):
    """Largest rotation angle of the rotational factors of ``u`` at offset ``ao`` (0 if
    none; NaN wins)."""
    best = 0.0
    for r in range(ft.shape[0]):
        kind, a = ft[r, 0], ft[r, 2] + ao
        if kind == KIND_RN:
            continue
        o = a if kind == KIND_SO3 else a + 3
        t = math.sqrt(u[o] * u[o] + u[o + 1] * u[o + 1] + u[o + 2] * u[o + 2])
        if t != t:
            return t
        if t > best:
            best = t
    return best


@njit(cache=True)
def magnitude_flat(ft, y, out, po, ao):
    """Error-norm scale of the point at offset ``po`` of ``y`` into offset ``ao`` of ``out``
    (``|g|`` on vector parts, 1 on angles)."""
    for r in range(ft.shape[0]):
        kind, p, a, n = ft[r, 0], ft[r, 1] + po, ft[r, 2] + ao, ft[r, 3]
        if kind == KIND_RN:
            for k in range(n):
                out[a + k] = abs(y[p + k])
        elif kind == KIND_SO3:
            out[a] = out[a + 1] = out[a + 2] = 1.0
        else:
            out[a], out[a + 1], out[a + 2] = abs(y[p + 3]), abs(y[p + 7]), abs(y[p + 11])
            out[a + 3] = out[a + 4] = out[a + 5] = 1.0


class CompiledGroup:
    """The compiled kernels of one space, for single points (see the module docstring).

    ``CompiledGroup.of(space)`` returns ``None`` for spaces with a group that has no
    compiled kernels.
    """

    def __init__(self, space, ft: np.ndarray):
        self.space, self.ft = space, ft
        self.ser = series_table()
        self.thr = float(TAYLOR_THRESHOLD)
        self.point_shape = tuple(space.point_shape)

    @classmethod
    def of(cls, space) -> "CompiledGroup | None":
        ft = factor_table(space)
        return None if ft is None else cls(space, ft)

    def retract(self, u: np.ndarray, y: np.ndarray) -> np.ndarray:
        out = np.empty(self.point_shape)
        retract_flat(self.ft, self.ser, self.thr, u, y.reshape(-1), out.reshape(-1), 0, 0)
        return out

    def dexpinv(self, u: np.ndarray, w: np.ndarray) -> np.ndarray:
        out = np.empty(w.shape)
        dexpinv_flat(self.ft, self.ser, self.thr, u, w, out, 0)
        return out

    def rotation_angle(self, u: np.ndarray) -> float:
        return float(rotation_angle_flat(self.ft, u, 0))

    def magnitude(self, y: np.ndarray) -> np.ndarray:
        out = np.empty(self.space.dim)
        magnitude_flat(self.ft, y.reshape(-1), out, 0, 0)
        return out
