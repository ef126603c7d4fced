"""Beam plugin: the compiled backend (``backend="numba"``) against the NumPy path.

What "agree" means here. Every comparison is ``max |numba - numpy| <= tol * S`` per field,
with ``S`` the *field scale*: the largest magnitude the field takes over the states this
test visits for the scene (rest, a deformed state with ~1e-2 increments, a state with
rotation increments above 1 rad). It is not the magnitude at each state separately,
because at rest several rate fields are pure round-off: for a stress-free configuration
``EA * (N2 c)`` cancels to ~``eps * EA * |N2| |c|``, i.e. relative noise 1e-10 (straight
beams) to 1e-1 (loads switched off). The NumPy path reproduces itself only to that level:
perturbing ``c`` by 1e-16 relative moves its rest rates exactly as much as switching
backends does (measured while writing this test; see the report of the backend).

Tolerances: 1e-12 of the field scale for ``increment_rate``, ``vector_field`` and
``action``; 1e-11 after 5 RKMK4 steps, because the NumPy path's own reproducibility after
5 steps (same run with ``c`` perturbed by 1e-16 relative) is ~3e-12 on ``v``, with
``|lambda| dt`` near the stability limit for the stiff scenes.
"""

import numpy as np
import pytest

import numba  # noqa: F401  (a core dependency)

from liegroup_int.integrators import integrate_fixed, resolve_method  # noqa: E402
from liegroup_int.problems.beam import BeamProblem  # noqa: E402
from liegroup_int.problems.beam.kernels.collocation import NumbaBeamKernels  # noqa: E402
from liegroup_int.scenes import load_scene  # noqa: E402
from liegroup_int.scenes.beam import problem  # noqa: E402

BEAM_SCENES = ["pendulum", "cantilever", "arch", "spinning_helix", "flying_spaghetti"]
FIELDS = ("c", "v", "w", "R", "K", "K_s")
TOL = 1e-12
TOL_STEPS = 1e-11
TIMES = (0.0, 0.1)  # 0.1 s: every time profile of the built-in scenes is switched on


def _pair(name, formulation="primal"):
    sc = load_scene(name, {"integrator.backend": "numpy", "space.formulation": formulation})
    pb = problem(sc)
    nb = BeamProblem(pb.space, pb.constants, pb.bcs, pb.loads, pb.initial, backend="numba",
                     formulation=formulation)
    return sc, pb, nb


def _respect_supports(pb, u):
    for e in pb.ends:
        if e.fix_position:
            u[[0, 2], e.index] = 0.0
        if e.fix_rotation:
            u[[1, 3], e.index] = 0.0
    return u


def _increments(pb, seed=0):
    """Deformed (~1e-2) and large-rotation (all collocation angles > 1 rad) increments."""
    rng = np.random.default_rng(seed)
    n = pb.n
    small = 1e-2 * rng.standard_normal((4, n, 3))
    small[0] *= 1e-2  # positions: strains ~ 1e-4 * n
    s = np.linspace(0.0, 1.0, n)[:, None]
    d = np.array([0.48, -0.6, 0.64])
    big = np.zeros((4, n, 3))
    big[0] = 1e-4 * rng.standard_normal((n, 3))
    big[1] = (1.3 + 1.0 * s) * d + 0.05 * rng.standard_normal((n, 3))
    big[2:] = 1e-2 * rng.standard_normal((2, n, 3))
    return _respect_supports(pb, small), _respect_supports(pb, big)


def _states(pb):
    y0 = pb.initial_state()
    small, big = _increments(pb)
    ang = np.linalg.norm(pb.N0 @ big[1], axis=1)  # (a clamped end and its neighbour stay below)
    assert np.mean(ang >= 1.0) > 0.9, "large-rotation state must use the closed-form branch"
    zero = pb.zero_increment(y0)
    return [("rest", y0, zero), ("deformed", pb.action(small, y0), small),
            ("large rotation", pb.action(big, y0), big)]


def _assert_close(got, ref, scale, tol, what):
    err = np.max(np.abs(got - ref))
    assert err <= tol * scale, f"{what}: |numba - numpy| = {err:.3e} > {tol:g} * scale {scale:.3e}"


@pytest.fixture(scope="module", params=[(s, "primal") for s in BEAM_SCENES],
                ids=lambda p: f"{p[0]}-{p[1]}")
def scene_pair(request):
    name, formulation = request.param
    return (f"{name} ({formulation})",) + _pair(name, formulation)


def test_increment_rate_agrees(scene_pair):
    name, _, pb, nb = scene_pair
    states = _states(pb)
    ref = {(lab, t): pb.increment_rate(t, y, u) for lab, y, u in states for t in TIMES}
    scale = [max(np.max(np.abs(k[f])) for k in ref.values()) for f in range(4)]
    for lab, y, u in states:
        for t in TIMES:
            got = nb.increment_rate(t, y, u)
            assert got.shape == (4, pb.n, 3)
            for f, fname in enumerate(("eta", "theta", "dv", "dw")):
                _assert_close(got[f], ref[lab, t][f], scale[f], TOL, f"{name} {lab} t={t} {fname}")
    # the plain vector field (u = 0) goes through the same kernel
    for lab, y, _ in states:
        ref_f, got_f = pb.vector_field(0.1, y), nb.vector_field(0.1, y)
        for f in range(4):
            _assert_close(got_f[f], ref_f[f], scale[f], TOL, f"{name} {lab} vector_field {f}")


def test_action_agrees_and_returns_new_state(scene_pair):
    name, _, pb, nb = scene_pair
    y0 = pb.initial_state()
    snapshot = y0.copy()
    for u in _increments(pb):
        ya, yb = pb.action(u, y0), nb.action(u, y0)
        for f in FIELDS:
            a, b = getattr(ya, f), getattr(yb, f)
            scale = 1.0 if f == "R" else max(np.max(np.abs(a)), np.max(np.abs(getattr(y0, f))), 1e-300)
            _assert_close(b, a, scale, TOL, f"{name} action {f}")
            assert not np.shares_memory(b, getattr(y0, f))
        assert nb.rotation_angle(u) == pytest.approx(pb.rotation_angle(u), rel=1e-14)
    # the input state is untouched and earlier results are not overwritten
    first = nb.action(_increments(pb)[0], y0)
    kept = first.copy()
    nb.action(_increments(pb, seed=1)[1], y0)
    for f in FIELDS:
        np.testing.assert_array_equal(getattr(y0, f), getattr(snapshot, f))
        np.testing.assert_array_equal(getattr(first, f), getattr(kept, f))


def test_five_rkmk4_steps_agree(scene_pair):
    name, sc, pb, nb = scene_pair
    tab, dt = resolve_method("rkmk4"), sc.integrator.dt
    y0 = pb.initial_state()
    start = {"rest": y0, "deformed": pb.action(_increments(pb)[0], y0)}
    res = {(lab, b): integrate_fixed(p, tab, (0.0, 5 * dt), y, dt)[1]
           for lab, y in start.items() for b, p in (("numpy", pb), ("numba", nb))}
    for f in FIELDS:
        scale = 1.0 if f == "R" else max(np.max(np.abs(getattr(r, f))) for r in res.values())
        for lab in start:
            _assert_close(getattr(res[lab, "numba"], f), getattr(res[lab, "numpy"], f), scale, TOL_STEPS,
                          f"{name} 5 steps from {lab}: {f}")


def test_dense_and_banded_solves_agree():
    _, pb, _ = _pair("spinning_helix")  # p = 6
    x = np.random.default_rng(3).standard_normal((4, pb.n, 3))
    n = pb.n
    ref = pb.space.solve(x.transpose(1, 0, 2).reshape(n, 12)).reshape(n, 4, 3).transpose(1, 0, 2)
    for solver in ("banded", "dense", "auto"):
        k = NumbaBeamKernels(pb, solver=solver)
        assert k.solver == ("dense" if solver == "dense" else "banded")
        np.testing.assert_allclose(k.solve(x), ref, rtol=0, atol=1e-14 * np.max(np.abs(ref)))


def test_backend_selection():
    _, pb, nb = _pair("cantilever")
    assert pb.backend == "numpy" and pb._nb is None
    assert nb.backend == "numba"
    with pytest.raises(ValueError, match="backend"):
        BeamProblem(pb.space, pb.constants, pb.bcs, pb.loads, pb.initial, backend="fortran")


def test_pickled_problem_keeps_time_varying_loads():
    """Round trip (multiprocessing workers): the end loads are rewritten per stage time."""
    import pickle

    _, pb, nb = _pair("flying_spaghetti")  # triangular load pulse at s = 0
    nb2 = pickle.loads(pickle.dumps(nb))
    y = pb.initial_state()
    u = pb.zero_increment(y)
    # at rest without load the rate is pure round-off (measured 6e-9 in the NumPy backend,
    # which the compiled kernels, with FMA contraction, round differently): the backends
    # agree to 1e-12 of the load's rate plus twice that floor
    floor = np.max(np.abs(pb.increment_rate(6.0, y, u)))
    for t in (1.0, 2.5, 1.0, 6.0):  # revisits a time (per-time cache) and ends with zero load
        np.testing.assert_array_equal(nb2.increment_rate(t, y, u), nb.increment_rate(t, y, u))
        k_np = pb.increment_rate(t, y, u)
        load_scale = max(np.max(np.abs(pb.increment_rate(2.5, y, u)[f])) for f in (2, 3))
        assert np.max(np.abs(nb2.increment_rate(t, y, u) - k_np)) <= TOL * load_scale + 2.0 * floor
