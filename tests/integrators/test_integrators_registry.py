"""One method registry: every name works in scenes, the CLI and ``integrate``."""

import numpy as np
import pytest

from liegroup_int import Rn, integrate
from liegroup_int.integrators import METHODS, resolve_method
from liegroup_int.scenes import SceneError, load_scene
from liegroup_int.tableaux import CF_REGISTRY, NAMES, REGISTRY, resolve


def test_methods_are_derived_from_the_tableaux():
    assert METHODS == {tab.method: tab.name for tab in [*REGISTRY.values(), *CF_REGISTRY.values()]}
    assert set(NAMES) == set(METHODS) | set(REGISTRY) | set(CF_REGISTRY)


@pytest.mark.parametrize("name", sorted(NAMES))
def test_every_name_works_everywhere(name):
    tab = resolve(name)
    assert resolve_method(name) is tab and resolve_method(name.upper()) is tab
    sc = load_scene("heavy_top", {"integrator.method": name, "t_end": 0.01, "integrator.dt": 1e-3})
    assert resolve_method(sc.integrator.method) is tab
    # integrate on R^1: dy/dt = -y, one step of size 1e-3 of any method is accurate to
    # its order (error <= ~1e-3^2 / 2 for Lie-Euler)
    sol = integrate(lambda t, y: -y, np.ones(1), (0.0, 1e-3), space=Rn(1), method=name, dt=1e-3)
    assert abs(sol.y_final[0] - np.exp(-1e-3)) < 1e-6


def test_unknown_name_lists_the_choices():
    with pytest.raises(ValueError, match="unknown method 'rk5'; expected one of: .*rkmk4"):
        resolve_method("rk5")
    with pytest.raises(ValueError, match="unknown method 'rk5'"):
        integrate(lambda t, y: -y, np.ones(1), (0.0, 1e-3), space=Rn(1), method="rk5", dt=1e-3)
    with pytest.raises(SceneError, match="integrator.method"):
        load_scene("heavy_top", {"integrator.method": "rk5"})
