"""Rigid bodies fixed to a beam end (``[[bodies]]``, Galerkin): a tip mass with rotary
inertia against the Euler-Bernoulli frequency equation, a hub spun up by a torque
against its angular momentum balance, the two backends, and the one-line refusals."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq

from liegroup_int.integrators import modal_analysis
from liegroup_int.io import read_history
from liegroup_int.runner import run_scene
from liegroup_int.scenes import KINDS, SceneError, builtin_path, load_scene

# the cantilever scene's steel, with a slender square section t = 5 mm (L / t = 200)
E, RHO, T, L = 2.1e11, 7800.0, 0.005, 1.0
RHO_A, EI = RHO * T**2, E * T**4 / 12


def _frequency_determinant(bl: float, mu: float, eta: float, eps: float = 0.0) -> float:
    """Euler-Bernoulli cantilever (clamped at 0) with a tip body of mass ``M = mu rhoA L`` and
    rotary inertia ``J = eta rhoA L^3`` about its centre, which lies ``e = eps L`` beyond the
    tip on the axis, ``bl = beta L``. The body's centre moves by ``w + e w_x``, so its kinetic
    energy is ``1/2 M (w + e w_x)_t^2 + 1/2 J w_xt^2`` and the Lagrangian's tip conditions are
    ``EI w_xxx + M omega^2 (w + e w_x) = 0`` and ``EI w_xx = J omega^2 w_x + M omega^2 e (w + e
    w_x)`` (with ``e = 0``: ``EI W_xx = J omega^2 W_x``, ``EI W_xxx = -M omega^2 W``). With
    ``W = a (cos - cosh) + b (sin - sinh)`` (clamped end) they have a non-zero solution where
    this vanishes."""
    c, s, ch, sh = np.cos(bl), np.sin(bl), np.cosh(bl), np.sinh(bl)
    W = np.array([c - ch, s - sh])
    W1 = bl * np.array([-s - sh, c - ch])
    W2 = bl**2 * np.array([-c - ch, -s - sh])
    W3 = bl**3 * np.array([s - sh, -c - ch])
    centre = W + eps * W1
    return float(np.linalg.det(np.array([W2 - eta * bl**4 * W1 - mu * eps * bl**4 * centre,
                                         W3 + mu * bl**4 * centre])))


def _beta_l(mu: float, eta: float, eps: float = 0.0) -> float:
    """The first root of :func:`_frequency_determinant`."""
    x = np.linspace(0.05, 3.0, 600)
    d = [_frequency_determinant(v, mu, eta, eps) for v in x]
    k = next(i for i in range(len(x) - 1) if np.sign(d[i]) != np.sign(d[i + 1]))
    return brentq(_frequency_determinant, x[k], x[k + 1], args=(mu, eta, eps), xtol=1e-15)


def test_the_frequency_equation_gives_the_tabulated_roots():
    """No tip body: 1.8751 (clamped-free); a tip mass equal to the beam's: 1.2479 (Blevins,
    Formulas for natural frequency and mode shape, table 8-8)."""
    assert _beta_l(0.0, 0.0) == pytest.approx(1.875104068711961, abs=1e-12)
    assert _beta_l(1.0, 0.0) == pytest.approx(1.2479, abs=1e-4)


def _scene(bodies, **over):
    return load_scene("cantilever", {"section.t": T, "loads.end.force": [0.0, 0.0, 0.0], "space.n_ctrl": 21,
                                     "bodies": bodies, **over})


@pytest.mark.parametrize("mu, eta", [(1.0, 0.0), (1.0, 0.1), (5.0, 0.02)])
def test_tip_body_first_frequency_matches_the_frequency_equation(mu, eta):
    """The first bending frequency with the body at the tip, against Euler-Bernoulli. The
    beam model adds shear and the sections' rotary inertia, which lower the frequency by
    (t / L)^2 effects: measured 6.4e-6 to 8.1e-6 below (1.7e-5 without a body; 4x that at
    t = 10 mm), asserted below and within 3e-5. The mesh (n_ctrl = 21) is converged to 1e-8."""
    sim = KINDS["beam"].build(_scene([{"at": "end", "mass": mu * RHO_A * L, "inertia": [eta * RHO_A * L**3] * 3}]))
    f = modal_analysis(sim.problem, 0.0, sim.y0, 2).modes[0].freq_hz
    ref = _beta_l(mu, eta) ** 2 / (2 * np.pi * L**2) * np.sqrt(EI / RHO_A)
    assert -3e-5 < f / ref - 1.0 < 0.0, (f, ref)


@pytest.mark.parametrize("mu, eta, eps", [(1.0, 0.01, 0.1), (0.5, 0.001, 0.3)])
def test_a_body_beyond_the_tip_matches_the_frequency_equation_with_its_offset(mu, eta, eps):
    """A body whose centre lies ``e = eps L`` beyond the tip on the axis (``offset = [0, 0,
    e]`` along the end section's d3): the first frequency against the Euler-Bernoulli
    equation with the offset in its tip conditions. The beam model's shear and section
    rotary inertia lower it by (t / L)^2 effects, as without an offset (the test above);
    asserted below and within 3e-5. The same body with its inertia moved to the end point by
    parallel axes (no coupling of the end's translation and rotation) is off by more than
    1e-2 (asserted), so the comparison sees the coupling."""
    e, M, J = eps * L, mu * RHO_A * L, eta * RHO_A * L**3
    ref = _beta_l(mu, eta, eps) ** 2 / (2 * np.pi * L**2) * np.sqrt(EI / RHO_A)
    sim = KINDS["beam"].build(_scene([{"at": "end", "mass": M, "inertia": [J] * 3, "offset": [0.0, 0.0, e]}]))
    f = modal_analysis(sim.problem, 0.0, sim.y0, 2).modes[0].freq_hz
    print("offset body", f, ref, f / ref - 1.0)
    assert -3e-5 < f / ref - 1.0 < 0.0, (f, ref)
    moved = KINDS["beam"].build(_scene([{"at": "end", "mass": M, "inertia": [J + M * e**2] * 3}]))
    f_moved = modal_analysis(moved.problem, 0.0, moved.y0, 2).modes[0].freq_hz
    assert abs(f_moved / ref - 1.0) > 1e-2, (f_moved, ref)


def _mid_span_determinant(bl: float, mu: float) -> float:
    """Euler-Bernoulli beam clamped at both ends with a point mass ``M`` at mid-span, its
    symmetric modes: the half ``0 <= x <= l = L / 2`` is clamped at 0 and has zero slope at
    ``l``, where it carries half the mass, ``EI W_xxx = -(M / 2) omega^2 W``; ``bl = beta
    l``, ``mu = M / (2 rhoA l)`` (the shapes and the form of :func:`_frequency_determinant`,
    whose first row is here ``W_x = 0``)."""
    c, s, ch, sh = np.cos(bl), np.sin(bl), np.cosh(bl), np.sinh(bl)
    W = np.array([c - ch, s - sh])
    W1 = bl * np.array([-s - sh, c - ch])
    W3 = bl**3 * np.array([s - sh, -c - ch])
    return float(np.linalg.det(np.array([W1, W3 + mu * bl**4 * W])))


@pytest.mark.parametrize("mass_ratio", [0.0, 0.5, 2.0])
def test_a_mass_at_mid_span_matches_the_frequency_equation(mass_ratio, tmp_path):
    """A body at an interior point (``at = "span@0.5"``: the member split there, its halves
    joined rigidly) of a steel beam clamped at both ends: the first frequency against the
    Euler-Bernoulli equation of :func:`_mid_span_determinant` for M / (rho A L) = 0, 0.5
    and 2 (without a mass its root is the clamped-clamped 4.7300 / 2 per half). The beam
    model's shear and section rotary inertia lower it by (t / L)^2 effects (1.4e-4 at
    t = 5 mm, hence the 2 mm strip here): measured -2.3e-5, -2.2e-5 and -1.7e-5 with
    n_ctrl 41 (21 per half); n_ctrl 61 moves them by at most 7e-6 (the finite-difference
    Jacobian's noise at this stiffness). Asserted below and within 1e-4, against the mass's
    own effect of -34 % and -60 %."""
    t = 0.002  # thinner than the other tests' 5 mm: the clamped-clamped mode's shear correction goes as (t / L)^2
    rho_a, ei = RHO * t**2, E * t**4 / 12
    l, M = L / 2, mass_ratio * rho_a * L
    mu = M / (2 * rho_a * l)
    x = np.linspace(0.5, 2.9, 500)
    d = [_mid_span_determinant(v, mu) for v in x]
    k = next(i for i in range(len(x) - 1) if np.sign(d[i]) != np.sign(d[i + 1]))
    bl = brentq(_mid_span_determinant, x[k], x[k + 1], args=(mu,), xtol=1e-15)
    if mass_ratio == 0.0:
        assert 2 * bl == pytest.approx(4.730040744862704, abs=1e-12)
    ref = bl**2 / (2 * np.pi * l**2) * np.sqrt(ei / rho_a)
    text = (builtin_path("cantilever").read_text().replace("[geometry]", "[[beams]]\nname = \"span\"")
            .replace("direction = [1.0, 0.0, 0.0]", "direction = [1.0, 0.0, 0.0]\nn_ctrl = 41"))
    assert "[[beams]]" in text and "n_ctrl = 41" in text  # the cantilever made a one-member frame
    (tmp_path / "span.toml").write_text(text)
    sc = load_scene(tmp_path / "span.toml", {"section.t": t, "loads.end.force": [0.0, 0.0, 0.0], "bc.end": "clamped",
                                             "bodies": [{"at": "span@0.5", "mass": M}]})
    sim = KINDS["beam"].build(sc)
    f = modal_analysis(sim.problem, 0.0, sim.y0, 2).modes[0].freq_hz
    print("mid-span mass", mass_ratio, f, ref, f / ref - 1.0)
    assert -1e-4 < f / ref - 1.0 < 0.0, (f, ref)


def _payload(backend: str = "numpy"):
    """The rubber pendulum (p = 3, n_ctrl = 8, undamped) free at both ends, under gravity,
    with a payload off its end (offset along d1, d2 and d3) pushed by a force at its centre,
    at a deformed, moving state (the action of a random increment)."""
    sc = load_scene("pendulum", {"space.n_ctrl": 8, "space.degree": 3, "material.kelvin_voigt": 0.0,
                                 "integrator.backend": backend, "bc.start": "free", "loads.gravity": [0.0, 0.0, -9.81],
                                 "bodies": [{"at": "end", "mass": 0.05, "inertia": [1e-5, 2e-5, 3e-5],
                                             "offset": [0.05, 0.02, 0.1], "force": [0.1, 0.2, 0.3]}]})
    sim = KINDS["beam"].build(sc)
    pb, y = sim.problem, sim.y0
    rng = np.random.default_rng(7)
    u = np.concatenate([rng.normal(0.0, s, (1, pb.n, 3)) for s in (1e-3, 0.1, 0.1, 1.0)])
    return pb, pb.action(u, y)


def test_a_body_off_the_end_balances_energy_and_momentum_at_the_rates():
    """At a deformed, moving state of a free beam with a payload off its end, the stage
    rates ``k`` make the time derivatives of the kinetic plus strain energy and of the
    linear momentum (with the body's ``m v . R (W x c)`` and ``m R (W x c)``) equal the power
    of the loads and their resultant (gravity on beam and body, the body's force): central
    differences along the action ``Lambda(+-h k, y)``, Richardson-extrapolated from h = 1e-6 s
    and h / 2 (truncation O(h^4)). The random state is violent (angular accelerations up to
    5e7 rad/s^2, a large strain energy), so the differences carry round-off of 1e-10 to 1e-9
    of the power below h = 1e-6 (the plain central difference converges like h^2 down to
    4e-9 at h = 5e-7). Measured: the energy rate within 1.7e-10 W of the power 0.107 W, the
    momentum rate equal to the resultant to 1e-15; asserted 1e-8 relative."""
    pb, y = _payload()
    k = pb.vector_field(0.0, y)

    def rate(fn, h):
        return (fn(pb.action(h * k, y)) - fn(pb.action(-h * k, y))) / (2 * h)

    def extrapolated(fn, h=1e-6):
        return (4 * rate(fn, h / 2) - rate(fn, h)) / 3

    power = pb.quadrature_rate(0.0, y)
    dE = extrapolated(pb.mechanical_energy)
    dp = extrapolated(lambda s: pb.momentum(s)[0])
    resultant = np.sum(pb.load_vector, axis=0) + np.array([0.1, 0.2, 0.3])
    print("energy rate", dE, "power", power, "momentum rate", dp, "resultant", resultant)
    assert abs(dE - power) <= 1e-8 * abs(power)
    assert np.max(np.abs(dp - resultant)) <= 1e-8 * np.max(np.abs(resultant))


def test_the_backends_agree_with_a_body_off_the_end():
    """Stage rates of the payload (:func:`_payload`) from the numba kernel and the NumPy
    twin, to round-off."""
    (pn, y), (pc, _) = _payload("numpy"), _payload("numba")
    _agree_to_round_off(pn, y, pn.vector_field(0.0, y), pc.vector_field(0.0, y))


def test_an_offset_body_s_weight_and_force_are_balanced_by_the_clamp():
    """Static equilibrium of the cantilever with a body off its end under gravity and a
    force at the body's centre: the clamp's force balances the weights and the force, and
    its couple their moments about the origin (the clamp), the body's acting at its
    deformed centre ``x + R c``. The force's imbalance is the sum of the free rows' residual
    forces (the internal forces sum to zero), so by Cauchy-Schwarz it is at most ``sqrt(n)``
    times the final residual norm: that is asserted. Newton stops at the residual's round-off
    floor (the stiff axial rows), measured 3.8e-9 of the load norm 5.14 N (2e-8 N); the
    imbalance measured 8.3e-10 N. The couple balances to 7e-14 N m; asserted 1e-7 of the
    moment."""
    from liegroup_int.problems.beam import solve_static

    c, m, F = np.array([0.0, 0.05, 0.1]), 0.2, np.array([3.0, -1.0, -2.0])
    sim = KINDS["beam"].build(_scene([{"at": "end", "mass": m, "inertia": [1e-4] * 3, "offset": list(c),
                                       "force": list(F)}], **{"loads.gravity": [0.0, 0.0, -9.81],
                                                             "integrator.backend": "numpy"}))
    pb = sim.problem
    res = solve_static(pb, load_steps=4, tol=1e-12)
    assert res.converged
    y, (b,) = res.state, pb.bodies
    centre = y.c[b.row] + y.R[b.point] @ c
    total = np.sum(pb.load_vector, axis=0) + F  # the weights of beam and body, and the force
    moment = np.sum(np.cross(y.c, pb.load_vector), axis=0) - np.cross(y.c[b.row], b.weight) \
        + np.cross(centre, b.weight + F)
    force, couple = pb.reactions(y)["start"]
    print("force", force + total, "couple", couple + moment, "centre moved by", centre - (np.array([1.0, 0, 0]) + c))
    floor = res.residuals[-1][-1] * res.load_norm  # the final residual norm [N]
    assert np.linalg.norm(force + total) <= np.sqrt(pb.n) * floor, (force + total, floor)
    assert np.max(np.abs(couple + moment)) <= 1e-7 * np.max(np.abs(moment))


def test_a_hub_spun_up_by_a_torque_balances_its_angular_momentum(tmp_path):
    """A beam hinged at its start with a hub (1 kg, 0.05 kg m^2) driven by a couple of 2 N m
    about z: the hinge's reaction passes through the axis, so the angular momentum about it
    is 2 t (closed to 2e-16 relative, measured); after 0.05 s the beam turns nearly rigidly,
    its tip at 1/2 alpha t^2 L with alpha = 2 / (0.05 + rhoA L^3 / 3) (measured within 0.4 %,
    asserted 2 %: the bending wave lags the hub); the energy balance closes."""
    sc = load_scene("cantilever", {"bc.start": "hinged", "loads.end.force": [0.0, 0.0, 0.0],
                                   "loads.start.couple": [0.0, 0.0, 2.0], "t_end": 0.05, "output.every": 0.005,
                                   "integrator.dt": "auto", "output.plots": False,
                                   "bodies": [{"at": "start", "mass": 1.0, "inertia": [0.05, 0.05, 0.05]}],
                                   "output.quantities": ["tip", "angular_momentum", "energy_balance"]})
    res = run_scene(sc, tmp_path)
    assert res.summary["status"] == "ok"
    h = read_history(tmp_path / "history.csv")
    assert np.max(np.abs(h["h_z"] - 2.0 * h["t"])) < 1e-13
    alpha = 2.0 / (0.05 + RHO * 1e-4 * L**3 / 3)  # the scene's 10 mm section
    assert h["tip_y"][-1] == pytest.approx(0.5 * alpha * 0.05**2 * L, rel=0.02)
    assert np.max(np.abs(h["energy_balance"])) < 1e-12


def _agree_to_round_off(np_problem, y, np_rates, nb_rates, factor: float = 5.0):
    """Per field of the rates: the backends agree to 1e-12 of the largest rate, or to
    ``factor`` times the round-off the state's conditioning amplifies, measured as the largest
    change of the NumPy rates when the positions are perturbed by +-1.1e-16 relative (three
    sign patterns): the stiff axial rows amplify round-off by ``E A / (rho A h^2)``, so an
    axial acceleration of 1e-5 carries ~1e-6 of it. Measured: the backends differ by 0.12 to
    0.22 times that floor where it decides (numpy 2.4)."""
    floor = np.zeros(np_rates.shape[0])
    for seed in (3, 4, 5):
        yp = y.copy()
        yp.c = yp.c * (1.0 + 1.1e-16 * np.sign(np.random.default_rng(seed).standard_normal(yp.c.shape)))
        floor = np.maximum(floor, np.max(np.abs(np_problem.vector_field(0.0, yp) - np_rates), axis=(1, 2)))
    err = np.max(np.abs(np_rates - nb_rates), axis=(1, 2))
    tol = np.maximum(1e-12 * np.max(np.abs(np_rates)), factor * floor)
    print("backends:", err, "round-off floor:", floor)
    assert np.all(err <= tol), (err, tol)


def test_the_backends_agree_with_a_tip_body():
    """Stage rates of the tip-mass cantilever under gravity, spinning (the gyroscopic couple
    of the body): the numba kernel against the NumPy twin, to round-off."""
    rates, twins = [], []
    for backend in ("numpy", "numba"):
        sim = KINDS["beam"].build(_scene([{"at": "end", "mass": 0.2, "inertia": [1e-3, 2e-3, 3e-3]}],
                                         **{"integrator.backend": backend, "loads.gravity": [0.0, 0.0, -9.81]}))
        y = sim.y0.copy()
        y.w[:] = np.linspace(0.0, 1.0, y.w.shape[0])[:, None] * np.array([3.0, -2.0, 5.0])
        y.v[:] = np.linspace(0.0, 1.0, y.v.shape[0])[:, None] * np.array([0.1, 0.2, -0.3])
        rates.append(sim.problem.vector_field(0.0, y))
        twins.append((sim.problem, y))
    _agree_to_round_off(*twins[0], rates[0], rates[1])
    assert np.max(np.abs(rates[0][3, -1])) > 1.0  # the end's angular acceleration is not trivial


#: smooth drives of the start (zero acceleration at t = 0): a spin-up of the clamped end about
#: a skew axis, and a speed-up of the hinged end across the beam
DRIVES = {"motion": {"motion.start.kind": "spin_up", "motion.start.rate": 20.0, "motion.start.time": 0.01,
                     "motion.start.axis": [0.0, 0.6, 0.8]},
          "translation": {"bc.start": "hinged", "translation.start.kind": "speed_up", "translation.start.rate": 1.0,
                          "translation.start.time": 0.01, "translation.start.axis": [0.0, 1.0, 0.0]}}


@pytest.mark.parametrize("drive", sorted(DRIVES))
def test_a_body_off_a_driven_end_closes_the_energy_balance(drive):
    """A body off the driven start (0.2 kg, offset along d1, d2 and d3, a force on it, under
    gravity): the support's reaction includes the body's coupling force on the prescribed
    rows, so the work of the drive (reaction times prescribed velocity, integrated by the
    engine) closes the energy balance over 0.01 s (RKMK4, h = 1e-6): measured 2.9e-15 J
    (spin-up, 0.67 J of work) and 9.2e-15 J (speed-up, 0.17 J); asserted 1e-12 J. Without the
    coupling force in the compiled reaction the balance misses by 0.023 J and 0.032 J. The
    NumPy twin's power equals the compiled one to 1e-12 relative at the final state."""
    from liegroup_int import integrate

    over = {"loads.gravity": [0.0, 0.0, -9.81], "space.n_ctrl": 12, **DRIVES[drive]}
    body = [{"at": "start", "mass": 0.2, "inertia": [1e-4, 2e-4, 3e-4], "offset": [0.03, 0.02, -0.05],
             "force": [0.1, 0.0, 0.0]}]
    pc, pn = (KINDS["beam"].build(_scene(body, **{"integrator.backend": b, **over})).problem
              for b in ("numba", "numpy"))
    y0 = pc.initial_state()
    res = integrate(pc, y0, (0.0, 0.01), dt=1e-6)
    defect = pc.mechanical_energy(res.y_final) - pc.mechanical_energy(y0) - res.stats.quadrature
    print(drive, "energy defect", defect, "work", res.stats.quadrature)
    assert abs(defect) <= 1e-12 and res.stats.quadrature > 0.1
    pc.increment_rate(0.01, res.y_final, np.zeros((4, pc.n, 3)))
    assert float(pc._nb._pw[0]) == pytest.approx(pn.quadrature_rate(0.01, res.y_final), rel=1e-12)


@pytest.mark.parametrize("bodies, over, match", [
    ([], {"output.quantities": ["tip", "bodies"]}, "'bodies' needs \\[\\[bodies\\]\\] entries"),
    ([{"at": "end", "mass": -1.0}], {}, "key 'mass'"),
    ([{"at": "end", "mass": 1.0}, {"at": "end", "mass": 2.0}], {}, "two bodies at the end"),
    ([{"at": "end", "mass": 1.0}], {"space.formulation": "primal"}, "key 'bodies': end bodies need"),
    ([{"at": "beam@0.5", "mass": 1.0}], {}, "key 'bodies': bodies at members' ends or interior points need the "
     "frame's members in \\[\\[beams\\]\\]"),
])
def test_body_refusals_are_one_line(bodies, over, match):
    with pytest.raises(SceneError, match=match) as exc:
        KINDS["beam"].build(_scene(bodies, **over))
    assert "\n" not in str(exc.value)


@pytest.mark.parametrize("at, match", [("post@1", "'post@1': expected \"<member>@<fraction>\" with a fraction"),
                                       ("arm@0.5", "no \\[\\[beams\\]\\] entry named 'arm'"),
                                       ("post@-0.2", "strictly between 0 and 1")])
def test_bad_interior_body_places_are_one_line(at, match):
    with pytest.raises(SceneError, match=rf"bodies\[0\]: key 'at': .*{match}") as exc:
        KINDS["beam"].build(load_scene("t_frame", {"bodies": [{"at": at, "mass": 0.5}]}))
    assert "\n" not in str(exc.value)


def _t_frame_modes(at: str, n: int = 4):
    sim = KINDS["beam"].build(load_scene("t_frame", {"bodies": [{"at": at, "mass": 0.5, "inertia": [2e-3] * 3}]}))
    return sim, np.array([m.freq_hz for m in modal_analysis(sim.problem, 0.0, sim.y0, n).modes])


def test_a_body_at_a_frame_joint():
    """A body at the T-frame's joint, named by any of the joined member ends: the post's
    end or an arm's start give the same frequencies (a rigid joint, an isotropic inertia;
    measured equal to 4e-11; asserted 1e-7, the finite differences' noise), lower than
    without the body; the momentum weights carry its mass; both backends agree."""
    sim, f_post = _t_frame_modes("post.end")
    _, f_arm = _t_frame_modes("left.start")
    bare = KINDS["beam"].build(load_scene("t_frame"))
    f_bare = np.array([m.freq_hz for m in modal_analysis(bare.problem, 0.0, bare.y0, 4).modes])
    assert np.allclose(f_post, f_arm, rtol=1e-7) and np.all(f_post < f_bare)
    assert np.sum(sim.problem.mass_weights) == pytest.approx(np.sum(bare.problem.mass_weights) + 0.5, rel=1e-12)
    rates, twins = [], []
    for backend in ("numpy", "numba"):
        s = KINDS["beam"].build(load_scene("t_frame", {"integrator.backend": backend,
                                                       "bodies": [{"at": "post.end", "mass": 0.5,
                                                                   "inertia": [1e-3, 2e-3, 3e-3]}]}))
        y = s.y0.copy()
        y.w[:] = np.linspace(0.0, 1.0, y.w.shape[0])[:, None] * np.array([2.0, -1.0, 3.0])
        rates.append(s.problem.vector_field(0.0, y))
        twins.append((s.problem, y))
    _agree_to_round_off(*twins[0], rates[0], rates[1])
    with pytest.raises(SceneError, match="key 'at' = 'mast.end': no \\[\\[beams\\]\\] entry named 'mast'"):
        KINDS["beam"].build(load_scene("t_frame", {"bodies": [{"at": "mast.end", "mass": 1.0}]}))


#: two collinear members along x, the first clamped at x = 0, joined at x = 1 m by a hinge
#: about z; a body off the second member's end (offset along d1, d2 and d3)
HINGED_ARM = {"beams": [{"name": "a", "kind": "straight", "length": 1.0, "direction": [1, 0, 0]},
                        {"name": "b", "kind": "straight", "length": 1.0, "direction": [1, 0, 0],
                         "origin": [1, 0, 0]}],
              "loads.end.force": [0.0, 0.0, 0.0], "loads.end.couple": [0.0, 0.0, 0.0]}


def _hinged_arm(backend: str, body: dict, stiffness: float, **over):
    joint = {"ends": ["a.end", "b.start"], "kind": "hinge", "axis": [0.0, 0.0, 1.0], "stiffness": stiffness}
    sc = load_scene("t_frame", {**HINGED_ARM, "joints": [joint], "integrator.backend": backend,
                                "bodies": [{"at": "b.end", **body}], **over})
    return KINDS["beam"].build(sc).problem


def test_a_body_off_the_end_of_a_hinged_member_balances_energy_and_keeps_the_hinge():
    """A hinged arm (spring 5 N m/rad) with a payload off its end (0.3 kg, offset along d1, d2
    and d3) under gravity and a 20 N push across the hinge's axis at the payload's centre,
    after 0.05 s of motion (RKMK4, h = 2e-5, the hinge turned and both members bent): the
    hinges' constraint rows follow the state, so the coupled bodies' responses are
    projected on them at every stage. The stage rates then keep the hinge (its rows on the
    angular accelerations hold to 1e-9 of them; asserted), the time derivative of the
    kinetic, strain and spring energy equals the power of the loads (central differences
    along the action, Richardson-extrapolated: 3e-11 relative measured, asserted 1e-8;
    responses left unprojected give 3e-5 and break the hinge's rows at order one) and the
    two backends agree to round-off."""
    from liegroup_int import integrate

    body = {"mass": 0.3, "inertia": [1e-3, 2e-3, 3e-3], "offset": [0.05, 0.1, 0.08], "force": [0.0, 20.0, 20.0]}
    over = {"space.n_ctrl": 8, "loads.gravity": [0.0, 0.0, -9.81]}
    pc, pn = _hinged_arm("numba", body, 5.0, **over), _hinged_arm("numpy", body, 5.0, **over)
    y = integrate(pc, pc.initial_state(), (0.0, 0.05), dt=2e-5).y_final
    k = pn.vector_field(0.05, y)
    _agree_to_round_off(pn, y, k, pc.vector_field(0.05, y))
    (h,) = pn.hinges
    assert abs(pn._hinge_springs(y)[0][0]) > 1e-3  # the hinge has turned
    (Ca, Cb, g), = pn._hinge_rows(y, k, "rotation")
    assert np.max(np.abs(Ca @ k[3, h.a] + Cb @ k[3, h.b] - g)) <= 1e-9 * np.max(np.abs(k[3]))

    def rate(fn, step):
        return (fn(pn.action(step * k, y)) - fn(pn.action(-step * k, y))) / (2 * step)

    power = pn.quadrature_rate(0.05, y)
    dE = (4 * rate(pn.mechanical_energy, 5e-7) - rate(pn.mechanical_energy, 1e-6)) / 3
    print("energy rate", dE, "power", power)
    assert abs(dE - power) <= 1e-8 * abs(power)


def test_a_stiff_hinged_arm_with_an_offset_body_swings_at_the_rigid_frequency():
    """The hinged arm made nearly rigid (EI = GJ = 1e8, EA = GA = 1e10) with a spring of
    100 N m/rad and a 0.5 kg body off its end: the lowest mode is the swing about the hinge,
    ``omega^2 = k / I`` with ``I`` the member's ``rhoA L^3 / 3 + rhoI L`` plus the body's
    ``m r^2 + J_zz`` about the axis (``r`` its centre's distance from the axis, ``R0 c``
    its offset turned into space). Measured 3.9e-6 below (the members' flexibility, 1.4e-3
    at EI = 1e5 and falling tenfold per decade, and the finite differences' noise); asserted
    1e-5. Responses left unprojected on the hinge give 1.2e-4 at EI = 1e7."""
    k, m, J, c = 100.0, 0.5, np.array([1e-2, 2e-2, 3e-2]), np.array([0.05, 0.1, 0.08])
    stiff = {f"section.{key}": 1e8 for key in ("EI1", "EI2", "GJ")} | {"section.EA": 1e10, "section.GA": 1e10}
    pb = _hinged_arm("numba", {"mass": m, "inertia": list(J), "offset": list(c)}, k, **stiff, **{"space.n_ctrl": 6})
    (b,) = pb.bodies
    R0 = pb.gs.R0[b.point]
    r = np.array([1.0, 0.0]) + (R0 @ c)[:2]
    inertia = 1.0 / 3.0 + 0.01 + m * (r @ r) + (R0 @ np.diag(J) @ R0.T)[2, 2]  # the scene's rhoA 1, rhoI 0.01
    f = modal_analysis(pb, 0.0, pb.initial_state(), 1).modes[0].freq_hz
    print("swing", f, "rigid", np.sqrt(k / inertia) / (2 * np.pi))
    assert f / (np.sqrt(k / inertia) / (2 * np.pi)) - 1.0 == pytest.approx(0.0, abs=1e-5)


def test_a_hinged_arm_s_spring_balances_the_moment_of_a_force_on_its_offset_body():
    """Static equilibrium of the hinged arm (spring 5 N m/rad) with a 3 N force across the
    hinge's axis on a body off the end (offset along d1, d2 and d3): the force twists and
    bends both members, so the hinge's axis tilts, and the spring's ``k phi`` (0.53 rad)
    equals the force's moment about the deformed axis through the joint, the force acting
    at the body's deformed centre ``x + R c``. Measured to 4e-16 N m of 2.6 N m; asserted
    1e-9 of it (Newton stops at 1e-10 of the load, and the joint's force passes through the
    axis)."""
    from liegroup_int.problems.beam import solve_static

    F, c = np.array([0.0, 3.0, 0.0]), np.array([0.05, 0.1, 0.08])
    pb = _hinged_arm("numpy", {"mass": 0.3, "inertia": [1e-3, 2e-3, 3e-3], "offset": list(c), "force": list(F)}, 5.0,
                     **{"space.n_ctrl": 8})
    res = solve_static(pb, load_steps=4, tol=1e-12)
    assert res.converged
    y, (b,), (h,) = res.state, pb.bodies, pb.hinges
    centre = y.c[b.row] + y.R[b.point] @ c
    axis = y.R[h.point_b] @ pb.gs.R0[h.point_b].T @ np.array([0.0, 0.0, 1.0])
    moment = axis @ np.cross(centre - y.c[h.b], F)
    phi = pb._hinge_springs(y)[0][0]
    print("k phi", 5.0 * phi, "moment", moment)
    assert phi > 0.3 and abs(5.0 * phi - moment) <= 1e-9 * abs(moment)


def test_a_driven_hub_s_reaction_carries_the_body_s_inertia():
    """A body at the driven start (spin-up about a skew axis) moves with the prescribed rows,
    so the beam's motion is the same with or without it, and the support's couple differs
    by the body's inertial couple ``J alpha + omega x J omega`` (spatial, ``alpha`` the
    prescribed angular acceleration): measured equal to round-off, asserted 1e-10 of it."""
    from liegroup_int import integrate

    J, t = np.array([1e-4, 2e-4, 3e-4]), 0.005
    out = []
    for bodies in ([], [{"at": "start", "mass": 0.2, "inertia": list(J)}]):
        pb = KINDS["beam"].build(_scene(bodies, **{"space.n_ctrl": 12, **DRIVES["motion"]})).problem
        y = integrate(pb, pb.initial_state(), (0.0, t), dt=1e-6).y_final
        out.append((y, pb.reactions(y, t)["start"][1]))
    (y0, c0), (y1, c1) = out
    assert np.array_equal(y0.w, y1.w)
    alpha = 20.0 / 0.01 * (1.0 - np.cos(2.0 * np.pi * t / 0.01)) * np.array([0.0, 0.6, 0.8])  # spin-up
    Js, omega = y1.R[0] @ np.diag(J) @ y1.R[0].T, y1.R[0] @ y1.w[0]
    expected = Js @ alpha + np.cross(omega, Js @ omega)
    assert np.max(np.abs(c1 - c0 - expected)) <= 1e-10 * np.max(np.abs(expected))
