"""Beam plugin: kinematics against finite differences, invariance, rest, conservation."""

import numpy as np
import pytest

from liegroup_int import SO3
from liegroup_int.integrators import integrate_fixed, resolve_method
from liegroup_int.integrators.spectrum import eigenvalues
from liegroup_int.problems.beam import BeamState, curvature_update
from liegroup_int.scenes import SceneError, builtin_names, load_scene
from liegroup_int.scenes.beam import problem

#: every built-in beam scene, from the registry (a new scene is covered without editing this file)
BEAM_SCENES = [n for n in builtin_names() if load_scene(n).kind == "beam"]


# ---------------------------------------------------------------- curvature update
def _field_R(s):
    """An analytic rotation field R(s) = exp(phi(s))."""
    phi = np.stack([0.7 * np.sin(s), 0.3 * s**2, 0.5 * np.cos(2 * s) - 0.2], axis=-1)
    return SO3.exp(phi)


def _material_curvature(Rfun, s, h=1e-5):
    """K = vee(R^T R_s) by central differences (4th order)."""
    Rs = (-Rfun(s + 2 * h) + 8 * Rfun(s + h) - 8 * Rfun(s - h) + Rfun(s - 2 * h)) / (12 * h)
    return SO3.vee(np.swapaxes(Rfun(s), -1, -2) @ Rs)


@pytest.mark.parametrize("amplitude", [1e-3, 0.3, 2.5])  # Taylor branch, mixed, closed form
def test_curvature_update_matches_finite_differences(amplitude):
    def theta(s):
        return amplitude * np.stack([np.cos(s), np.sin(1.3 * s), 0.5 + 0.2 * s], axis=-1) / 1.2

    def Rnew(s):
        return SO3.exp(theta(s)) @ _field_R(s)

    s = np.linspace(0.1, 1.2, 7)
    h = 1e-4
    th = theta(s)
    th_s = (theta(s + h) - theta(s - h)) / (2 * h)
    th_ss = (theta(s + h) - 2 * th + theta(s - h)) / h**2
    K = _material_curvature(_field_R, s)
    K_s = (_material_curvature(_field_R, s + h) - _material_curvature(_field_R, s - h)) / (2 * h)
    K_new, K_s_new = curvature_update(_field_R(s), K, K_s, th, th_s, th_ss)
    K_fd = _material_curvature(Rnew, s)
    K_s_fd = (_material_curvature(Rnew, s + h) - _material_curvature(Rnew, s - h)) / (2 * h)
    # FD truncation and round-off: ~1e-8 for K (4th-order, h=1e-5), ~1e-6 for K_s
    # (second differences of theta with h=1e-4 carry ~1e-8/h^2 round-off)
    np.testing.assert_allclose(K_new, K_fd, atol=1e-8)
    np.testing.assert_allclose(K_s_new, K_s_fd, atol=5e-6)


# ---------------------------------------------------------------- rest and invariance
def test_straight_beam_at_rest_stays_at_rest():
    sc = load_scene("cantilever", {"loads.end.force": [0.0, 0.0, 0.0]})
    pb = problem(sc)
    y0 = pb.initial_state()
    _, y, _ = integrate_fixed(pb, resolve_method("rkmk4"), (0.0, 1e-4), y0, 1e-6)
    # round-off of the axial strain (eps) times EA / (rho A) = 2.7e7 m^2/s^2 accelerates
    # the control points by ~1e-8 m/s^2 per unit length: displacements of a few 1e-14 m
    # after 1e-4 s (measured 1.4e-14); 1e-13 m = 450 eps L
    assert np.abs(y.c - y0.c).max() < 1e-13
    assert np.abs(y.v).max() < 1e-9
    assert np.abs(y.R - y0.R).max() < 1e-14


def _rigidly_moved(pb, Q, shift):
    """The reference state rotated by Q about the origin and shifted."""
    y0 = pb.initial_state()
    return BeamState(c=y0.c @ Q.T + shift, v=np.zeros_like(y0.v), w=np.zeros_like(y0.w),
                     R=Q @ y0.R, K=y0.K.copy(), K_s=y0.K_s.copy())


@pytest.mark.parametrize("name", ["cantilever", "arch", "spinning_helix", "flying_spaghetti"])
def test_rigid_motion_produces_no_strain(name):
    overrides = {"loads.distributed_force": [0.0, 0.0, 0.0], "loads.end.couple": [0.0, 0.0, 0.0],
                 "loads.end.force": [0.0, 0.0, 0.0], "loads.start.force": [0.0, 0.0, 0.0],
                 "loads.start.couple": [0.0, 0.0, 0.0], "initial.omega": [0.0, 0.0, 0.0],
                 "bc.start": "free", "bc.end": "free", "space.formulation": "primal"}  # collocation's strains
    pb = problem(load_scene(name, overrides))
    Q = SO3.exp(np.array([0.4, -1.1, 0.7]))
    y = _rigidly_moved(pb, Q, np.array([0.3, -0.2, 0.5]))
    rates = pb._rates(0.0, y, np.zeros((pb.n, 3)))
    # A rigid motion leaves only the round-off of the strains, about
    # eps * (|N1| + |N2|) * |c| (derivative matrices amplify the round-off of c), times
    # the acceleration per unit strain: C_N / mu (translation) and max(C_N, C_M) / J
    # (rotation; the shear couple c_s x n dominates). Allow 100x that bound; a wrong
    # strain measure gives strains of order 1, i.e. ~1e12 times more.
    strain_eps = np.finfo(float).eps * (np.abs(pb.N1).sum(1).max() + np.abs(pb.N2).sum(1).max()) * np.abs(y.c).max()
    assert np.abs(rates[:, 2]).max() < 100 * strain_eps * pb.CN.max() / pb.mu
    assert np.abs(rates[:, 3]).max() < 100 * strain_eps * max(pb.CN.max(), pb.CM.max()) / pb.Jm.min()


def test_free_beam_translates_rigidly():
    pb = problem(load_scene("flying_spaghetti", {"loads.start.force": [0.0, 0.0, 0.0],
                                                 "loads.start.couple": [0.0, 0.0, 0.0],
                                                 "initial.velocity": [1.0, -2.0, 0.5]}))
    y0 = pb.initial_state()
    _, y, _ = integrate_fixed(pb, resolve_method("rkmk4"), (0.0, 0.2), y0, 4e-4)
    np.testing.assert_allclose(y.c, y0.c + 0.2 * np.array([1.0, -2.0, 0.5]), atol=1e-12)
    assert np.abs(y.R - y0.R).max() < 1e-12


# ---------------------------------------------------------------- linear stability
@pytest.mark.parametrize("name, expected", [("pendulum", 3.1e4), ("cantilever", 2.4e6)])
def test_spectrum_at_rest_is_imaginary(name, expected):
    # primal collocation: the spectrum docs/theory.md section 4 records and the collocation
    # Neumann-end sign (the Galerkin spectrum has its own test in test_problems_beam_galerkin.py)
    pb = problem(load_scene(name, {"space.formulation": "primal"}))
    ev = eigenvalues(pb, 0.0, pb.initial_state())
    lam = np.abs(ev).max()
    print(f"{name}: |lambda|max = {lam:.4e} 1/s, max |Re| / |lambda|max = {np.abs(ev.real).max() / lam:.2e}")
    # independent bound: the spectrum holds the shear-rotation cut-off frequency
    # sqrt(G A k / rho I) of the Timoshenko beam, which no mesh removes (1.56e4 and 1.16e6 1/s)
    c = pb.constants
    assert lam >= np.sqrt(c.CN[0] / c.Jm[0])
    # regression pin, not derived: the values docs/theory.md section 4 records for p=4,
    # n_ctrl=31 (~3.1e4 pendulum, ~2.4e6 cantilever, about twice the cut-off), +-2 %
    assert abs(lam / expected - 1) < 0.02
    # purely imaginary up to the finite-difference error of the Jacobian (~1e-6 relative);
    # for the hinged pendulum this is also the check of the s = 0 Neumann sign: written
    # (m_c - m) instead of (m_c + m) it gets a real positive eigenvalue
    # (docs/theory.md section 6, "Neumann ends")
    assert np.abs(ev.real).max() < 1e-6 * lam


# ---------------------------------------------------------------- energy
def test_pendulum_energy_error_converges_in_space():
    errs, ns = [], [16, 31, 61]
    for n in ns:
        pb = problem(load_scene("pendulum", {"space.n_ctrl": n}))
        y0 = pb.initial_state()
        dt = 0.5 / 3.1e4 * (31 / n) ** 1.5
        _, y, _ = integrate_fixed(pb, resolve_method("rkmk4"), (0.0, 0.02), y0, dt)
        parts = pb.energy_parts(y)
        errs.append(abs(pb.energy(y) - pb.energy(y0)) / parts["kinetic"])
    slope = -np.polyfit(np.log(ns), np.log(errs), 1)[0]
    print(f"pendulum energy error / kinetic at t=0.02 s for n_ctrl={ns}: {errs}, rate {slope:.2f}")
    # collocation does not conserve energy exactly: the error is a space discretization
    # error that falls with n_ctrl (measured rate ~2.8); 1.5 leaves margin
    assert slope > 1.5 and errs[-1] < 1e-3


# ---------------------------------------------------------------- scene validation
@pytest.mark.parametrize("overrides, match", [
    ({"space.n_ctrl": 3}, "space.n_ctrl"),
    ({"space.degree": 6, "space.n_ctrl": 5}, "space.n_ctrl"),
    ({"material.E": -1.0}, "material.E"),
    ({"section.d": 0.0}, "section.d"),
    ({"bc.start": "glued"}, "bc.start"),
    ({"loads.end.couple": [1.0, 0.0]}, "loads.end.couple"),
    ({"bc.end": "clamped", "loads.end.force": [0.0, 0.0, 1.0]}, "clamped"),
])
def test_bad_beam_scene_values(overrides, match):
    with pytest.raises(SceneError, match=match):
        load_scene("pendulum", overrides)


@pytest.mark.parametrize("name", BEAM_SCENES)
def test_builtin_scenes_build(name):
    pb = problem(load_scene(name))
    y0 = pb.initial_state()
    assert pb.orth_error(y0) < 1e-14
    assert np.all(np.isfinite(pb.increment_rate(0.0, y0, pb.zero_increment(y0))))
