"""Beam plugin: the fused compiled fixed-step loop against the generic driver loop.

``integrate_fixed`` hands the steps between output times to
the compiled engine (``BeamProblem.compiled_kernels()``, ``backend="numba"``) when no per-step monitor is
given; with a monitor it runs its generic loop over the same compiled stage kernels.
The two differ only in how the stage combinations and the Newton-Schulz end step are
summed (compiled loops against NumPy/BLAS), i.e. by round-off, so the states agree to
the tolerance of :mod:`test_problems_beam_backends` (1e-11 of the field scale after 5
RKMK4 steps; measured <= 2e-12). Counters, output times and the errors raised must be
identical.
"""

import math

import numpy as np
import pytest

from liegroup_int.integrators import (METHODS, BlowUpError, IntegrationError, Problem, Stats, StepSizeError,
                                      integrate_fixed, resolve_method)
from liegroup_int.problems.beam import BeamProblem
from liegroup_int.integrators import stepper_for
from liegroup_int.problems.beam.kernels.profiles import profile_row, profile_value
from liegroup_int.problems.beam.model import EndLoad, Loads, Profile
from liegroup_int.scenes import load_scene
from liegroup_int.scenes.beam import problem

from test_problems_beam_backends import FIELDS, TOL_STEPS, _increments

BEAM_SCENES = ["pendulum", "cantilever", "arch", "spinning_helix", "flying_spaghetti", "rollup"]
TAB = resolve_method("rkmk4")


def _no_monitor(t, y, stats):
    """Any monitor keeps the driver on its generic loop."""


def _scene(name, backend="numba", formulation="primal"):
    sc = load_scene(name, {"integrator.backend": backend, "space.formulation": formulation})
    dt = sc.integrator.dt if isinstance(sc.integrator.dt, float) else 1e-5  # rollup: dt = "auto"
    return problem(sc), dt


class _Recorder:
    def __init__(self):
        self.t, self.y = [], []

    def __call__(self, t, y):
        self.t.append(t)
        self.y.append(y)


def _run(pb, y0, t_span, dt, fused, t_out=None, max_angle=1.0):
    """``(t, y, stats, recorder)``, or the raised error in place of ``(t, y)``."""
    rec, stats = _Recorder(), Stats()
    try:
        t, y, _ = integrate_fixed(pb, TAB, t_span, y0, dt, observer=rec, t_out=t_out,
                                  monitor=None if fused else _no_monitor, max_increment_angle=max_angle,
                                  stats=stats)
        return (t, y), stats, rec
    except IntegrationError as exc:
        return exc, stats, rec


def _same_stats(a, b, work=True):
    """Equal counters; the work of the loads (stage powers summed in compiled code with
    FMA contraction, against NumPy dot products) to round-off, unless ``work`` is false
    (a run blowing up amplifies that round-off like everything else)."""
    da, db = a.as_dict(), b.as_dict()
    da.pop("wall_time_s"), db.pop("wall_time_s")
    qa, qb = da.pop("quadrature"), db.pop("quadrature")
    assert da == db
    if not work:
        return
    # the stage velocities agree to ~1e-11 of their scale; the work sums stage powers of
    # both signs, so its relative agreement is looser: 1e-9 (measured 2e-12)
    assert qa == pytest.approx(qb, rel=1e-9, abs=1e-300, nan_ok=True)


@pytest.fixture(scope="module", params=[(s, "primal") for s in BEAM_SCENES],
                ids=lambda p: f"{p[0]}-{p[1]}")
def scene(request):
    name, formulation = request.param
    pb, dt = _scene(name, formulation=formulation)
    return f"{name} ({formulation})", pb, dt


def test_the_stepper_exists_only_where_it_should(scene):
    _, pb, _ = scene
    assert stepper_for(pb, TAB) is not None
    np_pb = BeamProblem(pb.space, pb.constants, pb.bcs, pb.loads, pb.initial, backend="numpy",
                        formulation=pb.formulation)
    assert stepper_for(np_pb, TAB) is None


@pytest.mark.parametrize("t0", [0.0, 0.1])  # 0.1 s: every time profile of the scenes is on
def test_fused_steps_agree_with_the_generic_loop(scene, t0, advance_calls):
    name, pb, dt = scene
    y0 = pb.initial_state()
    start = {"rest": y0, "deformed": pb.action(_increments(pb)[0], y0)}
    t_span, t_out = (t0, t0 + 5 * dt), [t0 + 2 * dt, t0 + 2.5 * dt]  # three advance calls, one short step
    res = {}
    for lab, y in start.items():
        snapshot = y.copy()
        for fused in (True, False):
            (t, yend), stats, rec = _run(pb, y, t_span, dt, fused, t_out)
            res[lab, fused] = yend
            if fused:
                fused_out = (t, stats, rec)
            else:
                assert t == fused_out[0]
                _same_stats(fused_out[1], stats)
                assert fused_out[2].t == rec.t and len(rec.t) == 4
                assert stats.steps == 6 and stats.rhs_evals == 6 * TAB.stages
        assert advance_calls == [2, 1, 3]  # the fused runs took the fused path, the others not
        advance_calls.clear()
        for f in FIELDS:  # the start state is not modified
            np.testing.assert_array_equal(getattr(y, f), getattr(snapshot, f))
    for f in FIELDS:
        scale = 1.0 if f == "R" else max(np.max(np.abs(getattr(r, f))) for r in res.values())
        for lab in start:
            err = np.max(np.abs(getattr(res[lab, True], f) - getattr(res[lab, False], f)))
            assert err <= TOL_STEPS * scale, f"{name} from {lab} at t0={t0}: {f} differs by {err:.3e} (scale {scale:.3e})"


def test_kelvin_voigt_damping_in_the_fused_loop():
    """The damped stage rates (strain-rate terms) go through the fused loop too."""
    sc = load_scene("pendulum", {"integrator.backend": "numba", "material.kelvin_voigt": 1e-5,
                                 "space.formulation": "primal"})  # against _scene's primal undamped run
    pb, dt = problem(sc), sc.integrator.dt
    y0 = pb.action(_increments(pb)[0], pb.initial_state())
    res = {fused: _run(pb, y0, (0.0, 5 * dt), dt, fused)[0][1] for fused in (True, False)}
    undamped = integrate_fixed(_scene("pendulum")[0], TAB, (0.0, 5 * dt), y0, dt)[1]
    for f in FIELDS:
        scale = 1.0 if f == "R" else np.max(np.abs(getattr(res[False], f)))
        err = np.max(np.abs(getattr(res[True], f) - getattr(res[False], f)))
        assert err <= TOL_STEPS * scale, f"{f} differs by {err:.3e} (scale {scale:.3e})"
    # and the damping acted: the velocities differ from the undamped run far above round-off
    assert np.max(np.abs(res[True].v - undamped.v)) > 1e-6 * np.max(np.abs(undamped.v))


@pytest.mark.parametrize("method", sorted(METHODS))
def test_every_tableau(method):
    """1 to 9 stages. Verner's 6(5) (weights up to 208 in size) amplifies round-off so
    much that NumPy and the generic numba loop differ by ~1e-10 here: the fused loop must
    agree with the generic one to 1e-11 of the field scale, or to twice that difference."""
    tab = resolve_method(method)
    pb, dt = _scene("arch")  # curved, tip couple switched on
    dt *= 0.25  # RKMK2 is weakly unstable at the scene's step
    np_pb = BeamProblem(pb.space, pb.constants, pb.bcs, pb.loads, pb.initial, backend="numpy")
    y0 = pb.action(_increments(pb)[0], pb.initial_state())
    res = {}
    for label, prob, monitor in (("fused", pb, None), ("generic", pb, _no_monitor), ("numpy", np_pb, None)):
        t, y, stats = integrate_fixed(prob, tab, (0.0, 4 * dt), y0, dt, monitor=monitor)
        assert stats.steps == 4 and stats.rhs_evals == 4 * tab.stages
        res[label] = y
    for f in FIELDS:
        scale = 1.0 if f == "R" else max(np.max(np.abs(getattr(r, f))) for r in res.values())
        err = np.max(np.abs(getattr(res["fused"], f) - getattr(res["generic"], f)))
        backends = np.max(np.abs(getattr(res["numpy"], f) - getattr(res["generic"], f)))
        assert err <= max(TOL_STEPS * scale, 2.0 * backends), f"{method}: {f} differs by {err:.3e} (scale {scale:.3e})"


def test_observed_states_are_independent():
    pb, dt = _scene("cantilever")
    _, _, rec = _run(pb, pb.initial_state(), (0.0, 4 * dt), dt, True, t_out=[dt, 2 * dt, 3 * dt])
    kept = [y.copy() for y in rec.y]
    assert len(rec.y) == 5
    for a, b in zip(rec.y[1:], rec.y[2:]):  # later outputs neither alias nor overwrite earlier ones
        assert not np.shares_memory(a.c, b.c) and not np.shares_memory(a.R, b.R)
    for y, k in zip(rec.y, kept):
        for f in FIELDS:
            np.testing.assert_array_equal(getattr(y, f), getattr(k, f))
    assert not np.array_equal(rec.y[1].v, rec.y[4].v)


@pytest.mark.parametrize("case", ["blow-up", "angle", "angle at the first step"])
def test_errors_match_the_generic_loop(case):
    """Same exception type, time, step number and message; same counters up to it."""
    if case == "angle at the first step":  # rigid spin 2 pi rad/s: 1.571e-4 rad per step
        pb, dt = _scene("spinning_helix")
        T, max_angle, t_out = 1e-2, 1.5e-4, None
    else:  # cantilever far above its stable step; the guard fires first unless disabled
        pb, dt = _scene("cantilever")
        dt, T, t_out = 2e-6, 1e-3, [3e-6, 4e-6]
        max_angle = math.inf if case == "blow-up" else 1.0
    expected = {"blow-up": BlowUpError, "angle": StepSizeError, "angle at the first step": StepSizeError}[case]
    got = {}
    for fused in (True, False):
        exc, stats, rec = _run(pb, pb.initial_state(), (0.0, T), dt, fused, t_out, max_angle)
        assert type(exc) is expected
        got[fused] = (exc.t, exc.step, str(exc), stats, rec.t)
    (t1, s1, m1, st1, o1), (t2, s2, m2, st2, o2) = got[True], got[False]
    assert (t1, s1, m1, o1) == (t2, s2, m2, o2)
    _same_stats(st1, st2, work=case != "blow-up")
    assert st1.rhs_evals == (st1.steps + 1) * TAB.stages and s1 == st1.steps + 1
    if case != "angle at the first step":
        assert st1.steps > 2  # the failure is in a later advance call than the first


def test_generic_kernels_unaffected_by_a_fused_run():
    """The stepper writes its stage loads into a private copy of the constant data."""
    pb, dt = _scene("flying_spaghetti")  # time-varying end loads
    y = pb.initial_state()
    u = pb.zero_increment(y)
    before = pb.increment_rate(2.5, y, u)
    integrate_fixed(pb, TAB, (1.0, 1.0 + 3 * dt), y, dt)
    np.testing.assert_array_equal(pb.increment_rate(2.5, y, u), before)


PROFILES = [
    Profile(),
    Profile("step", t_on=0.1, t_off=0.25),
    Profile("ramp", t_on=0.05, t_off=0.9, ramp=0.3),
    Profile("smooth", t_on=0.0, ramp=0.7),
    Profile("smooth", t_on=0.2, t_off=0.6, ramp=0.25),
    Profile("table", table=((0.0, 0.0), (2.5, 1.0), (5.0, 0.0))),
    Profile("table", table=((0.1, 2.0), (0.3, 2.0), (0.3, -1.0), (0.7, 0.5))),  # a jump at 0.3
]


@pytest.mark.parametrize("prof", PROFILES, ids=lambda p: p.kind)
def test_compiled_profiles_match_python(prof):
    row = profile_row(prof)
    nodes = [x for x in (prof.t_on, prof.t_off, prof.t_on + prof.ramp) if np.isfinite(x)]
    nodes += [float(p[0]) for p in prof.table]
    ts = np.concatenate([np.linspace(-1.0, 6.0, 701), nodes, np.nextafter(nodes, -np.inf),
                         np.nextafter(nodes, np.inf)])
    for t in ts:
        ref, got = prof(float(t)), profile_value(row, float(t))
        if prof.kind == "smooth":  # math.sin against np.sin: equal to an ulp
            assert got == pytest.approx(ref, rel=4e-16, abs=1e-300), t
        else:
            assert got == ref, t


def test_unusual_profiles_fall_back_to_the_generic_loop():
    class Doubled(Profile):
        def __call__(self, t):
            return 2.0 * super().__call__(t)

    unsorted = Profile("table", table=((0.0, 0.0), (1.0, 1.0), (0.5, 0.0)))
    assert profile_row(Doubled("step", t_off=1.0)) is None and profile_row(unsorted) is None
    pb, dt = _scene("cantilever")
    for prof in (Doubled("step", t_off=1.0), unsorted):
        loads = Loads(end=EndLoad(force=(0.0, 0.0, -100.0), force_profile=prof))
        nb = BeamProblem(pb.space, pb.constants, pb.bcs, loads, pb.initial, backend="numba")
        assert stepper_for(nb, TAB) is None
        _, y, stats = integrate_fixed(nb, TAB, (0.0, 3 * dt), nb.initial_state(), dt)
        assert stats.steps == 3 and nb.is_finite(y)


def test_default_hook_and_stats():
    assert Problem.compiled_kernels(None) is None and stepper_for(object(), TAB) is None
    st = Stats()
    st.accept_many(0, np.inf, 0.0)
    assert st.steps == 0 and st.h_min == np.inf and st.h_max == 0.0
    st.accept(0.5)
    st.accept_many(3, 0.25, 0.4)
    assert st.steps == 4 and st.h_min == 0.25 and st.h_max == 0.5
