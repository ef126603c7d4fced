"""Scene events (``[[events]]``): located on the dense output, terminal ones stop the run
there, direction filters, and one-line refusals."""

from __future__ import annotations

import numpy as np
import pytest

from liegroup_int import integrate
from liegroup_int.cli import main
from liegroup_int.io import read_history
from liegroup_int.runner import run_scene
from liegroup_int.scenes import KINDS, load_scene

BASE = {"output.plots": False, "output.hdf5": False}


def test_a_terminal_event_stops_the_cantilever_at_the_level(tmp_path):
    """The cantilever's tip falls through z = -0.1 m at t = 0.020722 s: the run stops there,
    its last row is the event (tip_z = -0.1 to 1e-12), and the time lies in the step where
    the stepped solution crosses (the same steps of 1e-6 s recorded one by one), within 1e-10
    s of the linear interpolation there (whose own error, dt^2 z'' / (8 z'), is ~3e-11 s)."""
    ev = [{"quantity": "tip_z", "value": -0.1, "direction": "falling", "terminal": True}]
    scene = load_scene("cantilever", {**BASE, "events": ev})
    res = run_scene(scene, tmp_path / "ev")
    s = res.summary
    assert s["status"] == "ok" and s["stopped_by_event"] == "tip_z = -0.1"
    t_ev = s["t_reached"]
    assert s["events"] == [{"name": "tip_z = -0.1", "t": t_ev, "terminal": True}]
    h = read_history(tmp_path / "ev" / "history.csv")
    assert h["t"][-1] == t_ev and abs(h["tip_z"][-1] + 0.1) < 1e-12 and np.all(h["tip_z"][:-1] > -0.1)
    sim = KINDS["beam"].build(scene)
    dt = scene.integrator.dt
    grid = dt * np.arange(20500, 20801)
    sol = integrate(sim.problem, sim.y0, (0.0, grid[-1]), method="rkmk4", dt=dt, t_eval=grid)
    z = np.array([sim.problem.tip(y)[2] for y in sol.y[1:]]) + 0.1
    k = int(np.argmax(z < 0.0))
    assert sol.t[1 + k - 1] <= t_ev <= sol.t[1 + k]
    t_lin = sol.t[k] + (sol.t[1 + k] - sol.t[k]) * z[k - 1] / (z[k - 1] - z[k])
    assert abs(t_ev - t_lin) < 1e-10


def test_direction_filters_and_non_terminal_events(tmp_path):
    """The tip swings about its static deflection (0.18 m): over 0.1 s it crosses -0.18 m
    falling (0.0285 s), then rising half a first-mode period later (1 / (2 x 8.3813 Hz) =
    0.0597 s; measured 0.0592, the higher modes ride on it: 5 % allowed); "both" lists the
    union, in time order. On 11 control points (p = 4) the crossing times are those of the
    scene's 31 to 1e-5 s (0.028531 and 0.087728 s against 0.028537 and 0.087722 s), in
    52700 steps of dt = auto against 77700."""
    ev = [{"name": "down", "quantity": "tip_z", "value": -0.18, "direction": "falling"},
          {"name": "up", "quantity": "tip_z", "value": -0.18, "direction": "rising"},
          {"name": "any", "quantity": "tip_z", "value": -0.18}]
    res = run_scene(load_scene("cantilever", {**BASE, "t_end": 0.1, "space.n_ctrl": 11, "integrator.dt": "auto",
                                              "events": ev}), tmp_path)
    found = res.summary["events"]
    by = {n: [e["t"] for e in found if e["name"] == n] for n in ("down", "up", "any")}
    assert len(by["down"]) == 1 and len(by["up"]) == 1
    assert np.allclose(sorted(by["down"] + by["up"]), by["any"], rtol=0, atol=1e-12)
    assert by["up"][0] - by["down"][0] == pytest.approx(1 / (2 * 8.3813), rel=0.05)
    assert res.summary["stopped_by_event"] is None and res.summary["t_reached"] == 0.1


@pytest.mark.parametrize("ev, match", [
    ([{"quantity": "tip_w"}], "key 'quantity' = 'tip_w' is not a recorded column; recorded: tip_x"),
    ([{"quantity": "tip_z", "direction": "down"}], "key 'direction'"),
    ([{"value": 1.0}], "key 'quantity'"),
    ([{"name": "a", "quantity": "tip_z"}, {"name": "a", "quantity": "energy"}], "two events share a name"),
])
def test_bad_events_are_one_line_before_anything_is_written(ev, match, tmp_path, capsys):
    rc = main(["run", "cantilever", "--out", str(tmp_path / "r"), "--set", f"events={_toml(ev)}", "--quiet"])
    err = capsys.readouterr().err
    assert rc == 2 and match in err and err.count("\n") == 1
    assert not (tmp_path / "r").exists()


def _toml(entries) -> str:
    """An inline TOML array of tables for --set."""
    def val(v):
        return f'"{v}"' if isinstance(v, str) else repr(v)
    return "[" + ", ".join("{" + ", ".join(f"{k}={val(v)}" for k, v in e.items()) + "}" for e in entries) + "]"
