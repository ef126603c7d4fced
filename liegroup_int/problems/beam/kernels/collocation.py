"""Compiled kernels of the collocation beam (``BeamProblem(..., backend="numba")``),
built from :mod:`.physics`.

Same mathematics as the NumPy path of :mod:`..problem`, one loop over the collocation
points per call:

* :func:`action_primal`: ``theta, theta_s, theta_ss`` at the points, ``R <- exp(hat(theta))
  R``, ``K <- K + R^T J_r(theta) theta_s`` and its s-derivative; ``c, v, w`` plus their
  increments.
* :func:`rates_primal`: strains (plus ``tau`` times their rates
  with Kelvin-Voigt damping), resultants, balance laws, enhanced collocation at Neumann
  ends, ``dexpinv``, prescribed rows, all into the ``(n, 12)`` right-hand side whose
  forward sweep runs in the same loop, then the ``M_c`` solve into the ``(4, n, 3)``
  rate. They return the power of the loads and supports minus the dissipation (0 unless
  the problem integrates it).

The data: :class:`CollocationData`, packed by :func:`.adapters.pack`. ``loads`` holds
the loads at the stage time, rows :data:`Q`, :data:`G`, :data:`MD` (distributed force,
gravity, distributed couple), then per end four rows from ``end_row`` (force, couple,
prescribed angular acceleration, prescribed acceleration) and per joint two rows from
``joint_row`` (force, couple).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from ....groups.kernels_numba import coef_ABCB1C1, coef_D
from ....groups.so3_coefficients import TAYLOR_THRESHOLD
from . import adapters as ad
from .adapters import F1, F2, F3, I1, c64
from .band import basis_windows, factor_mc, forward_row, solve_cols, window, window2, window3
from .physics import (dexpinv, dissipation, exp_rows, gamma_rate, gyroscopic, jr_times, jr_times_s,
                      load_power, point_load, resultant, strain)
from .profiles import LoadTable
from .vec3 import (add, axpy, cross, div, dot, inertia, norm, put, put_at, rot, rot_T, row, scale, sub,
                   sym_add, sym_solve, sym_times)

#: Largest ``n_ctrl`` for which ``solver="auto"`` uses the dense inverse of ``M_c``.
#: Measured (cantilever p = 4, whole stage-rate kernel, best of 30 x 500 calls):
#: n = 5: banded 1.29 us / dense 1.47 us; 8: 1.56 / 1.51; 12: 1.81 / 2.08;
#: 16: 2.08 / 2.48; 31: 3.16 / 5.32; 61: 5.31 / 31.2; 121: 14.2 / 105.
#: The dense inverse never wins by more than timing noise, so ``auto`` is banded; the
#: dense inverse remains the fallback when the no-pivot factorization fails its checks.
DENSE_MAX_N = 0

#: LLVM fast-math flags of the per-point kernels: only ``contract`` (a * b + c may become
#: one FMA, rounded once); no reassociation, no assumptions about NaN or infinities, so
#: results differ from the NumPy backend by round-off only.
FM = {"contract"}

Q, G, MD = 0, 1, 2  # rows of ``loads``: distributed force, gravity, distributed couple
FORCE, COUPLE, ALPHA, ACC = 0, 1, 2, 3  # an end's rows of ``loads``, from its ``end_row``


class CollocationData(NamedTuple):
    """Constant data and work arrays of the collocation kernels (``n`` points)."""

    band: F3  # (3, n, W) row windows of N0, N1, N2
    j0: I1  # (n,) first column of each window
    lu: F2  # (n, lower + upper + 1) banded LU of M_c, reciprocal pivots
    minv: F2  # (n, n) dense inverse of M_c, or (0, 0): banded solve
    lower: int
    upper: int
    ser: F2  # SO(3) series table (groups.kernels_numba.series_table)
    thr: float
    gamma0: F2  # (n, 3) reference strains and curvatures
    K0: F2
    K0_s: F2
    CN: F2  # (n, 3) section per point
    CM: F2
    J: F2
    mu: F1  # (n,)
    quad: F1  # (n,) quadrature weights
    tau: float
    power: bool  # compute the power of the loads (BeamProblem.quadrature_rate)
    has_q: bool
    has_m: bool
    loads: F2  # (rows, 3) loads at the stage time (module docstring)
    end_index: I1  # (ne,) per end: point, first row in loads, outward normal, C*/l_s,
    end_row: I1
    end_normal: F1
    end_factor: F1
    end_force: I1  # force and moment Neumann rows, follower loads, prescribed
    end_moment: I1  # rotation (moving), prescribed displacement (sliding)
    end_follower: I1
    end_moving: I1
    end_sliding: I1
    joint_a: I1  # (nj,) rigid joints: rows a and b, C*/l_s of both, first row in loads
    joint_b: I1
    joint_factor: F1
    joint_row: I1
    fixp: I1  # (n,) rows with prescribed zero position and velocity rates
    fixr: I1  # (n,) and rotation and angular velocity rates
    rhs: F2  # (n, 12) work: right-hand sides
    Gt: F2  # (n, 3) work: R^T c_s, N, M per point
    N: F2
    M: F2
    tmp: F2  # (n, 12) work of the dense solve, or (0, 12)


@njit(cache=True, _nrt=False, inline="always")
def unpack(flat, head):
    """The :class:`CollocationData` of :func:`.adapters.pack`'s arrays (views)."""
    return ad.unpack_as(CollocationData, flat, head)


# ====================================================================== action
@njit(cache=True, fastmath=FM, inline="always")
def _translate(u, c, v, w, c2, v2, w2):
    for i in range(c.shape[0]):
        for d in range(3):
            c2[i, d] = c[i, d] + u[0, i, d]
            v2[i, d] = v[i, d] + u[2, i, d]
            w2[i, d] = w[i, d] + u[3, i, d]


@njit(cache=True, fastmath=FM, inline="always")
def _rotate_left(R, R2, i, E):
    """``R2[i] = E R[i]``, ``E`` row by row."""
    for a in range(3):
        r0, r1, r2 = R[i, 0, a], R[i, 1, a], R[i, 2, a]
        R2[i, 0, a] = E[0] * r0 + E[1] * r1 + E[2] * r2
        R2[i, 1, a] = E[3] * r0 + E[4] * r1 + E[5] * r2
        R2[i, 2, a] = E[6] * r0 + E[7] * r1 + E[8] * r2


@njit(cache=True, fastmath=FM, inline="always")
def action_primal(u, c, v, w, R, K, Ks, c2, v2, w2, R2, K2, Ks2, d):
    """``Lambda(u, y)`` into ``c2, v2, w2, R2, K2, Ks2``, with the curvature derivative
    update ``K_s <- K_s - K x x + R^T d/ds(J_r theta_s)``, ``x = R^T J_r theta_s``."""
    _translate(u, c, v, w, c2, v2, w2)
    u1 = u[1]
    for i in range(c.shape[0]):
        th, ts, tss = window3(d.band, i, d.j0, u1, 0)
        cA, cB, cC, cB1, cC1 = coef_ABCB1C1(norm(th), d.ser, d.thr)
        _rotate_left(R, R2, i, exp_rows(cA, cB, th))
        x = rot_T(R, i, jr_times(cB, cC, th, ts))
        k = row(K, i)
        put(K2, i, add(k, x))
        put(Ks2, i, add(sub(row(Ks, i), cross(k, x)), rot_T(R, i, jr_times_s(cB, cC, cB1, cC1, th, ts, tss))))


# ====================================================================== stage rates
@njit(cache=True, fastmath=FM, inline="always")
def _end_terms(d, e, i, R, N, M, ns, tq, vc, wc):
    """Enhanced collocation of end ``e`` at point ``i``: ``(n_s, tq, power)``."""
    nrm, fac, r = d.end_normal[e], d.end_factor[e], d.end_row[e]
    power = 0.0
    if d.power and d.end_sliding[e]:  # the support's force on the end's velocity
        power += nrm * dot(rot(R, i, N), vc)
    if d.end_moving[e]:  # the support's couple on the end's angular velocity; no loads
        if d.power:
            power += nrm * dot(rot(R, i, M), wc)
        return ns, tq, power
    f = point_load(R, i, row(d.loads, r + FORCE), d.end_follower[e])
    m = point_load(R, i, row(d.loads, r + COUPLE), d.end_follower[e])
    if d.power:
        power += load_power(f, vc, m, wc)
    if d.end_force[e]:
        ns = add(ns, scale(fac, sub(f, scale(nrm, rot(R, i, N)))))
    if d.end_moment[e]:
        tq = add(tq, scale(fac, sub(rot_T(R, i, m), scale(nrm, M))))
    return ns, tq, power


@njit(cache=True, fastmath=FM, inline="always")
def _balance_row(d, i, R, N, M, ns, tq, vc, wc, th):
    """Distributed loads, end terms, ``dexpinv`` and prescribed rows: row ``i`` of the
    right-hand side. Returns the power of the loads at the point."""
    x, mu = d.rhs, d.mu[i]
    q = axpy(mu, row(d.loads, G), row(d.loads, Q))
    md = row(d.loads, MD)
    power = 0.0
    if d.has_q:
        ns = add(ns, q)
    if d.has_m:
        tq = add(tq, rot_T(R, i, md))
    if d.power and (d.has_q or d.has_m):
        power += d.quad[i] * load_power(q, vc, md, wc)
    moving = sliding = -1
    for e in range(d.end_index.shape[0]):
        if d.end_index[e] == i:
            ns, tq, p = _end_terms(d, e, i, R, N, M, ns, tq, vc, wc)
            power += p
            moving = e if d.end_moving[e] else moving
            sliding = e if d.end_sliding[e] else sliding
    zero = (0.0, 0.0, 0.0)
    put_at(x, i, 0, zero if d.fixp[i] else vc)
    put_at(x, i, 6, zero if d.fixp[i] else scale(1.0 / mu, ns) if sliding < 0
           else row(d.loads, d.end_row[sliding] + ACC))
    cD = coef_D(norm(th), d.ser, d.thr)
    put_at(x, i, 3, zero if d.fixr[i] else dexpinv(cD, th, wc))
    put_at(x, i, 9, zero if d.fixr[i] else rot(R, i, div(tq, row(d.J, i))) if moving < 0
           else row(d.loads, d.end_row[moving] + ALPHA))
    return power


@njit(cache=True, fastmath=FM, inline="always")
def _primal_rates(d, i, v, w, R, K, cs, css, wc, Omega, Gt):
    """Kelvin-Voigt: the material strain rates and their s-derivatives ``(dGamma,
    dGamma_s, dK, dK_s)`` (``dR^T/ds = -hat(K) R^T``)."""
    vs, vss = window2(d.band, 1, 2, i, d.j0, v, 0)
    ws, wss = window2(d.band, 1, 2, i, d.j0, w, 0)
    gd = gamma_rate(rot_T(R, i, vs), Omega, Gt)
    h = sub(sub(vss, cross(ws, cs)), cross(wc, css))
    gds = sub(rot_T(R, i, h), cross(K, gd))
    kd = rot_T(R, i, ws)
    kds = sub(rot_T(R, i, wss), cross(K, kd))
    return gd, gds, kd, kds


@njit(cache=True, fastmath=FM, inline="always")
def _primal_point(d, i, c, v, w, R, K, Ks, u1):
    """Resultants ``N, M``, ``n_s``, torque, ``v_c, w_c, theta_c`` and the dissipation at
    point ``i`` (primal: analytic s-derivatives of the pointwise resultants)."""
    B, j0 = d.band, d.j0
    cs, css = window2(B, 1, 2, i, j0, c, 0)
    vc, wc, th = window(B, 0, i, j0, v, 0), window(B, 0, i, j0, w, 0), window(B, 0, i, j0, u1, 0)
    k, CN, CM = row(K, i), row(d.CN, i), row(d.CM, i)
    Gt = rot_T(R, i, cs)
    Omega = rot_T(R, i, wc)
    gam, gs = strain(Gt, row(d.gamma0, i)), sub(rot_T(R, i, css), cross(k, Gt))
    km, kms = strain(k, row(d.K0, i)), strain(row(Ks, i), row(d.K0_s, i))
    gd = gds = kd = kds = (0.0, 0.0, 0.0)
    power = 0.0
    if d.tau != 0.0:
        gd, gds, kd, kds = _primal_rates(d, i, v, w, R, k, cs, css, wc, Omega, Gt)
        if d.power:
            power -= d.quad[i] * (dissipation(d.tau, CN, gd) + dissipation(d.tau, CM, kd))
    N, M = resultant(CN, gam, d.tau, gd), resultant(CM, km, d.tau, kd)
    ns = rot(R, i, add(cross(k, N), resultant(CN, gs, d.tau, gds)))
    tq = add(sub(add(cross(k, M), resultant(CM, kms, d.tau, kds)), gyroscopic(Omega, row(d.J, i))),
             cross(Gt, N))
    return N, M, ns, tq, vc, wc, th, power


@njit(cache=True, fastmath=FM, inline="always")
def rates_primal(c, v, w, R, K, Ks, u, out, d):
    """Stage rate ``M_c^-1 rhs`` of the primal formulation into ``out`` ``(4, n, 3)``
    (``u``: the stage increment; zeros for the plain vector field); returns the power."""
    fused = d.minv.shape[0] == 0 and d.joint_a.shape[0] == 0
    power = 0.0
    u1 = u[1]
    for i in range(c.shape[0]):
        N, M, ns, tq, vc, wc, th, p = _primal_point(d, i, c, v, w, R, K, Ks, u1)
        put(d.N, i, N)
        put(d.M, i, M)
        power += p + _balance_row(d, i, R, N, M, ns, tq, vc, wc, th)
        if fused:  # forward sweep of the banded solve (rows < i are final)
            forward_row(d.rhs, i, d.lu, d.lower, 0, 12)
    return power + _finish(d, v, w, R, out, fused)


@njit(cache=True, fastmath=FM, inline="always")
def _finish(d, v, w, R, out, forward_done):
    """Joint rows, then the ``M_c`` solve of the right-hand sides into ``out``; returns
    the power of the joint loads."""
    power = _joint_rows(d, v, w, R) if d.joint_a.shape[0] else 0.0
    _solve_rhs(d, out, forward_done)
    return power


@njit(cache=True, fastmath=FM, _nrt=False)
def _joint_rows(d, v, w, R):
    """Rigid joints (docs/theory.md section 13): rows ``a, b`` of each joint get one common
    rate from their own rows and the joint's balance residuals ``r_n = n_b - n_a + F``,
    ``r_m = m_b - m_a + C``: the mass-weighted mean of the two translational rows, the
    inertia-weighted mean (spatial inertias) of the angular ones. Returns the power of the
    joint loads."""
    x, power = d.rhs, 0.0
    for k in range(d.joint_a.shape[0]):
        a, b, fac, r = d.joint_a[k], d.joint_b[k], d.joint_factor[k], d.joint_row[k]
        F, C = row(d.loads, r), row(d.loads, r + 1)
        rn = add(sub(rot(R, b, row(d.N, b)), rot(R, a, row(d.N, a))), F)
        rm = add(sub(rot(R, b, row(d.M, b)), rot(R, a, row(d.M, a))), C)
        if d.power:
            power += load_power(F, row(v, a), C, row(w, a))
        Ia, Ib = inertia(R, a, row(d.J, a)), inertia(R, b, row(d.J, b))
        xa, xb = (x[a, 9], x[a, 10], x[a, 11]), (x[b, 9], x[b, 10], x[b, 11])
        al = sym_solve(sym_add(Ia, Ib), axpy(fac, rm, add(sym_times(Ia, xa), sym_times(Ib, xb))))
        mu_a, mu_b = d.mu[a], d.mu[b]
        for q in range(6):
            x[a, q] = x[b, q] = 0.5 * (x[a, q] + x[b, q])
        lin = scale(1.0 / (mu_a + mu_b), axpy(fac, rn, add(scale(mu_a, (x[a, 6], x[a, 7], x[a, 8])),
                                                             scale(mu_b, (x[b, 6], x[b, 7], x[b, 8])))))
        put_at(x, a, 6, lin)
        put_at(x, b, 6, lin)
        put_at(x, a, 9, al)
        put_at(x, b, 9, al)
    return power


@njit(cache=True, fastmath=False, _nrt=False)
def solve(x, flat, head):
    """``M_c^-1`` on an increment-shaped array ``x`` ``(4, n, 3)``, in place."""
    d = unpack(flat, head)
    ws = d.rhs
    for i in range(x.shape[1]):
        for f in range(4):
            for q in range(3):
                ws[i, 3 * f + q] = x[f, i, q]
    _solve_rhs(d, x, False)


@njit(cache=True, fastmath=False, inline="always")
def _solve_rhs(d, out, forward_done):
    """``out[f, :, :] = M_c^-1 rhs[:, 3 f:3 f + 3]``."""
    x = d.rhs
    solve_cols(x, d.lu, d.lower, d.upper, d.minv, forward_done, 0, 12, d.tmp)
    for i in range(x.shape[0]):
        for f in range(4):
            out[f, i, 0], out[f, i, 1], out[f, i, 2] = x[i, 3 * f], x[i, 3 * f + 1], x[i, 3 * f + 2]


# ====================================================================== entries from Python
# (the data as two arrays: one numba call costs ~0.1 us per array, ~5 us per NamedTuple of arrays)
# The entries (from Python, and from the engine's loops through their addresses) inline the
# action and the stage rate, with their fast-math flags: the named data are then built from
# ``flat, head`` only where read, instead of passed whole to a compiled function (an RKMK4
# step at n_ctrl 21: 14.6-15.3 us against 16.7-18.3 us).
@njit(cache=True, fastmath=FM, _nrt=False)
def call_action_primal(u, c, v, w, R, K, Ks, c2, v2, w2, R2, K2, Ks2, flat, head):
    action_primal(u, c, v, w, R, K, Ks, c2, v2, w2, R2, K2, Ks2, unpack(flat, head))


@njit(cache=True, fastmath=FM, _nrt=False)
def call_rates_primal(c, v, w, R, K, Ks, u, out, flat, head):
    return rates_primal(c, v, w, R, K, Ks, u, out, unpack(flat, head))


#: The engine's kernels of the collocation beam.
ENGINE_KERNELS = ad.engine_kernels("beam", 6)
STATE_FIELDS = ("c", "v", "w", "R", "K", "K_s")


# ====================================================================== Python side
def _end_data(pb, loads: np.ndarray, table: LoadTable, first_row: int) -> dict:
    """The end fields of :class:`CollocationData`; their loads into ``loads``/``table``."""
    ends = pb.ends
    out = {"end_row": np.array([first_row + 4 * k for k in range(len(ends))], dtype=np.int64)}
    for name, get in (("index", lambda e: e.index), ("force", lambda e: e.force_neumann),
                      ("moment", lambda e: e.moment_neumann), ("follower", lambda e: e.load.follower),
                      ("moving", lambda e: e.motion is not None), ("sliding", lambda e: e.translation is not None)):
        out[f"end_{name}"] = np.array([int(get(e)) for e in ends], dtype=np.int64)
    out["end_normal"] = np.array([e.normal for e in ends], dtype=float)
    out["end_factor"] = np.array([e.factor for e in ends], dtype=float)
    for k, e in enumerate(ends):
        r = first_row + 4 * k
        for motion, slot in ((e.translation, ACC), (e.motion, ALPHA)):
            if motion is not None:  # prescribed (angular) acceleration, per stage time
                s, prof = motion.acceleration_profile()
                table.add_or_fix(loads, r + slot, s * motion.unit_axis, prof)
        ld = e.load
        for slot, vec, prof, on in ((FORCE, ld.force, ld.force_profile, e.force_neumann),
                                    (COUPLE, ld.couple, ld.couple_profile, e.moment_neumann)):
            if on and np.any(vec):
                table.add_or_fix(loads, r + slot, vec, prof)
    return out


def _joint_data(pb, loads: np.ndarray, table: LoadTable, first_row: int) -> dict:
    """The joint fields of :class:`CollocationData`; their loads into ``loads``/``table``."""
    js = pb.joints
    for k, j in enumerate(js):
        for slot, vec, prof in (() if j.load is None else
                                ((0, j.load.force, j.load.force_profile), (1, j.load.couple, j.load.couple_profile))):
            if np.any(vec):
                table.add_or_fix(loads, first_row + 2 * k + slot, vec, prof)
    return {"joint_a": np.array([j.a for j in js], dtype=np.int64),
            "joint_b": np.array([j.b for j in js], dtype=np.int64),
            "joint_factor": np.array([j.factor_a + j.factor_b for j in js], dtype=float),
            "joint_row": np.array([first_row + 2 * k for k in range(len(js))], dtype=np.int64)}


def _solver(pb, solver: str):
    """``(lu, minv, name)`` of the ``M_c`` solve."""
    if solver not in ("auto", "banded", "dense"):
        raise ValueError(f"solver must be 'auto', 'banded' or 'dense', got {solver!r}")
    n, (lower, upper) = pb.n, pb.space.bandwidths
    N0 = np.asarray(pb.N0, dtype=float)
    ab = factor_mc(N0, lower, upper) if solver != "dense" else None
    dense = solver == "dense" or ab is None or (solver == "auto" and n <= DENSE_MAX_N)
    lu = ab if ab is not None else np.zeros((n, lower + upper + 1))
    return lu, (np.linalg.inv(N0) if dense else np.zeros((0, 0))), ("dense" if dense else "banded")


def collocation_data(pb, solver: str = "auto"):
    """``(CollocationData, LoadTable, solver name)`` of a :class:`~..problem.BeamProblem`."""
    from ....groups.kernels_numba import series_table

    n = pb.n
    lower, upper = (int(b) for b in pb.space.bandwidths)
    lu, minv, name = _solver(pb, solver)
    band, j0 = basis_windows([pb.N0, pb.N1, pb.N2])
    ne, nj = len(pb.ends), len(pb.joints)
    loads, table = np.zeros((3 + 4 * ne + 2 * nj, 3)), LoadTable()
    for r, vec in ((Q, pb.loads.distributed_force), (G, pb.loads.gravity), (MD, pb.m_dist)):
        table.add_or_fix(loads, r, vec, pb.loads.distributed_profile)
    ends, joints = _end_data(pb, loads, table, 3), _joint_data(pb, loads, table, 3 + 4 * ne)
    zeros = np.zeros((n, 3))
    per_point = [np.broadcast_to(np.asarray(a, dtype=float), (n, 3)) for a in (pb.CN, pb.CM, pb.Jm)]
    fixp, fixr = dirichlet_rows(pb)
    data = CollocationData(
        band, j0, lu, c64(minv), lower, upper, series_table(), float(TAYLOR_THRESHOLD), c64(pb.gamma0),
        c64(pb.K0) if pb.curved else zeros, c64(pb.K0_s) if pb.curved else zeros, *map(c64, per_point),
        np.broadcast_to(np.ravel(np.asarray(pb.mu, dtype=float)), (n,)).copy(), c64(pb.quad), float(pb.tau),
        bool(pb.has_quadrature), bool(pb.has_q), bool(pb.has_m), loads, **ends, **joints,
        fixp=fixp.astype(np.int64), fixr=fixr.astype(np.int64), rhs=np.zeros((n, 12)),
        Gt=zeros, N=zeros, M=zeros, tmp=np.zeros((n if name == "dense" else 0, 12)))
    return data, table, name


def dirichlet_rows(pb) -> tuple[np.ndarray, np.ndarray]:
    """Boolean ``(n,)`` masks ``(fixp, fixr)`` of the rows whose position (and velocity) and
    rotation (and angular velocity) rates are prescribed zero (a moving support's rows are
    not masked: the kernels set them)."""
    mask = pb._fix_rows
    return np.ascontiguousarray(mask[:, 0]), np.ascontiguousarray(mask[:, 1])


class NumbaBeamKernels(ad.KernelSet):
    """The compiled kernels of one :class:`~..problem.BeamProblem`.

    Parameters
    ----------
    pb : BeamProblem
    solver : {"auto", "banded", "dense"}
        ``M_c`` solve: banded LU without pivoting, the dense inverse, or ``auto`` (dense
        only for ``n <= DENSE_MAX_N``).
    """

    data_cls, fields = CollocationData, STATE_FIELDS

    def __init__(self, pb, solver: str = "auto"):
        data, table, self.solver = collocation_data(pb, solver)
        self.bandwidth = data.band.shape[2]
        super().__init__(data, table, pb.n)

    def kernels(self) -> tuple:
        return call_action_primal, call_rates_primal, ENGINE_KERNELS

    def solve(self, x):
        """``M_c^-1`` on an increment-shaped array ``(4, n, 3)`` (copy)."""
        x = np.array(x, dtype=float, copy=True)
        solve(x, self.flat, self.head)
        return x
