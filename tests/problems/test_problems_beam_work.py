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
@pytest.mark.parametrize("formulation", ["primal", "mixed"])
def test_work_of_a_dead_end_force_is_force_times_displacement(backend, formulation):
    sc = load_scene("cantilever", {"integrator.backend": backend, "space.formulation": formulation})
    pb = problem(sc)
    y0 = pb.initial_state()
    stats = Stats()
    _, y, _ = integrate_fixed(pb, resolve_method("rkmk4"), (0.0, 2e-4), y0, 1e-6, t_out=[1e-4], stats=stats)
    exact = float(np.dot(pb.loads.end.force, y.c[-1] - y0.c[-1]))
    assert abs(exact) > 1e-3  # 100 N over ~1e-4 m
    assert stats.quadrature == pytest.approx(exact, rel=1e-12)


@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_work_of_gravity_is_its_potential_drop(backend):
    sc = load_scene("pendulum", {"integrator.backend": backend, "space.formulation": "mixed"})
    pb = problem(sc)
    y0 = pb.initial_state()
    stats = Stats()
    _, y, _ = integrate_adaptive(pb, resolve_method("rkmk45"), (0.0, 0.02), y0, rtol=1e-8, atol=1e-10,
                                 h_max=5e-5, stats=stats)
    drop = float(pb.q @ (pb.quad @ (pb.N0 @ (y.c - y0.c))))
    assert drop > 1e-5
    assert stats.quadrature == pytest.approx(drop, rel=1e-12)


def test_no_loads_no_quadrature():
    pb = problem(load_scene("cantilever", {"loads.end.force": [0.0, 0.0, 0.0]}))
    assert not pb.has_quadrature
