"""Quadrature rules of the Galerkin space: exactness, rule-independent mass, rank checks."""

from __future__ import annotations

import numpy as np
import pytest

from liegroup_int.iga import CollocationSpace, GalerkinSpace, straight
from liegroup_int.iga.quadrature import RULES, exact_mass_rule, patch_rule


def space(p: int, n: int, length: float = 2.0) -> CollocationSpace:
    return CollocationSpace(straight(length, degree=p, n_ctrl=n))


@pytest.mark.parametrize("rule", [r for r in RULES if r != "greville"])
@pytest.mark.parametrize("p,n", [(2, 11), (4, 21), (6, 31)])
def test_gauss_rules_integrate_the_length(rule, p, n):
    """Every Gauss rule's bending and axial weights add up to the length (round-off)."""
    r = patch_rule(space(p, n), rule)
    assert abs(r.w_bending.sum() - 2.0) < 1e-13 and abs(r.w_axial.sum() - 2.0) < 1e-13


@pytest.mark.parametrize("p,n", [(2, 11), (3, 21), (4, 41), (6, 31)])
def test_greville_rule_integrates_every_basis_function(p, n):
    """The Greville rule (one point per control value) integrates each basis function
    exactly (round-off) with positive weights (measured smallest weight 0.04 to 0.12 knot
    spans, p = 8 to 2)."""
    sp = space(p, n)
    r = patch_rule(sp, "greville")
    um, wm = exact_mass_rule(sp)
    assert r.u.size == n
    assert np.max(np.abs(sp.point_matrix(r.u).T @ r.w_bending - sp.point_matrix(um).T @ wm)) < 1e-14
    assert np.all(r.w_bending > 0.0)


@pytest.mark.parametrize("rule", list(RULES))
def test_mass_does_not_depend_on_the_rule(rule):
    """The consistent mass is integrated exactly whatever the stiffness rule; the points
    start and end at the beam's ends, each once."""
    sp = space(4, 21)
    gs, ref = GalerkinSpace(sp, rule), GalerkinSpace(sp, "gauss-full")
    assert np.max(np.abs(gs.mass - ref.mass)) < 1e-15
    assert gs.u[0] == 0.0 and gs.u[-1] == 1.0 and gs.u[1] > 0.0 and gs.u[-2] < 1.0


def test_rule_with_too_few_points_is_rejected():
    """p - 1 = 1 Gauss point per interval at p = 2: n - 2 points cannot determine the
    n basis functions (singular point mass)."""
    with pytest.raises(ValueError, match="'gauss-pm1': its points do not determine the basis"):
        GalerkinSpace(space(2, 11), "gauss-pm1")


def test_unknown_rule_is_rejected():
    with pytest.raises(ValueError, match="quadrature rule: expected one of gauss, .*got 'simpson'"):
        GalerkinSpace(space(4, 11), "simpson")
