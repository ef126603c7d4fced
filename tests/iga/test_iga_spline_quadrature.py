"""Gaussian rules of spline spaces (``iga.spline_quadrature``) and the ``gauss-spline``,
``gauss-spline-reduced`` and ``auto`` rules of the Galerkin beam built on them."""

from __future__ import annotations

import numpy as np
import pytest

from liegroup_int.iga.bspline import basis_derivatives
from liegroup_int.iga.knots import open_uniform_knots
from liegroup_int.iga.quadrature import gauss_points, patch_rule
from liegroup_int.iga.spline_quadrature import SplineQuadratureError, gaussian_spline_rule, product_knots
from liegroup_int.scenes import load_scene
from liegroup_int.scenes.beam import problem
from liegroup_int.scenes.schema import SceneError


def _products(knots, p, u, w):
    """``sum_k w_k N_i'(u_k) N_j'(u_k)`` and ``sum_k w_k N_i'(u_k) N_j(u_k)`` (parameter space)."""
    B = basis_derivatives(knots, p, u, 1)
    return B[1].T @ (w[:, None] * B[1]), B[1].T @ (w[:, None] * B[0])


def _nonuniform(p: int) -> np.ndarray:
    """An open knot vector with uneven spans and a double interior knot."""
    inner = [0.07, 0.2, 0.2, 0.31, 0.5, 0.66, 0.9]
    return np.r_[np.zeros(p + 1), inner, np.ones(p + 1)]


@pytest.mark.parametrize("p,mesh", [(p, mesh) for p in (2, 3, 4, 5, 6) for mesh in ("uniform-11", "uniform-61",
                                                                                       "nonuniform") if (p, mesh) != (2, "nonuniform")])
def test_rule_integrates_the_stiffness_products_as_gauss_p(p, mesh):
    """The products ``N_i' N_j'`` and ``N_i' N_j`` of the beam's basis (the stiffness of a
    straight beam: degree 2p - 2 and 2p - 1) integrate as with p Gauss points per interval,
    which is exact there: equal to 1e-11 of the largest entry (round-off of the moment
    equations, solved to 1e-10 relative)."""
    knots = _nonuniform(p) if mesh == "nonuniform" else open_uniform_knots(p, int(mesh.split("-")[1]))
    x, w = gaussian_spline_rule(product_knots(knots, p), 2 * p - 1)
    ug, wg = gauss_points(knots, p)
    for got, ref in zip(_products(knots, p, x, w), _products(knots, p, ug, wg)):
        assert np.max(np.abs(got - ref)) < 1e-11 * np.max(np.abs(ref))
    assert np.all(np.diff(x) > 0) and x[0] >= 0 and x[-1] <= 1 and np.all(w > 0)


@pytest.mark.parametrize("p,mesh", [(p, mesh) for p in (3, 4, 5, 6) for mesh in ("uniform-11", "uniform-61",
                                                                                    "nonuniform")])
def test_reduced_rule_integrates_the_bending_products_as_gauss_p(p, mesh):
    """The Gaussian rule of the products ``N_i' N_j'`` (degree 2p - 2) integrates them as p
    Gauss points per interval (exact), to 1e-11 of the largest entry, with positive weights;
    the products ``N_i' N_j`` (degree 2p - 1), outside its space, differ by more than that
    (measured 6e-5 to 5e-2 of the largest entry; asserted above 1e-8): the rule is reduced
    on them."""
    knots = _nonuniform(p) if mesh == "nonuniform" else open_uniform_knots(p, int(mesh.split("-")[1]))
    x, w = gaussian_spline_rule(product_knots(knots, p, both_derivatives=True), 2 * p - 2)
    ug, wg = gauss_points(knots, p)
    (kk, kc), (kk_ref, kc_ref) = _products(knots, p, x, w), _products(knots, p, ug, wg)
    print(f"N'N': {np.max(np.abs(kk - kk_ref)) / np.max(np.abs(kk_ref)):.1e}, "
          f"N'N: {np.max(np.abs(kc - kc_ref)) / np.max(np.abs(kc_ref)):.1e}")
    assert np.max(np.abs(kk - kk_ref)) < 1e-11 * np.max(np.abs(kk_ref))
    assert np.max(np.abs(kc - kc_ref)) > 1e-8 * np.max(np.abs(kc_ref))
    assert np.all(np.diff(x) > 0) and x[0] >= 0 and x[-1] <= 1 and np.all(w > 0)


@pytest.mark.parametrize("p", [2, 3, 4, 5, 6])
def test_one_interval_gives_gauss_legendre(p):
    """On one knot interval the space is the polynomials of degree 2p - 1, whose Gaussian
    rule is unique: p Gauss-Legendre points (to 1e-12)."""
    x, w = gaussian_spline_rule(product_knots(open_uniform_knots(p, p + 1), p), 2 * p - 1)
    ug, wg = gauss_points(open_uniform_knots(p, p + 1), p)
    assert x.size == p
    assert np.max(np.abs(x - ug)) < 1e-12 and np.max(np.abs(w - wg)) < 1e-12


@pytest.mark.parametrize("p,n,expected", [(3, 61, 117), (4, 21, 44), (4, 61, 144), (4, 121, 294), (6, 61, 195)])
def test_point_count_is_half_the_space(p, n, expected):
    """ceil(D / 2) nodes for the D-dimensional product space, (p + 1) / 2 per interval in
    the interior: 0.63 of gauss-p's p per interval at p = 4, n_ctrl 61 (144 against 228)."""
    T = product_knots(open_uniform_knots(p, n), p)
    x, _ = gaussian_spline_rule(T, 2 * p - 1)
    assert x.size == expected == -(-(T.size - 2 * p) // 2)
    assert x.size < p * (n - p)


def test_c0_knot_raises():
    """A knot of multiplicity p makes the products discontinuous there: refused by name
    (``auto`` then takes gauss-p)."""
    with pytest.raises(SplineQuadratureError, match="multiplicity 2"):
        product_knots(_nonuniform(2), 2)


def test_unsolved_space_raises():
    """At p = 8 the iteration does not converge (measured moment error 1e-4): an error, not
    a rule that is not exact."""
    with pytest.raises(SplineQuadratureError, match="not found"):
        gaussian_spline_rule(product_knots(open_uniform_knots(8, 21), 8), 15)


@pytest.mark.parametrize("p,n,expected", [(3, 61, 88), (4, 21, 36), (4, 61, 116), (4, 121, 236), (6, 61, 168)])
def test_reduced_rule_has_about_p_over_2_points_per_interval(p, n, expected):
    """ceil(D / 2) nodes for the D-dimensional space of the products ``N_i' N_j'``, p / 2 per
    interval in the interior: 0.8 of gauss-spline's at p = 4, n_ctrl 61 (116 against 144)."""
    T = product_knots(open_uniform_knots(p, n), p, both_derivatives=True)
    x, _ = gaussian_spline_rule(T, 2 * p - 2)
    assert x.size == expected == -(-(T.size - 2 * p + 1) // 2)


@pytest.mark.parametrize("p,n,expected", [(2, 21, "gauss-p"), (3, 5, "gauss-spline"), (4, 21, "gauss-spline-reduced"),
                                          (6, 21, "gauss-spline-reduced"), (7, 21, "gauss-spline"), (8, 21, "gauss-p")])
def test_auto_rule_choice(p, n, expected):
    """``auto``: gauss-spline-reduced for p = 3..6 where its points determine the basis
    (not on the two knot intervals of p = 3, n_ctrl = 5), else gauss-spline for p = 3..7
    where it is found, else gauss-p; the rule names what it chose."""
    space = problem(load_scene("cantilever", {"space.degree": p, "space.n_ctrl": n})).space
    assert patch_rule(space, "auto").name == expected


def test_gauss_spline_at_p8_is_a_one_line_scene_error():
    with pytest.raises(SceneError, match=r"quadrature rule 'gauss-spline' at p = 8: .*choose space.quadrature"):
        problem(load_scene("cantilever", {"space.degree": 8, "space.quadrature": "gauss-spline"}))
