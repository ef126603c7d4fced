"""NURBS curves: rational basis, the quadratic arch, exact refinement, interpolation."""

import numpy as np
import pytest

from liegroup_int.iga.collocation import arc_length
from liegroup_int.iga.geometry import (
    ARCH_RADIUS,
    arc_nurbs_quadratic,
    helix_quarter,
    helix_quarter_exact,
    straight,
)
from liegroup_int.iga.knots import greville, open_uniform_knots
from liegroup_int.iga.nurbs import (
    NurbsCurve,
    elevate_degree,
    insert_knots,
    interpolate_at_greville,
    k_refine,
    max_geometric_error,
)

RNG = np.random.default_rng(314159)
CENTRE = np.array([ARCH_RADIUS, 0.0, 0.0])


def random_nurbs(p, interior, rng):
    knots = np.concatenate([np.zeros(p + 1), np.sort(interior), np.ones(p + 1)])
    n = knots.size - p - 1
    return NurbsCurve(p, knots, rng.normal(size=(n, 3)), rng.uniform(0.3, 3.0, n))


RANDOM_CURVES = [
    random_nurbs(1, [0.2, 0.5, 0.7], RNG),
    random_nurbs(2, [0.3, 0.3, 0.6], RNG),
    random_nurbs(3, [0.25, 0.4, 0.4, 0.4, 0.8], RNG),
    random_nurbs(4, [0.1, 0.5, 0.5, 0.9], RNG),
    random_nurbs(5, [], RNG),
]


def radial_error(curve, u):
    pts = curve.evaluate(u)[0]
    return np.abs(np.linalg.norm(pts - CENTRE, axis=1) - ARCH_RADIUS).max()


# ---------------------------------------------------------------- validation
@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(weights=[1.0, 0.0, 1.0]), "weights"),
        (dict(weights=[1.0, 1.0]), "weights"),
        (dict(control_points=np.zeros((3, 2))), "control_points"),
        (dict(control_points=np.zeros((4, 3))), "length"),
        (dict(knots=[0, 0, 0, 0.5, 1, 1]), "end with"),
    ],
)
def test_curve_validation(kwargs, message):
    args = dict(degree=2, knots=[0, 0, 0, 1, 1, 1], control_points=np.zeros((3, 3)))
    args.update(kwargs)
    with pytest.raises(ValueError, match=message):
        NurbsCurve(**args)


def test_curve_is_immutable():
    c = arc_nurbs_quadratic()
    with pytest.raises(ValueError):
        c.control_points[0, 0] = 1.0
    with pytest.raises(AttributeError):
        c.degree = 3


# ---------------------------------------------------------------- rational basis
@pytest.mark.parametrize("curve", RANDOM_CURVES + [arc_nurbs_quadratic(4, 12)])
def test_rational_partition_of_unity(curve):
    u = np.concatenate([RNG.random(200), [0.0, 1.0]])
    r = curve.basis(u, 3)
    assert r.shape == (4, u.size, curve.n_ctrl)
    np.testing.assert_allclose(r[0].sum(axis=1), 1.0, atol=1e-14)
    assert np.all(r[0] >= -1e-15)
    for k in (1, 2, 3):
        scale = max(1.0, np.abs(r[k]).max())
        np.testing.assert_allclose(r[k].sum(axis=1) / scale, 0.0, atol=1e-12)


@pytest.mark.parametrize("curve", RANDOM_CURVES + [arc_nurbs_quadratic(4, 12)])
def test_rational_derivatives_vs_central_differences(curve):
    """Central differences, h = 1e-6: truncation h^2/6 |R^(k+2)| and round-off
    eps/h ~ 1e-10 relative to the derivative scale; tolerance 1e-6 relative.
    Points within 2h of a knot are excluded."""
    h = 1e-6
    u = RNG.uniform(2 * h, 1 - 2 * h, 300)
    u = u[np.min(np.abs(u[:, None] - curve.knots[None, :]), axis=1) > 2 * h]
    nder = min(curve.degree, 3)
    r, rp, rm = curve.basis(u, nder), curve.basis(u + h, nder), curve.basis(u - h, nder)
    for k in range(1, nder + 1):
        fd = (rp[k - 1] - rm[k - 1]) / (2 * h)
        scale = np.abs(r[k]).max()
        np.testing.assert_allclose(fd / scale, r[k] / scale, atol=1e-6, rtol=0)
    # the same holds for the curve derivatives
    c, cp, cm = curve.evaluate(u, nder), curve.evaluate(u + h, nder), curve.evaluate(u - h, nder)
    for k in range(1, nder + 1):
        scale = np.abs(c[k]).max()
        np.testing.assert_allclose((cp[k - 1] - cm[k - 1]) / (2 * h) / scale, c[k] / scale, atol=1e-6)


def test_constant_weights_give_bspline_basis():
    c = RANDOM_CURVES[2]
    c1 = NurbsCurve(c.degree, c.knots, c.control_points, np.full(c.n_ctrl, 2.5))
    u = RNG.random(50)
    np.testing.assert_allclose(c1.basis(u, 3), c1.bspline_basis(u, 3), atol=1e-15)
    assert not c1.is_rational and c.is_rational


def test_basis_rejects_nder_above_three():
    with pytest.raises(ValueError, match="nder"):
        arc_nurbs_quadratic().basis([0.5], 4)


# ---------------------------------------------------------------- the arch
def test_arch_quadratic_is_exact_circle_of_length_one():
    c = arc_nurbs_quadratic()
    u = np.linspace(0.0, 1.0, 2001)
    assert radial_error(c, u) < 1e-12
    assert abs(arc_length(c, 1.0)[0] - 1.0) < 1e-12
    ends = c.evaluate([0.0, 1.0], 1)
    np.testing.assert_allclose(ends[0, 0], 0.0, atol=1e-15)
    np.testing.assert_allclose(ends[0, 1], ARCH_RADIUS * np.array([0.5, np.sqrt(3) / 2, 0]), atol=1e-15)
    tangent0 = ends[1, 0] / np.linalg.norm(ends[1, 0])
    np.testing.assert_allclose(tangent0, [0.0, 1.0, 0.0], atol=1e-15)


def test_arch_k_refinement_reproduces_curve():
    base = arc_nurbs_quadratic()
    fine = arc_nurbs_quadratic(4, 31)
    assert fine.degree == 4 and fine.n_ctrl == 31
    np.testing.assert_allclose(fine.knots, open_uniform_knots(4, 31), atol=1e-15)
    u = RNG.random(200)
    diff = np.abs(fine.evaluate(u)[0] - base.evaluate(u)[0]).max()
    assert diff < 1e-13
    assert radial_error(fine, u) < 1e-13
    assert abs(arc_length(fine, 1.0)[0] - 1.0) < 1e-12


# ---------------------------------------------------------------- refinement
@pytest.mark.parametrize("curve", RANDOM_CURVES)
@pytest.mark.parametrize("t", [1, 2, 3])
def test_degree_elevation_exact(curve, t):
    p = curve.degree
    up = elevate_degree(curve, p + t)
    assert up.degree == p + t
    v0, m0 = np.unique(curve.knots[p + 1: -p - 1], return_counts=True)
    v1, m1 = np.unique(up.knots[p + t + 1: -p - t - 1], return_counts=True)
    np.testing.assert_array_equal(v1, v0)
    np.testing.assert_array_equal(m1, m0 + t)
    assert up.n_ctrl == curve.n_ctrl + t * (v0.size + 1)
    u = np.concatenate([RNG.random(200), [0.0, 1.0], v0])
    scale = np.abs(curve.control_points).max()
    np.testing.assert_allclose(up.evaluate(u, 0)[0] / scale, curve.evaluate(u, 0)[0] / scale, atol=1e-13)


@pytest.mark.parametrize("curve", RANDOM_CURVES)
def test_knot_insertion_exact(curve):
    new = [0.15, 0.55, 0.55, 0.95][: curve.degree + 1] if curve.degree > 1 else [0.15, 0.55, 0.95]
    fine = insert_knots(curve, new)
    assert fine.n_ctrl == curve.n_ctrl + len(new)
    np.testing.assert_array_equal(fine.knots, np.sort(np.concatenate([curve.knots, new])))
    u = RNG.random(200)
    scale = np.abs(curve.control_points).max()
    np.testing.assert_allclose(fine.evaluate(u, 2) / scale, curve.evaluate(u, 2) / scale, atol=1e-12)


def test_k_refine_random_curve_and_span_splitting():
    curve = RANDOM_CURVES[2]  # p = 3, interior knots 0.25, 0.4 (x3), 0.8
    fine = k_refine(curve, 5, 40)
    assert fine.degree == 5 and fine.n_ctrl == 40
    # the existing knots survive with multiplicity + 2; new knots are simple
    values, counts = np.unique(fine.knots[6:-6], return_counts=True)
    np.testing.assert_array_equal(counts[np.isin(values, [0.25, 0.8])], [3, 3])
    assert counts[values == 0.4][0] == 5
    assert np.all(counts[~np.isin(values, [0.25, 0.4, 0.8])] == 1)
    u = RNG.random(200)
    scale = np.abs(curve.control_points).max()
    np.testing.assert_allclose(fine.evaluate(u)[0] / scale, curve.evaluate(u)[0] / scale, atol=1e-13)


def test_refinement_errors():
    c = arc_nurbs_quadratic()
    with pytest.raises(ValueError, match="lower the degree"):
        elevate_degree(c, 1)
    with pytest.raises(ValueError, match="cannot reach"):
        k_refine(c, 4, 4)
    with pytest.raises(ValueError, match="open interval"):
        insert_knots(c, [0.0])
    with pytest.raises(ValueError, match="multiplicity"):
        insert_knots(c, [0.5, 0.5, 0.5])
    assert k_refine(c, 2, 3) is c


# ---------------------------------------------------------------- interpolation
def test_interpolation_at_greville_points_and_polynomial_reproduction():
    def cubic(u):
        return np.stack([u, u**2 - 3 * u**3, 1 + 2 * u**3], axis=-1)

    curve = interpolate_at_greville(cubic, 3, 9)
    g = greville(curve.knots, 3)
    np.testing.assert_allclose(curve.evaluate(g)[0], cubic(g), atol=1e-14)
    assert max_geometric_error(curve, cubic) < 1e-13  # cubic is in the space
    with pytest.raises(ValueError, match="shape"):
        interpolate_at_greville(lambda u: u, 3, 9)


def test_straight_is_arc_length_parametrized():
    c = straight(2.5, direction=(0, 3, 4), degree=4, n_ctrl=11)
    u = RNG.random(100)
    np.testing.assert_allclose(c.evaluate(u)[0], 2.5 * u[:, None] * np.array([0, 0.6, 0.8]), atol=1e-14)
    np.testing.assert_allclose(np.linalg.norm(c.evaluate(u, 1)[1], axis=1), 2.5, atol=1e-13)


def test_helix_interpolation_convergence_rate():
    """Greville interpolation with p = 4 converges like h^(p+1) = h^5.

    Errors (max over 4001 samples) for 8, 16, 32, 64 elements; the fitted
    log-log slope is 5.004, and we require |slope - 5| < 0.25.
    """
    p = 4
    n_elems = np.array([8, 16, 32, 64])
    errors = np.array(
        [max_geometric_error(helix_quarter(p, n + p), helix_quarter_exact, 4001) for n in n_elems]
    )
    assert np.all(np.diff(errors) < 0)
    slope = np.polyfit(np.log(1.0 / n_elems), np.log(errors), 1)[0]
    assert abs(slope - (p + 1)) < 0.25, slope
    assert errors[-1] < 1e-11
