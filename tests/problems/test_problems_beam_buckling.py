"""Buckling loads and prestressed modes of the Galerkin beam (``buckling_loads``,
``prestressed_modes``, ``liegroup-int buckle``, ``liegroup-int modes --about static``): the
built-in clamped-free column against the exact buckling load of the Simo-Reissner column
and its prestressed first frequency against the axially loaded Euler-Bernoulli cantilever.

The column (``column.toml``): steel, L = 1 m, rectangle b = 10 mm (along d1), h = 5 mm
(along d2), shear factor 1, a dead compressive tip force of 20 N. Linearizing the planar
Simo-Reissner equations about the compressed straight state (n = -P e1 throughout,
Gamma1 = 1 - P cos(theta) / EA, Gamma2 = P sin(theta) / GA) gives
EI theta'' + P (1 + P / GA - P / EA) theta = 0, so with theta(0) = 0, theta'(L) = 0 the
critical load solves P (1 + P / GA - P / EA) = P_E = pi^2 EI / (4 L^2) (Haringx's shearable
column with the extensibility term). For this section the correction is 8.2e-6 relative:
above the tolerance of the first test, so the test checks the model's exact value and sees
the correction.
"""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
import scipy.optimize

from liegroup_int import buckling_loads, prestressed_modes
from liegroup_int.cli import main
from liegroup_int.integrators import modal_analysis
from liegroup_int.scenes import load_scene
from liegroup_int.scenes.beam import problem

E, NU, RHO, B, H, L, LOAD = 2.1e11, 0.3, 7800.0, 0.01, 0.005, 1.0, 20.0
EA, GA, MU = E * B * H, E / (2 * (1 + NU)) * B * H, RHO * B * H
EI1, EI2 = E * B * H**3 / 12, E * H * B**3 / 12  # weak (about d1) and strong axis
T_END = 0.5  # the scene's t_end: the load time of static, modes --about static and buckle


def haringx(p_euler: float) -> float:
    """The root of P (1 + P / GA - P / EA) = p_euler (module docstring)."""
    c = 1.0 / GA - 1.0 / EA
    return (np.sqrt(1.0 + 4.0 * c * p_euler) - 1.0) / (2.0 * c)


def euler(EI: float, k: int = 1) -> float:
    """The k-th Euler load of the clamped-free column, ((2k - 1) pi / 2)^2 EI / L^2."""
    return ((2 * k - 1) * np.pi / 2) ** 2 * EI / L**2


def _column(n_ctrl: int = 21, force: float = LOAD):
    return problem(load_scene("column", {"integrator.backend": "numpy", "space.n_ctrl": n_ctrl,
                                         "loads.end.force": [0.0, 0.0, -force]}))


def test_euler_load_of_the_clamped_free_column():
    """At n_ctrl = 21 the refined lowest factor times 20 N is the Simo-Reissner critical load
    to 1.3e-10 (measured; the secant iteration stops at rtol 1e-7 and the central-difference
    tangents carry ~1e-8 noise), asserted to 1e-6; Euler's pi^2 EI / (4 L^2) lies 8.2e-6
    above it. The linear factor (tangent secant over the first load step) is 3.1e-6 off:
    the prebuckling shortening (P / EA = 5e-6) makes the tangent slightly nonlinear in the
    load; asserted to 1e-5. The second and third factors are the strong plane's first
    (4.0 times the first: EI2 = 4 EI1) and the weak plane's second mode (nearly 9 times),
    from the linearization about the first critical state: extrapolated linearly in the
    load from there, they miss the quadratic term of the formula (c P^2, c = 1 / GA - 1 / EA
    = 1.5e-7 / N, over 160 N and 430 N), measured 1.9e-5 and 2.5e-5 above it; asserted to
    1e-4."""
    res = buckling_loads(_column(), 3, t=T_END)
    assert res.refined and res.singularity < 1e-6
    p_cr = haringx(euler(EI1))
    assert res.load_factors[0] * LOAD == pytest.approx(p_cr, rel=1e-6)
    assert euler(EI1) / p_cr - 1 == pytest.approx(8.2e-6, rel=0.01)
    assert abs(res.load_factors[0] * LOAD / euler(EI1) - 1) > 5e-6
    assert res.linear[0] * LOAD == pytest.approx(p_cr, rel=1e-5)
    assert res.load_factors[1:] * LOAD == pytest.approx([haringx(euler(EI2)), haringx(euler(EI1, 2))], rel=1e-4)


def portal_sway_root() -> float:
    """``k h`` of the fixed-base portal's sway buckling with equal I and h = L:
    tan(k h) = -k h / 6 on (pi / 2, pi) (``portal.toml``)."""
    return scipy.optimize.brentq(lambda x: np.tan(x) + x / 6.0, np.pi / 2 + 1e-9, np.pi - 1e-9)


def test_portal_frame_buckles_out_of_plane_then_sways_in_plane():
    """The built-in portal frame (three members joined rigidly, fixed feet, P = 1 on each
    top corner, EI = 1, h = L = 1, p = 4, n_ctrl = 21 per member): the refined lowest
    factor is the out-of-plane cantilever load pi^2 / 4 (both columns sway alike, the beam
    turns without twisting) and the in-plane sway factor is (k h)^2 with
    tan(k h) = -k h / 6 (Timoshenko & Gere's fixed-base portal), 7.379154; measured
    -1.6e-7 and -3.4e-7 (the axial and shear corrections are below 1e-6, EA = GA = 1e7);
    asserted to 1e-5. The sway mode is the first one whose largest displacement lies in
    the frame's plane (the mode between, 7.0915, is the antisymmetric out-of-plane one, in
    which the beam twists)."""
    res = buckling_loads(problem(load_scene("portal")), 3, t=0.05)
    assert res.refined
    assert res.load_factors[0] == pytest.approx(np.pi**2 / 4, rel=1e-5)
    in_plane = [k for k, v in enumerate(res.vectors) if np.abs(v[0, :, :2]).max() > np.abs(v[0, :, 2]).max()]
    print(f"factors {res.load_factors}, in-plane modes {in_plane}")
    assert in_plane and res.load_factors[in_plane[0]] == pytest.approx(portal_sway_root() ** 2, rel=1e-5)


def test_buckling_load_converges_with_the_mesh():
    """Coarse mesh: n_ctrl = 11 is 2.5e-7 above the exact load (measured), n_ctrl = 21
    within 1e-8 of it (measured -2.0e-9, at the refinement's secant noise): refining brings
    the factor to the formula. The prebuckling state is a pure compression: the path is
    followed in one load step per unit of the load factor (``load_steps`` 1; steps of a
    tenth move the coarse factor by 4e-10 and the fine one by 5e-9, measured)."""
    p_cr = haringx(euler(EI1))
    coarse = buckling_loads(_column(11), 1, t=T_END, load_steps=1).load_factors[0] * LOAD / p_cr - 1
    fine = buckling_loads(_column(21), 1, t=T_END, load_steps=1).load_factors[0] * LOAD / p_cr - 1
    assert 1e-7 < coarse < 1e-6 and abs(fine) < 1e-8


def _det(omega: float, P: float) -> float:
    """Frequency determinant of the Euler-Bernoulli cantilever under a compressive dead tip
    load P (weak plane): EI w'''' + P w'' + mu w_tt = 0, w = A cosh(a x) + B sinh(a x) +
    C cos(b x) + D sin(b x); w(0) = w'(0) = 0, w''(L) = 0, EI w'''(L) + P w'(L) = 0."""
    s = np.sqrt(P**2 + 4 * EI1 * MU * omega**2)
    a, b = np.sqrt((s - P) / (2 * EI1)), np.sqrt((s + P) / (2 * EI1))
    ch, sh, co, si = np.cosh(a * L), np.sinh(a * L), np.cos(b * L), np.sin(b * L)
    return float(np.linalg.det(np.array([
        [1.0, 0.0, 1.0, 0.0], [0.0, a, 0.0, b],
        [a * a * ch, a * a * sh, -b * b * co, -b * b * si],
        [(EI1 * a**3 + P * a) * sh, (EI1 * a**3 + P * a) * ch, (EI1 * b**3 - P * b) * si,
         -(EI1 * b**3 - P * b) * co]])))


def eb_omega(P: float) -> float:
    """The lowest root of :func:`_det` (bracketed on a grid below 1.2 times the unloaded one)."""
    w0 = 1.875104068711961**2 * np.sqrt(EI1 / MU) / L**2
    grid = np.linspace(1e-6, 1.2, 2401) * w0
    d = np.array([_det(w, P) for w in grid])
    k = int(np.flatnonzero(d[:-1] * d[1:] < 0)[0])
    return scipy.optimize.brentq(_det, grid[k], grid[k + 1], args=(P,), xtol=1e-14, rtol=1e-15)


def test_eb_reference_values():
    """The determinant's roots: the unloaded cantilever's 1.8751^2 sqrt(EI / mu) / L^2 and
    zero frequency at the Euler load (the determinant vanishes as omega -> 0 there)."""
    w0 = 1.875104068711961**2 * np.sqrt(EI1 / MU) / L**2
    assert eb_omega(0.0) == pytest.approx(w0, rel=1e-12)
    assert eb_omega(0.999 * euler(EI1)) / w0 < 0.04


def test_prestressed_first_frequency_follows_the_axially_loaded_beam():
    """About the equilibrium under P = 0.3, 0.9, 0.99 of the model's critical load, the
    ratio f(P)^2 / f(0)^2 agrees with the Euler-Bernoulli ratio at the same fraction of its
    own Euler load to 1e-4: the Simo-Reissner beam adds shear and rotary inertia (its f(0)
    is 1.75e-5 below Euler-Bernoulli's, 3.5e-5 in f^2), which mostly cancel in the ratio
    (measured differences 4e-6 to 6e-6 at 0.3, 5e-6 to 2.6e-5 at 0.9 over the quadrature
    rules gauss-spline and gauss-spline-reduced, n_ctrl 21 and 31 and BLAS thread counts).
    At 0.99, f^2 is 1 % of f(0)^2, so the noise of the linearization about the static state
    (central-difference tangents, the static solve's tolerance) weighs 100 times more:
    measured -1.1e-4 to +1.0e-4 over the same variants, asserted to 3e-4. The frequency
    tends to zero like 1 - P / P_cr, with the factor 1.076 (0.9) and 1.085 (0.99) of the
    exact curve: the one-term estimate f^2 = f0^2 (1 - P / P_cr) is 8.5 % low near the
    critical load."""
    p_cr = haringx(euler(EI1))
    f0 = prestressed_modes(_column(force=0.0), 1, t=T_END, load_steps=1).report.modes[0].freq_hz
    w0 = eb_omega(0.0)
    for frac in (0.3, 0.9, 0.99):
        pm = prestressed_modes(_column(force=frac * p_cr), 1, t=T_END, load_steps=2)
        assert pm.static.converged
        ratio = (pm.report.modes[0].freq_hz / f0) ** 2
        eb = (eb_omega(frac * euler(EI1)) / w0) ** 2
        assert ratio == pytest.approx(eb, rel=3e-4 if frac > 0.95 else 1e-4), frac
        if frac > 0.5:
            assert 1.0 < ratio / (1 - frac) < 1.1
    assert ratio < 0.011  # at 0.99 P_cr the first frequency is a tenth of f(0)


def test_prestressed_modes_at_zero_load_are_the_plain_modes():
    """No load: the static solve stays at the reference (its Newton steps are round-off,
    1e-16 m, against the residual's floor of 1.3e-8 N at zero load norm), so the modes about
    it are those of the plain modal analysis up to the central-difference Jacobian's noise
    (measured 5.7e-7 on mode 1, below 2e-9 on the others; asserted to 2e-6)."""
    pb = _column(force=0.0)
    pm = prestressed_modes(pb, 4, t=T_END)
    plain = modal_analysis(pb, 0.0, pb.initial_state(), 4)
    assert np.max(np.abs(pm.static.state.c - pb.initial_state().c)) < 1e-14
    assert [m.freq_hz for m in pm.report.modes] == pytest.approx([m.freq_hz for m in plain.modes], rel=2e-6)


def test_prestressed_modes_refuse_collocation():
    pb = problem(load_scene("column", {"integrator.backend": "numpy", "space.formulation": "primal"}))
    with pytest.raises(ValueError, match='static needs space.formulation = "galerkin"'):
        prestressed_modes(pb, 2)
    with pytest.raises(ValueError, match='static needs space.formulation = "galerkin"'):
        buckling_loads(pb, 2)


# ---------------------------------------------------------------------------- commands

def test_buckle_command(tmp_path, capsys):
    out = tmp_path / "b"
    assert main(["buckle", "column", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "column: 3 lowest critical load factors (lowest refined along the load path;" in text
    s = json.loads((out / "summary.json").read_text())
    crit = s["modes"][0]["critical_loads"]["loads.end.force"]
    assert crit[2] == pytest.approx(-haringx(euler(EI1)), rel=1e-6) and crit[:2] == [0.0, 0.0]
    rows = list(csv.DictReader(open(out / "buckle.csv")))
    assert [r["dominant"] for r in rows] == ["u2", "u1", "u2"]  # weak plane, strong plane, weak plane
    assert f"{float(rows[0]['load_factor']):.8g}" in text
    assert len(list(out.glob("mode_*.vtu"))) == 3 and (out / "modes.pvd").exists()
    assert (out / "buckle.png").stat().st_size > 10000


def test_buckle_refuses_collocation_and_unconfirmed_loads(tmp_path, capsys):
    assert main(["buckle", "column", "--set", "space.formulation=primal", "--out", str(tmp_path / "c")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and 'buckle needs space.formulation = "galerkin" (got "primal")' in err
    assert main(["buckle", "column", "--n", "0"]) == 2
    assert "--n 0" in capsys.readouterr().err
    # the 45-degree bend under its transverse tip force does not buckle: the secant
    # predictions are not confirmed along the load path, exit 3 with the files written.
    # The refinement cycles through max_refine = 20 equilibria on any mesh; n_ctrl = 7
    # (p = 4) runs them in half the time of the scene's 21 (measured 1.0 s and 1.9 s CPU)
    assert main(["buckle", "bend45", "--n", "1", "--set", "space.n_ctrl=7", "--out", str(tmp_path / "b")]) == 3
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "no critical load confirmed along the load path" in err
    assert (tmp_path / "b" / "summary.json").exists()


@pytest.mark.parametrize("command", ["static", "buckle"])
def test_static_commands_refuse_a_rigid_body_scene_by_its_kind(command, tmp_path, capsys):
    """Not a complaint about the backend key the commands set for beams."""
    assert main([command, "heavy_top", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err == f"error: builtin:heavy_top: {command} needs a beam scene (problem = \"beam\"), not 'rigid_body'\n"


def test_modes_of_a_rigid_body_lists_the_files_it_wrote(tmp_path, capsys):
    assert main(["modes", "heavy_top", "--out", str(tmp_path)]) == 0
    assert capsys.readouterr().out.splitlines()[-1] == f"-> {tmp_path} (modes.csv)"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["modes.csv"]


def test_modes_about_static_command(tmp_path, capsys):
    """The column under its 20 N (0.37 of the critical load): the header names the
    equilibrium, the first frequency is the API's (the command runs the compiled kernels,
    the API here NumPy: they differ by the finite-difference Jacobian's noise, measured
    2.2e-7, asserted to 2e-6) and lies below the unloaded one by the
    Euler-Bernoulli ratio (to 1e-4, as above), and the finer mesh (about its own
    equilibrium) moves it by less than 1e-5 (measured 9e-7)."""
    out = tmp_path / "m"
    assert main(["modes", "column", "--about", "static", "--n", "2", "--steps", "2", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "column: 2 lowest modes of the linearization about the static equilibrium (load factor 1, " in text
    assert "(space.n_ctrl = 38)" in text
    rows = list(csv.DictReader(open(out / "modes.csv")))
    f = float(rows[0]["freq_hz"])
    assert f == pytest.approx(prestressed_modes(_column(), 1, t=T_END, load_steps=2).report.modes[0].freq_hz,
                              rel=2e-6)
    f0 = prestressed_modes(_column(force=0.0), 1, t=T_END, load_steps=1).report.modes[0].freq_hz
    ratio = (eb_omega(LOAD / haringx(euler(EI1)) * euler(EI1)) / eb_omega(0.0)) ** 2
    assert (f / f0) ** 2 == pytest.approx(ratio, rel=1e-4)
    assert float(rows[0]["rel_change_finer"]) < 1e-5 and rows[0]["dominant"] == "u2"
    assert len(list(out.glob("mode_*.vtu"))) == 2


def test_modes_about_static_refuses_collocation(tmp_path, capsys):
    assert main(["modes", "column", "--about", "static", "--set", "space.formulation=primal",
                 "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and 'modes --about static needs space.formulation = "galerkin"' in err
    assert main(["modes", "column", "--about", "static", "--steps", "0", "--out", str(tmp_path)]) == 2
    assert "--steps 0" in capsys.readouterr().err


def test_modes_about_static_near_the_buckling_load_pairs_the_finer_mesh(tmp_path, capsys):
    """At 0.99 P_cr the first mode (0.4365 Hz, |lambda| = 1.1e-6 |lambda|max) lies below the
    finer mesh's own near-zero threshold; paired by the coarse mesh's threshold, it moves
    by 3e-5 to 1.4e-4 on the finer mesh (measured over the quadrature rules gauss-spline
    and gauss-spline-reduced and BLAS thread counts: the meshes' critical loads differ by
    1e-9, and the linearization's noise weighs 1 / (1 - P / P_cr) = 100 times more in
    f^2), asserted below 5e-4, half the threshold that flags a mode UNCONVERGED."""
    force = float(0.99 * haringx(euler(EI1)))
    assert main(["modes", "column", "--about", "static", "--n", "1", "--steps", "2",
                 "--set", f"loads.end.force=[0, 0, {-force!r}]", "--out", str(tmp_path)]) == 0
    text = capsys.readouterr().out
    row = next(csv.DictReader(open(tmp_path / "modes.csv")))
    assert float(row["freq_hz"]) == pytest.approx(0.4365, rel=1e-3)
    assert float(row["rel_change_finer"]) < 5e-4 and "UNCONVERGED" not in text


def test_lateral_torsional_buckling_of_a_narrow_cantilever():
    """A narrow cantilever (EI_weak = 100, EI_strong = 1e4, GJ = 80 N m^2, L = 1 m) loaded at
    the tip in its stiff plane buckles sideways and twists (Prandtl 1899): P = 4.0126
    sqrt(EI_weak GJ) / L^2 = 358.90 N with the prebuckling deflection neglected. Along the
    load path the deflection raises it by the factor 1 / sqrt((1 - EI_weak / EI_strong)(1 -
    GJ / EI_strong)) (Trahair, Flexural-torsional buckling of structures, 1993: a first-order
    estimate): 362.16 N; measured 362.62 (+1.3e-3, n_ctrl 11; 21 and 31 agree to 6e-8),
    asserted 3e-3. The refinement follows the path in steps of at most one unit of the load
    factor (``load_steps`` 1: 5 equilibria, 38 Newton iterations); its factor agrees with
    steps of a tenth (109 load steps, 285 Newton iterations) to 2.4e-10 (measured).

    The linear analysis (the secant of the tangent over the first tenth of the load) has
    the sideways-twisting mode at +7.4e-3 of Prandtl's value (measured +7.37e-3, +7.45e-3,
    +7.48e-3 with first steps of 0.01, 0.1, 0.15: the prebuckling deflection, as along the
    path), asserted 1e-2. Its lowest factor there is an in-plane mode (no sideways
    displacement) that moves with the first step (-1.3e-2, -2.4e-4, +5.8e-3 of Prandtl's
    value): it is not the buckling load, and the sideways mode is picked by its shape."""
    over = {"problem": "beam", "t_end": 1.0, "integrator.dt": 1e-4, "geometry.kind": "straight",
            "geometry.length": 1.0, "section.shape": "explicit", "section.EA": 1e8, "section.GA": 4e7,
            "section.EI1": 100.0, "section.EI2": 1e4, "section.GJ": 80.0, "section.rhoA": 1.0,
            "section.rhoI1": 1e-4, "section.rhoI2": 1e-2, "bc.start": "clamped", "bc.end": "free",
            "space.n_ctrl": 11, "integrator.backend": "numpy", "loads.end.force": [0.0, 100.0, 0.0]}
    pb = problem(load_scene("cantilever", over))
    lin = buckling_loads(pb, n=2, refine=False)
    sideways = [k for k in range(lin.linear.size) if np.abs(np.asarray(lin.linear_vectors[k])[0, :, 2]).max() > 0.1]
    res = buckling_loads(pb, n=1, load_steps=1)
    prandtl = 4.0126 * np.sqrt(100.0 * 80.0) / 100.0  # load factor on the 100 N tip force
    assert len(sideways) == 1 and lin.linear[sideways[0]] == pytest.approx(prandtl, rel=1e-2)
    path = prandtl / np.sqrt((1 - 100.0 / 1e4) * (1 - 80.0 / 1e4))
    assert res.refined and res.load_factors[0] == pytest.approx(path, rel=3e-3)


def test_argyris_right_angle_frame_buckles_sideways_at_the_published_load():
    """The built-in ``argyris_frame`` (two 240 mm legs of a 30 x 0.6 mm aluminium strip at a
    right angle, clamped, a dead in-plane force along the first leg at the free end): its
    lowest critical load against Argyris et al.'s 1.088 N (CMAME 17/18, 1979; reproduced
    by Simo & Vu-Quoc 1986 and Nachbagauer & Gerstmayr 2013). Measured 1.087519 N at
    n_ctrl 11 per leg and 1.087519 at 21 (where the refinement stops at the tangents'
    round-off: its last three predictions agree to 1.2e-6, ``accuracy``): 4.4e-4 below, within
    the published digits (1.0875 rounds to 1.088); asserted within 1e-3 (the published
    value's last digit, and section details the sources do not state, such as the shear
    factor). The buckling mode is out of the frame's plane: the in-plane displacements of
    the mode are below 1e-6 of its out-of-plane ones (measured 1e-13)."""
    loads = []
    for n_ctrl in (11, 21):
        pb = problem(load_scene("argyris_frame", {"integrator.backend": "numpy", "space.n_ctrl": n_ctrl}))
        res = buckling_loads(pb, 1, t=0.01)
        assert res.refined
        loads.append(res.load_factors[0])  # the scene's force is 1 N
        mode = res.vectors[0][0]  # the position increments, spatial
        print(f"argyris frame n_ctrl {n_ctrl}: {loads[-1]:.7f} N, {loads[-1] / 1.088 - 1:.2e} from 1.088; "
              f"in-plane share of the mode {np.abs(mode[:, :2]).max() / np.abs(mode[:, 2]).max():.1e}")
        assert np.abs(mode[:, :2]).max() <= 1e-6 * np.abs(mode[:, 2]).max()
        assert res.accuracy <= 1e-5
    assert loads[0] == pytest.approx(1.088, rel=1e-3)
    assert loads[1] == pytest.approx(loads[0], rel=1e-5)


def _pinned_column(n_ctrl: int = 21):
    """The column hinged at its base and on a roller at its top (it slides along z and does
    not twist there), under the same dead 20 N."""
    return problem(load_scene("column", {"integrator.backend": "numpy", "space.n_ctrl": n_ctrl,
                                         "bc.start": "hinged", "bc.end": "roller"}))


def test_euler_load_of_the_pinned_pinned_column():
    """Hinged base, roller top: the critical load solves P (1 + P / GA - P / EA) = pi^2 EI / L^2
    (theta'(0) = theta'(L) = 0 in the module docstring's equation), four times the clamped-free
    one. At n_ctrl = 21 the refined factor is within 1e-6 of it (measured 1.6e-8); the second,
    the strong plane's (EI2 = 4 EI1), extrapolated from the first critical state, within 1e-4
    (measured 3.8e-5, the quadratic term as in the clamped-free test). The prebuckling state
    is a pure compression, so the path is followed in one load step per unit of the load
    factor (``load_steps`` 1: 23 Newton iterations; steps of a tenth give both factors to
    2e-11, measured)."""
    res = buckling_loads(_pinned_column(), 2, t=T_END, load_steps=1)
    p_cr = haringx(np.pi**2 * EI1 / L**2)
    print(f"pinned-pinned: {res.load_factors * LOAD} N against {p_cr}, {haringx(np.pi**2 * EI2 / L**2)}; relative "
          f"{res.load_factors[0] * LOAD / p_cr - 1:.2e}")
    assert res.refined and res.singularity < 1e-6
    assert res.load_factors[0] * LOAD == pytest.approx(p_cr, rel=1e-6)
    assert res.load_factors[1] * LOAD == pytest.approx(haringx(np.pi**2 * EI2 / L**2), rel=1e-4)


def test_roller_is_refused_where_it_does_not_apply(tmp_path, capsys):
    """A roller is a static support: `run` refuses it in one line, collocation and a tilted
    end tangent are refused by name."""
    from liegroup_int.scenes import SceneError

    rc = main(["run", "column", "--set", "bc.start=hinged", "--set", "bc.end=roller", "--out", str(tmp_path / "r")])
    err = capsys.readouterr().err.strip()
    assert rc == 2 and "roller" in err and "\n" not in err and not (tmp_path / "r").exists()
    with pytest.raises(SceneError, match="roller.*galerkin"):
        problem(load_scene("column", {"bc.end": "roller", "space.formulation": "primal"}))
    with pytest.raises(SceneError, match="roller.*coordinate axis"):
        problem(load_scene("column", {"bc.start": "hinged", "bc.end": "roller",
                                      "geometry.direction": [0.0, 0.6, 0.8]}))


def test_pinned_pinned_reactions_balance_the_loads(tmp_path):
    """`static` on the hinged-roller column under its 20 N and a lateral 3 N/m: the two
    supports' forces balance the applied loads to 1e-8 N (the Newton tolerance; the roller
    takes the lateral share only), and by symmetry each takes half the lateral load to 1e-6
    (the compression's P-delta moment is symmetric too)."""
    out = tmp_path / "st"
    assert main(["static", "column", "--set", "bc.start=hinged", "--set", "bc.end=roller",
                 "--set", "loads.distributed_force=[3.0,0.0,0.0]", "--out", str(out)]) == 0
    rec = json.loads((out / "summary.json").read_text())["reactions"]
    start, end = (np.array(rec[k]["force"]) for k in ("start", "end"))
    applied = np.array([3.0 * L, 0.0, -LOAD])
    print(start, end, start + end + applied)
    assert np.all(np.abs(start + end + applied) < 1e-8)
    assert end[2] == 0.0 and start[0] == pytest.approx(end[0], rel=1e-6)


def test_pinned_portal_sways_at_the_classical_load():
    """The portal on pins about z (``bc.start = bc.end = "pinned"``: the feet hold their
    position and turn about the frame's normal only): the sway mode comes first, at
    (k h)^2 with k h tan(k h) = 6 (the beam holds the tops with 6 EI / L, the feet are
    free to turn): 1.8212928. The linear factor (secant over the first load step; the
    prebuckling state is a pure compression) measured -1.9e-6, asserted to 1e-5; the next
    one is the out-of-plane pi^2 / 4 (the pins hold the feet against turning out of the
    plane), measured -1.6e-7."""
    pb = problem(load_scene("portal", {"bc.start": "pinned", "bc.end": "pinned", "integrator.backend": "numpy"}))
    assert [comp for _, comp in pb.pins] and len(pb.pins) == 2
    res = buckling_loads(pb, 2, t=0.05, refine=False)
    kh = scipy.optimize.brentq(lambda x: x * np.tan(x) - 6.0, 1e-6, np.pi / 2 - 1e-9)
    print(f"linear factors {res.linear}, sway formula {kh**2:.8g}")
    assert res.linear[0] == pytest.approx(kh**2, rel=1e-5)
    assert res.linear[1] == pytest.approx(np.pi**2 / 4, rel=1e-5)


def test_pinned_feet_take_the_loads_and_no_couple_about_the_pin():
    """Static equilibrium of the pinned portal under a sideways force of 0.1 on the left
    corner as well (solved to a residual of 1e-11 of the load): the feet's reactions
    balance the applied forces to 4.6e-8 along x and 1.1e-9 along y: round-off of the
    internal forces, EA = 1e7 times positions known to 1e-16 (the same frame on clamped feet:
    6.6e-8; the gap does not grow with the load: 3e-8 without the sideways force, 8e-8
    with 0.001 of it); asserted to 2e-7 absolute. No pin takes a couple about its axis.
    An axis that is not an axis of the end section is refused."""
    from liegroup_int.problems.beam.statics import solve_static

    pb = problem(load_scene("portal", {"bc.start": "pinned", "bc.end": "pinned", "integrator.backend": "numpy",
                                       "point_loads": [{"s": 1 / 3, "force": [0.1, -1.0, 0.0]},
                                                       {"s": 2 / 3, "force": [0.0, -1.0, 0.0]}]}))
    st = solve_static(pb, load_steps=2, t=0.05, tol=1e-11)
    reac = pb.reactions(st.state, 0.05)
    total = sum(f for f, _ in reac.values())
    print(f"reactions {reac}, sum {total}")
    assert np.allclose(total, [-0.1, 2.0, 0.0], rtol=0.0, atol=2e-7)
    for f, c in reac.values():
        assert abs(c[2]) < 1e-12
    with pytest.raises(ValueError, match="bc.pin_axis"):
        problem(load_scene("portal", {"bc.start": "pinned", "bc.pin_axis": [1.0, 1.0, 0.0]}))


def test_pinned_and_roller_ends_refuse_a_run(capsys):
    assert main(["run", "portal", "--set", "bc.start=pinned", "--out", "unused"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "'pinned' is for `liegroup-int static`" in err[0]
