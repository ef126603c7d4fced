"""Arc-length continuation through a limit point: a clamped shallow arch under a central
point load snaps through. The path agrees with load-controlled Newton where that converges,
its peak is a limit point (the tangent turns singular there), and load control fails beyond it."""

from __future__ import annotations

import numpy as np
import pytest

from liegroup_int.problems.beam.arclength import arc_length_path
from liegroup_int.problems.beam.statics import StaticDivergence, solve_static, tangent_matrix
from liegroup_int.scenes import load_scene
from liegroup_int.scenes.beam import problem

R, ALPHA, P = 100.0, np.radians(10.0), 1000.0  # radius, half-angle (rise 1.52, span 34.7), load


def _arch(**over):
    """Clamped-clamped circular arch (exact quadratic NURBS), point load -P e2 at mid-span."""
    cp = [-R * np.sin(ALPHA), 0, 0, 0, R / np.cos(ALPHA) - R * np.cos(ALPHA), 0, R * np.sin(ALPHA), 0, 0]
    keys = {"problem": "beam", "t_end": 1.0, "integrator.dt": 1e-3, "geometry.kind": "nurbs", "geometry.degree": 2,
            "geometry.control_points": cp, "geometry.weights": [1.0, float(np.cos(ALPHA)), 1.0],
            "section.shape": "explicit", "section.EA": 1e7, "section.GA": 4e6, "section.EI1": 1e5,
            "section.EI2": 1e5, "section.GJ": 1e5, "section.rhoA": 1.0, "section.rhoI1": 1.0, "section.rhoI2": 1.0,
            "bc.start": "clamped", "bc.end": "clamped", "space.n_ctrl": 21, "integrator.backend": "numpy",
            "point_loads": [{"s": 0.5, "force": [0.0, -P, 0.0]}], "loads.end.force": [0.0, 0.0, 0.0], **over}
    return problem(load_scene("cantilever", keys))


@pytest.fixture(scope="module")
def path():
    pb = _arch()
    return pb, arc_length_path(pb, steps=30, ds=0.05, lam_max=3.0)


def _mid(pb, y):
    return pb.centreline(y, np.array([0.5]))[0]


def test_the_path_snaps_through_a_limit_point(path):
    """The load factor rises to a limit, falls while the crown passes below the chord, and
    rises again: the classical snap-through curve."""
    pb, p = path
    lam = np.array(p.load_factors)
    mid = np.array([_mid(pb, y)[1] for y in p.states])
    assert p.converged and p.limit >= np.max(lam)
    k = int(np.argmax(lam))
    assert 0 < k < len(lam) - 1 and np.all(np.diff(lam[:k + 1]) > 0) and lam[k + 1] < lam[k]
    assert np.all(np.diff(mid) < 0)  # the crown moves down all along the path
    assert mid[-1] < 0.0 < mid[0] and lam[-1] > np.min(lam[k:])  # through the chord, rising again


def test_the_path_agrees_with_load_control_before_the_limit(path):
    """At the path's load factor 0.4462 (below the limit), Newton with load stepping finds
    the same equilibrium: crown displacement to 1e-7 (both converge to 1e-8 of the load)."""
    pb, p = path
    k = 9
    assert p.load_factors[k] == pytest.approx(0.4462, abs=1e-4)
    res = solve_static(pb, load_steps=4, load_factor=p.load_factors[k])
    assert np.max(np.abs(_mid(pb, res.state) - _mid(pb, p.states[k]))) < 1e-7


def test_the_limit_load_converges_with_the_arc_length_step():
    """The limit (the peak of the parabola through the top three points) at ds = 0.025 and
    0.0125: 0.775785 and 0.775773 (ds = 0.05: 0.7719), asserted within 1e-4 of each other.
    The corrector stops at 1e-5 of the load: the limits are those at the default 1e-8 to
    5e-9, with 132 corrector iterations instead of 216."""
    pb = _arch()
    a, b = (arc_length_path(pb, steps=200, ds=ds, until_limit=True, tol=1e-5).limit for ds in (0.025, 0.0125))
    assert abs(a - b) < 1e-4 * b and b == pytest.approx(0.7758, abs=5e-4)


def test_the_peak_is_a_limit_point_and_load_control_leaves_the_branch_past_it(path):
    """The tangent's determinant changes sign between the points around the peak (one
    eigenvalue crosses zero). Load control to 0.99 of the limit (0.7758) converges on the
    loaded arch (crown still above 0.9); to 1.01 of it there is no equilibrium near the
    loaded arch: Newton either fails or lands on the snapped branch (crown below the chord)."""
    pb, p = path
    lam = np.array(p.load_factors)
    k = int(np.argmax(lam))
    signs = [np.linalg.slogdet(tangent_matrix(pb, p.states[j], p.load_factors[j]).matrix)[0] for j in (k - 1, k + 1)]
    assert signs[0] == -signs[1]
    limit = 0.7758
    assert _mid(pb, solve_static(pb, load_steps=20, load_factor=0.99 * limit).state)[1] > 0.9
    try:
        crown = _mid(pb, solve_static(pb, load_steps=20, load_factor=1.01 * limit).state)[1]
    except StaticDivergence:
        crown = -np.inf
    assert crown < 0.0


def test_static_command_follows_the_path(tmp_path, path):
    """``liegroup-int static ARCH --arc-length 0.05``: exit 0, the path to load factor 1 in
    history.csv and its limit in summary.json, the same as arc_length_path's (the ``path``
    fixture: the same arch and ds, 30 steps, past the limit)."""
    import json

    from liegroup_int.cli import main

    cp = [float(x) for x in (-R * np.sin(ALPHA), 0, 0, 0, R / np.cos(ALPHA) - R * np.cos(ALPHA), 0,
                             R * np.sin(ALPHA), 0, 0)]
    scene = tmp_path / "arch.toml"
    scene.write_text(f"""problem = "beam"
t_end = 1.0
[integrator]
dt = 1e-3
[geometry]
kind = "nurbs"
degree = 2
control_points = {cp!r}
weights = [1.0, {float(np.cos(ALPHA))!r}, 1.0]
[space]
n_ctrl = 21
[section]
shape = "explicit"
EA = 1e7
GA = 4e6
EI1 = 1e5
EI2 = 1e5
GJ = 1e5
rhoA = 1.0
rhoI1 = 1.0
rhoI2 = 1.0
[bc]
start = "clamped"
end = "clamped"
[[point_loads]]
s = 0.5
force = [0.0, {-P!r}, 0.0]
""")
    out = tmp_path / "out"
    assert main(["static", str(scene), "--arc-length", "0.05", "--steps", "60", "--out", str(out)]) == 0
    s = json.loads((out / "summary.json").read_text())
    rows = np.loadtxt(out / "history.csv", delimiter=",", skiprows=1)
    assert s["converged"] and s["load_factors"][-1] > 1.0 and rows.shape[0] == len(s["load_factors"])
    lam = np.array(path[1].load_factors)
    assert len(s["load_factors"]) > lam.size
    np.testing.assert_allclose(s["load_factors"][:lam.size], lam, rtol=1e-12, atol=0)
    np.testing.assert_allclose(rows[:lam.size, 1], lam, rtol=1e-12, atol=0)
    assert s["limit_load_factor"] == pytest.approx(path[1].limit, rel=1e-12)
    assert main(["static", str(scene), "--arc-length", "-1", "--out", str(tmp_path / "bad")]) == 2


def test_a_singular_tangent_ends_the_path_instead_of_raising(monkeypatch):
    """A tangent that LU finds exactly singular (here from the fifth factorization on,
    made zero) ends the path like a corrector that does not converge: the steps before it
    are kept, ``converged`` is False, and nothing raises (the CLI then prints one line)."""
    from liegroup_int.problems.beam import arclength

    pb = _arch(**{"space.n_ctrl": 11})
    real = arclength._System.tangent
    calls = []

    def tangent(self, *args, **kwargs):
        calls.append(1)
        J = real(self, *args, **kwargs)
        return J if len(calls) <= 4 else J * 0.0

    monkeypatch.setattr(arclength._System, "tangent", tangent)
    res = arc_length_path(pb, steps=10, ds=0.05)
    print(f"{len(res.load_factors) - 1} steps kept, converged {res.converged}")
    assert not res.converged and len(res.load_factors) >= 2
