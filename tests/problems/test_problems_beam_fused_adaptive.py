"""Beam plugin: the fused compiled adaptive loop against the generic adaptive loop.

``integrate_adaptive`` hands all attempts between two output times to
the compiled engine (``BeamProblem.compiled_kernels()``, ``backend="numba"``) when no per-step monitor
is given. The compiled loop sums the stage combinations, the error norm and the
Newton-Schulz end step in plain sequential order, the generic loop with NumPy/BLAS.
With the generic loop's summations replaced by the same sequential order
(:func:`sequential_sums`), the two runs are bitwise identical: step sequence, counters,
output times, states, errors. Without it they differ by round-off, which the step-size
controller amplifies (the embedded error estimate is a cancelling difference): the
accepted step sequence then agrees to ~1e-11 relative and the states to ~1e-8 to 1e-6
relative over tens of steps; a borderline accept/reject can flip (measured: step counts
differ by up to 20 % in 5 of 36 scene/method/tolerance cases over 40 nominal steps, all RKMK65).
"""

import math

import numpy as np
import pytest

import liegroup_int.integrators.drivers as drivers
import liegroup_int.integrators.rkmk as rkmk
from liegroup_int.integrators import (IntegrationError, Problem, StepSizeError, Stats, integrate_adaptive,
                                      resolve_method)
from liegroup_int.problems.beam import BeamProblem
from liegroup_int.integrators import stepper_for
from liegroup_int.integrators.engine import CompiledStepper
from liegroup_int.groups.kernels_numba import normalize_rotations as _newton_schulz
from liegroup_int.scenes import load_scene
from liegroup_int.scenes.beam import problem

FIELDS = ("c", "v", "w", "R", "K", "K_s")
BEAM_SCENES = ["pendulum", "cantilever", "arch", "spinning_helix", "flying_spaghetti", "rollup"]


def _fields(y):
    """The state's fields (the Galerkin state has no ``K_s``)."""
    return [f for f in FIELDS if hasattr(y, f)]


def _no_monitor(t, y, stats):
    """Any monitor keeps the driver on its generic loop."""


def _scene(name, formulation="primal"):
    sc = load_scene(name, {"integrator.backend": "numba", "space.formulation": formulation})
    dt = sc.integrator.dt if isinstance(sc.integrator.dt, float) else 1e-5  # rollup: dt = "auto"
    return problem(sc), dt


def _combine_sequential(weights, K, h, total=None):
    """:func:`rkmk.combine` summed in the order of the compiled ``_combine``."""
    n = weights.shape[0]
    if total is None or n == 1:
        return h * (weights[0] * K[0]) if n == 1 else (h * (weights @ K[:n].reshape(n, -1))).reshape(K.shape[1:])
    k0 = K[0]
    acc = weights[1] * (K[1] - k0)
    for l in range(2, n):
        acc = acc + weights[l] * (K[l] - k0)
    return (acc + total * k0) * h


def _error_norm_sequential(err, scale, rtol, atol):
    w = (err / (atol + rtol * scale)).ravel()
    return float(np.sqrt(np.cumsum(w * w)[-1] / w.size))


def _end_step_compiled(y):
    R = np.array(y.R, dtype=float, order="C")
    _newton_schulz(R)
    y.R = R
    return y


@pytest.fixture
def sequential_sums(monkeypatch):
    """The generic loop with the compiled loop's summation order (combine, error norm,
    end step); returns a function that patches a problem's end step."""
    monkeypatch.setattr(rkmk, "combine", _combine_sequential)
    monkeypatch.setattr(drivers, "error_norm", _error_norm_sequential)

    def patch(pb):
        monkeypatch.setattr(pb, "end_step", _end_step_compiled)
        return pb

    return patch


@pytest.fixture
def adaptive_calls(monkeypatch):
    calls = []
    original = CompiledStepper.advance_to

    def counted(self, *args, **kw):
        calls.append(args[2])  # stop
        return original(self, *args, **kw)

    monkeypatch.setattr(CompiledStepper, "advance_to", counted)
    return calls


def _run(pb, tab, t_span, y0, fused, **kw):
    """``((t, y) or the raised error, stats as a dict, observed times)``."""
    ts, stats = [], Stats()
    try:
        t, y, _ = integrate_adaptive(pb, tab, t_span, y0, observer=lambda t, y: ts.append(t),
                                     monitor=None if fused else _no_monitor, stats=stats, **kw)
        res = (t, y)
    except IntegrationError as exc:
        res = exc
    d = stats.as_dict()
    d.pop("wall_time_s")
    return res, d, ts


def _same_counters(da, db):
    """Equal counters; the work of the loads to round-off (compiled stage powers with FMA
    contraction against NumPy dot products)."""
    da, db = dict(da), dict(db)
    qa, qb = da.pop("quadrature"), db.pop("quadrature")
    assert da == db
    # the stage velocities agree to ~1e-11 of their scale; the work sums stage powers of
    # both signs, so its relative agreement is looser: 1e-9 (measured 2e-12)
    assert qa == pytest.approx(qb, rel=1e-9, abs=1e-300, nan_ok=True)


def _assert_bitwise(a, b):
    _same_counters(a[1], b[1])
    assert a[2] == b[2]
    (ta, ya), (tb, yb) = a[0], b[0]
    assert ta == tb
    for f in _fields(ya):
        np.testing.assert_array_equal(getattr(ya, f), getattr(yb, f))


#: Every scene once and every pair twice per formulation: the compiled loop is one function
#: per formulation's kernels (a pair is data to it), the scenes exercise the kernels' branches
#: (loads, supports, joints, spin, follower couples).
SCENE_PAIRS = list(zip(BEAM_SCENES, ["rkmk32", "rkmk45", "rkmk65", "rkmk32", "rkmk45", "rkmk65"]))


@pytest.mark.parametrize("name,method", SCENE_PAIRS)
@pytest.mark.parametrize("formulation", ["primal", "galerkin"])
def test_same_steps_as_the_generic_loop_in_the_same_summation_order(name, method, formulation, sequential_sums,
                                                                    adaptive_calls):
    pb, dt = _scene(name, formulation)
    sequential_sums(pb)
    y0 = pb.initial_state()
    snapshot = y0.copy()
    T = 20 * dt
    for rtol in (1e-5, 1e-8):
        kw = dict(rtol=rtol, atol=1e-3 * rtol, h_max=4 * dt, t_out=[T / 3, T / 2])
        fused = _run(pb, resolve_method(method), (0.0, T), y0, True, **kw)
        assert len(adaptive_calls) == 3
        generic = _run(pb, resolve_method(method), (0.0, T), y0, False, **kw)
        assert len(adaptive_calls) == 3  # the monitor kept the generic loop
        adaptive_calls.clear()
        _assert_bitwise(fused, generic)
        assert fused[1]["steps"] > 3 and len(fused[2]) == 4  # t0 and three stops
    for f in _fields(y0):  # the start state is not modified
        np.testing.assert_array_equal(getattr(y0, f), getattr(snapshot, f))


@pytest.mark.parametrize("name", ["pendulum", "cantilever", "spinning_helix"])
def test_agrees_with_the_plain_generic_loop_to_round_off(name):
    """Without the summation-order patch: same counters here (short span, loose
    tolerance), states equal to round-off amplified by the controller."""
    pb, dt = _scene(name)
    y0 = pb.initial_state()
    T = 20 * dt
    kw = dict(rtol=1e-5, atol=1e-8, h_max=4 * dt, t_out=[T / 2])
    a = _run(pb, resolve_method("rkmk45"), (0.0, T), y0, True, **kw)
    b = _run(pb, resolve_method("rkmk45"), (0.0, T), y0, False, **kw)
    assert a[0][0] == b[0][0] and a[2] == b[2]
    for key in ("steps", "rejected", "rhs_evals"):
        assert a[1][key] == b[1][key]
    assert a[1]["h_max"] == pytest.approx(b[1]["h_max"], rel=1e-6)
    for f in FIELDS:
        scale = 1.0 if f == "R" else np.max(np.abs(getattr(b[0][1], f)))
        assert np.max(np.abs(getattr(a[0][1], f) - getattr(b[0][1], f))) <= 1e-6 * scale


@pytest.mark.parametrize("case", ["max_steps", "resumed max_steps", "underflow", "non-finite", "angle"])
def test_limits_and_rejections_match_the_generic_loop(case, sequential_sums):
    """Same exception, message, time and step, same counters, bitwise same states."""
    kw = {}
    if case in ("max_steps", "resumed max_steps"):
        pb, dt = _scene("cantilever")
        kw = dict(rtol=1e-6, atol=1e-9, max_steps=7, t_out=[3 * dt])
    elif case == "underflow":  # rigid spin, impossible rotation guard: rejected until h underflows
        pb, dt = _scene("spinning_helix")
        kw = dict(rtol=1e-5, atol=1e-8, h0=1e-3, max_increment_angle=1e-20)
    elif case == "non-finite":  # first try far above the stable step: inf/NaN error, fac_min
        pb, dt = _scene("cantilever")
        kw = dict(rtol=1e-5, atol=1e-8, h0=1e-2, max_increment_angle=math.inf)
    else:  # rigid spin, tight rotation guard: rejections by the angle
        pb, dt = _scene("spinning_helix")
        kw = dict(rtol=1e-3, atol=1e-6, h0=1e-3, max_increment_angle=1.5e-4)
    sequential_sums(pb)
    tab = resolve_method("rkmk45")
    got = []
    for fused in (True, False):
        stats = Stats(steps=5) if case == "resumed max_steps" else Stats()
        ts = []
        try:
            t, y, _ = integrate_adaptive(pb, tab, (0.0, 10 * dt), pb.initial_state(), observer=lambda t, y: ts.append(t),
                                         monitor=None if fused else _no_monitor, stats=stats, **kw)
            res = (t, y)
        except IntegrationError as exc:
            res = (type(exc), str(exc), exc.t, exc.step)
        d = stats.as_dict()
        d.pop("wall_time_s")
        got.append((res, d, ts))
    (ra, da, ta), (rb, db, tb) = got
    _same_counters(da, db)
    assert ta == tb
    if case in ("non-finite", "angle"):
        assert da["rejected"] >= 1
        _assert_bitwise(got[0], got[1])
    else:
        assert ra == rb and ra[0] is StepSizeError
        assert ("max_steps=7" in ra[1]) == ("max_steps" in case)
        assert ("underflow" in ra[1]) == (case == "underflow")


def test_the_hook_exists_only_where_it_should():
    pb, _ = _scene("cantilever")
    assert isinstance(stepper_for(pb, resolve_method("rkmk45")), CompiledStepper)
    with pytest.raises(ValueError, match="no embedded pair"):  # a fixed-step method has no adaptive loop
        stepper_for(pb, resolve_method("rkmk4")).advance_to(0.0, pb.initial_state(), 1.0, 0.1, 1e-4, 0.0,
                                                                   1e-6, 1e-9, 1.0, 10, 1.0, ())
    np_pb = BeamProblem(pb.space, pb.constants, pb.bcs, pb.loads, pb.initial, backend="numpy")
    assert stepper_for(np_pb, resolve_method("rkmk45")) is None
    assert Problem.compiled_kernels(None) is None
