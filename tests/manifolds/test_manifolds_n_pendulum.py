"""The N-fold 3D pendulum on (TS^2)^N (examples/n_pendulum.py): energy and constraints."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from liegroup_int import integrate

_spec = importlib.util.spec_from_file_location(
    "n_pendulum", Path(__file__).resolve().parents[2] / "examples" / "n_pendulum.py")
n_pendulum = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(n_pendulum)


def test_double_pendulum_energy_drift_shrinks_at_rkmk4s_order():
    """N = 2, unit masses and links, T = 1: energy drift 9.2e-5, 3.3e-6, 1.2e-7 J at dt =
    0.02, 0.01, 0.005 (fitted slope 4.8; at least 3.7 required), constraints to 1e-13
    (measured 2e-15). A wrong force or mass matrix would not conserve energy at all."""
    space, gen, y0, energy = n_pendulum.n_pendulum(2)
    E0 = energy(y0)
    dts = np.array([0.02, 0.01, 0.005])
    drift = []
    for dt in dts:
        y = integrate(gen, y0, (0.0, 1.0), space=space, method="rkmk4", dt=dt).y_final
        assert space.constraint(y) <= 1e-13
        drift.append(abs(energy(y) - E0))
    slope = np.polyfit(np.log(dts), np.log(drift), 1)[0]
    assert slope >= 3.7, (drift, slope)


def test_variable_steps_and_ten_links():
    """The adaptive RKMK45 pair (tolerance 1e-8, T = 1) on the double pendulum: energy
    within 1e-6 J (measured 6.5e-9 over 0.5 s with the example's settings); the 10-fold
    pendulum, RKMK4 at dt = 2e-3 over 0.1 s: energy within 1e-8 J (measured 1.1e-10 over
    0.2 s), constraints to 1e-13."""
    space, gen, y0, energy = n_pendulum.n_pendulum(2)
    sol = integrate(gen, y0, (0.0, 1.0), space=space, method="rkmk45", rtol=1e-8, atol=1e-8)
    assert sol.stats.steps > 10 and abs(energy(sol.y_final) - energy(y0)) <= 1e-6
    space, gen, y0, energy = n_pendulum.n_pendulum(10)
    y = integrate(gen, y0, (0.0, 0.1), space=space, method="rkmk4", dt=2e-3).y_final
    assert space.constraint(y) <= 1e-13
    assert abs(energy(y) - energy(y0)) <= 1e-8


def test_sizes_must_match():
    with pytest.raises(ValueError):
        n_pendulum.n_pendulum(2, masses=[1.0, 1.0, 1.0])
