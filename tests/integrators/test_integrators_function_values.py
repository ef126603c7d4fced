"""Kernels handed to the compiled loops as first-class function values
(:class:`~liegroup_int.integrators.engine.FunctionValue`): the loops call them through an
address looked up once per value, not at every call (numba does that for a bare
dispatcher, about 40 us a function), and a pickled value looks its address up afresh."""

import pickle

import numpy as np
from numba import njit

import liegroup_int.integrators.engine as engine
from liegroup_int import SO3, integrate
from liegroup_int.integrators import resolve_method
from liegroup_int.integrators.drivers import stepper_for
from liegroup_int.scenes import load_scene
from liegroup_int.scenes.beam import problem


@njit(cache=True)
def _spin(t, y):
    return np.array([0.0, 0.0, 1.0 + t])


def _count_lookups(monkeypatch) -> list:
    import numba.experimental.function_type as ft

    seen, real = [], ft._get_wrapper_address

    def counted(fn, sig):  # numba asks a FunctionValue at every call; it asks the dispatcher once
        if not isinstance(fn, engine.FunctionValue):
            seen.append(getattr(fn, "__name__", fn))
        return real(fn, sig)

    monkeypatch.setattr(ft, "_get_wrapper_address", counted)
    return seen


def test_the_beam_loops_look_up_each_kernel_address_once(monkeypatch):
    """Ten one-step calls of the Galerkin pendulum's fixed loop: one lookup for the stage
    rate and one for the action, and the ten states equal one ten-step call's."""
    pb = problem(load_scene("pendulum", {"space.n_ctrl": 11, "integrator.backend": "numba"}))
    st = stepper_for(pb, resolve_method("rkmk4"))
    values = [x for x in st.cp.data if isinstance(x, engine.FunctionValue)]
    assert [v.fn.__name__ for v in values] == ["call_rates", "call_action"]
    seen = _count_lookups(monkeypatch)
    y, dt = pb.initial_state(), 1e-5
    for k in range(10):
        y = st.advance(k * dt, y, (k + 1) * dt, dt, 1, np.inf).y
    assert seen == ["call_rates", "call_action"]
    whole = st.advance(0.0, pb.initial_state(), 10 * dt, dt, 10, np.inf).y
    assert np.array_equal(whole.c, y.c) and np.array_equal(whole.R, y.R)


def test_a_user_field_is_looked_up_once_over_many_output_times(monkeypatch):
    seen = _count_lookups(monkeypatch)
    sol = integrate(_spin, np.eye(3), (0.0, 0.1), space=SO3, method="rkmk4", dt=1e-3,
                    t_eval=np.linspace(0.0, 0.1, 51))
    assert len(sol.t) == 51
    assert seen.count("_spin") == 1, seen


def test_a_pickled_value_looks_its_address_up_afresh():
    pb = problem(load_scene("pendulum", {"space.n_ctrl": 11, "integrator.backend": "numba"}))
    value = next(x for x in pb.compiled_kernels().data if isinstance(x, engine.FunctionValue))
    address = value.__wrapper_address__()
    copy = pickle.loads(pickle.dumps(value))
    assert copy._address is None and copy.signature() == value.signature()
    assert copy.__wrapper_address__() == address  # the same process: the same compiled code
