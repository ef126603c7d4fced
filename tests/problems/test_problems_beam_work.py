"""Work of the external loads (``Stats.quadrature``) and the energy balance.

The drivers integrate the loads' power ``P(t, y)`` over the stage states with the step's
weights. For a dead end force the position increment of the end control point is
``h sum b_r v_r(L)`` too, so the work equals ``F . (c(L, t) - c(L, 0))`` to round-off;
for gravity it equals ``q . int (c - c0) ds`` with the same collocation quadrature.
"""

import numpy as np
import pytest

from liegroup_int.integrators import Stats, integrate_adaptive, integrate_fixed, resolve_method
from liegroup_int.scenes import load_scene
from liegroup_int.scenes.beam import problem


@pytest.mark.parametrize("backend", ["numpy", "numba"])
@pytest.mark.parametrize("formulation", ["primal", "galerkin"])
def test_work_of_a_dead_end_force_is_force_times_displacement(backend, formulation):
    sc = load_scene("cantilever", {"integrator.backend": backend, "space.formulation": formulation})
    pb = problem(sc)
    y0 = pb.initial_state()
    stats = Stats()
    _, y, _ = integrate_fixed(pb, resolve_method("rkmk4"), (0.0, 2e-4), y0, 1e-6, t_out=[1e-4], stats=stats)
    exact = float(np.dot(pb.loads.end.force, y.c[-1] - y0.c[-1]))
    assert abs(exact) > 1e-3  # 100 N over ~1e-4 m
    assert stats.quadrature == pytest.approx(exact, rel=1e-12)


@pytest.mark.parametrize("backend, t_end", [("numpy", 0.005), ("numba", 0.02)], ids=["numpy", "numba"])
def test_work_of_gravity_is_its_potential_drop(backend, t_end):
    """Adaptive RKMK45: one rejected step, steps growing to 1.4e-5 s. The NumPy backend runs
    the first 5 ms (446 steps, a drop of 1.0e-4 J), the compiled one 20 ms (1777 steps,
    1.6e-3 J); the quadrature matches the drop to 1.3e-15 relative (measured), 1e-12 is
    the bound."""
    sc = load_scene("pendulum", {"integrator.backend": backend, "space.formulation": "primal"})
    pb = problem(sc)
    y0 = pb.initial_state()
    stats = Stats()
    _, y, _ = integrate_adaptive(pb, resolve_method("rkmk45"), (0.0, t_end), y0, rtol=1e-8, atol=1e-10,
                                 h_max=5e-5, stats=stats)
    drop = float(pb.q @ (pb.quad @ (pb.N0 @ (y.c - y0.c))))
    assert drop > 1e-5
    assert stats.quadrature == pytest.approx(drop, rel=1e-12)


def test_no_loads_no_quadrature():
    pb = problem(load_scene("cantilever", {"loads.end.force": [0.0, 0.0, 0.0]}))
    assert not pb.has_quadrature


def test_viscous_dissipation_closes_the_balance():
    """With Kelvin-Voigt damping the quadrature is the work of the loads minus the energy
    dissipated. Flying spaghetti (Galerkin, n_ctrl = 21, tau = 1e-3 s), 2.5 s of its load
    pulse: the work of the end loads alone (trapezoidal rule at 1 ms outputs on the power
    of the undamped twin problem, which is the loads' power only) misses the dissipation D;
    the quadrature must not. Measured: D = 0.206 J, energy change minus the quadrature
    2.6e-12 J (the Galerkin form conserves energy: only RKMK4's error is left), minus the
    loads' work alone -0.206 J."""
    sc = load_scene("flying_spaghetti", {"space.formulation": "galerkin", "material.kelvin_voigt": 1e-3,
                                         "space.n_ctrl": 21})
    pb = problem(sc)
    loads_only = pb.with_kelvin_voigt(0.0)
    y0 = pb.initial_state()
    stats = Stats()
    ts = np.arange(0.0, 2.5 + 1e-12, 1e-3)
    power = []

    def observe(t, y):
        power.append(loads_only.quadrature_rate(t, y))

    _, y, _ = integrate_fixed(pb, resolve_method("rkmk4"), (0.0, 2.5), y0, 1e-4, observer=observe, t_out=ts[1:],
                              stats=stats)
    work_loads = np.trapezoid(power, ts)
    dissipated = work_loads - stats.quadrature
    gained = pb.mechanical_energy(y) - pb.mechanical_energy(y0)
    assert dissipated > 0.1  # a real share of the 399 J the loads put in
    assert abs(gained - stats.quadrature) < 0.1 * dissipated
    assert abs(gained - work_loads) > 0.5 * dissipated
