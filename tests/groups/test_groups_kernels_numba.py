"""Compiled single-point group kernels against their NumPy twins (groups/kernels_numba.py).

Tolerance 1e-13 (relative to the magnitude of the compared quantity): both evaluate the same
closed forms and Taylor polynomials; only the summation order differs.
"""

import numpy as np
import pytest

from liegroup_int import SE3, SO3, Power, Product, Rn
from liegroup_int.groups.kernels_numba import CompiledGroup

SPACES = {
    "R3": Rn(3),
    "SO3": SO3,
    "SE3": SE3,
    "SO3xR3": Product(SO3, Rn(3)),
    "SE3^3": Power(SE3, 3),
    "SE3xSO3xR2": Product(SE3, SO3, Rn(2)),
    "(SO3xR3)^2": Power(Product(SO3, Rn(3)), 2),
}
ANGLES = [1e-9, 1e-3, 0.3, 0.99, 1.01, 2.0, np.pi - 1e-6]  # both branches, near identity and pi


def _algebra(space, rng, angle):
    """A random algebra element whose rotational parts have the given angle."""
    xi = rng.standard_normal(space.dim)
    cg = CompiledGroup.of(space)
    for kind, _, a, _ in cg.ft:
        if kind != 0:
            o = a if kind == 1 else a + 3
            xi[o:o + 3] *= angle / np.linalg.norm(xi[o:o + 3])
    return xi


@pytest.mark.parametrize("name", sorted(SPACES))
@pytest.mark.parametrize("angle", ANGLES)
def test_kernels_match_the_numpy_api(name, angle):
    space = SPACES[name]
    cg = CompiledGroup.of(space)
    assert cg is not None
    rng = np.random.default_rng(7)
    y = space.exp(_algebra(space, rng, 1.3))
    u = _algebra(space, rng, angle)
    w = rng.standard_normal(space.dim)
    np.testing.assert_allclose(cg.retract(u, y), space.retract(u, y), rtol=0, atol=1e-13 * max(1.0, np.abs(y).max()))
    ref = space.dexpinv(u, w)
    np.testing.assert_allclose(cg.dexpinv(u, w), ref, rtol=0, atol=1e-13 * np.abs(ref).max())
    assert cg.rotation_angle(u) == pytest.approx(float(np.max(space.rotation_angle(u), initial=0.0)), rel=1e-14)
    np.testing.assert_array_equal(cg.magnitude(y), space.magnitude(y))


def test_groups_without_kernels():
    class Unknown(type(SO3)):  # a group of the user's own: no compiled kernels
        name = "unknown"

    assert CompiledGroup.of(Product(Unknown(), Rn(3))) is None
    assert CompiledGroup.of(Power(Unknown(), 2)) is None


@pytest.mark.parametrize("method, kw", [("rkmk4", {"dt": 1e-3}), ("rkmk45", {"rtol": 1e-9, "atol": 1e-12})])
def test_integrate_single_point_agrees_with_the_numpy_path(method, kw):
    """The README's free rigid body, 0.5 s: the compiled single-point path of GroupProblem
    against the same problem with the kernels switched off (NumPy API). Round-off only:
    measured 4e-15 (fixed) and a few 1e-15 (adaptive, same step sequence)."""
    from liegroup_int import integrate
    from liegroup_int.integrators import GroupProblem

    I = np.array([1.0, 2.0, 3.0])
    space = Product(SO3, Rn(3))

    def f(t, y):
        R, W = space.split(y)
        return np.concatenate([R @ W, np.cross(I * W, W) / I])

    y0 = space.join(np.eye(3), np.array([0.01, 5.0, 0.01]))
    fast, slow = GroupProblem(space, f), GroupProblem(space, f)
    slow._compiled = None
    a = integrate(fast, y0, (0.0, 0.5), method=method, **kw)
    b = integrate(slow, y0, (0.0, 0.5), method=method, **kw)
    assert a.stats.steps == b.stats.steps and a.stats.rejected == b.stats.rejected
    np.testing.assert_allclose(a.y_final, b.y_final, rtol=0, atol=1e-12)
