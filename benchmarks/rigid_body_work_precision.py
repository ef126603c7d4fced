"""Work-precision benchmark: rigid bodies, liegroup_int RKMK vs scipy.integrate.solve_ivp.

Two problems on SO(3) x R^3, state ``(R, W)`` (body angular velocity ``W``):

1. **Free body near its intermediate axis** (the README's "Python in ten lines" example,
   ``liegroup_int/bench/free_body.py``): ``I = (1, 2, 3)``, ``R0 = I``, ``W0 = (0.01, 5, 0.01)``,
   ``t in [0, 20]`` s. The user's vector field, in three forms: a ``numba.njit`` ``f`` (the
   compiled engine runs the whole fixed-step or adaptive loop), the README's plain-Python
   NumPy ``f`` (generic Python loop), and for the peer a unit-quaternion RHS (plain floats, or
   written the NumPy way).
2. **Non-symmetric heavy top** (built-in ``RigidBody(...).problem()``, compiled kernels)::

       dR/dt = R hat(W)
       I dW/dt = (I W) x W + m g (Gamma x chi),   Gamma = R^T e3

   ``I = (1.0, 0.8, 0.5)`` kg m^2, ``m = 1`` kg, ``chi = (0, 0, 0.5)`` m, ``g = 9.81`` m/s^2,
   ``R0 = exp(hat(0.5 e1))``, ``W0 = (0.4, -0.2, 6.0)`` rad/s, ``t in [0, 10]`` s.

Error of a run: ``|R(T) - R_ref(T)|_F + |W(T) - W_ref(T)|_2`` at the final time only (no
dense output is involved). References: RKMK6 at a small fixed step, checked against half
that step (and, for the free body, against DOP853 at tolerance 1e-13).

Ours: ``liegroup_int.integrate`` with fixed-step RKMK2/3/4/6 over a range of steps and the
embedded pairs RKMK32/45/65 over a range of tolerances (``rtol = atol = tol``), no monitor:
with the built-in rigid body or a ``numba.njit`` ``f`` both run in the compiled engine; with
a plain Python ``f``, in the generic loop. The FSAL pairs (32, 45, 65) reuse the last stage.

Peer: ``scipy.integrate.solve_ivp`` (DOP853; RK45 on the heavy top; ``rtol = atol = tol``)
on the same equations in the unit-quaternion embedding ``q' = q (x) (0, W) / 2``. ``q(T)``
is normalised before it is turned into ``R``; the drift ``| |q| - 1 |`` is reported apart.

Measured targets (ratios ours / scipy DOP853 in CPU time):

1. free body, njit ``f``: CPU to reach errors 1e-6 and 1e-9 (log-log interpolation along
   each method's Pareto front; the cheapest single run reaching the level is reported too),
   against DOP853 with the plain-float RHS; the first call's overhead apart (measured in a
   fresh process);
2. free body, plain Python ``f`` against DOP853 with its NumPy-style RHS at ``rtol = 1e-9``
   and at equal error; the generic loop's overhead per stage without ``f`` (an ``f``
   returning a precomputed array);
3. heavy top, adaptive rkmk45/rkmk65 (compiled engine) against scipy's best at each error
   level of the table;
4. FSAL: RHS evaluations per accepted step, with reuse and without (stages per attempt;
   the generic loop also measured with reuse switched off).

Timing: ``time.process_time()`` (CPU seconds); a run shorter than ``min_time`` is repeated
in a batch until the batch takes at least ``min_time``; best of ``repeats`` batches; every
runner is called once before it is timed (numba compilation excluded).

Usage (from the repository root)::

    python benchmarks/rigid_body_work_precision.py          # full sweep, writes docs + PNG
    python benchmarks/rigid_body_work_precision.py --quick  # smoke test, prints only (figure in --out)
"""

from __future__ import annotations

import datetime as _dt
import math
import os
import platform
import time
from pathlib import Path

import numba
import numpy as np
import scipy
from scipy.integrate import solve_ivp

import liegroup_int
from liegroup_int import SO3, IntegrationError, integrate, resolve_method
from liegroup_int.bench import free_body as FB
from liegroup_int.bench.table import figure_dir, parser
from liegroup_int.bench.timing import best_of
from liegroup_int.groups.so3 import rotation_to_quaternion
from liegroup_int.integrators import GroupProblem
from liegroup_int.problems import RigidBody

SECTION = "rigid_body_work_precision"
START, END = f"<!-- {SECTION}:start -->", f"<!-- {SECTION}:end -->"
ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "benchmarks.md"
PNG_NAME = "rigid_body_work_precision.png"
COMMAND = "python benchmarks/rigid_body_work_precision.py"

# -- heavy top ----------------------------------------------------------------------------
INERTIA = (1.0, 0.8, 0.5)
MASS, COM, GRAVITY = 1.0, (0.0, 0.0, 0.5), 9.81
TILT = 0.5  # rad, about body/spatial e1
W0 = np.array([0.4, -0.2, 6.0])
T_END = 10.0

TOP = RigidBody(inertia=INERTIA, mass=MASS, com=COM, gravity=GRAVITY)
R0 = SO3.exp(np.array([TILT, 0.0, 0.0]))
Y0 = TOP.state(R0, W0)
E0 = float(TOP.energy(Y0))
LZ0 = float(TOP.casimir(Y0))

# -- targets ------------------------------------------------------------------------------
ERROR_LEVELS = (1e-4, 1e-6, 1e-8, 1e-10)  # heavy top (target 3)
FB_LEVELS = (1e-6, 1e-9)                    # free body, njit f (target 1)
FB_TOL = 1e-9                               # free body, Python f (target 2)
TARGET_NJIT, TARGET_PY = 1 / 5, 25.0

# -- sweeps -------------------------------------------------------------------------------
# Fixed step: numbers of steps over [0, T] (h = T / N). Adaptive: tolerances.
FULL = {
    "ref_steps": 4000,  # reference RKMK6 at h = T/ref_steps, checked against h/2 (used as ref)
    "fixed": {
        "rkmk2": [100, 200, 400, 800, 1600, 3200],
        "rkmk3": [100, 200, 400, 800, 1600, 3200],
        "rkmk4": [100, 200, 400, 800, 1600, 3200],
        "rkmk6": [100, 160, 250, 400, 640, 1000, 1600],
    },
    "adaptive": {
        "rkmk32": [1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7],
        "rkmk45": [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12, 1e-13],
        "rkmk65": [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12],
    },
    "scipy": {
        "RK45": [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10],
        "DOP853": [1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12, 1e-13],
        # same method, RHS written with np.cross / slicing (shows how much of the gap is RHS style)
        "DOP853-numpy": [1e-5, 1e-7, 1e-9, 1e-11, 1e-13],
    },
    "fb": {
        "ref_steps": 4000,  # rkmk6 at h = 20/4000 (round-off, not truncation, limits it: see fb_reference)
        "njit_fixed": {"rkmk4": [500, 1000, 2000, 4000, 8000, 16000],
                       "rkmk6": [250, 400, 640, 1000, 1600, 2500]},  # not ref_steps: that is the reference
        "njit_adaptive": {"rkmk45": [1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12],
                          "rkmk65": [1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12]},
        "python_adaptive": {"rkmk45": [1e-7, 1e-8, 1e-9, 1e-10], "rkmk65": [1e-7, 1e-8, 1e-9, 1e-10]},
        "scipy": {"DOP853": [1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12, 1e-13],
                  "DOP853-numpy": [1e-7, 1e-8, 1e-9, 1e-10, 1e-11]},
        "first_calls": ("rkmk4", "rkmk45"),
    },
    "min_time": 0.1,
    "repeats": 5,
}
QUICK = {
    "ref_steps": 1000,
    "fixed": {"rkmk4": [100, 400], "rkmk6": [100, 250]},
    "adaptive": {"rkmk45": [1e-5, 1e-8], "rkmk65": [1e-4, 1e-7, 1e-10]},
    "scipy": {"RK45": [1e-5, 1e-8], "DOP853": [1e-5, 1e-8, 1e-11], "DOP853-numpy": [1e-5]},
    "min_time": 0.0,
    "repeats": 1,
}


# -- helpers ------------------------------------------------------------------------------
def timed(fn, min_time: float, repeats: int):
    """``(result, best CPU seconds per call)`` after one untimed call (compilation,
    caches); short calls are batched to ``min_time``."""
    t = best_of(fn, repeats, min_time)
    return t.result, t.seconds


def state_error(R, W, R_ref, W_ref) -> float:
    return float(np.linalg.norm(R - R_ref) + np.linalg.norm(W - W_ref))


def quat_to_rot(q: np.ndarray) -> np.ndarray:
    """Rotation matrix of a unit quaternion ``(w, x, y, z)`` (body to spatial)."""
    w, x, y, z = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def make_quat_rhs():
    """Plain-float RHS of the heavy top in the quaternion embedding, state ``(q, W)``."""
    I1, I2, I3 = INERTIA
    c1, c2, c3 = (MASS * GRAVITY * c for c in COM)

    def rhs(t, s):
        w, x, y, z, W1, W2, W3 = s.tolist()
        # Gamma = R(q)^T e3 = third row of R(q) (unit-quaternion formula)
        g1 = 2.0 * (x * z - w * y)
        g2 = 2.0 * (y * z + w * x)
        g3 = 1.0 - 2.0 * (x * x + y * y)
        a1, a2, a3 = I1 * W1, I2 * W2, I3 * W3
        return np.array([
            0.5 * (-x * W1 - y * W2 - z * W3),
            0.5 * (w * W1 + y * W3 - z * W2),
            0.5 * (w * W2 + z * W1 - x * W3),
            0.5 * (w * W3 + x * W2 - y * W1),
            (a2 * W3 - a3 * W2 + g2 * c3 - g3 * c2) / I1,
            (a3 * W1 - a1 * W3 + g3 * c1 - g1 * c3) / I2,
            (a1 * W2 - a2 * W1 + g1 * c2 - g2 * c1) / I3,
        ])

    return rhs


def make_quat_rhs_numpy():
    """The same RHS written the usual NumPy way (np.cross, array slicing), for comparison."""
    I = np.asarray(INERTIA, dtype=float)
    mgchi = MASS * GRAVITY * np.asarray(COM, dtype=float)

    def rhs(t, s):
        q, W = s[:4], s[4:]
        w, v = q[0], q[1:]
        x, y, z = v
        gamma = np.array([2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y)])
        qdot = 0.5 * np.concatenate(([-(v @ W)], w * W + np.cross(v, W)))
        Wdot = (np.cross(I * W, W) + np.cross(gamma, mgchi)) / I
        return np.concatenate((qdot, Wdot))

    return rhs


RHS_VARIANTS = {"float": make_quat_rhs, "numpy": make_quat_rhs_numpy}


def diagnostics(R, W):
    y = TOP.state(R, W)
    dE = abs(float(TOP.energy(y)) - E0) / abs(E0)
    dLz = abs(float(TOP.casimir(y)) - LZ0) / abs(LZ0)
    return dE, dLz


def attempts(r) -> int:
    return r["steps"] + (r["rejected"] or 0)


# -- heavy-top runs -----------------------------------------------------------------------
def run_ours(method, *, dt=None, tol=None, ref=None, cfg=None):
    problem = TOP.problem()
    if dt is not None:
        fn = lambda: integrate(problem, Y0, (0.0, T_END), method=method, dt=dt)  # noqa: E731
    else:
        fn = lambda: integrate(problem, Y0, (0.0, T_END), method=method, rtol=tol, atol=tol)  # noqa: E731
    sol, cpu = timed(fn, cfg["min_time"], cfg["repeats"])
    R, W = TOP.split(sol.y_final)
    dE, dLz = diagnostics(R, W)
    return {
        "lib": "liegroup_int", "method": method, "param": ("h", dt) if dt is not None else ("tol", tol),
        "steps": sol.stats.steps, "rejected": sol.stats.rejected, "nfev": sol.stats.rhs_evals,
        "cpu": cpu, "err": state_error(R, W, *ref), "dE": dE, "dLz": dLz,
        "geom": float(TOP.orth_error(sol.y_final)), "geom_kind": "orth",
    }


def run_scipy(name, tol, ref, cfg):
    method, _, variant = name.partition("-")
    rhs = RHS_VARIANTS[variant or "float"]()
    s0 = np.concatenate((rotation_to_quaternion(R0), W0))
    fn = lambda: solve_ivp(rhs, (0.0, T_END), s0, method=method, rtol=tol, atol=tol)  # noqa: E731
    sol, cpu = timed(fn, cfg["min_time"], cfg["repeats"])
    if not sol.success:
        raise RuntimeError(f"solve_ivp {method} tol={tol}: {sol.message}")
    q, W = sol.y[:4, -1], sol.y[4:, -1]
    nq = float(np.linalg.norm(q))
    R = quat_to_rot(q / nq)
    dE, dLz = diagnostics(R, W)
    return {
        "lib": "scipy", "method": name, "param": ("tol", tol),
        "steps": len(sol.t) - 1, "rejected": None, "nfev": int(sol.nfev),
        "cpu": cpu, "err": state_error(R, W, *ref), "dE": dE, "dLz": dLz,
        "geom": abs(nq - 1.0), "geom_kind": "qnorm",
    }


def reference(n_steps: int):
    problem = TOP.problem()
    t0 = time.process_time()
    a = integrate(problem, Y0, (0.0, T_END), method="rkmk6", dt=T_END / n_steps)
    b = integrate(problem, Y0, (0.0, T_END), method="rkmk6", dt=T_END / (2 * n_steps))
    cpu = time.process_time() - t0
    Ra, Wa = TOP.split(a.y_final)
    Rb, Wb = TOP.split(b.y_final)
    return (Rb.copy(), Wb.copy()), state_error(Ra, Wa, Rb, Wb), cpu


# -- free-body runs -----------------------------------------------------------------------
class NoReuse(GroupProblem):
    """The generic loop with the FSAL reuse switched off (for target 4 only)."""

    fsal_reuse = False


def fb_split(y):
    R, W = FB.SPACE.split(np.asarray(y))
    return np.asarray(R), np.asarray(W)


def fb_row(variant, method, param, sol, cpu, ref, outputs=1):
    R, W = fb_split(sol.y_final)
    st = sol.stats
    return {
        "lib": "liegroup_int", "method": method, "variant": variant, "group": f"{method} ({'njit f' if variant == 'njit' else 'Python f'})",
        "param": param, "steps": st.steps, "rejected": st.rejected, "nfev": st.rhs_evals, "cpu": cpu,
        "err": state_error(R, W, *ref), "dE": abs(FB.energy(W) - FB.E0) / FB.E0,
        "geom": float(np.abs(R.T @ R - np.eye(3)).max()), "outputs": outputs, "y": np.array(sol.y_final),
    }


def fb_run_ours(variant, method, *, dt=None, tol=None, ref, cfg, t_eval=None):
    """One free-body run: ``variant`` "njit" (compiled engine), "python" (generic loop) or
    "python, no reuse" (generic loop, FSAL reuse off)."""
    f = FB.f_njit if variant == "njit" else FB.f_python
    target = NoReuse(FB.SPACE, FB.f_python) if variant == "python, no reuse" else f
    kw = {"dt": dt} if dt is not None else {"rtol": tol, "atol": tol}
    fn = lambda: integrate(target, FB.Y0, (0.0, FB.T_END), space=FB.SPACE, method=method, t_eval=t_eval, **kw)  # noqa: E731
    sol, cpu = timed(fn, cfg["min_time"], cfg["repeats"])
    outputs = 1 if t_eval is None else len(sol.t) - 1
    return fb_row(variant, method, ("h", dt) if dt is not None else ("tol", tol), sol, cpu, ref, outputs)


def fb_run_scipy(name, tol, ref, cfg):
    method, _, variant = name.partition("-")
    rhs = FB.quat_rhs_numpy if variant == "numpy" else FB.quat_rhs_float
    fn = lambda: solve_ivp(rhs, (0.0, FB.T_END), FB.quat0(), method=method, rtol=tol, atol=tol)  # noqa: E731
    sol, cpu = timed(fn, cfg["min_time"], cfg["repeats"])
    if not sol.success:
        raise RuntimeError(f"solve_ivp {method} tol={tol}: {sol.message}")
    q, W = sol.y[:4, -1], sol.y[4:, -1]
    nq = float(np.linalg.norm(q))
    return {
        "lib": "scipy", "method": name, "variant": variant or "float", "group": name, "param": ("tol", tol),
        "steps": len(sol.t) - 1, "rejected": None, "nfev": int(sol.nfev), "cpu": cpu,
        "err": state_error(quat_to_rot(q / nq), W, *ref), "dE": abs(FB.energy(W) - FB.E0) / FB.E0,
        "geom": abs(nq - 1.0), "outputs": 1,
    }


def fb_reference(n_steps: int):
    """RKMK6 with the njit f at ``h = T / n_steps``; its difference to ``h / 2`` and to DOP853
    at tolerance 1e-13 (quaternions). Over 20 s near the intermediate axis round-off grows
    with the number of steps, so the coarser run is the reference (its truncation error
    is far below the round-off of either)."""
    t0 = time.process_time()
    a = integrate(FB.f_njit, FB.Y0, (0.0, FB.T_END), space=FB.SPACE, method="rkmk6", dt=FB.T_END / n_steps)
    b = integrate(FB.f_njit, FB.Y0, (0.0, FB.T_END), space=FB.SPACE, method="rkmk6", dt=FB.T_END / (2 * n_steps))
    d = solve_ivp(FB.quat_rhs_float, (0.0, FB.T_END), FB.quat0(), method="DOP853", rtol=1e-13, atol=1e-13)
    cpu = time.process_time() - t0
    ref = tuple(x.copy() for x in fb_split(a.y_final))
    Rb, Wb = fb_split(b.y_final)
    q = d.y[:4, -1]
    return ref, state_error(Rb, Wb, *ref), state_error(quat_to_rot(q / np.linalg.norm(q)), d.y[4:, -1], *ref), cpu


def first_call_times(methods):
    """``{method: {"first", "second"}}`` CPU seconds of integrate with the njit f, each in a
    fresh process (:func:`liegroup_int.bench.free_body.first_calls_fresh`)."""
    return {m: FB.first_calls_fresh(m) for m in methods}


def generic_overhead(cfg, run45):
    """Per-stage cost of the generic loop without ``f`` (an ``f`` returning a precomputed
    array), the README ``f`` alone, and the same figure by subtraction from the real run."""
    xi = FB.f_python(0.0, FB.Y0)
    const = lambda t, y: xi  # noqa: E731
    res = {}
    for key, method, kw in (("adaptive rkmk45", "rkmk45", {"rtol": FB_TOL, "atol": FB_TOL}),
                            ("fixed rkmk4", "rkmk4", {"dt": FB.T_END / 2000})):
        fn = lambda method=method, kw=kw: integrate(const, FB.Y0, (0.0, FB.T_END), space=FB.SPACE, method=method,  # noqa: E731
                                                    **kw)
        sol, cpu = timed(fn, cfg["min_time"], cfg["repeats"])
        res[key] = (cpu / sol.stats.rhs_evals * 1e6, sol.stats.rhs_evals)
    batch = lambda: [FB.f_python(0.0, FB.Y0) for _ in range(500)]  # noqa: E731
    _, t = timed(batch, cfg["min_time"], cfg["repeats"])
    res["f_python"] = t / 500 * 1e6
    sc = FB.quat0()
    batch = lambda: [FB.quat_rhs_numpy(0.0, sc) for _ in range(500)]  # noqa: E731
    _, t = timed(batch, cfg["min_time"], cfg["repeats"])
    res["rhs_numpy"] = t / 500 * 1e6
    batch = lambda: [FB.quat_rhs_float(0.0, sc) for _ in range(500)]  # noqa: E731
    _, t = timed(batch, cfg["min_time"], cfg["repeats"])
    res["rhs_float"] = t / 500 * 1e6
    if run45 is not None:
        res["subtracted rkmk45"] = run45["cpu"] / run45["nfev"] * 1e6 - res["f_python"]
    return res


# -- analysis -----------------------------------------------------------------------------
def frontier(rows, key="cpu"):
    """Pareto front of ``(err, cost)``: points sorted by cost whose error improves on all cheaper ones."""
    pts = sorted(((r[key], r["err"]) for r in rows if np.isfinite(r["err"]) and r["err"] > 0), key=lambda p: p[0])
    out, best = [], np.inf
    for c, e in pts:
        if e < best:
            out.append((c, e))
            best = e
    return out


def cost_at(rows, level, key="cpu"):
    """Cost to reach error ``level``, interpolated in log-log along the front; None if out of range."""
    pts = frontier(rows, key)
    if len(pts) < 2:
        return None
    errs = np.array([e for _, e in pts])
    costs = np.array([c for c, _ in pts])
    if not (errs[-1] <= level <= errs[0]):
        return None
    le, lc = np.log(errs[::-1]), np.log(costs[::-1])  # increasing error for np.interp
    return float(np.exp(np.interp(np.log(level), le, lc)))


def best_at(groups, level, key="cpu"):
    best = None
    for name, rows in groups.items():
        c = cost_at(rows, level, key)
        if c is not None and (best is None or c < best[1]):
            best = (name, c)
    return best


def cheapest_reaching(rows, level):
    """The cheapest single run (CPU) with error at most ``level``, or None."""
    ok = [r for r in rows if r["err"] <= level]
    return min(ok, key=lambda r: r["cpu"]) if ok else None


def group_rows(rows, lib, variants=True):
    """Rows of one library by group (method); ``variants=False`` drops the NumPy-RHS scipy variant."""
    out = {}
    for r in rows:
        if r["lib"] == lib and (variants or not r["method"].endswith("-numpy")):
            out.setdefault(r.get("group", r["method"]), []).append(r)
    return out


def float_coefficient_defects(methods):
    """Order-1/2 condition defects of each tableau *after rounding its coefficients to float64*.

    Evaluated in exact rational arithmetic on the rounded values, with the rounded ``c``:
    the engine forms every stage increment as ``h (c_r K_0 + sum_l a_rl (K_l - K_0))`` and the
    step as ``h (K_0 + sum_l b_l (K_l - K_0))`` (``rkmk.combine``), so the effective row sums
    are ``c_r`` and the weights sum to 1 whatever the rounding of ``A`` and ``b``; the first
    column is the defect ``sum(b) - 1`` of the rounded weights that this form removes.
    """
    from fractions import Fraction

    out = {}
    for m in methods:
        try:
            tab = resolve_method(m)
            b = [Fraction(float(x)) for x in np.asarray(tab.b_f)]
        except Exception:  # noqa: BLE001 - diagnostics only
            continue
        c = [Fraction(float(x)) for x in np.asarray(tab.c_f)]
        out[m] = (float(sum(b) - 1), float(sum(bi * ci for bi, ci in zip(b, c)) - Fraction(1, 2)),
                  float(np.max(np.abs(np.asarray(tab.A_f)))), float(np.max(np.abs(np.asarray(tab.b_f)))))
    return out


def per_eval_costs(rows):
    """Median CPU microseconds per RHS evaluation (runs of >= 500 evals)."""
    sel = {
        "fixed": lambda r: r["lib"] == "liegroup_int" and r["param"][0] == "h",
        "adaptive": lambda r: r["lib"] == "liegroup_int" and r["param"][0] == "tol",
        "scipy": lambda r: r["lib"] == "scipy" and not r["method"].endswith("-numpy"),
        "scipy-numpy": lambda r: r["lib"] == "scipy" and r["method"].endswith("-numpy"),
    }
    res = {}
    for key, ok in sel.items():
        v = [r["cpu"] / r["nfev"] * 1e6 for r in rows if ok(r) and r["nfev"] >= 500]
        res[key] = float(np.median(v)) if v else float("nan")
    return res


def fb_per_eval_costs(rows):
    res = {}
    for g in ("njit", "python"):
        v = [r["cpu"] / r["nfev"] * 1e6 for r in rows if r.get("variant") == g and r["nfev"] >= 500]
        res[g] = float(np.median(v)) if v else float("nan")
    for g in ("float", "numpy"):
        v = [r["cpu"] / r["nfev"] * 1e6 for r in rows if r["lib"] == "scipy" and r["variant"] == g]
        res["scipy-" + g] = float(np.median(v)) if v else float("nan")
    return res


# -- targets ------------------------------------------------------------------------------
def fmt_run(r):
    if r is None:
        return "n/a"
    kind, val = r["param"]
    return f"{r.get('group', r['method'])} {kind}={val:.3g}: {r['cpu']:.3g} s, err {r['err']:.1e}"


def ratio_txt(a, b, digits=3):
    return "n/a" if a is None or b is None else f"{a / b:.{digits}g}"


def target1(fb_rows):
    """Free body, njit f vs DOP853 (plain-float RHS) at FB_LEVELS."""
    ours = {g: rs for g, rs in group_rows(fb_rows, "liegroup_int").items() if g.endswith("(njit f)")}
    peer = [r for r in fb_rows if r["group"] == "DOP853"]
    header = ["error level", "ours best (interp.)", "DOP853 (interp.)", "ratio ours/DOP853",
              "per method: ratio"] + ["cheapest run reaching it: ours", "DOP853", "ratio"]
    out, res = [], []
    for lev in FB_LEVELS:
        o, p = best_at(ours, lev), cost_at(peer, lev)
        per = ", ".join(f"{g.split()[0]} {ratio_txt(cost_at(rs, lev), p, 2)}" for g, rs in ours.items())
        oc = cheapest_reaching([r for rs in ours.values() for r in rs], lev)
        pc = cheapest_reaching(peer, lev)
        out.append([f"{lev:.0e}", "n/a" if o is None else f"{o[0].split()[0]} {o[1]:.3g} s",
                    "n/a" if p is None else f"{p:.3g} s", ratio_txt(o and o[1], p), per,
                    fmt_run(oc), fmt_run(pc), ratio_txt(oc and oc["cpu"], pc and pc["cpu"])])
        res.append({"level": lev, "ours": o, "peer": p, "ratio": (o[1] / p) if o and p else None,
                    "ratio_cheapest": (oc["cpu"] / pc["cpu"]) if oc and pc else None, "ours_run": oc, "peer_run": pc})
    return header, out, res


def target2(fb_rows, over):
    """Free body, Python f (generic loop) vs DOP853 with the NumPy-style RHS."""
    at = lambda g: next((r for r in fb_rows if r["group"] == g and r["param"] == ("tol", FB_TOL)), None)  # noqa: E731
    pn, pf = at("DOP853-numpy"), at("DOP853")
    header = ["ours (Python f)", "CPU s", "RHS evals", "error", "vs DOP853 NumPy RHS, same tol",
              "vs DOP853 float RHS, same tol", "equal error: ours interp. / DOP853 NumPy RHS"]
    out, res = [], {"peer": pn, "peer_float": pf, "same_tol": {}, "equal": None}
    py = {g: rs for g, rs in group_rows(fb_rows, "liegroup_int").items() if g.endswith("(Python f)")}
    for g in py:
        r = at(g)
        if r is None:
            continue
        rat = r["cpu"] / pn["cpu"] if pn else None
        res["same_tol"][g] = rat
        out.append([f"{g} tol={FB_TOL:.0e}", f"{r['cpu']:.3g}", f"{r['nfev']}", f"{r['err']:.1e}",
                    ratio_txt(r["cpu"], pn and pn["cpu"]), ratio_txt(r["cpu"], pf and pf["cpu"]), ""])
    if pn is not None:
        o = best_at(py, pn["err"])
        res["equal"] = (o[0], o[1], o[1] / pn["cpu"]) if o else None
        out.append([f"best at error {pn['err']:.1e}" + (f" ({o[0]})" if o else ""), "n/a" if o is None else f"{o[1]:.3g}",
                    "", "", "", "", "n/a" if o is None else f"{o[1] / pn['cpu']:.3g}"])
    for name, r in (("DOP853, NumPy RHS", pn), ("DOP853, float RHS", pf)):
        if r is not None:
            out.append([f"peer: {name} tol={FB_TOL:.0e}", f"{r['cpu']:.3g}", f"{r['nfev']}", f"{r['err']:.1e}",
                        "", "", ""])
    return header, out, res


def target3(rows):
    """Heavy top, adaptive rkmk45/rkmk65 (compiled engine) vs scipy's best (float RHS)."""
    ours = group_rows(rows, "liegroup_int")
    peer = group_rows(rows, "scipy", variants=False)
    ad = {m: ours[m] for m in ("rkmk45", "rkmk65") if m in ours}
    header = ["error level", "scipy best", "rkmk45 CPU s", "rkmk45 / scipy", "rkmk65 CPU s", "rkmk65 / scipy",
              "best adaptive / scipy", "ours at least as fast"]
    out, res = [], []
    for lev in ERROR_LEVELS:
        p = best_at(peer, lev)
        c = {m: cost_at(rs, lev) for m, rs in ad.items()}
        avail = [v for v in c.values() if v is not None]
        best = min(avail) if avail else None
        ok = None if best is None or p is None else best <= p[1]
        out.append([f"{lev:.0e}", "n/a" if p is None else f"{p[0]} {p[1]:.3g}",
                    *[x for m in ("rkmk45", "rkmk65") for x in
                      ("n/a" if c.get(m) is None else f"{c[m]:.3g}", ratio_txt(c.get(m), p and p[1]))],
                    ratio_txt(best, p and p[1]), "n/a" if ok is None else ("yes" if ok else "**no**")])
        res.append({"level": lev, "peer": p, "costs": c, "ratio": (best / p[1]) if best and p else None, "ok": ok})
    return header, out, res


def summary(rows):
    """Heavy top: best of each library (all methods), fixed and adaptive separately, in CPU and evaluations."""
    ours, peer = group_rows(rows, "liegroup_int"), group_rows(rows, "scipy", variants=False)
    fixed = {m: rs for m, rs in ours.items() if rs[0]["param"][0] == "h"}
    adaptive = {m: rs for m, rs in ours.items() if rs[0]["param"][0] == "tol"}
    header = ["error level", "ours best (CPU s)", "scipy best (CPU s)", "CPU ratio ours/scipy",
              "ours fixed-step / scipy", "ours adaptive / scipy",
              "ours best (RHS evals)", "scipy best (RHS evals)", "RHS-eval ratio ours/scipy"]
    out = []
    for lev in ERROR_LEVELS:
        o, p = best_at(ours, lev), best_at(peer, lev)
        of, oa = best_at(fixed, lev), best_at(adaptive, lev)
        on, pn = best_at(ours, lev, "nfev"), best_at(peer, lev, "nfev")
        cell = lambda b, fmt: "n/a" if b is None else f"{b[0]} {fmt(b[1])}"  # noqa: E731
        rat = lambda a, b: f"{a[1] / b[1]:.3g}" if a and b else "n/a"  # noqa: E731
        out.append([f"{lev:.0e}", cell(o, lambda v: f"{v:.3g}"), cell(p, lambda v: f"{v:.3g}"), rat(o, p),
                    "n/a" if of is None else f"{of[0]} {rat(of, p)}", "n/a" if oa is None else f"{oa[0]} {rat(oa, p)}",
                    cell(on, lambda v: f"{v:.0f}"), cell(pn, lambda v: f"{v:.0f}"), rat(on, pn)])
    return header, out


def target4(rows, fb_rows, extra):
    """FSAL: evaluations per accepted step with reuse, and without (stages x attempts)."""
    def near(rs, method, tol):
        rs = [r for r in rs if r["method"] == method and r["param"][0] == "tol"]
        return min(rs, key=lambda r: abs(math.log(r["param"][1] / tol))) if rs else None

    cases = [("heavy top", "compiled (built-in)", near([r for r in rows if r["lib"] == "liegroup_int"], "rkmk45", 1e-8)),
             ("heavy top", "compiled (built-in)", near([r for r in rows if r["lib"] == "liegroup_int"], "rkmk65", 1e-8))]
    cases += [("free body", "compiled (njit f)", r) for r in extra["njit"]]
    cases += [("free body", "generic (Python f)", r) for r in extra["python"]]
    header = ["problem", "path", "method, tol", "output intervals", "accepted", "rejected", "RHS evals",
              "evals / accepted step", "without reuse: stages x attempts", "saved", "CPU s"]
    out, res = [], []
    for prob, path, r in cases:
        if r is None:
            continue
        stages = resolve_method(r["method"]).stages
        without = stages * attempts(r)
        measured = r.get("variant") == "python, no reuse"
        per = r["nfev"] / r["steps"]
        out.append([prob, path + (", reuse off" if measured else ""), f"{r['method']} tol={r['param'][1]:.0e}",
                    f"{r.get('outputs', 1)}", f"{r['steps']}", f"{r['rejected']}", f"{r['nfev']}", f"{per:.3f}",
                    f"{without}" + (" (= measured)" if measured and without == r["nfev"] else ""),
                    "-" if measured else f"{1 - r['nfev'] / without:.1%}", f"{r['cpu']:.3g}"])
        res.append({"problem": prob, "path": path, "row": r, "per_step": per, "without": without})
    return header, out, res


# -- formatting ---------------------------------------------------------------------------
HEADER = ["library", "method", "h / tol", "steps", "RHS evals", "CPU s", "error", "|E-E0|/|E0|",
          "|Lz-Lz0|/|Lz0|", "orth. err / ||q|-1|"]
FB_HEADER = ["library", "f / RHS", "method", "h / tol", "steps", "RHS evals", "CPU s", "error", "|E-E0|/|E0|",
             "orth. err / ||q|-1|"]


def fmt_row(r):
    kind, val = r["param"]
    steps = f"{r['steps']}" + (f" (+{r['rejected']} rej)" if r.get("rejected") else "")
    return [r["lib"], r["method"], f"{kind}={val:.3g}", steps, f"{r['nfev']}", f"{r['cpu']:.3g}",
            f"{r['err']:.2e}", f"{r['dE']:.1e}", f"{r['dLz']:.1e}", f"{r['geom']:.1e}"]


def fb_fmt_row(r):
    kind, val = r["param"]
    steps = f"{r['steps']}" + (f" (+{r['rejected']} rej)" if r.get("rejected") else "")
    form = {"njit": "numba.njit f", "python": "Python f", "float": "plain floats", "numpy": "NumPy style"}[r["variant"]]
    return [r["lib"], form, r["method"].replace("-numpy", ""), f"{kind}={val:.3g}", steps, f"{r['nfev']}",
            f"{r['cpu']:.3g}", f"{r['err']:.2e}", f"{r['dE']:.1e}", f"{r['geom']:.1e}"]


def md_table(header, rows):
    esc = lambda cells: [c.replace("|", "\\|") for c in cells]  # noqa: E731 - pipes inside cells
    out = ["| " + " | ".join(esc(header)) + " |", "|" + "|".join("---" for _ in header) + "|"]
    out += ["| " + " | ".join(esc(x)) + " |" for x in rows]
    return "\n".join(out)


def plot(rows, fb_rows, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(14, 7.6))
    styles = {
        "rkmk2": ("tab:blue", "o", "-"), "rkmk3": ("tab:orange", "o", "-"), "rkmk4": ("tab:green", "o", "-"),
        "rkmk6": ("tab:red", "o", "-"), "rkmk32": ("tab:orange", "s", "--"), "rkmk45": ("tab:green", "s", "--"),
        "rkmk65": ("tab:red", "s", "--"), "RK45": ("black", "^", ":"), "DOP853": ("tab:purple", "v", ":"),
        "DOP853-numpy": ("tab:gray", "v", ":"),
    }

    def curve(ax, rs, name, label, hollow=False):
        rs = sorted(rs, key=lambda r: r["cpu"])
        color, marker, ls = styles.get(name, (None, "x", "-"))
        ax.loglog([r["cpu"] for r in rs], [r["err"] for r in rs], ls if not hollow else ":", marker=marker,
                  color=color, label=label, ms=5, mfc="none" if hollow else color)

    for lev in ERROR_LEVELS:
        ax1.axhline(lev, color="0.6", lw=0.6, ls="--", zorder=0)
    for lib in ("liegroup_int", "scipy"):
        for name, rs in group_rows(rows, lib).items():
            label = f"{name} ({'fixed h' if rs[0]['param'][0] == 'h' else 'adaptive'})" if lib == "liegroup_int" \
                else f"scipy {name.replace('-numpy', ', NumPy RHS')} (quaternions)"
            curve(ax1, rs, name, label)
    ax1.set_title(f"Heavy top (built-in, compiled), T={T_END:g} s")
    for lev in FB_LEVELS:
        ax2.axhline(lev, color="0.6", lw=0.6, ls="--", zorder=0)
    for lib in ("liegroup_int", "scipy"):
        for rs in group_rows(fb_rows, lib).values():
            m = rs[0]["method"]
            if lib == "liegroup_int":
                kind = "fixed h" if rs[0]["param"][0] == "h" else "adaptive"
                label = f"{m} ({kind}), {'numba.njit f' if rs[0]['variant'] == 'njit' else 'Python f'}"
                curve(ax2, rs, m, label, hollow=rs[0]["variant"] != "njit")
            else:
                curve(ax2, rs, m, f"scipy {m.replace('-numpy', ', NumPy RHS')} (quaternions)")
    ax2.set_title(f"Free body near the intermediate axis (README), T={FB.T_END:g} s")
    for ax in (ax1, ax2):
        ax.set_xlabel("CPU time [s] (time.process_time, best of N)")
        ax.set_ylabel(r"error at T: $|R-R_{ref}|_F + |W-W_{ref}|$")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7.5, loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=2, frameon=False)
    fig.tight_layout()
    os.makedirs(os.path.dirname(path), exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def verdict(ok):
    return "n/a" if ok is None else ("**met**" if ok else "**missed**")


def headline(t1, t2, t3, t4, comp):
    """The target table: ``(rows, notes)``."""
    rows = []
    for x in t1:
        ok = None if x["ratio"] is None else x["ratio"] <= TARGET_NJIT
        rows.append([f"1. free body, njit f: CPU to error {x['level']:.0e}", "<= 0.2",
                     "n/a" if x["ratio"] is None else f"{x['ratio']:.3f} ({x['ours'][0].split()[0]}; "
                     f"cheapest run reaching it: {ratio_txt(x['ratio_cheapest'], 1.0)})", verdict(ok)])
    st = t2["same_tol"]
    if st:
        g, r = min(st.items(), key=lambda kv: kv[1] if kv[1] is not None else np.inf)
        ok = None if r is None else r <= TARGET_PY
        rows.append([f"2. free body, Python f vs DOP853 NumPy RHS, rtol {FB_TOL:.0e}", "<= 25",
                     "; ".join(f"{k.split()[0]} {v:.2f}" for k, v in st.items() if v is not None), verdict(ok)])
    if t2["equal"]:
        g, _, r = t2["equal"]
        rows.append([f"2. same, at equal error ({t2['peer']['err']:.1e})", "<= 25", f"{r:.2f} ({g.split()[0]})",
                     verdict(r <= TARGET_PY)])
    for x in t3:
        rows.append([f"3. heavy top, adaptive rkmk45/65 vs scipy best, error {x['level']:.0e}", "<= 1",
                     "n/a" if x["ratio"] is None else f"{x['ratio']:.3f}", verdict(x["ok"])])
    for x in t4:
        r = x["row"]
        if r["method"] == "rkmk45" and r.get("variant") != "python, no reuse":
            rows.append([f"4. FSAL, {x['problem']}, {x['path']}, rkmk45, {r.get('outputs', 1)} output interval(s)",
                         "6 + small", (f"{x['per_step']:.3f} evals / accepted step ({r['nfev']} vs "
                                       f"{x['without']} without reuse)"), "shown"])
    if comp:
        rows.append(["first call of a new njit f, fresh process (engine loops from the disk cache; not in the ratios)", "-",
                     "; ".join(f"{m} {v['first'] - v['second']:.1f} s" for m, v in comp.items()), "-"])
    return rows


def plateau(rs):
    """``(floor, gain)`` when the last two tolerance decades of an adaptive sweep gain less than 4x in error."""
    rs = sorted((r for r in rs if r["param"][0] == "tol"), key=lambda r: -r["param"][1])
    if len(rs) < 3 or rs[-1]["param"][1] > 1e-2 * rs[-3]["param"][1] * 1.01:
        return None
    gain = rs[-3]["err"] / max(rs[-1]["err"], 1e-300)
    return (min(r["err"] for r in rs), gain) if gain < 4 else None


def _reading_free_body(fb_rows, t1, t2, over, fpe) -> list[str]:
    parts = []
    ok1 = [x for x in t1 if x["ratio"] is not None]
    if ok1:
        ours = {g: rs for g, rs in group_rows(fb_rows, "liegroup_int").items() if g.endswith("(njit f)")}
        peer = [r for r in fb_rows if r["group"] == "DOP853"]
        ev = []
        for x in ok1:
            on, pn = best_at(ours, x["level"], "nfev"), cost_at(peer, x["level"], "nfev")
            if on and pn:
                ev.append(f"{on[1] / pn:.2f}x at {x['level']:.0e} ({on[0].split()[0]})")
        parts.append(
            f"**Free body, njit f.** The compiled engine costs about {fpe['njit']:.2g} us per stage (the user's f "
            f"included; it allocates its return array), solve_ivp about {fpe['scipy-float']:.1f} us per evaluation "
            f"with the plain-float RHS. Counted in evaluations, our cheapest method needs "
            + (", ".join(ev) if ev else "n/a") + " of DOP853's; in CPU time "
            + ", ".join(f"{x['ratio']:.3f}x at {x['level']:.0e} ({x['ours'][0].split()[0]})" for x in ok1)
            + " (target <= 0.2). "
        )
    if t2["same_tol"] and t2["peer"]:
        st = ", ".join(f"{k.split()[0]} {v:.2f}x" for k, v in t2["same_tol"].items() if v is not None)
        eq = "" if not t2["equal"] else f"; at equal error ({t2['peer']['err']:.1e}) {t2['equal'][2]:.2f}x"
        parts.append(
            f"**Free body, Python f.** Against DOP853 with the NumPy-style RHS at rtol {FB_TOL:.0e}: {st}{eq} "
            f"(target <= 25x). Through the generic loop a stage costs about {fpe['python']:.0f} us: the README f "
            f"alone {over['f_python']:.1f} us and the loop without f {over['adaptive rkmk45'][0]:.1f} us (adaptive "
            f"rkmk45; fixed-step rkmk4 {over['fixed rkmk4'][0]:.1f} us; by subtraction from the real rkmk45 run "
            f"{over.get('subtracted rkmk45', float('nan')):.1f} us). solve_ivp pays about {fpe['scipy-numpy']:.0f} us "
            f"per evaluation with the NumPy-style RHS (the RHS alone {over['rhs_numpy']:.1f} us); the same "
            f"equations as plain floats cost {over['rhs_float']:.1f} us, which is why the njit f, not the "
            f"generic loop, is the way to beat solve_ivp with a good RHS. "
        )
    return parts


def _reading_heavy_top_fsal(t3, t4, pe) -> list[str]:
    parts = []
    ok3 = [x for x in t3 if x["ratio"] is not None]
    if ok3:
        lo, hi = min(x["ratio"] for x in ok3), max(x["ratio"] for x in ok3)
        bad = ", ".join(f"{x['level']:.0e}" for x in ok3 if not x["ok"])
        parts.append(
            f"**Heavy top.** The adaptive pairs run in the compiled engine at about {pe['adaptive']:.2g} us per "
            f"stage (fixed-step methods {pe['fixed']:.2g} us), against {pe['scipy']:.1f} us per solve_ivp evaluation "
            f"(plain-float RHS; {pe['scipy-numpy']:.0f} us NumPy-style): the best of rkmk45/rkmk65 needs "
            f"{lo:.3f}-{hi:.3f}x scipy's best CPU time at the levels both reach"
            + (f", but is slower at {bad}. " if bad else ". ")
        )
    many = [x for x in t4 if x["row"].get("outputs", 1) > 1]
    one = [x for x in t4 if x["row"].get("outputs", 1) == 1 and x["path"] == many[0]["path"]
           and x["row"]["method"] == many[0]["row"]["method"]] if many else []
    if many and one:
        a, b = one[0]["row"], many[0]["row"]
        parts.append(
            f"**FSAL.** rkmk45 costs 6 evaluations per attempt plus one at the start: "
            f"{a['nfev']} = 6 x {attempts(a)} + {a['nfev'] - 6 * attempts(a)} with one output; without reuse it "
            f"would be 7 per attempt ({one[0]['without']}). With {b['outputs']} output times the states come from "
            f"the dense output: the same {b['steps']} accepted steps (against {a['steps']}), and "
            f"{b['nfev']} = 6 x {attempts(b)} + {b['nfev'] - 6 * attempts(b)} evaluations, the extra ones the "
            f"interpolant's two bootstrapped stages on each step with an output time inside. "
        )
    return parts


def _reading_plateaus(rows, fb_rows, defects) -> list[str]:
    parts = []
    for name, rr, sel in (("heavy top", rows, lambda r: True), ("free body", fb_rows, lambda r: r.get("variant") == "njit")):
        for m in ("rkmk32", "rkmk45", "rkmk65"):
            pl = plateau([r for r in rr if r["method"] == m and sel(r)])
            if pl is None:
                continue
            d = defects.get(m)
            why = "" if d is None or abs(d[1]) < 1e-13 else (
                f" A likely cause: its tableau has coefficients up to {d[2]:.0f} (A) and {d[3]:.0f} (b); rounded to "
                f"float64 they violate the second-order condition by {abs(d[1]):.0e} (the other tableaux: ~1e-16), "
                f"a global error term that shrinks only like h.")
            parts.append(f"**{m} on the {name}** stops converging at about {pl[0]:.0e} (its two tightest tolerance "
                         f"decades gain {pl[1]:.1f}x in error).{why} ")
    return parts


def _reading_geometry(rows, fb_rows, ref_info) -> str:
    geom_o = max(r["geom"] for r in rows + fb_rows if r["lib"] == "liegroup_int")
    geom_s = max(r["geom"] for r in rows + fb_rows if r["lib"] == "scipy")
    return (
        f"**Geometry.** R stays orthogonal to {geom_o:.0e} in every run of ours with no projection; the "
        f"quaternion state drifts off the unit sphere by up to {geom_s:.0e} (loosest tolerance; q is normalised "
        f"before the error is measured, which favours scipy). "
        f"**Caveats.** The references are uncertain by about {ref_info['top']:.0e} (heavy top) and "
        f"{max(ref_info['fb_half'], ref_info['fb_dop']):.0e} (free body: near the intermediate axis round-off "
        f"grows with the step count, so free-body errors below about 1e-10 say little). Timings are CPU seconds "
        f"on a shared 2-core VM and move by roughly 10-20% between runs; the ratios far from their targets are "
        f"robust to that, those near 1 are not."
    )


def reading(rows, fb_rows, t1, t2, t3, t4, over, pe, fpe, ref_info, defects):
    """The prose reading of the results (documentation section)."""
    parts = (_reading_free_body(fb_rows, t1, t2, over, fpe) + _reading_heavy_top_fsal(t3, t4, pe)
             + _reading_plateaus(rows, fb_rows, defects) + [_reading_geometry(rows, fb_rows, ref_info)])
    return "\n\n".join(parts)


def write_doc(block: str, path: str):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    section = f"{START}\n{block.rstrip()}\n{END}"
    if os.path.exists(path):
        with open(path, encoding="utf-8") as fh:
            text = fh.read()
    else:
        text = "# Benchmarks\n\nSections between `<!-- name:start -->` / `<!-- name:end -->` markers are generated by the scripts in `benchmarks/`; edit the scripts, not the sections.\n"
    i, j = text.find(START), text.find(END)
    if i != -1 and j != -1 and j > i:
        text = text[:i] + section + text[j + len(END):]
    else:
        text = text.rstrip("\n") + "\n\n" + section + "\n"
    with open(path, "w", encoding="utf-8") as fh:
        fh.write(text)


# -- main ---------------------------------------------------------------------------------
def add_row(rows, skipped, fn, label, fmt) -> None:
    """Append ``fn()`` to ``rows`` and print it with ``fmt``; a run stopped by the driver
    (e.g. the 1 rad rotation-increment guard) goes to ``skipped`` with ``label``."""
    try:
        rows.append(fn())
    except IntegrationError as exc:
        skipped.append(f"{label}: {type(exc).__name__}: {exc}")
        print("   skipped", skipped[-1], flush=True)
        return
    print("  ", " ".join(fmt(rows[-1])), flush=True)


def sweep_free_body(fcfg, cfg, ref):
    fb_rows, skipped = [], []

    def add(fn, label):
        add_row(fb_rows, skipped, fn, f"free body {label}", fb_fmt_row)

    for m, ns in fcfg["njit_fixed"].items():
        for n in ns:
            add(lambda m=m, n=n: fb_run_ours("njit", m, dt=FB.T_END / n, ref=ref, cfg=cfg), f"{m} njit h={FB.T_END / n:.3g}")
    for variant, key in (("njit", "njit_adaptive"), ("python", "python_adaptive")):
        for m, tols in fcfg[key].items():
            for tol in tols:
                add(lambda m=m, tol=tol, v=variant: fb_run_ours(v, m, tol=tol, ref=ref, cfg=cfg), f"{m} {variant} tol={tol:.3g}")
    for m, tols in fcfg["scipy"].items():
        for tol in tols:
            add(lambda m=m, tol=tol: fb_run_scipy(m, tol, ref, cfg), f"{m} tol={tol:.3g}")
    return fb_rows, skipped


def heavy_top_sweep(cfg, skipped):
    """Every heavy-top run of ``cfg`` (ours and scipy's) and the reference's step check."""
    print(f"\nheavy top: I={INERTIA}, m={MASS}, chi={COM}, g={GRAVITY}, tilt={TILT} rad, "
          f"W0={tuple(float(w) for w in W0)}, T={T_END}")
    ref, ref_diff, ref_cpu = reference(cfg["ref_steps"])
    h_ref = T_END / cfg["ref_steps"]
    print(f"reference: rkmk6 h={h_ref:.3g} vs h/2={h_ref / 2:.3g}: difference {ref_diff:.2e} ({ref_cpu:.1f} CPU s)")
    rows = []
    for kind, sweep in (("fixed", cfg["fixed"]), ("adaptive", cfg["adaptive"])):
        for m, vals in sweep.items():
            for v in vals:
                kw = {"dt": T_END / v} if kind == "fixed" else {"tol": v}
                add_row(rows, skipped, lambda m=m, kw=kw: run_ours(m, ref=ref, cfg=cfg, **kw), f"heavy top {m} {kw}",
                        fmt_row)
    for m, tols in cfg["scipy"].items():
        for tol in tols:
            rows.append(run_scipy(m, tol, ref, cfg))
            print("  ", " ".join(fmt_row(rows[-1])), flush=True)
    return rows, ref_diff


def quick(args):
    """The heavy top alone (built-in compiled plugin, kernels cached on disk): the free
    body's sweep and its fresh-process first-call probes are left out."""
    print("quick mode: heavy top only (the free body's sweep and first-call probes are left out)")
    rows, _ = heavy_top_sweep(QUICK, [])
    h3, r3, _ = target3(rows)
    sh, srows = summary(rows)
    print("\nheavy-top runs:\n" + md_table(HEADER, [fmt_row(r) for r in rows]))
    print("\nTarget 3 (heavy top, adaptive, compiled engine vs scipy best):\n" + md_table(h3, r3))
    print("\nHeavy top, all methods:\n" + md_table(sh, srows))
    if not args.no_write:
        png = figure_dir(args, ROOT / "docs" / "img") / PNG_NAME
        plot(rows, [], str(png))
        print(f"wrote {png}")


def free_body_part(cfg) -> dict:
    """Every free-body run (targets 1, 2, 4): the compile probes, the reference, the sweep,
    the FSAL runs and the generic loop's overhead."""
    fcfg = cfg["fb"]
    print(f"free body (README): I={FB.INERTIA}, W0={FB.W0}, T={FB.T_END}")
    comp = first_call_times(fcfg["first_calls"])
    for m, v in comp.items():
        print(f"numba.njit f, first integrate call ({m}, fresh process): {v['first']:.2f} s CPU, second "
              f"{v['second'] * 1e3:.2f} ms -> compile {v['first'] - v['second']:.2f} s")
    fb_ref, fb_half, fb_dop, fb_cpu = fb_reference(fcfg["ref_steps"])
    print(f"reference: rkmk6 h={FB.T_END / fcfg['ref_steps']:.3g}; h/2 differs by {fb_half:.1e}, DOP853 tol 1e-13 "
          f"by {fb_dop:.1e} ({fb_cpu:.1f} CPU s, compilation included)")
    fb_rows, skipped = sweep_free_body(fcfg, cfg, fb_ref)

    # FSAL rows and the generic loop with reuse switched off (same tolerance as target 2)
    t_eval = np.linspace(0.0, FB.T_END, 201)
    extra = {"njit": [fb_run_ours("njit", "rkmk45", tol=FB_TOL, ref=fb_ref, cfg=cfg),
                      fb_run_ours("njit", "rkmk45", tol=FB_TOL, ref=fb_ref, cfg=cfg, t_eval=t_eval),
                      fb_run_ours("njit", "rkmk65", tol=FB_TOL, ref=fb_ref, cfg=cfg)],
             "python": [fb_run_ours("python", "rkmk45", tol=FB_TOL, ref=fb_ref, cfg=cfg),
                        fb_run_ours("python, no reuse", "rkmk45", tol=FB_TOL, ref=fb_ref, cfg=cfg)]}
    agree = float(np.abs(extra["njit"][0]["y"] - extra["python"][0]["y"]).max())
    same_steps = (extra["njit"][0]["steps"], extra["njit"][0]["rejected"]) == \
        (extra["python"][0]["steps"], extra["python"][0]["rejected"])
    print(f"njit vs Python f, rkmk45 tol {FB_TOL:.0e}: final states differ by {agree:.1e}, same steps: {same_steps}")
    over = generic_overhead(cfg, extra["python"][0])

    return dict(comp=comp, fb_ref=fb_ref, fb_half=fb_half, fb_dop=fb_dop, fb_rows=fb_rows, skipped=skipped,
                extra=extra, agree=agree, same_steps=same_steps, over=over)


def analyse(cfg, fb: dict, rows, ref_diff) -> dict:
    """The targets' tables, the per-evaluation costs and the tableaux' defects."""
    fb_rows, extra, over = fb["fb_rows"], fb["extra"], fb["over"]
    h1, r1, t1 = target1(fb_rows)
    h2, r2, t2 = target2(fb_rows, over)
    h3, r3, t3 = target3(rows)
    sh, srows = summary(rows)
    h4, r4, t4 = target4(rows, fb_rows, extra)
    pe, fpe = per_eval_costs(rows), fb_per_eval_costs(fb_rows)
    defects = float_coefficient_defects(list(cfg["fixed"]) + list(cfg["adaptive"]))
    ref_info = {"top": ref_diff, "fb_half": fb["fb_half"], "fb_dop": fb["fb_dop"]}
    heads = headline(t1, t2, t3, t4, fb["comp"])
    hh = ["target", "goal", "measured", "verdict"]
    fb_table = [fb_fmt_row(r) for r in fb_rows]
    table_rows = [fmt_row(r) for r in rows]

    text = reading(rows, fb_rows, t1, t2, t3, t4, over, pe, fpe, ref_info, defects)
    return dict(h1=h1, r1=r1, h2=h2, r2=r2, h3=h3, r3=r3, sh=sh, srows=srows, h4=h4, r4=r4, pe=pe, fpe=fpe,
                defects=defects, heads=heads, hh=hh, fb_table=fb_table, table_rows=table_rows, text=text)


def print_report(fb: dict, a: dict) -> None:
    over, pe, fpe = fb["over"], a["pe"], a["fpe"]
    print("\nfree body runs:\n" + md_table(FB_HEADER, a["fb_table"]))
    print("\nheavy-top runs:\n" + md_table(HEADER, a["table_rows"]))
    print("\nTarget 1 (free body, numba.njit f vs DOP853 plain-float RHS):\n" + md_table(a["h1"], a["r1"]))
    print("\nTarget 2 (free body, Python f vs DOP853 NumPy-style RHS):\n" + md_table(a["h2"], a["r2"]))
    print(f"generic loop per stage without f: adaptive rkmk45 {over['adaptive rkmk45'][0]:.1f} us "
          f"({over['adaptive rkmk45'][1]} evals), fixed rkmk4 {over['fixed rkmk4'][0]:.1f} us; "
          f"README f alone {over['f_python']:.1f} us; by subtraction {over.get('subtracted rkmk45', float('nan')):.1f} us")
    print("\nTarget 3 (heavy top, adaptive, compiled engine vs scipy best):\n" + md_table(a["h3"], a["r3"]))
    print("\nHeavy top, all methods:\n" + md_table(a["sh"], a["srows"]))
    print("\nTarget 4 (FSAL):\n" + md_table(a["h4"], a["r4"]))
    print(f"\nCPU per RHS evaluation (median, runs >= 500 evals): heavy top fixed {pe['fixed']:.2g} us, "
          f"adaptive {pe['adaptive']:.2g} us, scipy {pe['scipy']:.2g} / NumPy RHS {pe['scipy-numpy']:.2g} us; "
          f"free body njit {fpe['njit']:.2g} us, Python f {fpe['python']:.2g} us, scipy {fpe['scipy-float']:.2g} / "
          f"NumPy RHS {fpe['scipy-numpy']:.2g} us")
    print("\norder-condition defects of the float64-rounded tableaux (order 1, order 2; max|A|, max|b|):")
    for m, (d1, d2, amax, bmax) in a["defects"].items():
        print(f"  {m:7s} {d1: .1e} {d2: .1e}   {amax:7.1f} {bmax:7.1f}")
    print("\n" + md_table(a["hh"], a["heads"]))
    print("\n" + a["text"])


def _doc_names(cfg, fb: dict, a: dict, ref_diff: float, wall: float) -> dict:
    """The names the documentation templates use."""
    h_ref = T_END / cfg["ref_steps"]
    return dict(cfg=cfg, fcfg=cfg["fb"], wall=wall, h_ref=h_ref, ref_diff=ref_diff, date=_dt.date.today().isoformat(),
                sk="" if not fb["skipped"] else "\nSkipped runs: " + "; ".join(f"`{x}`" for x in fb["skipped"]) + "\n",
                **{k: fb[k] for k in ("comp", "fb_half", "fb_dop", "over", "agree", "same_steps")}, **a)


def doc_head(cfg, wall, hh, heads, date, **_) -> str:
    return f"""## Rigid bodies: work-precision, liegroup_int vs scipy `solve_ivp`

Generated on {date} by

```
{COMMAND}
```

(Python {platform.python_version()}, NumPy {np.__version__}, SciPy {scipy.__version__}, numba {numba.__version__}, liegroup_int {liegroup_int.__version__}; {platform.machine()}, {os.cpu_count()} CPUs, shared VM; total script runtime {wall:.0f} s.)
Ratios are CPU time ours / scipy (`time.process_time()`; runs shorter than {cfg['min_time']} s batched; best of
{cfg['repeats']} batches; every runner called once before timing, so numba compilation is excluded and reported
apart). Error = `|R(T) - R_ref(T)|_F + |W(T) - W_ref(T)|` at the final time. Peer:
`solve_ivp(method="DOP853")` (and RK45 on the heavy top), `rtol = atol = tol`, on unit quaternions
`q' = q (x) (0, W) / 2`; `q(T)` normalised before conversion to `R`.

{md_table(hh, heads)}

"""


def doc_free_body(fcfg, comp, fb_half, fb_dop, over, agree, same_steps, h1, r1, h2, r2, fb_table, **_) -> str:
    return f"""### Free body near the intermediate axis (the README's example; targets 1, 2)

`I = {FB.INERTIA}`, `R0 = I`, `W0 = {FB.W0}`, `t in [0, {FB.T_END:g}]` s (the body flips about every 3 s);
`liegroup_int/bench/free_body.py` holds the four forms of the right-hand side. Ours: `integrate(f, y0, (0, 20),
space=Product(SO3, Rn(3)), ...)` with a `numba.njit` f (the whole fixed-step or adaptive loop runs in the compiled
engine) or the README's plain-Python NumPy f (generic Python loop); fixed-step rkmk4/rkmk6 and adaptive
rkmk45/rkmk65 with `rtol = atol = tol`. Peer RHS: plain floats (`s.tolist()`, the fastest Python form) or
NumPy style (slicing, `np.cross`, like the README's f). Reference: rkmk6 (njit) with `h = {FB.T_END / fcfg['ref_steps']:.3g}`;
`h/2` differs from it by {fb_half:.1e} and DOP853 at tolerance 1e-13 by {fb_dop:.1e} (round-off, amplified near the
separatrix, grows with the number of steps, so the coarser run is the reference).

**Target 1, numba.njit f, against DOP853 with the plain-float RHS.** CPU to reach each error, interpolated in
log-log along each method's Pareto front ("ours best": the cheapest of rkmk4/rkmk6/rkmk45/rkmk65 there); the
cheapest single run reaching the level is shown as a check that does not interpolate. First-call overhead of
a new njit f (first `integrate` call in a fresh process minus a second call, the engine's loops loaded from
numba's disk cache; not in the ratios):
{", ".join(f"{m} {v['first'] - v['second']:.1f} s" for m, v in comp.items())}.

{md_table(h1, r1)}

**Target 2, the README's plain-Python f (generic loop), against DOP853 with the NumPy-style RHS** at
`rtol = atol = {FB_TOL:.0e}`, and at equal error (ours interpolated to DOP853's error at that tolerance):

{md_table(h2, r2)}

Generic-loop overhead per stage, excluding f (an f returning a precomputed array, CPU / RHS evaluations):
{over['adaptive rkmk45'][0]:.1f} us adaptive rkmk45 (`rtol = {FB_TOL:.0e}`, {over['adaptive rkmk45'][1]} evaluations),
{over['fixed rkmk4'][0]:.1f} us fixed-step rkmk4 (`h = 0.01`); by subtraction from the real rkmk45 run
(CPU / evaluations minus the README f alone, {over['f_python']:.1f} us per call):
{over.get('subtracted rkmk45', float('nan')):.1f} us. The peer's RHS alone: {over['rhs_numpy']:.1f} us NumPy style,
{over['rhs_float']:.1f} us plain floats. The njit and the Python f take {"the same" if same_steps else "different"} accepted and rejected steps and end
{agree:.0e} apart (rkmk45, `tol = {FB_TOL:.0e}`).

<details><summary>All free-body runs</summary>

{md_table(FB_HEADER, fb_table)}

</details>

"""


def doc_heavy_top(h_ref, ref_diff, h3, r3, sh, srows, table_rows, sk, h4, r4, pe, fpe, text, **_) -> str:
    return f"""### Heavy top (built-in `RigidBody(...).problem()`, compiled; target 3)

Non-symmetric heavy top on SO(3) x R^3, body frame: `dR/dt = R hat(W)`,
`I dW/dt = (I W) x W + m g (Gamma x chi)`, `Gamma = R^T e3`, with `I = {INERTIA}` kg m^2,
`m = {MASS:g}` kg, `chi = {COM}` m, `g = {GRAVITY}` m/s^2, `R0 = exp(hat({TILT} e1))`,
`W0 = {tuple(float(w) for w in W0)}` rad/s, `t in [0, {T_END:g}]` s (about {np.linalg.norm(W0) * T_END / (2 * np.pi):.0f} turns).
Reference: RKMK6 with `h = {h_ref / 2:.3g}`; the run with `h = {h_ref:.3g}` differs from it by {ref_diff:.1e}.
Ours: fixed `h` (rkmk2/3/4/6) or `rtol = atol = tol` (rkmk32/45/65), all through the compiled engine (no monitor).
Peer: RK45 and DOP853 with the plain-float RHS (`DOP853-numpy`: NumPy style, shown, not used for "scipy best").

**Target 3, adaptive rkmk45/rkmk65 against scipy's best** (log-log interpolation along each method's Pareto
front; scipy best: the cheaper of RK45 and DOP853 at that error):

{md_table(h3, r3)}

All methods (best of each library; fixed-step and adaptive separately; in CPU and in RHS evaluations):

{md_table(sh, srows)}

<details><summary>All heavy-top runs</summary>

Energy and vertical-momentum (`Lz = (R I W) . e3`) drift relative to their initial values at `T`; last column
`|R^T R - I|_F` (ours) or `| |q| - 1 |` (scipy).

{md_table(HEADER, table_rows)}

</details>
{sk}
### FSAL reuse (target 4)

The pairs rkmk45 (7 stages) and rkmk65 (9) are first-same-as-last: the last stage's field starts the next
step, so an attempt costs one evaluation less, across output times too (the compiled engine carries it from one
call to the next). "Without reuse" is stages x attempts; the generic loop was also run with the reuse switched
off (a `GroupProblem` subclass with `fsal_reuse = False`) to measure it.

{md_table(h4, r4)}

CPU per RHS evaluation (median over runs with >= 500 evaluations): heavy top, compiled engine: fixed-step
{pe['fixed']:.2g} us, adaptive {pe['adaptive']:.2g} us; solve_ivp {pe['scipy']:.1f} us (plain floats), {pe['scipy-numpy']:.0f} us
(NumPy style). Free body: njit f {fpe['njit']:.2g} us, Python f {fpe['python']:.0f} us; solve_ivp {fpe['scipy-float']:.1f} us
(plain floats), {fpe['scipy-numpy']:.0f} us (NumPy style).

![work-precision](img/rigid_body_work_precision.png)

{text}
"""


def main(argv=None):
    ap = parser(__doc__, quick_help="small sweep for a smoke test; no docs (the figure goes to --out)")
    ap.add_argument("--no-write", action="store_true", help="do not write docs/benchmarks.md or the PNG")
    args = ap.parse_args(argv)
    if args.quick:
        return quick(args)
    cfg = FULL
    wall0, cpu0 = time.perf_counter(), time.process_time()
    fb = free_body_part(cfg)
    rows, ref_diff = heavy_top_sweep(cfg, fb["skipped"])
    a = analyse(cfg, fb, rows, ref_diff)
    print_report(fb, a)
    wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
    print(f"\ntotal runtime: {wall:.1f} s wall, {cpu:.1f} s CPU (this process; compile probes run in subprocesses)")
    if args.no_write:
        return
    png = figure_dir(args, ROOT / "docs" / "img") / PNG_NAME
    plot(rows, fb["fb_rows"], str(png))
    print(f"wrote {png}")
    names = _doc_names(cfg, fb, a, ref_diff, wall)
    write_doc(doc_head(**names) + doc_free_body(**names) + doc_heavy_top(**names), str(DOC))
    print(f"wrote the '{SECTION}' section of {DOC.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
