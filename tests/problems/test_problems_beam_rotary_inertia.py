"""Rotary-inertia scaling (``section.rotary_inertia_scale``): the scaled model against the
analytic Timoshenko beam, the ``"auto"`` factor against its definition, the stable step it
buys, and its one-line refusals."""

from __future__ import annotations

import math

import numpy as np
import pytest

from liegroup_int.problems.errors import ParameterError
from liegroup_int.integrators import spectral_radius
from liegroup_int.problems.beam.galerkin_linear import distinct_frequencies, natural_frequencies
from liegroup_int.problems.beam.inertia_scaling import rotary_inertia_shift, size_rotary_inertia
from liegroup_int.problems.beam.model import SectionConstants
from liegroup_int.scenes import SceneError, load_scene
from liegroup_int.scenes.beam import problem

AT_REST = {"material.kelvin_voigt": 0.0, "loads.end.force": [0.0, 0.0, 0.0]}
#: Steel, square 0.05 m on 1 m, hinged at both ends: thick enough that rotary inertia moves
#: the second bending mode by 0.4 % at s = 10.
THICK = {**AT_REST, "section.t": 0.05, "bc.start": "hinged", "bc.end": "hinged", "space.degree": 4,
         "space.n_ctrl": 41}


def timoshenko_simply_supported(k: int, c: SectionConstants, length: float, scale: float = 1.0) -> float:
    """Lower root of the Timoshenko beam's mode ``k``, hinged at both ends (``w, psi`` in
    ``sin``/``cos`` of ``a = k pi / L``): ``rho A rho I w^4 - (rho A (EI a^2 + kGA) + rho I kGA a^2) w^2
    + kGA EI a^4 = 0``, with the rotary inertia ``rho I`` times ``scale``."""
    a = k * math.pi / length
    kga, ei, ra, ri = c.CN[0], c.CM[0], c.mu, scale * c.Jm[0]
    b = ra * (ei * a**2 + kga) + ri * kga * a**2
    disc = b * b - 4 * ra * ri * kga * ei * a**4
    return math.sqrt((b - math.sqrt(disc)) / (2 * ra * ri))


def test_section_scale_multiplies_the_bending_rotary_inertia_only():
    c = SectionConstants(CN=(1.0, 1.0, 2.0), CM=(3.0, 3.0, 4.0), mu=5.0, Jm=(0.1, 0.2, 0.3))
    assert c.with_rotary_inertia_scale(4.0).Jm == pytest.approx((0.4, 0.8, 0.3))
    for bad in (0.5, float("nan"), float("inf")):
        with pytest.raises(ParameterError, match="rotary_inertia_scale"):
            c.with_rotary_inertia_scale(bad)


@pytest.mark.parametrize("scale", [1.0, 10.0, 100.0])
def test_scaled_frequencies_match_the_timoshenko_beam(scale):
    """The first two bending frequencies of the scaled Galerkin beam (p = 4, n_ctrl = 41)
    against the analytic Timoshenko beam with ``scale rho I``: within 1e-9 (the space error,
    measured 2e-11), and the shift the scale causes within 1e-4 of itself."""
    pb = problem(load_scene("cantilever", THICK))
    got = distinct_frequencies(natural_frequencies(pb, scale), 2)
    exact = np.array([timoshenko_simply_supported(k, pb.constants, 1.0, scale) for k in (1, 2)])
    print(f"s = {scale:g}: {got} against {exact}, relative {got / exact - 1}")
    assert np.all(np.abs(got / exact - 1) < 1e-9)
    if scale > 1:
        shift = got / distinct_frequencies(natural_frequencies(pb), 2) - 1
        exact_shift = exact / np.array([timoshenko_simply_supported(k, pb.constants, 1.0) for k in (1, 2)]) - 1
        assert np.all(np.abs(shift / exact_shift - 1) < 1e-4)


@pytest.mark.parametrize("tol", [1e-4, 1e-3])
def test_auto_factor_is_the_largest_within_the_tolerance_or_the_saturation(tol):
    """Cantilever (p = 4, n_ctrl = 31): the chosen factor moves the lowest 6 distinct modes
    by at most ``tol``; when the tolerance set it, 1 % more would exceed it; when the top
    frequency's floor set it, the top there is within 1 % of the floor."""
    pb = problem(load_scene("cantilever", AT_REST))
    rep = size_rotary_inertia(pb, 6, tol)
    print(rep.as_dict())
    assert rep.max_shift <= tol and rep.scale > 1.0 and rep.step_gain > 1.0
    if rep.limit == "tolerance":
        assert max(abs(x) for x in rotary_inertia_shift(pb, 1.01 * rep.scale, 6)[0]) > tol
    else:
        assert rep.limit == "saturation"
        assert natural_frequencies(pb, rep.scale)[-1] <= 1.011 * natural_frequencies(pb, 1e4)[-1]


def test_auto_scale_raises_the_stable_step_by_the_reported_gain():
    """Built from the scene: the spectral radius the stable step is taken from (power
    iteration on the nonlinear rates at t = 0) falls by the report's top-frequency ratio, to
    2 % (measured 1.274 on the cantilever at tol 1e-3), and the run reports it."""
    over = {**AT_REST, "section.rotary_inertia_scale": "auto"}
    scaled, plain = problem(load_scene("cantilever", over)), problem(load_scene("cantilever", AT_REST))
    rep = scaled.rotary_inertia_report
    assert rep is not None and rep.limit in ("tolerance", "saturation") and rep.scale > 1.2
    lam = [spectral_radius(pb, 0.0, pb.initial_state()) for pb in (plain, scaled)]
    print(f"gain: report {rep.step_gain:.4f}, spectral radii {lam[0] / lam[1]:.4f}")
    assert abs(lam[0] / lam[1] / rep.step_gain - 1) < 0.02


def test_given_scale_is_reported_with_its_shift():
    pb = problem(load_scene("cantilever", {**AT_REST, "section.rotary_inertia_scale": 3.0}))
    rep = pb.rotary_inertia_report
    assert rep.limit == "given" and rep.scale == 3.0 and rep.tol is None
    assert pb.Jm[0, 0] == pytest.approx(3.0 * 7800.0 * 0.01**4 / 12)
    assert all(x < 0 for x in rep.shifts) and rep.step_gain > 1.0


@pytest.mark.parametrize("over,match", [
    ({"section.rotary_inertia_scale": 0.5}, "rotary_inertia_scale.*factor >= 1"),
    ({"section.rotary_inertia_scale": "auto", "space.formulation": "primal"}, "needs space.formulation"),
    ({"section.rotary_inertia_scale": "auto", "space.n_ctrl": 400}, "dense eigenproblem.*give a number"),
])
def test_refusals_are_one_line(over, match):
    with pytest.raises(SceneError, match=match) as err:
        problem(load_scene("cantilever", {**AT_REST, **over}))
    assert "\n" not in str(err.value)
