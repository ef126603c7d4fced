"""A numba.njit vector field on Sphere() runs in the compiled engine and agrees with the
plain Python one."""

from __future__ import annotations

import numpy as np
import pytest
from numba import njit

from liegroup_int import ActionProblem, Sphere, integrate


@njit
def _llg_njit(t, m):
    H = np.array([0.2 + 0.5 * m[0], 0.0, 1.0])
    c = np.array([m[1] * H[2] - m[2] * H[1], m[2] * H[0] - m[0] * H[2], m[0] * H[1] - m[1] * H[0]])
    return (H + 0.1 * c) / 1.01


def _llg_py(t, m):
    H = np.array([0.2 + 0.5 * m[0], 0.0, 1.0])
    return (H + 0.1 * np.cross(m, H)) / 1.01


@pytest.mark.parametrize("method", ["rkmk4", "rkmk45"])
def test_njit_field_on_the_sphere_matches_python(method):
    """Same steps, same numbers to round-off (measured 6e-15 after 50,000 steps; 1e-12
    allowed here over 2,000); |m| = 1 kept. The compiled engine takes the run (the problem
    offers kernels); benchmarks of the gain live in docs/benchmarks.md, not here."""
    S = Sphere()
    m0 = S.project(np.array([0.0, 1.0, 0.3]))
    assert ActionProblem(S, _llg_njit).compiled_kernels() is not None
    assert ActionProblem(S, _llg_py).compiled_kernels() is None
    kw = dict(dt=1e-3) if method == "rkmk4" else dict(rtol=1e-9, atol=1e-9)
    a = integrate(_llg_njit, m0, (0.0, 2.0), space=S, method=method, **kw)
    b = integrate(_llg_py, m0, (0.0, 2.0), space=S, method=method, **kw)
    assert a.stats.steps == b.stats.steps
    assert np.max(np.abs(a.y_final - b.y_final)) <= 1e-12
    assert S.constraint(a.y_final) <= 1e-14


def test_njit_field_refuses_batches_in_one_line():
    S = Sphere()
    with pytest.raises(ValueError, match="runs on one point of shape \\(3,\\)"):
        integrate(_llg_njit, S.sample(np.random.default_rng(0), (2,)), (0.0, 0.1), space=S, dt=1e-2)


@njit
def _pendula_njit(t, y):
    """Two independent spherical pendula (g / L = 9.81 and 4.0) on (TS^2)^2: per link the
    generator (rho, theta) = ((g / L) e3, w)."""
    out = np.empty(12)
    for j, g in enumerate((9.81, 4.0)):
        out[6 * j:6 * j + 3] = np.array([0.0, 0.0, g])
        out[6 * j + 3:6 * j + 6] = y[6 * j + 3:6 * j + 6]
    return out


def _pendula_py(t, y):
    Y = np.asarray(y).reshape(2, 6)
    return np.concatenate([[0.0, 0.0, 9.81], Y[0, 3:], [0.0, 0.0, 4.0], Y[1, 3:]])


def test_njit_field_on_tangent_spheres_matches_python():
    """(TS^2)^2 with SE(3) per link: the compiled engine (SE(3)'s compiled exp and
    dexpinv, the TS^2 action) against the generic loop, to round-off over 1,000 RKMK4
    steps; both constraints kept."""
    from liegroup_int import ProductSpace, TangentSphere

    M = ProductSpace.power(TangentSphere(), 2)
    y0 = M.project(np.array([0.6, 0.0, -0.8, 0.0, 0.0, 2.0, 0.0, 0.5, -0.8, 1.0, 0.0, 0.3]))
    assert ActionProblem(M, _pendula_njit).compiled_kernels() is not None
    a = integrate(_pendula_njit, y0, (0.0, 1.0), space=M, method="rkmk4", dt=1e-3).y_final
    b = integrate(_pendula_py, y0, (0.0, 1.0), space=M, method="rkmk4", dt=1e-3).y_final
    assert np.max(np.abs(a - b)) <= 1e-12
    assert M.constraint(a) <= 1e-13


@njit
def _toda_njit(t, L):
    """The Toda flow L' = [B(L), L], B = triu(L) - tril(L): in SOn's coordinates
    (hat(xi)[j, i] = xi, i < j) xi = -L[i, j]."""
    n = L.shape[0]
    out = np.empty(n * (n - 1) // 2)
    k = 0
    for i in range(n):
        for j in range(i + 1, n):
            out[k] = -L[i, j]
            k += 1
    return out


def _toda_py(t, L):
    from liegroup_int import SOn

    return SOn(L.shape[0]).vee(np.triu(L, 1) - np.tril(L, -1))


A6 = np.diag([5.0, 4.0, 2.0, 1.0, 0.5, 0.2]) + 0.1 * np.ones((6, 6))


@njit
def _oja_njit(t, Y):
    """Oja's subspace flow on Stiefel(6, 2): the generator A Y Y^T - Y Y^T A."""
    P = Y @ Y.T
    G = A6 @ P - P @ A6
    n = G.shape[0]
    out = np.empty(n * (n - 1) // 2)
    k = 0
    for i in range(n):
        for j in range(i + 1, n):
            out[k] = 0.5 * (G[j, i] - G[i, j])
            k += 1
    return out


def _oja_py(t, Y):
    from liegroup_int import SOn

    return SOn(6).vee(A6 @ Y @ Y.T - Y @ Y.T @ A6)


@pytest.mark.parametrize("method", ["rkmk4", "rkmk45"])
@pytest.mark.parametrize("case", ["toda", "oja"])
def test_njit_field_on_son_spaces_matches_python(case, method):
    """Isospectral(5) (the Toda lattice) and Stiefel(6, 2) (Oja's flow): a numba.njit f runs
    in the compiled engine (SO(n) kernels: Taylor scaling-and-squaring exp, the commutator
    series of dexpinv truncated as integrate() truncates it) and gives the generic path's
    steps and numbers to round-off (measured 1.5e-14 after 1,000 Toda steps; 1e-12
    allowed); the spectrum and orthonormality are kept."""
    from liegroup_int import Isospectral, Stiefel

    rng = np.random.default_rng(2)
    if case == "toda":
        M, fn, fp = Isospectral(5), _toda_njit, _toda_py
        y0 = np.diag(rng.standard_normal(5)) + np.diag(rng.uniform(0.5, 1.5, 4), 1) \
            + np.diag(rng.uniform(0.5, 1.5, 4), -1)
        y0 = 0.5 * (y0 + y0.T)
    else:
        M, fn, fp = Stiefel(6, 2), _oja_njit, _oja_py
        y0 = M.sample(rng)
    assert ActionProblem(M, fn, dexpinv_order=3).compiled_kernels() is not None
    assert ActionProblem(M, fp, dexpinv_order=3).compiled_kernels() is None
    kw = dict(dt=0.01) if method == "rkmk4" else dict(rtol=1e-9, atol=1e-9)
    a = integrate(fn, y0, (0.0, 5.0), space=M, method=method, **kw)
    b = integrate(fp, y0, (0.0, 5.0), space=M, method=method, **kw)
    assert a.stats.steps == b.stats.steps
    assert np.max(np.abs(a.y_final - b.y_final)) <= 1e-12
    if case == "toda":
        assert np.max(np.abs(np.linalg.eigvalsh(a.y_final) - np.linalg.eigvalsh(y0))) <= 1e-12
    else:
        assert M.constraint(a.y_final) <= 1e-13
