"""First-same-as-last reuse in the generic drivers and in the compiled engine.

For an FSAL pair the last row of A is b, so the last stage state is the step's end state;
with reuse it is taken as such, and its vector field serves the next step. That saves one
evaluation per attempt (Dormand-Prince 5(4), ``rkmk45``: 6 after the first) and changes
the numbers only by the summation order of the end increment: bit for bit for rkmk32 and
rkmk45, 4e-14 for Verner's nine-stage rkmk65 (measured).
"""

import numpy as np
import pytest

from liegroup_int.integrators import integrate_adaptive, integrate_fixed, resolve_method
from liegroup_int.problems.rigid_body import RigidBody, RigidBodyProblem


class NoReuse(RigidBodyProblem):
    @property
    def fsal_reuse(self):
        return False


def _top():
    body = RigidBody(inertia=(1.0, 1.0, 0.5), mass=1.0, com=(0.0, 0.0, 0.5), gravity=9.81)
    y0 = body.state(np.eye(3), np.array([0.3, 0.0, 10.0]))
    return body, y0


@pytest.mark.parametrize("method", ["rkmk32", "rkmk45", "rkmk65"])
def test_adaptive_fsal_saves_an_evaluation_per_attempt_and_changes_nothing(method):
    body, y0 = _top()
    tab = resolve_method(method)
    assert tab.fsal
    runs = {}
    for reuse, cls in ((True, RigidBodyProblem), (False, NoReuse)):
        pb = cls(body)
        assert pb.fsal_reuse is reuse
        # a monitor keeps the generic loop (the compiled engine is tested below)
        runs[reuse] = integrate_adaptive(pb, tab, (0.0, 1.0), y0, rtol=1e-8, atol=1e-10, t_out=[0.5],
                                         monitor=lambda *a: None)
    (_, ya, sa), (_, yb, sb) = runs[True], runs[False]
    np.testing.assert_allclose(ya, yb, rtol=0, atol=0 if method != "rkmk65" else 1e-12)
    attempts = sa.steps + sa.rejected
    assert (sa.steps, sa.rejected) == (sb.steps, sb.rejected) and attempts > 10
    assert sb.rhs_evals == tab.stages * attempts
    assert sa.rhs_evals == (tab.stages - 1) * attempts + 1


@pytest.mark.parametrize("method", ["rkmk32", "rkmk45", "rkmk65"])
def test_compiled_engine_reuses_the_last_stage(method, monkeypatch):
    """The engine's FSAL: one evaluation less per attempt, kept from one compiled call (one
    per output interval) to the next, so only the first attempt of the run evaluates f; the
    same numbers as without reuse (bit for bit for rkmk32/rkmk45, 1e-12 for rkmk65) and as
    the generic loop (to round-off: compiled sums against NumPy's)."""
    from liegroup_int.integrators import engine

    body, y0 = _top()
    tab = resolve_method(method)
    runs = {}
    original = engine.CompiledStepper.__init__
    for reuse in (True, False):
        def init(self, cp, tab_, reuse=reuse):
            original(self, cp, tab_)
            self.fsal = self.fsal and reuse

        monkeypatch.setattr(engine.CompiledStepper, "__init__", init)
        runs[reuse] = integrate_adaptive(RigidBodyProblem(body), tab, (0.0, 1.0), y0, rtol=1e-8, atol=1e-10,
                                         t_out=[0.5])
    monkeypatch.undo()
    generic = integrate_adaptive(RigidBodyProblem(body), tab, (0.0, 1.0), y0, rtol=1e-8, atol=1e-10,
                                 t_out=[0.5], monitor=lambda *a: None)
    (_, ya, sa), (_, yb, sb) = runs[True], runs[False]
    np.testing.assert_allclose(ya, yb, rtol=0, atol=0 if method != "rkmk65" else 1e-12)
    np.testing.assert_allclose(ya, generic[1], rtol=0, atol=1e-11)
    attempts = sa.steps + sa.rejected
    assert (sa.steps, sa.rejected) == (sb.steps, sb.rejected) == (generic[2].steps, generic[2].rejected)
    assert sb.rhs_evals == tab.stages * attempts
    assert sa.rhs_evals == (tab.stages - 1) * attempts + 1  # two output intervals, one start
    assert sa.rhs_evals == generic[2].rhs_evals


def test_fixed_step_fsal_and_non_fsal_methods():
    body, y0 = _top()
    for method, saved in (("rkmk45", True), ("rkmk4", False)):
        tab = resolve_method(method)
        _, ya, sa = integrate_fixed(RigidBodyProblem(body), tab, (0.0, 0.1), y0, 1e-3, monitor=lambda *a: None)
        _, yb, sb = integrate_fixed(NoReuse(body), tab, (0.0, 0.1), y0, 1e-3, monitor=lambda *a: None)
        np.testing.assert_array_equal(ya, yb)
        expected = (tab.stages - 1) * sa.steps + 1 if saved else tab.stages * sa.steps
        assert sa.rhs_evals == expected and sb.rhs_evals == tab.stages * sb.steps


def test_beam_keeps_every_evaluation():
    """The beam re-orthonormalizes R after each step (end_step): its first stage is not
    its last stage state, so nothing is reused."""
    from liegroup_int.scenes import load_scene
    from liegroup_int.scenes.beam import problem

    assert not problem(load_scene("cantilever")).fsal_reuse
