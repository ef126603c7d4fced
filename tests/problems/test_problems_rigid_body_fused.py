"""Rigid body: the fused compiled fixed-step loop against the generic driver loop.

``integrate_fixed`` hands the steps between output times to
the compiled engine (``RigidBodyProblem.compiled_kernels()``, numba) when no per-step monitor is given;
with a monitor it runs its generic NumPy loop. Both evaluate the same formulas; they
differ only in the order of a few 3-term sums (``einsum``/BLAS against explicit loops),
i.e. by round-off: measured <= 2.3e-14 relative (max-norm over the state) in the runs of
:func:`test_every_tableau_agrees_with_the_generic_loop` (143 steps; the heavy top amplifies
round-off, ~1e-13 after 10^4 steps), hence ``TOL = 1e-13``.
Counters, output times and the errors raised must be identical.
"""

import math

import numpy as np
import pytest

from liegroup_int import SO3
from liegroup_int.integrators import (
    METHODS,
    BlowUpError,
    IntegrationError,
    Stats,
    StepSizeError,
    integrate_fixed,
    resolve_method,
)
from liegroup_int.integrators.methods import is_commutator_free
from liegroup_int.integrators.problem import GroupProblem
from liegroup_int.problems import RigidBody, RigidBodyProblem
from liegroup_int.integrators import stepper_for
from liegroup_int.integrators.engine import CompiledStepper

TOL = 1e-13
FREE = RigidBody(inertia=(1.0, 2.0, 2.5))
TOP = RigidBody(inertia=(1.0, 0.8, 0.5), mass=1.0, com=(0.0, 0.1, 0.5), gravity=9.81)
BODIES = {"free": FREE, "heavy": TOP}
TAB = resolve_method("rkmk4")


def _no_monitor(t, y, stats):
    """Any monitor keeps the driver on its generic loop."""


class _Recorder:
    def __init__(self):
        self.t, self.y = [], []

    def __call__(self, t, y):
        self.t.append(t)
        self.y.append(y)


def _states(body, batch=()):
    """Reproducible start states of shape ``batch + (12,)``."""
    rng = np.random.default_rng(7)
    n = int(np.prod(batch, dtype=int))
    R = SO3.exp(rng.normal(size=(max(n, 1), 3)))
    W = rng.normal(size=(max(n, 1), 3)) * 2.0 + np.array([0.4, -0.2, 6.0])
    y = body.state(R, W)
    return y[0] if batch == () else y.reshape(batch + (12,))


def _run(body, y0, t_span, dt, fused, tab=TAB, t_out=None, max_angle=1.0):
    """``(t, y)`` or the raised error, the stats and the observer's record."""
    rec, stats = _Recorder(), Stats()
    try:
        t, y, _ = integrate_fixed(body.problem(), tab, t_span, y0, dt, observer=rec, t_out=t_out,
                                  monitor=None if fused else _no_monitor, max_increment_angle=max_angle,
                                  stats=stats)
        return (t, y), stats, rec
    except IntegrationError as exc:
        return exc, stats, rec


def _same_stats(a, b, tab=None):
    """Equal counters. Both loops reuse the last stage of an FSAL pair as the next first one
    (one evaluation less per step) and keep it across output times: ``(stages - 1) steps +
    1`` evaluations."""
    da, db = a.as_dict(), b.as_dict()
    da.pop("wall_time_s"), db.pop("wall_time_s")
    if tab is not None and tab.fsal:
        assert da["rhs_evals"] == (tab.stages - 1) * a.steps + 1
    assert da == db


def _rel(a, b):
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


def test_the_stepper_exists_only_where_it_should():
    pb = TOP.problem()
    assert isinstance(pb, RigidBodyProblem) and isinstance(pb, GroupProblem)
    assert isinstance(stepper_for(pb, TAB), CompiledStepper)

    class Damped(RigidBody):  # user-defined torque: the generic path must run it
        def vector_field(self, t, y):
            out = super().vector_field(t, y)
            out[..., 3:] -= 0.1 * self.split(y)[1]
            return out

    assert stepper_for(Damped(inertia=(1.0, 2.0, 2.5)).problem(), TAB) is None
    replaced = TOP.problem()
    replaced.f = lambda t, y: TOP.vector_field(t, y)
    assert stepper_for(replaced, TAB) is None

    class Custom(RigidBodyProblem):
        def end_step(self, y):
            return y

    assert stepper_for(Custom(TOP), TAB) is None


@pytest.mark.parametrize("batch", [(), (5,), (2, 3)], ids=["single", "batch5", "batch2x3"])
@pytest.mark.parametrize("kind", sorted(BODIES))
# the compiled engine runs the RKMK tableaux; commutator-free schemes stay in the generic loop
@pytest.mark.parametrize("method", sorted(m for m in METHODS if not is_commutator_free(resolve_method(m))))
def test_every_tableau_agrees_with_the_generic_loop(method, kind, batch, advance_calls):
    body, tab = BODIES[kind], resolve_method(method)
    y0 = _states(body, batch)
    keep = y0.copy()
    t_out = [0.05, 0.05, 0.3, 0.7]  # several advance calls, a repeated output time, short last steps
    (t1, y1), st1, rec1 = _run(body, y0, (0.0, 1.0), 7e-3, True, tab, t_out)
    assert len(advance_calls) == len(t_out) + 1  # the compiled engine took every interval
    (t2, y2), st2, rec2 = _run(body, y0, (0.0, 1.0), 7e-3, False, tab, t_out)
    assert len(advance_calls) == len(t_out) + 1  # and the monitored run none
    np.testing.assert_array_equal(y0, keep)  # the start state is not modified
    assert t1 == t2 == 1.0 and y1.shape == y2.shape == y0.shape
    assert rec1.t == rec2.t
    _same_stats(st1, st2, tab)
    for a, b in zip(rec1.y, rec2.y):
        assert _rel(a, b) <= TOL, f"{method}/{kind}{batch}: relative difference {_rel(a, b):.2e}"


@pytest.mark.parametrize("kind", sorted(BODIES))
def test_closed_form_branches(kind):
    """Increments of 1 to 1.6 rad: exp and dexpinv on their closed forms (>= 1 rad)."""
    body = BODIES[kind]
    y0 = body.state(SO3.exp(np.array([0.5, 0.0, 0.0])), np.array([0.3, -0.2, 8.0]))
    outs = [_run(body, y0, (0.0, 3.0), 0.19, fused, resolve_method("rkmk6"), max_angle=3.0) for fused in (True, False)]
    ((_, y1), st1, _), ((_, y2), st2, _) = outs
    _same_stats(st1, st2)
    assert _rel(y1, y2) <= 1e-12


def test_observed_states_are_independent():
    y0 = _states(TOP, (3,))
    _, _, rec = _run(TOP, y0, (0.0, 0.4), 0.01, True, t_out=[0.1, 0.2, 0.3])
    kept = [y.copy() for y in rec.y]
    assert len(rec.y) == 5
    for a, b in zip(rec.y[1:], rec.y[2:]):  # later outputs neither alias nor overwrite earlier ones
        assert not np.shares_memory(a, b)
    assert not np.shares_memory(rec.y[0], rec.y[1])
    for y, k in zip(rec.y, kept):
        np.testing.assert_array_equal(y, k)
    assert not np.array_equal(rec.y[1], rec.y[4])


@pytest.mark.filterwarnings("ignore::RuntimeWarning")
@pytest.mark.parametrize("case", ["blow-up", "blow-up in a batch", "angle", "angle at the first step"])
def test_errors_match_the_generic_loop(case):
    """Same exception type, time, step number and message; same counters and outputs up to it."""
    t_out = [0.25, 0.5]
    if case.startswith("blow-up"):  # explicit steps far too large: |W| grows until it overflows
        batch = (4,) if case.endswith("batch") else ()
        y0 = _states(FREE, batch)
        y0[(2, slice(9, 12)) if batch else slice(9, 12)] *= 10.0 if batch else 12.0  # only one body of a batch is fast
        body, dt, T, max_angle, expected = FREE, 0.1, 50.0, math.inf, BlowUpError
    elif case == "angle":  # heavy top: the spin rate varies, the increments reach the bound later
        body, y0, dt, T, expected = TOP, _states(TOP), 0.1, 5.0, StepSizeError
        max_angle = None
    else:
        body, y0, dt, T, max_angle, expected = TOP, _states(TOP), 0.1, 5.0, 0.05, StepSizeError
    if max_angle is None:  # just above the first step's increment angle
        first = stepper_for(TOP.problem(), TAB).advance(0.0, y0, dt, dt, 1, 0.0)
        assert first.status == "angle" and first.steps == 0
        max_angle = first.angle * 1.02
    got = {}
    for fused in (True, False):
        exc, stats, rec = _run(body, y0, (0.0, T), dt, fused, TAB, t_out, max_angle)
        assert type(exc) is expected, (case, fused, exc)
        got[fused] = (exc.t, exc.step, str(exc), stats, rec.t)
    (t1, s1, m1, st1, o1), (t2, s2, m2, st2, o2) = got[True], got[False]
    assert (t1, s1, m1, o1) == (t2, s2, m2, o2)
    _same_stats(st1, st2)
    assert st1.rhs_evals == (st1.steps + 1) * TAB.stages and s1 == st1.steps + 1
    if case != "angle at the first step":
        assert st1.steps > 3  # the failure is in a later advance call than the first
    else:
        assert st1.steps == 0


def test_advance_contract():
    st = stepper_for(TOP.problem(), TAB)
    y0 = _states(TOP, (2,))
    res = st.advance(0.0, y0, 0.1, 0.03, 4, 1.0)  # steps end at 0.03, 0.06, 0.09, 0.1
    assert res.status == "ok" and res.steps == 4 and res.t == 0.1 and res.y.shape == (2, 12)
    assert res.h_max == 0.03 and math.isclose(res.h_min, 0.1 - 0.09, rel_tol=1e-12)
    assert math.isnan(res.t_fail)
    with pytest.raises(ValueError):
        st.advance(0.0, np.zeros(9), 0.1, 0.1, 1, 1.0)
