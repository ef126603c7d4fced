"""Knot vectors, B-spline basis functions and banded collocation matrices."""

import numpy as np
import pytest
import scipy.linalg
from scipy.interpolate import BSpline

from liegroup_int.iga.bspline import (
    band_widths,
    band_widths_from_spans,
    basis_derivatives,
    basis_derivatives_local,
    find_spans,
    to_banded,
)
from liegroup_int.iga.knots import greville, open_uniform_knots, validate_knots

RNG = np.random.default_rng(20240611)


def knots_with_multiplicity(p):
    """Non-uniform open knot vector with an interior knot of multiplicity p."""
    interior = np.sort(np.concatenate([[0.1, 0.27, 0.5, 0.81], [0.63] * p]))
    return np.concatenate([np.zeros(p + 1), interior, np.ones(p + 1)])


KNOT_CASES = [(p, open_uniform_knots(p, 9)) for p in (1, 2, 3, 4, 5)] + [
    (p, knots_with_multiplicity(p)) for p in (1, 2, 3, 4)
]


# ---------------------------------------------------------------- knots
def test_open_uniform_knots_values():
    k = open_uniform_knots(3, 7)
    np.testing.assert_array_equal(k, [0, 0, 0, 0, 0.25, 0.5, 0.75, 1, 1, 1, 1])
    assert open_uniform_knots(4, 5).tolist() == [0.0] * 5 + [1.0] * 5


@pytest.mark.parametrize(
    "knots, degree, n_ctrl, message",
    [
        ([0, 0, 0.5, 0.4, 1, 1], 1, None, "non-decreasing"),
        ([0, 0, 0, 0.5, 1, 1], 2, None, "end with"),
        ([0, 0.1, 0.5, 1, 1], 1, None, "start with"),
        ([0, 0, 0, 0.5, 1, 1, 1], 2, 5, "length"),
        ([0, 0, 0.5, 0.5, 1, 1], 1, None, "multiplicity"),
        ([0, 0, 0, 1, 1, 1], 0, None, "degree"),
        ([0, 0, np.nan, 1, 1], 1, None, "non-finite"),
        ([0, 0, 1, 1], 2, None, "too short"),
    ],
)
def test_validate_knots_rejects(knots, degree, n_ctrl, message):
    with pytest.raises(ValueError, match=message):
        validate_knots(knots, degree, n_ctrl)


def test_open_uniform_knots_rejects_too_few_ctrl():
    with pytest.raises(ValueError, match="n_ctrl"):
        open_uniform_knots(3, 3)


def test_greville_open_uniform_cubic():
    g = greville(open_uniform_knots(3, 7), 3)
    np.testing.assert_allclose(g, [0, 1 / 12, 3 / 12, 6 / 12, 9 / 12, 11 / 12, 1], atol=1e-15)
    assert g[0] == 0.0 and g[-1] == 1.0


@pytest.mark.parametrize("p, knots", KNOT_CASES)
def test_greville_linear_precision(p, knots):
    """sum_j N_j(u) g_j = u (linear precision) and the abscissae increase strictly."""
    g = greville(knots, p)
    assert g.size == knots.size - p - 1
    assert np.all(np.diff(g) > 0)
    u = np.linspace(0, 1, 101)
    np.testing.assert_allclose(basis_derivatives(knots, p, u)[0] @ g, u, atol=1e-14)


# ---------------------------------------------------------------- basis
@pytest.mark.parametrize("p, knots", KNOT_CASES)
def test_partition_of_unity_and_derivative_sums(p, knots):
    u = np.concatenate([RNG.random(300), knots[p:-p]])
    d = basis_derivatives(knots, p, u, nder=min(p, 3))
    np.testing.assert_allclose(d[0].sum(axis=1), 1.0, atol=1e-14)
    assert np.all(d[0] >= -1e-15)
    for k in range(1, d.shape[0]):
        scale = max(1.0, np.abs(d[k]).max())
        np.testing.assert_allclose(d[k].sum(axis=1) / scale, 0.0, atol=1e-13)


@pytest.mark.parametrize("p, knots", KNOT_CASES)
def test_matches_scipy_bspline(p, knots):
    """Independent reference: scipy.interpolate.BSpline (de Boor evaluation)."""
    n = knots.size - p - 1
    u = np.concatenate([RNG.random(100), [0.0, 0.63, 1 - 1e-12]])
    d = basis_derivatives(knots, p, u, nder=p)
    for k in range(p + 1):
        ref = BSpline(knots, np.eye(n), p)(u, nu=k)
        scale = max(1.0, np.abs(ref).max())
        np.testing.assert_allclose(d[k] / scale, ref / scale, atol=1e-13, rtol=0)


@pytest.mark.parametrize("p, knots", KNOT_CASES)
def test_derivatives_vs_central_differences(p, knots):
    """Central differences with h = 1e-6.

    Truncation error h^2/6 |N'''| <~ 1e-12 * 1e4 and round-off
    eps |N| / h ~ 1e-10 (relative to the derivative scale), so 1e-6 relative
    to the largest |d^k N| is a safe bound.  Points within 2h of a knot are
    excluded (derivatives of order >= p - m + 1 jump there).
    """
    h = 1e-6
    u = RNG.uniform(2 * h, 1 - 2 * h, 400)
    u = u[np.min(np.abs(u[:, None] - knots[None, :]), axis=1) > 2 * h]
    nder = min(p, 3)
    d = basis_derivatives(knots, p, u, nder)
    plus = basis_derivatives(knots, p, u + h, nder)
    minus = basis_derivatives(knots, p, u - h, nder)
    for k in range(1, nder + 1):
        fd = (plus[k - 1] - minus[k - 1]) / (2 * h)
        scale = np.abs(d[k]).max()
        np.testing.assert_allclose(fd / scale, d[k] / scale, atol=1e-6, rtol=0)


def test_derivatives_beyond_degree_vanish():
    knots = open_uniform_knots(3, 10)
    d = basis_derivatives(knots, 3, RNG.random(50), nder=5)
    assert d.shape == (6, 50, 10)
    assert np.all(d[4:] == 0.0)


def test_local_support_and_shapes():
    p, knots = 3, knots_with_multiplicity(3)
    u = np.array([0.0, 0.1, 0.63, 0.7, 1.0])
    spans, local = basis_derivatives_local(knots, p, u, 2)
    assert local.shape == (3, 5, p + 1)
    np.testing.assert_array_equal(spans, find_spans(knots, p, u))
    assert np.all(knots[spans] <= u) and np.all(u[:-1] < knots[spans[:-1] + 1])
    dense = basis_derivatives(knots, p, u, 2)
    for i, s in enumerate(spans):
        outside = np.ones(dense.shape[2], bool)
        outside[s - p: s + 1] = False
        assert np.all(dense[:, i, outside] == 0.0)
    # end point u = 1: only the last basis function is 1
    np.testing.assert_array_equal(dense[0, -1], np.eye(dense.shape[2])[-1])


def test_scalar_and_out_of_range_parameters():
    knots = open_uniform_knots(2, 5)
    assert basis_derivatives(knots, 2, 0.3, 1).shape == (2, 1, 5)
    assert basis_derivatives(knots, 2, 1.0 + 1e-14).shape == (1, 1, 5)
    with pytest.raises(ValueError, match=r"\[0, 1\]"):
        basis_derivatives(knots, 2, [0.5, 1.1])


# ---------------------------------------------------------------- banded
@pytest.mark.parametrize("p, n", [(2, 12), (3, 20), (4, 31), (5, 40)])
def test_banded_collocation_solve(p, n):
    knots = open_uniform_knots(p, n)
    g = greville(knots, p)
    a = basis_derivatives(knots, p, g)[0]
    lower, upper = band_widths_from_spans(find_spans(knots, p, g), p)
    lo, up = band_widths(a)
    # the span pattern is a structural bound (p, p); the actual band is narrower
    assert (lower, upper) == (p, p)
    assert lo <= lower and up <= upper
    rhs = RNG.normal(size=(n, 3))
    for widths in ((lower, upper), (lo, up)):
        ab = to_banded(a, *widths)
        x = scipy.linalg.solve_banded(widths, ab, rhs)
        np.testing.assert_allclose(x, np.linalg.solve(a, rhs), atol=1e-12)


def test_to_banded_rejects_wide_matrix():
    with pytest.raises(ValueError, match="band"):
        to_banded(np.ones((4, 4)), 1, 1)
