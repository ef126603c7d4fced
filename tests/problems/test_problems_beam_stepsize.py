"""Automatic stable step on every beam scene, and blow-up detection just beyond it."""

import numpy as np
import pytest

from liegroup_int.integrators import IntegrationError, integrate_fixed, resolve_method, stable_step
from liegroup_int.scenes import load_scene
from liegroup_int.scenes.beam import KIND
from liegroup_int.tableaux import imaginary_axis_limit

SCENES = ["pendulum", "cantilever", "arch", "spinning_helix", "flying_spaghetti"]
N_STEPS = 150


@pytest.mark.parametrize("name", SCENES)
def test_auto_dt_is_stable_and_1p5x_limit_blows_up(name):
    scene = load_scene(name, {"integrator.dt": "auto", "integrator.method": "rkmk4"})
    sim = KIND.build(scene)
    dt, lam = sim.info["dt_auto"], sim.info["lambda_max"]
    tab = resolve_method("rkmk4")
    # auto: 0.8 of the RK4 imaginary-axis limit 2 sqrt(2)
    assert abs(lam * dt - 0.8 * 2 * np.sqrt(2)) < 1e-9
    pb, y0 = sim.problem, sim.y0
    _, y, _ = integrate_fixed(pb, tab, (0.0, N_STEPS * dt), y0, dt)
    # stable: finite, and the tip moved by a physical amount only (< 10% of the length)
    assert pb.is_finite(y) and np.linalg.norm(pb.tip(y) - pb.tip(y0)) < 0.1 * pb.space.length
    # 1.5x the limit: |R(iy)| ~ 10 per step for the top modes -> caught within N_STEPS
    dt_bad = 1.5 * imaginary_axis_limit(tab) / lam
    with pytest.raises(IntegrationError):
        integrate_fixed(pb, tab, (0.0, N_STEPS * dt_bad), y0, dt_bad)


def test_weakly_unstable_methods_get_a_growth_budget_rule():
    step = stable_step(resolve_method("rkmk6"), 2.4e6, 0.05)
    assert step.rule == "growth budget" and "unstable on the imaginary axis" in step.warning
    # the fastest mode then grows by at most 2x over the run: |R(iy)|^N <= 2
    from liegroup_int.tableaux import imaginary_axis_growth

    n = 0.05 / step.dt
    assert float(imaginary_axis_growth(resolve_method("rkmk6"), step.y)) ** n <= 2.0 + 1e-9
