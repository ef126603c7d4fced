"""The README's free rigid body, the case of ``benchmarks/rigid_body_work_precision.py``.

State ``y = (R, W)`` on SO(3) x R^3 (``Product(SO3, Rn(3))``, stored flat: ``R`` row by
row, then ``W``), ``I = (1, 2, 3)``, ``R0 = I``, ``W0 = (0.01, 5.0, 0.01)`` (spin about the
intermediate axis, slightly perturbed: the body flips every few seconds), ``t in [0, 20]``.
The vector field returns the left increment rate ``(R W, (I W) x W / I)``.

Three forms of the same right-hand side:

* :func:`f_python`: the README's plain-Python ``f`` (NumPy, ``space.split``, ``np.cross``);
* :func:`f_njit`: the same written for ``numba.njit`` (array in, array out), which the
  compiled engine runs inside its fixed-step and adaptive loops;
* :func:`quat_rhs_float` / :func:`quat_rhs_numpy`: the peer's unit-quaternion form for
  ``scipy.integrate.solve_ivp``, state ``(q, W)``, ``q' = q (x) (0, W) / 2``, as plain floats
  or written the usual NumPy way.

:func:`first_calls` times the first calls of ``integrate`` with :func:`f_njit` in a fresh
process (numba compiles ``f`` and the engine's loops for it; a user's ``f`` is not cached
on disk): ``benchmarks/free_body_first_call.py``.
"""

from __future__ import annotations

import time

import numpy as np
from numba import njit

from .. import SO3, Product, Rn, integrate

INERTIA = (1.0, 2.0, 3.0)
W0 = (0.01, 5.0, 0.01)
T_END = 20.0
SPACE = Product(SO3, Rn(3))
Y0 = SPACE.join(np.eye(3), np.array(W0))
_I = np.array(INERTIA)
I1, I2, I3 = INERTIA  # numba freezes these globals into f_njit


def f_python(t, y):
    """The README's ``f`` (generic Python path)."""
    R, W = SPACE.split(y)
    return np.concatenate([R @ W, np.cross(_I * W, W) / _I])


@njit
def f_njit(t, y):
    """The same field for the compiled engine: ``y`` flat (12,), returns a new (6,)."""
    out = np.empty(6)
    for i in range(3):
        out[i] = y[3 * i] * y[9] + y[3 * i + 1] * y[10] + y[3 * i + 2] * y[11]
    a0, a1, a2 = I1 * y[9], I2 * y[10], I3 * y[11]
    out[3] = (a1 * y[11] - a2 * y[10]) / I1
    out[4] = (a2 * y[9] - a0 * y[11]) / I2
    out[5] = (a0 * y[10] - a1 * y[9]) / I3
    return out


def quat_rhs_float(t, s):
    """Peer RHS, plain floats (the fastest Python form for a 7-dimensional state)."""
    w, x, y, z, W1, W2, W3 = s.tolist()
    a1, a2, a3 = I1 * W1, I2 * W2, I3 * W3
    return np.array([
        0.5 * (-x * W1 - y * W2 - z * W3),
        0.5 * (w * W1 + y * W3 - z * W2),
        0.5 * (w * W2 + z * W1 - x * W3),
        0.5 * (w * W3 + x * W2 - y * W1),
        (a2 * W3 - a3 * W2) / I1,
        (a3 * W1 - a1 * W3) / I2,
        (a1 * W2 - a2 * W1) / I3,
    ])


def quat_rhs_numpy(t, s):
    """Peer RHS written the usual NumPy way (slicing, ``np.cross``), like :func:`f_python`."""
    q, W = s[:4], s[4:]
    w, v = q[0], q[1:]
    qdot = 0.5 * np.concatenate(([-(v @ W)], w * W + np.cross(v, W)))
    return np.concatenate((qdot, np.cross(_I * W, W) / _I))


def quat0() -> np.ndarray:
    return np.concatenate(([1.0, 0.0, 0.0, 0.0], W0))


def energy(W) -> float:
    return 0.5 * float(np.dot(_I * W, W))


E0 = energy(np.array(W0))


def first_calls(method: str, t_end: float = T_END) -> dict:
    """CPU seconds of the first and the second ``integrate`` call with :func:`f_njit`
    over ``[0, t_end]`` (fixed step ``T_END / 2000``, or ``rtol = atol = 1e-8``)."""
    kw = {"rtol": 1e-8, "atol": 1e-8} if method in ("rkmk32", "rkmk45", "rkmk65") else {"dt": T_END / 2000}
    out = {"method": method}
    for key in ("first", "second"):
        t0 = time.process_time()
        integrate(f_njit, Y0, (0.0, t_end), space=SPACE, method=method, **kw)
        out[key] = time.process_time() - t0
    return out


def first_calls_fresh(method: str, t_end: float = T_END) -> dict:
    """:func:`first_calls` of ``method`` in a new Python process (nothing compiled yet)."""
    import json
    import subprocess
    import sys

    code = f"import json; from liegroup_int.bench.free_body import first_calls; " \
           f"print(json.dumps(first_calls({method!r}, {t_end!r})))"
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])
