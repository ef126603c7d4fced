"""modal_analysis on systems with known modes: frequencies, damping ratios, growth."""

from __future__ import annotations

import numpy as np
import pytest

from liegroup_int import GroupProblem, Rn
from liegroup_int.integrators import modal_analysis


def _oscillators(omegas, zetas):
    """Uncoupled damped oscillators x'' + 2 zeta omega x' + omega^2 x = 0 on R^(2k)."""
    w, z = np.asarray(omegas, float), np.asarray(zetas, float)
    k = w.size

    def f(t, y):
        x, v = y[:k], y[k:]
        return np.concatenate([v, -w**2 * x - 2 * z * w * v])

    return GroupProblem(Rn(2 * k), f)


def test_frequencies_and_damping_ratios():
    omegas, zetas = [3.0, 40.0, 7.0], [0.0, 0.05, 0.3]
    rep = modal_analysis(_oscillators(omegas, zetas), 0.0, np.ones(6), n=3)
    assert rep.size == 6 and rep.zero_modes == 0
    got = [(m.freq_hz, m.damping_ratio) for m in rep.modes]
    want = sorted((w / (2 * np.pi), z) for w, z in zip(omegas, zetas))
    # central differences on a linear field are exact up to rounding: 1e-9 relative
    for (f, z), (fw, zw) in zip(got, want):
        assert f == pytest.approx(fw, rel=1e-9) and z == pytest.approx(zw, abs=1e-9)
    assert not any(m.growing for m in rep.modes)
    v = rep.modes[0].vector
    assert v.shape == (6,) and np.linalg.norm(v) == pytest.approx(1.0)


def test_growth_needs_the_duration():
    """Negative damping: growing; with a duration over which it grows by less than e: not."""
    rep = modal_analysis(_oscillators([10.0], [-0.01]), 0.0, np.ones(2), n=1)
    assert rep.modes[0].growing and rep.modes[0].damping_ratio == pytest.approx(-0.01, rel=1e-6)
    # Re lambda = 0.1 1/s: e-folding after 10 s
    assert not modal_analysis(_oscillators([10.0], [-0.01]), 0.0, np.ones(2), n=1, duration=5.0).modes[0].growing
    assert modal_analysis(_oscillators([10.0], [-0.01]), 0.0, np.ones(2), n=1, duration=20.0).modes[0].growing


def test_rejects_bad_n():
    with pytest.raises(ValueError, match="at least one mode"):
        modal_analysis(_oscillators([1.0], [0.0]), 0.0, np.ones(2), n=0)
