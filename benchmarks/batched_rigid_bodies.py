"""Many heavy tops in one call (batched group layer) against a loop of solve_ivp.

    python benchmarks/batched_rigid_bodies.py [--n 10000] [--quick]

N heavy tops with random initial attitudes and spins are integrated over T seconds by
one ``integrate`` call on states of shape ``(N, 12)`` (RKMK4 and RKMK6, fixed step), and
by scipy's ``solve_ivp`` (DOP853, quaternion form, plain-float right-hand side) body by
body. Errors are measured against RKMK6 at a 4x smaller step, as max over bodies of
``|R - R_ref|_F + |W - W_ref|``; scipy's tolerance is chosen so its error is at least as
small as ours. scipy is timed on a subset of the bodies and scaled linearly (its cost per
body does not depend on N); the subset size is printed.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

from liegroup_int import SO3, integrate
from liegroup_int.bench.table import markdown, parser
from liegroup_int.bench.timing import cpu
from liegroup_int.problems import RigidBody

TOP = RigidBody(inertia=(1.0, 0.8, 0.5), mass=1.0, com=(0.0, 0.0, 0.5), gravity=9.81)


def initial_states(n: int, seed: int = 1):
    rng = np.random.default_rng(seed)
    axis = rng.standard_normal((n, 3))
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    R0 = SO3.exp(axis * rng.uniform(0.1, 1.0, (n, 1)))
    W0 = np.column_stack([rng.uniform(-1, 1, n), rng.uniform(-1, 1, n), rng.uniform(4.0, 8.0, n)])
    return R0, W0


def quat_rhs(t, x, I=np.array(TOP.inertia), mgchi=TOP.mass * TOP.gravity * np.array(TOP.com)):
    w, a, b, c, p, q, r = x
    # Gamma = R^T e3 from the unit quaternion (w, a, b, c)
    g0, g1, g2 = 2 * (a * c - w * b), 2 * (b * c + w * a), w * w - a * a - b * b + c * c
    n = w * w + a * a + b * b + c * c
    g0, g1, g2 = g0 / n, g1 / n, g2 / n
    I1, I2, I3 = I
    t1 = (I2 - I3) * q * r + g1 * mgchi[2] - g2 * mgchi[1]
    t2 = (I3 - I1) * r * p + g2 * mgchi[0] - g0 * mgchi[2]
    t3 = (I1 - I2) * p * q + g0 * mgchi[1] - g1 * mgchi[0]
    return [0.5 * (-a * p - b * q - c * r), 0.5 * (w * p + b * r - c * q), 0.5 * (w * q + c * p - a * r),
            0.5 * (w * r + a * q - b * p), t1 / I1, t2 / I2, t3 / I3]


def quat_to_R(q):
    w, a, b, c = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (b * b + c * c), 2 * (a * b - w * c), 2 * (a * c + w * b)],
                     [2 * (a * b + w * c), 1 - 2 * (a * a + c * c), 2 * (b * c - w * a)],
                     [2 * (a * c - w * b), 2 * (b * c + w * a), 1 - 2 * (a * a + b * b)]])


def error(R, W, Rr, Wr):
    return float(np.max(np.linalg.norm(R - Rr, axis=(-2, -1)) + np.linalg.norm(W - Wr, axis=-1)))


def scipy_bodies(R0, W0, sub, T, tol):
    """End attitudes and spins of the bodies ``sub`` by DOP853 at ``rtol = atol = tol``."""
    Rs, Ws = [], []
    for i in sub:
        q = Rotation.from_matrix(R0[i]).as_quat()  # (x, y, z, w)
        x0 = np.concatenate([[q[3]], q[:3], W0[i]])
        s = solve_ivp(quat_rhs, (0.0, T), x0, method="DOP853", rtol=tol, atol=tol)
        Rs.append(quat_to_R(s.y[:4, -1]))
        Ws.append(s.y[4:, -1])
    return np.array(Rs), np.array(Ws)


def compare(method, h, R0, W0, y0, T, n, subset):
    """One row: ours at step ``h``, then DOP853 tightened until its error is <= ours."""
    ref = integrate(TOP.problem(), y0, (0.0, T), method="rkmk6", dt=h / 4).y_final
    Rr, Wr = TOP.split(ref)
    sol, cpu_ours = cpu(lambda: integrate(TOP.problem(), y0, (0.0, T), method=method, dt=h))
    err = error(*TOP.split(sol.y_final), Rr, Wr)
    sub = np.arange(subset)
    for tol in (1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12):
        (Rs, Ws), cpu_s = cpu(lambda: scipy_bodies(R0, W0, sub, T, tol))
        err_s = error(Rs, Ws, Rr[sub], Wr[sub])
        if err_s <= err:
            break
    cpu_s *= n / subset
    return [method, f"{h:.3g}", f"{err:.2e}", f"{cpu_ours:.3g}", f"{tol:.0e}", f"{err_s:.2e}", f"{cpu_s:.3g}",
            f"{cpu_s / cpu_ours:.1f}x"]


def main(argv=None):
    ap = parser(__doc__)
    ap.add_argument("--n", type=int, default=10_000)
    ap.add_argument("--T", type=float, default=2.0)
    ap.add_argument("--subset", type=int, default=200, help="bodies timed with solve_ivp")
    a = ap.parse_args(argv)
    if a.quick:
        a.n, a.subset, a.T = 200, 5, 0.2
    R0, W0 = initial_states(a.n)
    y0 = TOP.state(R0, W0)
    rows = [compare(method, h, R0, W0, y0, a.T, a.n, a.subset) for method, h in (("rkmk4", 0.01), ("rkmk6", 0.02))]
    print(f"{a.n} heavy tops over T = {a.T} s; solve_ivp timed on {a.subset} bodies and scaled to {a.n}\n")
    print(markdown(["ours", "h", "max error", "CPU s", "DOP853 tol", "DOP853 max error", "DOP853 CPU s",
                    "ratio DOP853 / ours"], rows))
    return rows


if __name__ == "__main__":
    main()
