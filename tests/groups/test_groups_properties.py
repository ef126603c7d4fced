"""Property tests of the Lie group layer, written once and run on every group.

Groups: SO3, SE3, R1, R3, SO3 x R3, SE3 x SO3 x R2, SO3^4, SE3^2 (see
``test_groups_strategies.GROUPS``). Conventions (docs/theory.md, section "Conventions"): left increments,
``hat(a) @ h == cross(a, h)``, and ``dexp`` is the left-trivialized derivative
``d/dt exp(xi(t)) = hat(dexp(xi, xi')) @ exp(xi(t))``.

Errors are measured with ``max_error``: ``max|a - b| / max(1, max|b|)``. Unless a test
says otherwise, u = 2.2e-16 is the unit round-off and every tolerance is
"some ulps times the condition number of the map"; the reason is stated next to each.
"""

from __future__ import annotations

import hypothesis.strategies as st
import numpy as np
import pytest
from hypothesis import given, settings

from liegroup_int.groups import SO3
from test_groups_strategies import (
    BATCH,
    GROUP_IDS,
    GROUPS,
    MATRIX_GROUP_IDS,
    MATRIX_GROUPS,
    act_points,
    algebra,
    assert_close,
    flat,
    index,
    max_error,
    points,
    tangents,
)

group_params = pytest.mark.parametrize("G", GROUPS, ids=GROUP_IDS)
matrix_group_params = pytest.mark.parametrize("G", MATRIX_GROUPS, ids=MATRIX_GROUP_IDS)


# ------------------------------------------------------------------ 1. exp(log(g)) = g
@group_params
@pytest.mark.parametrize("regime", ["generic", "small", "near_pi", "pi"])
@given(data=st.data())
def test_exp_log_roundtrip(G, regime, data):
    g = G.exp(data.draw(algebra(G, regime)))
    # 1e-13: exp and log are each accurate to a few ulps, and exp o log is the identity
    # even across the branch cut at pi (either sign of the axis gives the same g).
    # Translations (SE3) pass through J_l and J_l^-1, whose condition number is <= ~2
    # for angles <= pi. Measured: <= 2e-15.
    assert_close(G.exp(G.log(g)), g, 1e-13)


# -------------------------------------------------------------- 2. log(exp(xi)) = xi
@group_params
@pytest.mark.parametrize("regime", ["generic", "small", "near_pi_log"])
@given(data=st.data())
def test_log_exp_roundtrip(G, regime, data):
    xi = data.draw(algebra(G, regime))
    # 1e-12: |d log| = |J^-1| <= pi/2 for angles < pi, so rounding in exp (a few ulps)
    # becomes a few ulps in log; near pi the principal log is discontinuous at
    # distance delta >= 1e-4 >> u, which does not amplify. Measured: <= 2e-15.
    assert_close(G.log(G.exp(xi)), xi, 1e-12)


@group_params
@given(data=st.data())
def test_log_exp_very_near_pi(G, data):
    """delta = pi - angle in 1e-9 .. 1e-6: log(exp(xi)) against xi, which the
    quaternion-based log achieves to round-off (see the tolerance note); exp(log(g)) = g
    in this regime is test_exp_log_roundtrip's "near_pi" case."""
    xi = data.draw(algebra(G, "near_pi"))
    g = G.exp(xi)
    # 1e-12: the log branch is still unique since delta >= 1e-9 >> u; a perturbation of
    # R by k*u moves the quaternion scalar w = cos(angle/2) ~ delta/2 by k*u, which
    # changes the log by at most ~k*u (atan2 form). The quaternion log measured
    # <= 2e-15 here, far below the tolerance, which only guards against a
    # trace/arccos-type log (error ~ u/delta ~ 1e-7 at delta = 1e-9).
    assert_close(G.log(g), xi, 1e-12)


# ------------------------------------------------------ 3. dexpinv is the inverse of dexp
@group_params
@given(data=st.data())
def test_dexpinv_inverts_dexp(G, data):
    xi = data.draw(algebra(G, "dexpinv"))
    v = data.draw(tangents(G))
    # 1e-12: J_l(theta) is normal with eigenvalues 1 and modulus 2 sin(theta/2)/theta
    # >= 0.65 for theta <= pi - 0.1 (the pole of dexpinv is at 2 pi), so cond <= ~1.6;
    # on SE3 the coupling block Q adds a factor ~|rho| <= 5. A few ulps times that.
    # Measured: <= 1e-15.
    assert_close(G.dexpinv(xi, G.dexp(xi, v)), v, 1e-12)
    assert_close(G.dexp(xi, G.dexpinv(xi, v)), v, 1e-12)


@group_params
@given(data=st.data())
def test_dexp_and_dexpinv_fix_xi(G, data):
    """ad_xi(xi) = 0, so every series in ad_xi maps xi to itself."""
    xi = data.draw(algebra(G, "mixed"))
    # 1e-13: the ad-terms cancel exactly in exact arithmetic; what is left is the
    # rounding of cross(xi, xi) ~ u |xi|^2 times coefficients <= 1.
    assert_close(G.dexp(xi, xi), xi, 1e-13)
    assert_close(G.dexpinv(xi, xi), xi, 1e-13)


# ---------------------------------------------- 4. dexp is the derivative of exp (FD)
EPS = 1e-6


@matrix_group_params
@given(data=st.data())
def test_dexp_matches_finite_difference_of_exp_matrix(G, data):
    """d/dt exp(xi + t v)|_0 == hat(dexp(xi, v)) @ exp(xi) (left trivialization)."""
    xi, v = data.draw(algebra(G, "fd")), data.draw(tangents(G))
    fd = (G.exp(xi + EPS * v) - G.exp(xi - EPS * v)) / (2 * EPS)
    analytic = G.hat(G.dexp(xi, v)) @ G.exp(xi)
    # 1e-7: central difference, truncation ~ eps^2 |v|^3 |d^3 exp| ~ 1e-11, rounding
    # ~ u |exp| / eps ~ 1e-9 (entries of exp <= ~6).
    assert_close(fd, analytic, 1e-7)


@group_params
@given(data=st.data())
def test_dexp_matches_finite_difference_via_log(G, data):
    """log(exp(xi + eps v) exp(xi - eps v)^-1) / (2 eps) = dexp(xi, v) + O(eps^2).

    (With exp(xi + t v) = exp(X(t)) exp(xi), BCH gives X(eps) - X(-eps) + O(eps^3).)
    """
    xi, v = data.draw(algebra(G, "fd")), data.draw(tangents(G))
    fd = G.log(G.compose(G.exp(xi + EPS * v), G.inverse(G.exp(xi - EPS * v)))) / (2 * EPS)
    # 1e-7: O(eps^2) truncation ~ 1e-11, rounding of the near-identity product
    # ~ u |g|^2 / eps ~ 1e-9.
    assert_close(fd, G.dexp(xi, v), 1e-7)


@matrix_group_params
@given(data=st.data())
def test_dexpinv_matches_finite_difference_of_log(G, data):
    """Inverse statement: d/dt log(exp(t eta) exp(xi)) at 0 = dexpinv(xi, eta)."""
    xi, eta = data.draw(algebra(G, "fd")), data.draw(tangents(G))
    g = G.exp(xi)
    fd = (G.log(G.compose(G.exp(EPS * eta), g)) - G.log(G.compose(G.exp(-EPS * eta), g))) / (2 * EPS)
    # 1e-7: as above; log's condition |J^-1| <= ~1.5 at angle <= 3.
    assert_close(fd, G.dexpinv(xi, eta), 1e-7)


# ------------------------------------------------ 5. closed forms == Bernoulli series
@group_params
@given(data=st.data())
def test_closed_forms_match_series(G, data):
    xi, v = data.draw(algebra(G, "series")), data.draw(tangents(G))
    # order 60: the terms decay like (|xi| / 2 pi)^k <= 0.32^k (times k |rho| on SE3),
    # so the truncation is < 1e-25.
    # 1e-12: closed forms and series are each accurate to ~k*u with k ~ |rho| * 10
    # (the series sums up to ~2^k/k! growth of ad^k before cancellation). Measured
    # <= 2e-15.
    assert_close(G.dexp(xi, v), G.dexp_series(xi, v, 60), 1e-12)
    assert_close(G.dexpinv(xi, v), G.dexpinv_series(xi, v, 60), 1e-12)


@group_params
@given(data=st.data())
def test_default_dexp_fallbacks_match_closed_forms(G, data):
    """The base-class fallbacks (30/40-term series) agree with the overrides."""
    from liegroup_int.groups.base import LieGroup

    xi, v = data.draw(algebra(G, "series")), data.draw(tangents(G))
    # 1e-12: the fallbacks truncate at 30/40 terms: (1.99/2pi)^40 ~ 1e-20 relative.
    assert_close(LieGroup.dexp(G, xi, v), G.dexp(xi, v), 1e-12)
    assert_close(LieGroup.dexpinv(G, xi, v), G.dexpinv(xi, v), 1e-12)


# ------------------------------------------------------------------- 6. Ad and ad
@group_params
@given(data=st.data())
def test_Ad_is_a_homomorphism(G, data):
    g, h = data.draw(points(G)), data.draw(points(G))
    # 1e-13: a product of two (6x6 at most) matrices with entries <= ~6, a few ulps
    # each, relative to max(1, |Ad|).
    assert_close(G.Ad(G.compose(g, h)), G.Ad(g) @ G.Ad(h), 1e-13)
    # and Ad(g^-1) = Ad(g)^-1 (same reason)
    assert_close(G.Ad(G.inverse(g)) @ G.Ad(g), np.eye(G.dim), 1e-13)


@group_params
@pytest.mark.parametrize("regime", ["small", "generic"])
@given(data=st.data())
def test_Ad_is_conjugation(G, regime, data):
    """g exp(xi) g^-1 = exp(Ad_g xi): holds for every xi whose rotation angles are < pi
    (Ad preserves them), not only small ones."""
    g, xi = data.draw(points(G)), data.draw(algebra(G, regime))
    lhs = G.log(G.compose(G.compose(g, G.exp(xi)), G.inverse(g)))
    # 1e-12: three products of matrices with entries <= ~6 (u * 36 * 3), then log with
    # |J^-1| <= 1.5 at angle <= 3; relative to max(1, |Ad xi|). Measured <= 1e-14.
    assert_close(lhs, G.Ad(g) @ xi, 1e-12)


@group_params
@given(data=st.data())
def test_ad_is_derivative_of_Ad(G, data):
    xi = data.draw(algebra(G, "generic"))
    fd = (G.Ad(G.exp(EPS * xi)) - G.Ad(G.exp(-EPS * xi))) / (2 * EPS)
    # 1e-7: central difference, truncation eps^2 |xi|^3 / 6 ~ 1e-11, rounding
    # u |Ad| / eps ~ 1e-9.
    assert_close(fd, G.ad(xi), 1e-7)


@group_params
@given(data=st.data())
def test_ad_is_antisymmetric_and_Ad_equivariant(G, data):
    xi, eta = data.draw(tangents(G)), data.draw(tangents(G))
    g = data.draw(points(G))
    # 1e-14: entries of ad are (sums of) products of two O(1) numbers: exact up to 1 ulp.
    assert_close(G.bracket(xi, eta), -G.bracket(eta, xi), 1e-14)
    # Ad_g [xi, eta] = [Ad_g xi, Ad_g eta]; 1e-13: a few matrix products, entries <= ~6.
    Ad = G.Ad(g)
    assert_close(Ad @ G.bracket(xi, eta), G.bracket(Ad @ xi, Ad @ eta), 1e-13)


@matrix_group_params
@given(data=st.data())
def test_ad_and_Ad_agree_with_matrix_commutator_and_conjugation(G, data):
    """hat(ad_xi eta) = [hat xi, hat eta] and hat(Ad_g xi) = g hat(xi) g^-1."""
    xi, eta, g = data.draw(tangents(G)), data.draw(tangents(G)), data.draw(points(G))
    X, Y = G.hat(xi), G.hat(eta)
    # 1e-14: products of O(1) numbers, one rounding each.
    assert_close(G.hat(G.bracket(xi, eta)), X @ Y - Y @ X, 1e-14)
    # 1e-13: two 4x4 products with entries <= ~6.
    assert_close(G.hat(G.Ad(g) @ xi), g @ X @ G.inverse(g), 1e-13)
    np.testing.assert_array_equal(G.vee(X), xi)


# -------------------------------------------------------------- 7. group axioms
@group_params
@given(data=st.data())
def test_associativity(G, data):
    a, b, c = (data.draw(points(G)) for _ in range(3))
    # 1e-13: two matrix products with entries <= ~6 on each side.
    assert_close(G.compose(G.compose(a, b), c), G.compose(a, G.compose(b, c)), 1e-13)


@group_params
@given(data=st.data())
def test_identity_and_inverse(G, data):
    g = data.draw(points(G))
    e = G.identity()
    # exact: multiplying by I (or adding 0) involves no rounding.
    np.testing.assert_array_equal(G.compose(g, e), g)
    np.testing.assert_array_equal(G.compose(e, g), g)
    # 1e-14: g g^-1 = I up to the orthogonality of the rotation blocks (a few ulps) and
    # the translation R R^T t - t (entries <= ~6).
    assert_close(G.compose(g, G.inverse(g)), e, 1e-14)
    assert_close(G.compose(G.inverse(g), g), e, 1e-14)
    # inverse is an involution: exact (transpose / negation, and R^T R^T t).
    assert_close(G.inverse(G.inverse(g)), g, 1e-14)


@group_params
@given(data=st.data())
def test_exp_of_negative_is_inverse(G, data):
    xi = data.draw(algebra(G, "mixed"))
    # 1e-14: exp(-xi) is exp(xi) with the sign of the odd terms flipped: same rounding.
    assert_close(G.exp(-xi), G.inverse(G.exp(xi)), 1e-14)


@group_params
def test_exp_zero_and_log_identity_exact(G):
    for batch in [(), (2, 3)]:
        np.testing.assert_array_equal(G.exp(np.zeros(batch + (G.dim,))), G.identity(batch))
        np.testing.assert_array_equal(G.log(G.identity(batch)), np.zeros(batch + (G.dim,)))
        assert G.identity(batch).shape == batch + G.point_shape


@group_params
@given(data=st.data())
def test_one_parameter_subgroup(G, data):
    """exp(s xi) exp(t xi) = exp((s + t) xi)."""
    xi = data.draw(algebra(G, "generic"))
    s, t = data.draw(st.floats(-1.0, 1.0)), data.draw(st.floats(-1.0, 1.0))
    # 1e-13: products of matrices with entries <= ~6.
    assert_close(G.compose(G.exp(s * xi), G.exp(t * xi)), G.exp((s + t) * xi), 1e-13)


# ------------------------------------------------------------------------ 8. act
@group_params
@given(data=st.data())
def test_act_is_a_left_action(G, data):
    g, h, p = data.draw(points(G)), data.draw(points(G)), data.draw(act_points(G))
    # 1e-13: two matrix-vector products with entries <= ~6.
    assert_close(G.act(G.compose(g, h), p), G.act(g, G.act(h, p)), 1e-13)
    # exact: the identity acts trivially.
    np.testing.assert_array_equal(flat(G.act(G.identity(), p)), flat(p))


@matrix_group_params
@given(data=st.data())
def test_act_matches_homogeneous_matrix(G, data):
    g, p = data.draw(points(G)), data.draw(act_points(G))
    expected = g @ p if G is SO3 else (g @ np.append(p, 1.0))[:3]
    # 1e-14: same products, possibly different summation order.
    assert_close(G.act(g, p), expected, 1e-14)


# ------------------------------------------------------------------- 9. batching
@group_params
@settings(max_examples=max(10, settings.default.max_examples // 2))  # 6 entries x 12 ops each
@given(data=st.data())
def test_batched_equals_loop(G, data):
    xi = data.draw(algebra(G, "mixed", BATCH))
    v = data.draw(tangents(G, BATCH))
    h = data.draw(points(G, BATCH))
    p = data.draw(act_points(G, BATCH))
    g = G.exp(xi)
    batched = {
        "exp": g,
        "log": G.log(g),
        "inverse": G.inverse(g),
        "compose": G.compose(g, h),
        "dexp": G.dexp(xi, v),
        "dexpinv": G.dexpinv(xi, v),
        "ad": G.ad(xi),
        "Ad": G.Ad(g),
        "act": G.act(g, p),
        "retract": G.retract(v, h),
        "rotation_angle": G.rotation_angle(xi),
        "magnitude": G.magnitude(g),
    }
    assert batched["exp"].shape == BATCH + G.point_shape
    assert batched["log"].shape == BATCH + (G.dim,)
    assert batched["ad"].shape == BATCH + (G.dim, G.dim)
    assert batched["Ad"].shape == BATCH + (G.dim, G.dim)
    for i in np.ndindex(*BATCH):
        gi = G.exp(xi[i])
        single = {
            "exp": gi,
            "log": G.log(gi),
            "inverse": G.inverse(gi),
            "compose": G.compose(gi, h[i]),
            "dexp": G.dexp(xi[i], v[i]),
            "dexpinv": G.dexpinv(xi[i], v[i]),
            "ad": G.ad(xi[i]),
            "Ad": G.Ad(gi),
            "act": G.act(gi, index(p, i)),
            "retract": G.retract(v[i], h[i]),
            "rotation_angle": G.rotation_angle(xi[i]),
            "magnitude": G.magnitude(gi),
        }
        for name, val in single.items():
            # 1e-15: the same formulas; batched matmul/einsum may sum in another order
            # (BLAS vs. loop), i.e. 1-2 ulps of the largest entry.
            err = max_error(index(batched[name], i), val)
            assert err <= 1e-15, f"{name}[{i}]: batched vs single differ by {err:.2e}"


@group_params
@settings(max_examples=max(10, settings.default.max_examples // 2))  # 6 entries each
@given(data=st.data())
def test_broadcasting_single_against_batch(G, data):
    g = data.draw(points(G))
    h = data.draw(points(G, BATCH))
    out = G.compose(g, h)
    assert out.shape == BATCH + G.point_shape
    for i in np.ndindex(*BATCH):
        # 1e-15: as in test_batched_equals_loop.
        assert max_error(out[i], G.compose(g, h[i])) <= 1e-15


# ----------------------------------------------------- 10. hat, vee, normalize, sample
@group_params
@given(data=st.data())
def test_hat_vee_and_the_bracket(G, data):
    """vee(hat(xi)) = xi exactly, and hat carries the bracket to the matrix commutator:
    hat([xi, eta]) = hat(xi) hat(eta) - hat(eta) hat(xi) (ad and hat agree)."""
    xi, eta = data.draw(algebra(G, "generic")), data.draw(algebra(G, "generic"))
    np.testing.assert_array_equal(G.vee(G.hat(xi)), xi)
    H, E = G.hat(xi), G.hat(eta)
    # 1e-13: products of entries up to ~2 pi, summed over at most ~30 terms.
    assert_close(G.hat(G.bracket(xi, eta)), H @ E - E @ H, 1e-13)


@group_params
def test_normalize_pulls_drifted_points_back(G):
    """Valid points are kept to round-off; a drift e of the rotations becomes O(e^2)."""
    rng = np.random.default_rng(11)
    g = G.sample(rng, (5,))
    assert g.shape == (5,) + G.point_shape
    assert max_error(G.normalize(g), g) <= 4e-16 * 8
    e = 1e-6
    drifted = g * (1.0 + e * rng.standard_normal(g.shape))
    fixed = G.normalize(drifted)
    # the group's own constraint residual: log(exp(...)) round trips only on the group
    assert max_error(G.exp(G.log(fixed)), fixed) <= max(1e-11, 50 * e * e)


def test_compiled_normalize_equals_numpy():
    from liegroup_int.groups.kernels_numba import normalize_rotations

    rng = np.random.default_rng(5)
    R = SO3.sample(rng, (7,)) + 1e-7 * rng.standard_normal((7, 3, 3))
    out = R.copy()
    normalize_rotations(out)
    np.testing.assert_allclose(out, SO3.normalize(R), rtol=0, atol=1e-15)
    I = np.swapaxes(out, -1, -2) @ out - np.eye(3)
    assert np.abs(I).max() < 1e-12  # drift 1e-7 -> ~1e-14
