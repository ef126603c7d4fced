"""`liegroup-int modes`: the cantilever's frequencies against the Timoshenko beam and
Euler-Bernoulli, their convergence under refinement, the files, and growing modes flagged."""

from __future__ import annotations

import csv
import functools
import math

import meshio
import numpy as np
import pytest

from liegroup_int.cli import main
from liegroup_int.integrators import modal_analysis
from liegroup_int.scenes import KINDS, builtin_descriptions, load_scene

from timoshenko_reference import cantilever_hz  # tests/scenes, on the path under pytest

# the cantilever scene: steel, square t = 0.01 m, L = 1 m, shear factor 1
E, NU, RHO, T, L = 2.1e11, 0.2, 7800.0, 0.01, 1.0
BETA_L = np.array([1.875104068711961, 4.694091132974175, 7.854757438237613])
EB_HZ = BETA_L**2 / (2 * math.pi * L**2) * math.sqrt(E * T**4 / 12 / (RHO * T**2))  # 8.382, 52.53, 147.08


@functools.lru_cache(maxsize=1)
def _timoshenko_values() -> tuple:
    return tuple(cantilever_hz(E, E / (2 * (1 + NU)), 1.0, RHO, T**2, T**4 / 12, L))


def _timoshenko_hz() -> np.ndarray:
    """The Timoshenko beam's three lowest frequencies [Hz] for this section
    (timoshenko_reference.py: 40-digit Chebyshev collocation, 0.8 s, computed once per
    process), a fresh array each call."""
    return np.array(_timoshenko_values())


def _bending_hz(degree: int, n_ctrl: int, formulation: str) -> np.ndarray:
    """The first three bending frequencies (each a degenerate pair: square section)."""
    scene = load_scene("cantilever", {"space.degree": degree, "space.n_ctrl": n_ctrl,
                                      "space.formulation": formulation})
    sim = KINDS["beam"].build(scene)
    f = np.array([m.freq_hz for m in modal_analysis(sim.problem, 0.0, sim.y0, 6).modes])
    assert np.allclose(f[0::2], f[1::2], rtol=1e-6)  # the two bending planes (FD noise: 1e-7)
    return f[0::2]


def test_euler_bernoulli_values():
    assert EB_HZ == pytest.approx([8.382, 52.53, 147.08], rel=2e-4)


def test_cantilever_frequencies_converge_to_the_timoshenko_beam():
    """The linearized Simo-Reissner beam is a Timoshenko beam (shear factor 1 here): the
    modes converge to its frequencies, computed independently (timoshenko_reference.py,
    8.3813507, 52.504381, 146.92053 Hz; its own error below 3e-9, timoshenko_reference.py),
    at the primal collocation's order. Measured: p = 4 over n_ctrl = 21, 31, 41 at fitted
    rates 4.1-4.4 (errors 3.2e-3 -> 1.5e-4 for mode 1, the smallest 1.5e-4); p = 8,
    n_ctrl = 31 within 1.1e-8, 2.4e-8, 4.7e-7 (the finite-difference Jacobian's floor is
    about 5e-8). Euler-Bernoulli lies above by the shear and rotary-inertia effect, 6.6e-5,
    4.6e-4 and 1.1e-3 relative."""
    ref = _timoshenko_hz()
    assert np.all(ref < EB_HZ) and np.max(np.abs(ref / EB_HZ - 1)) < 1.2e-3
    ns = np.array([21, 31, 41])
    err = np.array([np.abs(_bending_hz(4, int(n), "primal") / ref - 1) for n in ns])
    assert np.all(np.diff(err, axis=0) < 0)
    for k in range(3):
        rate = np.polyfit(np.log(1.0 / (ns - 1)), np.log(err[:, k]), 1)[0]
        assert 3.5 < rate < 5.5, (k, rate)
    assert np.max(np.abs(_bending_hz(8, 31, "primal") / ref - 1)) < 2e-6


def test_modes_command_writes_table_shapes_and_picture(tmp_path, capsys):
    out = tmp_path / "m"
    assert main(["modes", "cantilever", "--n", "6", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "6 lowest modes" in text and "GROWING" not in text
    rows = list(csv.DictReader(open(out / "modes.csv")))
    assert [int(r["mode"]) for r in rows] == list(range(1, 7))
    f = np.array([float(r["freq_hz"]) for r in rows])
    # default Galerkin, p = 4, n_ctrl = 31: the Timoshenko frequencies to 2.5e-8 (measured;
    # the finite-difference Jacobian's floor is about 5e-8), asserted to 1e-6
    ref = _timoshenko_hz()
    assert f[0::2] == pytest.approx(ref, rel=1e-6)
    # bending; each degenerate pair recombined into one plane each (square section)
    assert [sorted(r["dominant"] for r in rows[k:k + 2]) for k in (0, 2, 4)] == [["u2", "u3"]] * 3
    for k in (1, 2):
        disp = meshio.read(out / f"mode_0{k}.vtu").point_data["displacement"]
        assert disp.shape == (101, 3) and np.max(np.linalg.norm(disp, axis=1)) == pytest.approx(1.0)
        assert np.linalg.norm(disp[0]) < 1e-12  # clamped end
        # out of its plane: the finite-difference noise of the eigenvectors (measured 5e-10)
        assert np.sort(np.max(np.abs(disp), axis=0))[1] < 1e-6
    assert (out / "modes.pvd").exists() and (out / "modes.png").stat().st_size > 10000


def test_modes_flags_a_growing_mode(tmp_path, capsys):
    """The undamped primal arch at p = 2 has a real growing mode at rest (locking)."""
    assert main(["modes", "arch", "--set", "space.formulation=primal", "--set", "space.degree=2",
                 "--set", "material.kelvin_voigt=0", "--n", "2",
                 "--out", str(tmp_path / "a")]) == 0
    out, err = capsys.readouterr()
    assert "GROWING" in out and "growing mode(s) at t = 0" in err


def test_modes_rejects_bad_n(capsys):
    assert main(["modes", "cantilever", "--n", "0"]) == 2
    assert "--n 0" in capsys.readouterr().err


@pytest.mark.parametrize("scene_name", [n for n in sorted(builtin_descriptions()) if load_scene(n).kind == "beam"])
def test_modes_on_every_builtin_beam_scene(scene_name, tmp_path, capsys):
    """Every built-in beam scene: two modes, a table row each, one VTU each. Without the
    finer-mesh estimate (the same modal analysis on n_ctrl = 2 n_ctrl - p, tested on the
    cantilever and the column): its dense eigenproblem, twice the size, is most of the
    command's time (1.8 of 2.4 s on the spinning helix, measured)."""
    assert main(["modes", scene_name, "--n", "2", "--no-estimate", "--out", str(tmp_path)]) == 0
    rows = list(csv.DictReader(open(tmp_path / "modes.csv")))
    assert len(rows) == 2 and all(float(r["freq_hz"]) > 0 for r in rows)
    assert len(list(tmp_path.glob("mode_*.vtu"))) == 2
    capsys.readouterr()


def _modes_rows(capsys, tmp_path, *args):
    assert main(["modes", "cantilever", "--out", str(tmp_path), *args]) == 0
    return capsys.readouterr().out, list(csv.DictReader(open(tmp_path / "modes.csv")))


def test_modes_estimates_the_discretization_error_from_the_finer_mesh(tmp_path, capsys):
    """On a coarse mesh (p = 4, n_ctrl = 9) the bending pairs are 2.3e-6, 6.9e-4 and 1.9e-2
    above the Timoshenko values; the finer mesh (n_ctrl = 14) is 2^-2p ~ 1/256 as far off,
    so the relative change estimates the coarse error (measured: 0.991-0.996 of it; asserted
    within 15 % for the two pairs above the noise), and only the third pair is flagged."""
    text, rows = _modes_rows(capsys, tmp_path, "--n", "6", "--set", "space.n_ctrl=9")
    ref = _timoshenko_hz()
    f = np.array([float(r["freq_hz"]) for r in rows])[0::2]
    est = np.array([float(r["rel_change_finer"]) for r in rows])[0::2]
    true = f / ref - 1.0
    assert true[2] > 1e-2 and est[2] == pytest.approx(true[2], rel=0.15)
    assert est[1] == pytest.approx(true[1], rel=0.15)
    assert "(space.n_ctrl = 14)" in text and "modes 5, 6 change by more than 0.001" in text
    assert text.count("UNCONVERGED") == 2


def test_modes_header_separates_supports_from_rigid_body_motion(tmp_path, capsys):
    """The clamp holds 6 degrees of freedom: 12 zero eigenvalues, none left for rigid-body
    motion; the default mesh's bending pairs move by less than 1e-6 on the finer mesh (the
    finite-difference Jacobian's noise is ~1e-7)."""
    text, rows = _modes_rows(capsys, tmp_path, "--n", "4")
    assert "12 zero eigenvalues: 12 from the 6 degrees of freedom held by supports and joints, 0 from free" in text
    assert max(float(r["rel_change_finer"]) for r in rows) < 1e-6 and "UNCONVERGED" not in text


def test_modes_without_estimate_says_so(tmp_path, capsys):
    text, rows = _modes_rows(capsys, tmp_path, "--n", "2", "--no-estimate")
    assert "discretization error: not estimated (--no-estimate)" in text
    assert [r["rel_change_finer"] for r in rows] == ["", ""]


def test_modes_at_a_loaded_reference_say_it_is_not_an_equilibrium(tmp_path, capsys):
    """The cantilever at t = 0 carries its tip force on the unstressed reference: ``modes``
    notes on stderr that the state is not in equilibrium and names ``--about static``;
    without the force the reference is an equilibrium and nothing is noted."""
    assert main(["modes", "cantilever", "--n", "2", "--no-estimate", "--out", str(tmp_path / "a")]) == 0
    err = capsys.readouterr().err
    assert "not in equilibrium under the loads" in err and "--about static" in err and err.count("\n") == 1
    assert main(["modes", "cantilever", "--n", "2", "--no-estimate", "--set", "loads.end.force=[0,0,0]",
                 "--out", str(tmp_path / "b")]) == 0
    assert "equilibrium" not in capsys.readouterr().err
