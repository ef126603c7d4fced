"""The energy-balance guard stopping REAL runs of a built-in beam scene.

No fake energies: the defect ``E_kin + E_strain - W - E0`` comes from integrating the
pendulum scene. Two real causes:

* a step 2.5 % beyond the stability limit, with the start guard that would refuse it
  switched off (``guard.dt = false``): the top mode of the discretization grows by
  ``|R(2.9 i)| = 1.19`` per RK4 step from round-off and feeds energy no load supplied.
  Run as a user runs it, ``python -m liegroup_int run ...`` in a subprocess: exit code 3,
  one line on stderr naming the energy balance (and, by the failure diagnosis, the step),
  no traceback, and the history up to the failing output time on disk.
* a resolved run under a tolerance tighter than its space discretization error: the
  collocation energy defect of the pendulum is 0.2 % to 0.4 % of the energy scale
  (measured over 0.3 s), so ``guard.energy_balance = 1e-3`` must stop it at its first output.
"""

import json
import subprocess
import sys

import numpy as np
import pytest

from liegroup_int.cli import main
from liegroup_int.integrators import resolve_method
from liegroup_int.io import read_history
from liegroup_int.scenes import KINDS, load_scene
from liegroup_int.tableaux import imaginary_axis_limit

QUANTITIES = 'output.quantities=["tip", "energy", "energy_balance", "work"]'


def _read(out):
    return json.loads((out / "summary.json").read_text()), read_history(out / "history.csv")


def _one_line(err):
    """The whole stderr is one ``error: ...`` line."""
    assert "Traceback" not in err
    assert err.count("\n") == 1 and err.endswith("\n") and err.startswith("error: "), err
    return err.strip()


def _check_history(s, h, tol):
    """The history holds the rows up to the failing output time, the failing row included,
    and the guard stopped at the first row whose defect exceeded ``tol`` of the scale."""
    assert s["history_rows"] == len(h["t"]) >= 2
    assert h["t"][0] == 0.0 and np.all(np.diff(h["t"]) > 0)
    assert h["t"][-1] == pytest.approx(s["t_reached"], rel=1e-12)
    scale = s["energy_balance"]["energy_scale"]
    defect = np.abs(h["energy_balance"])
    assert defect[-1] > tol * scale  # the failing row is on disk
    # the scale only grows during a run, so every earlier row passed with a scale <= this one
    assert np.all(defect[:-1] <= tol * scale)
    assert s["energy_balance"]["defect"] == pytest.approx(h["energy_balance"][-1], rel=1e-12)


def test_a_step_beyond_the_stability_limit_breaks_the_energy_balance(tmp_path):
    scene = load_scene("pendulum", {"integrator.dt": "auto"})
    lam = KINDS["beam"].build(scene).info["lambda_max"]  # the estimate the start guard uses
    tab = resolve_method("rkmk4")
    y = 2.9  # |lambda| dt, 2.5 % beyond RK4's limit 2 sqrt(2)
    assert y > imaginary_axis_limit(tab)
    dt = y / lam
    t_end = 600 * dt
    out = tmp_path / "unstable"
    # no plots: drawing them (0.7 s of the 2.2 s subprocess, matplotlib's import included)
    # after a failed run is checked by the next test
    proc = subprocess.run(
        [sys.executable, "-m", "liegroup_int", "run", "pendulum", "--out", str(out), "--quiet",
         "--set", "guard.dt=false", "--set", f"integrator.dt={dt!r}", "--set", f"t_end={t_end!r}",
         "--set", f"output.every={2 * dt!r}", "--set", "output.paraview=false", "--set", "output.plots=false",
         "--set", QUANTITIES],
        check=False, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 3, proc.stderr
    assert "Traceback" not in proc.stdout
    err = _one_line(proc.stderr)
    assert err.startswith("error: pendulum: energy balance broken at t=")
    assert "guard.energy_balance = 0.5" in err
    assert "the step is beyond the stability limit" in err  # the diagnosis names the real cause
    assert f"are in {out}" in err
    s, h = _read(out)
    assert s["status"] == "failed" and "energy balance broken" in s["error"]
    assert s["energy_balance"]["worst_fraction"] > 0.5
    # the top mode starts at round-off (~1e-16 of the motion) and needs about
    # log(1e16) / log(1.19) = 210 steps to reach the energy of the motion: not the first
    # steps (something else would be broken), and before t_end (600 steps)
    assert 100 < s["steps"] < 600
    _check_history(s, h, 0.5)
    assert (out / "results.h5").exists()  # the streamed copy was closed on failure too


def test_a_tolerance_below_the_discretization_error_stops_a_resolved_run(tmp_path, capsys):
    # primal collocation: its energy error (not conservative) is the discretization error here
    out = tmp_path / "tight"
    rc = main(["run", "pendulum", "--out", str(out), "--quiet", "--set", "space.formulation=primal",
               "--set", "guard.energy_balance=1e-3",
               "--set", "t_end=0.02", "--set", "output.every=0.005", "--set", "output.paraview=false",
               "--set", "output.hdf5=false", "--set", QUANTITIES])
    captured = capsys.readouterr()
    assert rc == 3
    err = _one_line(captured.err)
    assert err.startswith("error: pendulum: energy balance broken at t=0.005:")
    assert "guard.energy_balance = 0.001" in err
    assert "so not the step" in err  # the scene's dt is within the stability limit
    s, h = _read(out)
    assert s["status"] == "failed" and s["t_reached"] == pytest.approx(0.005, rel=1e-12)
    # the defect is the collocation energy error of a resolved run: above the 0.1 %
    # tolerance and below 1 % (measured 0.28 % at t = 0.005 s)
    assert 1e-3 < s["energy_balance"]["worst_fraction"] < 1e-2
    _check_history(s, h, 1e-3)
    assert len(h["t"]) == 2  # t = 0 and the failing first output
    assert (out / "history.png").exists() and (out / "shapes.png").exists()  # plots of a failed run
