"""Collocation space: arc-length basis matrices, solver and reference geometry."""

import numpy as np
from scipy.interpolate import BSpline
import pytest

from liegroup_int.iga.collocation import CollocationSpace, default_reference_vector, vee
from liegroup_int.iga.geometry import (
    ARCH_RADIUS,
    HELIX_RADIUS,
    arc_nurbs_quadratic,
    helix_quarter,
    straight,
)
from liegroup_int.iga.nurbs import NurbsCurve

RNG = np.random.default_rng(2718)
E1, E2, E3 = np.eye(3)


@pytest.fixture(scope="module")
def arch():
    return CollocationSpace(arc_nurbs_quadratic(4, 31))


@pytest.fixture(scope="module")
def helix():
    return CollocationSpace(helix_quarter(4, 31))


@pytest.fixture(scope="module")
def beam():
    return CollocationSpace(straight(2.0, (1, 0, 0), degree=3, n_ctrl=12))


def all_spaces(arch, helix, beam):
    return [arch, helix, beam]


# ---------------------------------------------------------------- frames
def test_frames_are_rotations(arch, helix, beam):
    for sp in all_spaces(arch, helix, beam):
        r = sp.R0
        assert r.shape == (sp.n_ctrl, 3, 3)
        gram = np.swapaxes(r, 1, 2) @ r
        assert np.abs(gram - np.eye(3)).max() < 1e-13
        np.testing.assert_allclose(np.linalg.det(r), 1.0, atol=1e-13)
        # d3 is the unit tangent
        np.testing.assert_allclose(r[:, :, 2], sp.c0_s, atol=1e-15)


def test_default_reference_vector_rule():
    np.testing.assert_array_equal(default_reference_vector([1, 0, 0]), E2)
    np.testing.assert_array_equal(default_reference_vector([0, 1, 0]), E3)
    np.testing.assert_array_equal(default_reference_vector([0, 0, 1]), E1)
    np.testing.assert_array_equal(default_reference_vector([0.1, 0.8, -0.5]), E1)


def test_straight_beam_frame_and_zero_curvature(beam):
    np.testing.assert_allclose(beam.R0, np.broadcast_to(np.column_stack([E2, E3, E1]), beam.R0.shape), atol=1e-15)
    assert np.abs(beam.K0).max() < 1e-13 and np.abs(beam.K0_s).max() < 1e-12
    np.testing.assert_allclose(beam.jac, 2.0, atol=1e-13)
    np.testing.assert_allclose(beam.s_c, 2.0 * beam.u_c, atol=1e-14)
    assert abs(beam.length - 2.0) < 1e-13
    # a user reference vector e3 gives d1 = e3, d2 = e1 x e3 = -e2
    sp = CollocationSpace(beam.curve, reference_vector=(0, 0, 5))
    np.testing.assert_allclose(sp.R0[0], np.column_stack([E3, -E2, E1]), atol=1e-15)


def test_parallel_reference_vector_raises(beam, arch):
    with pytest.raises(ValueError, match="tangent"):
        CollocationSpace(beam.curve, reference_vector=(1, 1e-4, 0))
    # e1 is fine at u = 0 of the arch but within 1 deg of the tangent nowhere;
    # e2 is the tangent at u = 0
    CollocationSpace(arch.curve, reference_vector=E1)
    with pytest.raises(ValueError, match="tangent"):
        CollocationSpace(arch.curve, reference_vector=E2)
    with pytest.raises(ValueError, match="reference_vector"):
        CollocationSpace(arch.curve, reference_vector=(0, 0, 0))


@pytest.mark.parametrize("n_ctrl, degree", [(3, 2), (31, 4)])
def test_arch_curvature_about_binormal(n_ctrl, degree):
    """Default frame: d1 = e3 (binormal), d2 = d3 x e3 (inward normal), so
    d3' = d2 / R and K0 = vee(R0^T R0') = (-1/R, 0, 0) = (-pi/3, 0, 0)."""
    sp = CollocationSpace(arc_nurbs_quadratic(degree, n_ctrl))
    np.testing.assert_allclose(sp.reference_vector, E3)
    np.testing.assert_allclose(sp.R0[:, :, 0], np.broadcast_to(E3, (n_ctrl, 3)), atol=1e-14)
    inward = np.array([ARCH_RADIUS, 0, 0]) - sp.c0
    np.testing.assert_allclose(sp.R0[:, :, 1], inward / ARCH_RADIUS, atol=1e-13)
    np.testing.assert_allclose(sp.c0_ss, inward / ARCH_RADIUS**2, atol=1e-11)
    expected = np.broadcast_to([-1.0 / ARCH_RADIUS, 0.0, 0.0], sp.K0.shape)
    np.testing.assert_allclose(sp.K0, expected, atol=1e-11)
    assert np.abs(sp.K0_s).max() < 1e-9
    assert abs(sp.length - 1.0) < 1e-12
    # s_c equals R * polar angle of the point (exact arc length)
    theta = np.arctan2(sp.c0[:, 1], ARCH_RADIUS - sp.c0[:, 0])
    np.testing.assert_allclose(sp.s_c, ARCH_RADIUS * theta, atol=1e-12)
    assert sp.l_s_start == pytest.approx(0.5 * sp.s_c[1])
    assert sp.l_s_end == pytest.approx(0.5 * (1.0 - sp.s_c[-2]))


def test_helix_curvature_vs_frame_differences(helix):
    """K0 and K0_s against central differences (h = 1e-5 in u) of the frame.

    dR0/ds ~ (R0(u+h) - R0(u-h)) / (2 h J): truncation ~ h^2 |R0'''| J^2 / 6
    ~ 1e-10 and round-off ~ eps / h ~ 1e-11; tolerance 1e-7.
    """
    h = 1e-5
    u = np.concatenate([helix.u_c[1:-1], RNG.uniform(h, 1 - h, 20)])
    r, k, k_s = helix.frame(u)
    rp, kp, _ = helix.frame(u + h)
    rm, km, _ = helix.frame(u - h)
    jac = np.linalg.norm(helix.curve.evaluate(u, 1)[1], axis=1)[:, None]
    k_fd = vee(np.swapaxes(r, 1, 2) @ ((rp - rm) / (2 * h * jac[:, :, None])))
    np.testing.assert_allclose(k_fd, k, atol=1e-7)
    np.testing.assert_allclose((kp - km) / (2 * h * jac), k_s, atol=1e-7)
    # frame() at u_c is the stored collocation data
    r_c, k_c, ks_c = helix.frame(helix.u_c)
    np.testing.assert_allclose(r_c, helix.R0, atol=1e-15)
    np.testing.assert_allclose(k_c, helix.K0, atol=1e-13)
    np.testing.assert_allclose(ks_c, helix.K0_s, atol=1e-12)
    # the helix is curved and its projection frame twists: K0_s is not zero
    assert np.abs(helix.K0_s).max() > 1e-2


def test_helix_curvature_magnitude(helix):
    """|K0|^2 - K3^2 = kappa^2 of the exact helix, kappa = R / (R^2 + c^2), c = 1/pi
    (the interpolation error, ~1e-9 at n = 31, bounds the agreement)."""
    c = 1.0 / np.pi
    kappa = HELIX_RADIUS / (HELIX_RADIUS**2 + c**2)
    bend = np.linalg.norm(helix.K0[:, :2], axis=1)
    np.testing.assert_allclose(bend, kappa, rtol=1e-6)
    assert helix.length == pytest.approx(np.sqrt(13) / 4, abs=1e-9)


# ---------------------------------------------------------------- basis matrices
@pytest.mark.parametrize("name", ["arch", "helix"])
def test_arc_length_basis_vs_differences(name, arch, helix):
    """N1, N2 against central differences in u divided by J (h = 1e-6,
    tolerance 1e-6 relative to the matrix scale, see the B-spline tests)."""
    sp = {"arch": arch, "helix": helix}[name]
    h = 1e-6
    u = sp.u_c[1:-1]
    u = u[np.min(np.abs(u[:, None] - sp.curve.knots[None, :]), axis=1) > 2 * h]
    assert u.size > 5
    b, bp, bm = sp.basis_s(u), sp.basis_s(u + h), sp.basis_s(u - h)
    jac = np.linalg.norm(sp.curve.evaluate(u, 1)[1], axis=1)[:, None]
    for k in (1, 2):
        fd = (bp[k - 1] - bm[k - 1]) / (2 * h * jac)
        scale = np.abs(b[k]).max()
        np.testing.assert_allclose(fd / scale, b[k] / scale, atol=1e-6)
    rows = np.searchsorted(sp.u_c, u)
    np.testing.assert_allclose(b[1], sp.N1[rows], atol=1e-12)
    np.testing.assert_allclose(b[2], sp.N2[rows], atol=1e-9)


def test_basis_matrices_consistency(arch, helix, beam):
    for sp in all_spaces(arch, helix, beam):
        n = sp.n_ctrl
        for m in (sp.N0, sp.N1, sp.N2):
            assert m.shape == (n, n)
        # N0 against an independent evaluation: scipy's B-spline design matrix, made rational
        # with the weights (R = N w / (N . w)); agreement to a few ulps of the O(1) entries
        c = sp.curve
        B = BSpline.design_matrix(sp.u_c, c.knots, c.degree).toarray()
        w = np.ones(n) if c.weights is None else np.asarray(c.weights, dtype=float)
        np.testing.assert_allclose(sp.N0, B * w / (B @ w)[:, None], rtol=0, atol=1e-14)
        np.testing.assert_allclose(sp.N0.sum(axis=1), 1.0, atol=1e-14)
        np.testing.assert_allclose(sp.N1.sum(axis=1) / np.abs(sp.N1).max(), 0.0, atol=1e-13)
        np.testing.assert_allclose(sp.N2.sum(axis=1) / np.abs(sp.N2).max(), 0.0, atol=1e-13)
        # the geometry itself: N_k @ P = d^k c0 / ds^k
        p = sp.curve.control_points
        np.testing.assert_allclose(sp.N0 @ p, sp.c0, atol=1e-14)
        np.testing.assert_allclose(sp.N1 @ p, sp.c0_s, atol=1e-12)
        np.testing.assert_allclose(sp.N2 @ p, sp.c0_ss, atol=1e-9)
        assert sp.u_c[0] == 0.0 and sp.u_c[-1] == 1.0
        np.testing.assert_allclose(sp.point_matrix(1.0) @ p, sp.curve.control_points[-1:], atol=1e-15)


@pytest.mark.parametrize("solver", ["banded", "lu"])
def test_solve_recovers_control_points(solver, arch):
    sp = CollocationSpace(arch.curve, solver=solver)
    lower, upper = sp.bandwidths
    i, j = np.indices(sp.N0.shape)
    assert np.all(sp.N0[(i - j > lower) | (j - i > upper)] == 0.0)
    # a known spline in the same (rational) space
    coeffs = RNG.normal(size=(sp.n_ctrl, 3))
    values = sp.point_matrix(sp.u_c) @ coeffs
    np.testing.assert_allclose(sp.solve(values), coeffs, atol=1e-12)
    np.testing.assert_allclose(sp.solve(sp.c0), sp.curve.control_points, atol=1e-13)
    vec = RNG.normal(size=sp.n_ctrl)
    np.testing.assert_allclose(sp.solve(sp.N0 @ vec), vec, atol=1e-12)
    many = RNG.normal(size=(sp.n_ctrl, 7))
    np.testing.assert_allclose(sp.solve(sp.N0 @ many), many, atol=1e-12)
    with pytest.raises(ValueError, match="rhs"):
        sp.solve(np.zeros(sp.n_ctrl + 1))


def test_collocation_data_is_read_only(arch):
    with pytest.raises(ValueError):
        arch.N0[0, 0] = 2.0
    with pytest.raises(ValueError):
        arch.K0[0, 0] = 2.0


def test_rejects_non_curve():
    with pytest.raises(ValueError, match="NurbsCurve"):
        CollocationSpace(np.zeros((3, 3)))
    line = NurbsCurve(1, [0, 0, 1, 1], [[0, 0, 0], [0, 0, 1]])
    with pytest.raises(ValueError, match="solver"):
        CollocationSpace(line, solver="qr")
