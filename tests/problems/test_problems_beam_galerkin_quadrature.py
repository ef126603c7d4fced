"""Quadrature rules of the Galerkin beam's stiffness (``space.quadrature``): ``gauss-p``
(p Gauss points per knot interval for every term), ``gauss-spline`` (the Gaussian rule
of the products ``N_i' N_j``, about (p + 1) / 2 points per interval) and
``gauss-spline-reduced`` (of the products ``N_i' N_j'``, about p / 2 points per interval;
the ``auto`` default for p = 3..6) against the two-rule ``gauss`` (p + 1 for bending, p for
axial and shear): rank, spectrum at rest, natural frequencies, energy, backends.
benchmarks/galerkin_quadrature.py prints every rule."""

from __future__ import annotations

import numpy as np
import pytest

from liegroup_int.integrators import eigenvalues, integrate_fixed, resolve_method, spectral_radius
from liegroup_int.problems.beam.galerkin_linear import (distinct_frequencies, energy_nullity, natural_frequencies,
                                                     strain_operator)
from liegroup_int.scenes import load_scene
from liegroup_int.scenes.beam import problem
from liegroup_int.scenes.schema import SceneError

RULE = "gauss-p"
TESTED = ("gauss-p", "gauss-spline", "gauss-spline-reduced")
AT_REST = {"material.kelvin_voigt": 0.0, "loads.end.force": [0.0, 0.0, 0.0]}


def galerkin(scene, rule, p, n, **extra):
    return problem(load_scene(scene, {"space.formulation": "galerkin", "space.quadrature": rule,
                                      "space.degree": p, "space.n_ctrl": n, **extra}))


@pytest.mark.parametrize("p,n,rule", [(p, n, rule) for p, n in [(2, 11), (3, 21), (4, 11), (4, 41), (6, 31)]
                                      for rule in TESTED if (p, rule) != (2, "gauss-spline-reduced")])
def test_no_zero_energy_modes(p, n, rule):
    """The strain-energy Hessian of the free beam has the 6 rigid motions as its null
    space, nothing more (singular values below 1e-10 of the largest count as zero; the
    smallest nonzero one is measured 1e-4 to 4.5e-4 of the largest)."""
    null, smallest = energy_nullity(galerkin("cantilever", rule, p, n, **AT_REST))
    print(f"p={p} n={n}: nullity {null}, smallest nonzero singular value {smallest:.2g}")
    assert null == 6
    assert smallest > 1e-6


@pytest.mark.parametrize("rule,tol", [("gauss-p", 1e-4), ("gauss-spline", 1e-2), ("gauss-spline-reduced", 5e-2)])
def test_spectrum_at_rest_is_imaginary_and_as_large_as_gauss(rule, tol):
    """Pendulum, p = 4, n_ctrl = 31: max Re(lambda) is finite-difference noise (below 1e-7
    |lambda|max, as the gauss rule) and |lambda|max (the stable step) equals the gauss
    rule's: gauss-p to 1e-6 (measured), gauss-spline within 1 % (measured 0.16 % smaller:
    its shear terms of degree 2p are integrated differently), gauss-spline-reduced within
    5 % (measured 3.0 % smaller: its shear terms of degree 2p - 1 are reduced too; a larger
    stable step)."""
    lam = {}
    for rule in (rule, "gauss"):
        pb = galerkin("pendulum", rule, 4, 31, **{"material.kelvin_voigt": 0.0})
        ev = eigenvalues(pb, 0.0, pb.initial_state())
        lam[rule] = float(np.max(np.abs(ev)))
        print(f"{rule}: max Re {ev.real.max():.3g} 1/s, |lambda|max {lam[rule]:.6g}")
        assert ev.real.max() <= 1e-7 * lam[rule]
    assert abs(lam[rule] / lam["gauss"] - 1) < tol


def test_straight_beam_stiffness_equals_the_gauss_rule():
    """Cantilever, p = 4, n_ctrl = 21: p points integrate the bending energy of a straight
    beam at rest exactly (degree 2p - 2) and the axial and shear terms as the gauss rule,
    so the Hessians of the strain energy agree to round-off (measured 4e-17 of the
    largest entry)."""
    S = strain_operator(galerkin("cantilever", RULE, 4, 21, **AT_REST))
    S_ref = strain_operator(galerkin("cantilever", "gauss", 4, 21, **AT_REST))
    K, K_ref = S.T @ S, S_ref.T @ S_ref
    print(f"largest difference {np.max(np.abs(K - K_ref)) / np.max(np.abs(K_ref)):.2g} of the largest entry")
    assert np.max(np.abs(K - K_ref)) < 1e-13 * np.max(np.abs(K_ref))


def test_arch_frequencies_match_the_gauss_rule():
    """The curved NURBS arch, p = 4, n_ctrl = 21 (bending now under-integrated by p
    points): the first eight frequencies agree with the gauss rule's to 1e-6 (measured
    1.1e-8, the eigensolver's round-off on the lowest ones)."""
    over = {"material.kelvin_voigt": 0.0, "loads.end.couple": [0.0, 0.0, 0.0]}
    w = natural_frequencies(galerkin("arch", RULE, 4, 21, **over))[:8]
    w_ref = natural_frequencies(galerkin("arch", "gauss", 4, 21, **over))[:8]
    print(f"largest relative difference {np.max(np.abs(w / w_ref - 1)):.2g}")
    assert np.max(np.abs(w / w_ref - 1)) < 1e-6


@pytest.mark.parametrize("rule", TESTED)
def test_frequencies_converge_at_order_2p(rule):
    """Cantilever, p = 4, n_ctrl = 9, 13, 21: the 2nd to 4th distinct frequencies converge
    to the reference (gauss rule, p = 6, n_ctrl = 61; its own change to n_ctrl = 81 is
    below 1e-9) with log-log slopes against the knot span of about 2p = 8 (measured
    7.8 to 8.1; gauss-spline-reduced 6.8 on the 2nd frequency; asserted > 6.5)."""
    ref = distinct_frequencies(natural_frequencies(galerkin("cantilever", "gauss", 6, 61, **AT_REST)), 4)
    sizes = np.array([9, 13, 21])
    err = np.array([np.abs(distinct_frequencies(natural_frequencies(galerkin("cantilever", rule, 4, int(n), **AT_REST)), 4) / ref - 1)
                    for n in sizes])
    slopes = [np.polyfit(np.log(1.0 / (sizes - 4)), np.log(err[:, j]), 1)[0] for j in (1, 2, 3)]
    print(f"errors {err[:, 1:].tolist()}, slopes {slopes}")
    assert min(slopes) > 6.5
    assert np.all(err[-1, 1:] < 1e-5)


@pytest.mark.parametrize("rule", TESTED)
def test_pendulum_energy_is_conserved(rule):
    """Pendulum, p = 4, n_ctrl = 31, undamped, RKMK4 at |lambda| h = 2 over 0.2 s: the
    energy drifts by 3.1e-11 to 3.5e-11 J (largest kinetic energy 0.14 J), as with the gauss rule
    (benchmarks/galerkin_quadrature.py)."""
    pb = galerkin("pendulum", rule, 4, 31, **{"material.kelvin_voigt": 0.0})
    y0 = pb.initial_state()
    E0, rec = pb.energy(y0), []
    integrate_fixed(pb, resolve_method("rkmk4"), (0.0, 0.2), y0, 2.0 / spectral_radius(pb, 0.0, y0),
                    observer=lambda t, y: rec.append(pb.energy(y, t)), t_out=np.linspace(0.0, 0.2, 21)[1:])
    drift = np.max(np.abs(np.array(rec) - E0))
    print(f"energy drift over 0.2 s: {drift:.3g} J")
    assert drift < 1e-9


@pytest.mark.parametrize("rule", [*TESTED, "greville"])
@pytest.mark.parametrize("scene", ["arch", "pendulum"])
def test_backends_agree(scene, rule):
    """Stage rates of both backends at a perturbed state, for the recommended rule and for
    the Greville rule (its points include the beam's ends): equal to round-off
    (1e-11 relative, as the gauss rule's test)."""
    a = galerkin(scene, rule, 4, 21, **{"integrator.backend": "numpy"})
    b = galerkin(scene, rule, 4, 21, **{"integrator.backend": "numba"})
    rng = np.random.default_rng(5)
    y = a.action(1e-3 * rng.standard_normal((4, a.n, 3)), a.initial_state())
    u = 1e-3 * rng.standard_normal((4, a.n, 3))
    ka, kb = a.increment_rate(0.1, y, u), b.increment_rate(0.1, y, u)
    scale = np.max(np.abs(ka), axis=(1, 2))
    assert np.all(np.max(np.abs(ka - kb), axis=(1, 2)) <= 1e-11 * scale)


def _short_piece_frame(rule):
    """Right-angle frame, p = 4, n_ctrl = 21 per leg, a point load at a fifth of the second
    leg: the piece before it has p + 1 control values (one knot interval)."""
    return load_scene("right_angle_cantilever", {
        "space.quadrature": rule, "space.degree": 4, "space.n_ctrl": 21,
        "point_loads": [{"s": 0.6, "force": [0.0, 0.0, 1.0]}]})


def test_a_rule_with_fewer_points_than_a_patch_has_basis_functions_is_refused():
    """gauss-p (and gauss-spline) put 4 points on the one-interval piece of 5 basis
    functions: the point mass is singular, its last Cholesky pivot round-off of either
    sign; the rule is refused in one line instead of projecting through it."""
    with pytest.raises(ValueError, match="'gauss-p': its points do not determine the basis"):
        problem(_short_piece_frame("gauss-p"))


def test_reduced_spline_rule_at_p2_is_refused():
    """At p = 2 the products ``N_i' N_j'`` are piecewise constants: one point per interval,
    fewer than the basis functions, so the point mass is singular and the rule is refused
    in one line (``auto`` takes gauss-p there)."""
    with pytest.raises(SceneError, match="'gauss-spline-reduced': its points do not determine the basis"):
        galerkin("cantilever", "gauss-spline-reduced", 2, 21)


def test_auto_takes_gauss_on_a_one_interval_piece():
    """``auto`` keeps the spline rule on the long pieces and takes ``gauss`` (p + 1 points
    per interval) on the short one. The frame's spectrum at rest is imaginary (max Re below
    1e-7 of |lambda|max, finite-difference noise) and its |lambda|max within 1 % of the
    gauss rule's everywhere (the same bound as the straight pendulum's above)."""
    lam = {}
    for rule in ("auto", "gauss"):
        pb = problem(_short_piece_frame(rule))
        ev = eigenvalues(pb, 0.0, pb.initial_state())
        lam[rule] = float(np.max(np.abs(ev)))
        print(f"{rule}: rules {pb.gs.rules_used}, max Re {ev.real.max():.3g} 1/s, |lambda|max {lam[rule]:.6g}")
        assert ev.real.max() <= 1e-7 * lam[rule]
    assert set(problem(_short_piece_frame("auto")).gs.rules_used) == {"gauss", "gauss-spline-reduced"}
    assert abs(lam["auto"] / lam["gauss"] - 1) < 1e-2
