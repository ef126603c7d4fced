"""SO(n): group axioms, exp/log, ad/Ad, dexp/dexpinv and the Cayley map, n = 2..6
(property tests; SO(3)'s own tests are in test_groups_properties.py)."""

from __future__ import annotations

import hypothesis.strategies as st
import numpy as np
import pytest
import scipy.linalg
from hypothesis import given, settings

from liegroup_int.groups import SOn, resolve

NS = [2, 3, 4, 5, 6]


@st.composite
def algebra(draw, G: SOn, max_angle: float = 3.0, batch: tuple = (2,)):
    """Algebra elements whose rotation angles (the spectral norm of hat) are below max_angle."""
    seed = draw(st.integers(0, 2**32 - 1))
    scale = draw(st.floats(1e-8, 1.0))
    xi = np.random.default_rng(seed).standard_normal(batch + (G.dim,))
    ang = np.maximum(G.rotation_angle(xi), 1e-300)
    return xi * (scale * max_angle / ang)[..., None]


@pytest.mark.parametrize("n", NS)
@settings(max_examples=25, deadline=None)
@given(data=st.data())
def test_exp_is_a_rotation_and_log_inverts_it(n, data):
    G = SOn(n)
    xi = data.draw(algebra(G, 3.0))
    g = G.exp(xi)
    assert np.allclose(np.swapaxes(g, -1, -2) @ g, np.eye(n), atol=1e-13)
    assert np.allclose(np.linalg.det(g), 1.0, atol=1e-12)
    assert np.allclose(g, scipy.linalg.expm(G.hat(xi)), atol=1e-13)
    # log is the principal branch: recovers xi below angle pi
    assert np.allclose(G.exp(G.log(g)), g, atol=1e-12)
    assert np.allclose(G.log(g), xi, atol=1e-10)
    assert np.allclose(G.vee(G.hat(xi)), xi, atol=0)


@pytest.mark.parametrize("n", NS)
@settings(max_examples=20, deadline=None)
@given(data=st.data())
def test_ad_Ad_and_the_bracket(n, data):
    G = SOn(n)
    xi, eta = data.draw(algebra(G, 2.0)), data.draw(algebra(G, 2.0))
    A, B = G.hat(xi), G.hat(eta)
    assert np.allclose(G.hat(G.bracket(xi, eta)), A @ B - B @ A, atol=1e-13)
    g = G.exp(xi)
    assert np.allclose(G.hat(np.einsum("...ij,...j->...i", G.Ad(g), eta)), g @ B @ np.swapaxes(g, -1, -2), atol=1e-13)
    # Ad_exp(xi) = exp(ad_xi)
    assert np.allclose(G.Ad(g), scipy.linalg.expm(G.ad(xi)), atol=1e-12)


@pytest.mark.parametrize("n", NS)
@settings(max_examples=20, deadline=None)
@given(data=st.data())
def test_dexp_by_finite_differences_and_dexpinv_inverts_it(n, data):
    """``d/dt exp(xi + t v) exp(xi)^-1 = hat(dexp(xi, v))`` (central differences, h = 1e-6:
    error ~1e-10), and ``dexpinv(xi, dexp(xi, v)) = v`` up to the documented limit: rotation
    angles below pi, so that two of them sum below the pole at 2 pi. At angle pi - 0.05 the
    inverse amplifies round-off by at most ``1 / sinc`` of the summed angles, about 60, so
    1e-11 leaves a factor ~100 over the worst round-off."""
    G = SOn(n)
    xi, v = data.draw(algebra(G, np.pi - 0.05, ())), data.draw(algebra(G, 1.0, ()))
    h = 1e-6
    fd = (G.exp(xi + h * v) - G.exp(xi - h * v)) / (2 * h) @ G.exp(xi).T
    assert np.allclose(G.hat(G.dexp(xi, v)), fd, atol=1e-8)
    assert np.allclose(G.dexpinv(xi, G.dexp(xi, v)), v, atol=1e-11)


@pytest.mark.parametrize("n", NS)
def test_closed_forms_agree_with_the_series_inside_its_radius(n):
    """Inside half the series' radius (angles <= pi / 2, |ad| <= pi) 60 Bernoulli terms
    converge to round-off, so the eigenbasis closed forms must match them to 1e-12."""
    G = SOn(n)
    rng = np.random.default_rng(n)
    xi = rng.standard_normal((8, G.dim))
    xi *= (rng.uniform(0.0, np.pi / 2, 8) / G.rotation_angle(xi))[:, None]
    v = rng.standard_normal((8, G.dim))
    assert np.abs(G.dexp(xi, v) - G.dexp_series(xi, v, 60)).max() <= 1e-12
    assert np.abs(G.dexpinv(xi, v) - G.dexpinv_series(xi, v, 60)).max() <= 1e-12


@pytest.mark.parametrize("n", NS)
@settings(max_examples=20, deadline=None)
@given(data=st.data())
def test_cayley_map_and_its_inverse_derivative(n, data):
    G = SOn(n)
    xi, v = data.draw(algebra(G, 2.5, ())), data.draw(algebra(G, 1.0, ()))
    g = G.cay(xi)
    assert np.allclose(g.T @ g, np.eye(n), atol=1e-13) and np.linalg.det(g) == pytest.approx(1.0)
    h = 1e-6
    fd = (G.cay(xi + h * v) - G.cay(xi - h * v)) / (2 * h) @ g.T  # = hat(dcay(xi, v))
    assert np.allclose(G.dcayinv(xi, G.vee(fd)), v, atol=1e-8)
    # second-order agreement with exp
    small = 1e-3 * xi / max(G.rotation_angle(xi), 1e-300)
    assert np.max(np.abs(G.cay(small) - G.exp(small))) <= 1e-9


def test_names_and_errors():
    assert resolve("SO4") == SOn(4) and SOn(4).dim == 6 and SOn(4).name == "SO(4)"
    with pytest.raises(ValueError, match="n must be >= 2"):
        SOn(1)
    G = SOn(4)
    g = G.exp(np.full(6, 0.3))
    r = G.normalize(g + 1e-8 * np.ones((4, 4)))  # quadratic: 1e-8 off -> ~1e-16 off
    assert np.allclose(r.T @ r, np.eye(4), atol=1e-14)
    assert G.act(g, np.array([1.0, 0, 0, 0])) == pytest.approx(g[:, 0])
