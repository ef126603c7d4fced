"""Run guards: a dt beyond the stable step, a spurious growing mode at rest, the energy
balance, and failure diagnoses that name the real cause (liegroup_int/guards.py)."""

import json

import numpy as np
import pytest

from liegroup_int.cli import main
from liegroup_int.guards import EnergyBalance, BalanceError
from liegroup_int.integrators import Stats
from liegroup_int.io import read_history


#: the paper's collocation, whose spurious modes at rest the spectrum guards and "auto" treat
PRIMAL = ("--set", "space.formulation=primal")


def _run(capsys, *args):
    rc = main(["run", *args, "--quiet"])
    return rc, capsys.readouterr().err


def test_dt_beyond_the_stable_step_of_a_finer_mesh_is_refused(tmp_path, capsys):
    # the paper's pendulum dt = 5e-5 s, default Galerkin formulation: stable at n_ctrl = 31
    # (|lambda|max = 2.37e4 1/s, |lambda| dt = 1.18), 61 and 81 (5.19e4 1/s: 2.59), but not
    # at n_ctrl = 101 (|lambda|max = 6.41e4 1/s, measured: 3.2 > 2.83, RK4's limit)
    out = tmp_path / "p101"
    rc, err = _run(capsys, "pendulum", "--out", str(out), "--set", "space.n_ctrl=101")
    assert rc == 2 and err.count("\n") == 1
    assert "key 'integrator.dt' = 5e-05 s is beyond the stable step" in err and "n_ctrl=101" in err
    stable = float(err.split("the stable step ")[1].split(" s")[0])
    assert 4.2e-5 < stable < 4.6e-5  # 2.83 / 6.41e4 = 4.42e-5
    assert not out.exists()  # nothing was started, nothing written


def test_spurious_growing_mode_at_rest_is_refused(tmp_path, capsys):
    # primal collocation, cantilever p = 8, n_ctrl = 11: a complex pair with
    # Re lambda = +9.0e3 1/s at rest (docs/verification.md, stability map)
    out = tmp_path / "p8"
    rc, err = _run(capsys, "cantilever", "--out", str(out), *PRIMAL, "--set", "space.degree=8",
                   "--set", "space.n_ctrl=11", "--set", "material.kelvin_voigt=0")
    assert rc == 2 and err.count("\n") == 1
    assert "spurious growing mode of this discretization (primal collocation, p=8, n_ctrl=11)" in err
    assert "kelvin_voigt" in err and "whatever dt" in err
    assert 'try space.formulation = "galerkin"' in err  # the formulation that finishes comes first
    assert not out.exists()


def test_kelvin_voigt_auto_removes_the_growth_and_reports_it(tmp_path, capsys):
    # primal arch, p = 6, n_ctrl = 21: a complex pair at +1.0e2 1/s at rest (stability map);
    # the sizing finds tau ~ 2e-8 s, a damping ratio ~ 5e-7 on the first mode
    out = tmp_path / "kv"
    rc, err = _run(capsys, "arch", "--out", str(out), *PRIMAL, "--set", "space.degree=6", "--set", "space.n_ctrl=21",
                   "--set", "t_end=1e-3", "--set", "integrator.dt=auto", "--set", "output.paraview=false")
    assert rc == 0, err
    s = json.loads((out / "summary.json").read_text())
    kv = s["kelvin_voigt_auto"]
    assert kv["max_real_undamped"] > 10 and kv["max_real"] <= 1e-2
    assert 0 < kv["tau"] < 1e-6 and kv["zeta1"] < 1e-5  # light damping of the first mode
    assert s["discretization"]["kelvin_voigt"] == kv["tau"]
    assert s["guards"]["max_re_lambda"] <= 1e-2  # the start probe (the sizing's spectrum) saw no growth


def test_kelvin_voigt_auto_refuses_heavy_damping(tmp_path, capsys):
    # primal cantilever, p = 8, n_ctrl = 11 (three elements): removing its pair would take
    # a damping ratio 5.5e-3 on the first mode, beyond what "auto" accepts (1e-3)
    rc, err = _run(capsys, "cantilever", "--out", str(tmp_path / "no"), *PRIMAL, "--set", "space.degree=8",
                   "--set", "space.n_ctrl=11")
    assert rc == 2 and err.count("\n") == 1
    assert "key 'material.kelvin_voigt' = 'auto'" in err and "not a high-frequency artefact" in err
    assert not (tmp_path / "no").exists()


def test_energy_balance_breaks_when_a_spurious_mode_grows(tmp_path, capsys):
    # the same (primal) discretization run anyway: the growing pair feeds energy that no load
    # supplied; the balance guard stops the run and the diagnosis names the pair
    out = tmp_path / "grow"
    rc, err = _run(capsys, "cantilever", "--out", str(out), *PRIMAL, "--set", "space.degree=8", "--set", "space.n_ctrl=11",
                   "--set", "material.kelvin_voigt=0", "--set", "guard.spectrum=false", "--set", "integrator.dt=auto", "--set", "output.paraview=false",
                   "--set", 'output.quantities=["tip","energy_balance","work"]')
    assert rc == 3 and err.count("\n") == 1
    assert "energy balance broken" in err and "spurious growing mode" in err and "complex pair" in err
    assert "reduce dt" not in err  # not a step-size problem
    assert 'try space.formulation = "galerkin"' in err
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "failed" and s["energy_balance"]["worst_fraction"] > 0.5
    h = read_history(out / "history.csv")
    assert abs(h["energy_balance"][-1]) > 0.5 * np.max(np.abs(h["work"]))  # the failing row is on disk
    assert h["t"][-1] == pytest.approx(s["t_reached"])


def test_energy_balance_closes_on_a_resolved_run(tmp_path, capsys):
    # pendulum (gravity only), 0.2 s, default Galerkin formulation (energy-conserving in
    # space): the balance is RKMK4's time error, measured 9.5e-12 J, 2.8e-8 of the 0.14 J of
    # work; asserted below 1e-6 J (the pendulum's energy target) and 1e-6 of the work
    out = tmp_path / "pend"
    rc, err = _run(capsys, "pendulum", "--out", str(out), "--set", "t_end=0.2", "--set", "output.paraview=false",
                   "--set", 'output.quantities=["tip","energy_balance","work"]')
    assert rc == 0, err
    s = json.loads((out / "summary.json").read_text())
    assert s["energy_balance"]["worst_fraction"] < 1e-6 and abs(s["energy_balance"]["defect"]) < 1e-6
    assert s["energy_balance"]["work"] > 0.1  # gravity did work


def test_energy_balance_unit():
    stats = Stats()
    bal = EnergyBalance(lambda y: y, stats, e0=1.0, tolerance=0.5)
    stats.quadrature = 2.0
    bal(0.1, 3.0)  # E - W - E0 = 0
    assert bal.defect == 0.0 and bal.scale == 3.0
    with pytest.raises(BalanceError, match="energy balance broken at t=0.2"):
        bal(0.2, 7.0)  # defect 4 of scale 7
    bal2 = EnergyBalance(lambda y: y, Stats(), e0=0.0, tolerance=0.0)
    bal2(0.1, 10.0)  # tolerance 0: records, never stops
    assert bal2.worst == 1.0
    with pytest.raises(BalanceError):
        bal2(0.2, np.nan)  # non-finite always stops
