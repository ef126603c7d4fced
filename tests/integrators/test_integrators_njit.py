"""A user's ``numba.njit`` vector field on each built-in group: the whole fixed-step and
adaptive loops run in the compiled engine (integrators/engine.py, compiled_group.py) and
agree with the generic Python path.

Tolerance 1e-12: the same step arithmetic (stage combinations in the same order, the groups'
compiled kernels against the same kernels called from Python); what differs is the
rounding of ``f`` itself (compiled with LLVM against the Python function run by NumPy).
"""

import numpy as np
import pytest
from numba import njit

from liegroup_int import SE3, SO3, Power, Product, Rn, integrate
from liegroup_int.integrators import GroupProblem, StateRecorder, integrate_adaptive, resolve_method


@njit
def _linear(t, y):  # R^3: dy/dt = A y + sin t
    out = np.empty(3)
    out[0] = -0.5 * y[0] + y[1]
    out[1] = -y[0] - 0.2 * y[1] + np.sin(t)
    out[2] = 0.3 * y[2] * np.cos(t)
    return out


@njit
def _spin(t, R):  # SO(3): a time-varying spatial angular velocity tied to R
    out = np.empty(3)
    out[0] = 1.0 + 0.5 * R[0, 2]
    out[1] = 0.3 * np.cos(2.0 * t)
    out[2] = 2.0 - R[1, 0]
    return out


@njit
def _screw(t, g):  # SE(3): twist depending on the position
    out = np.empty(6)
    out[0] = 1.0 - 0.1 * g[1, 3]
    out[1] = 0.2 * g[0, 3]
    out[2] = 0.5
    out[3] = 0.3
    out[4] = -0.2 * g[2, 3]
    out[5] = 2.0 + 0.1 * np.sin(t)
    return out


@njit
def _free_body(t, y):  # SO(3) x R^3, the README's body: y = (R row by row, W)
    out = np.empty(6)
    for i in range(3):
        out[i] = y[3 * i] * y[9] + y[3 * i + 1] * y[10] + y[3 * i + 2] * y[11]
    w0, w1, w2 = y[9], y[10], y[11]
    out[3] = (2.0 * w1 * w2 - 3.0 * w2 * w1) / 1.0
    out[4] = (3.0 * w2 * w0 - 1.0 * w0 * w2) / 2.0
    out[5] = (1.0 * w0 * w1 - 2.0 * w1 * w0) / 3.0
    return out


@njit
def _two_rotors(t, y):  # Power(SO3, 2): two rotations coupled through their third columns
    out = np.empty(6)
    out[0], out[1], out[2] = 1.0, 0.5 * y[11], 0.0
    out[3], out[4], out[5] = 0.2 * y[2], 0.0, 1.5
    return out


CASES = {
    "R3": (Rn(3), _linear, np.array([1.0, 0.0, 0.5])),
    "SO3": (SO3, _spin, SO3.exp(np.array([0.3, -0.2, 0.1]))),
    "SE3": (SE3, _screw, SE3.exp(np.array([0.1, 0.2, 0.3, 0.2, 0.1, -0.3]))),
    "SO3xR3": (Product(SO3, Rn(3)), _free_body, Product(SO3, Rn(3)).join(np.eye(3), np.array([0.01, 5.0, 0.01]))),
    "SO3^2": (Power(SO3, 2), _two_rotors, Power(SO3, 2).join(SO3.exp(np.array([[0.1, 0.0, 0.2], [0.0, 0.3, 0.0]])))),
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_compiled_loop_agrees_with_the_python_path(name):
    space, f, y0 = CASES[name]
    pb = GroupProblem(space, f)
    assert pb.compiled_kernels() is not None
    a = integrate(pb, y0, (0.0, 0.5), method="rkmk4", dt=1e-3, t_eval=[0.25])
    b = integrate(GroupProblem(space, f.py_func), y0, (0.0, 0.5), method="rkmk4", dt=1e-3, t_eval=[0.25])
    assert a.stats.steps == b.stats.steps == 500 and a.stats.rhs_evals == b.stats.rhs_evals
    assert len(a.y) == len(b.y) == 3
    for ya, yb in zip(a.y, b.y):
        np.testing.assert_allclose(ya, yb, rtol=0, atol=1e-12 * max(1.0, np.abs(yb).max()))


@pytest.mark.parametrize("method", ["rkmk45", "rkmk65"])
@pytest.mark.parametrize("name", sorted(CASES))
def test_compiled_adaptive_loop_agrees_with_the_python_path(name, method):
    """Same accepted and rejected steps, states to 1e-12 (relative), both landing on the
    output time 0.5 (the driver's ``t_out``); FSAL saves one evaluation per attempt on both
    paths, across the output time too."""
    space, f, y0 = CASES[name]
    tab = resolve_method(method)
    a, b = StateRecorder(), StateRecorder()
    _, _, sa = integrate_adaptive(GroupProblem(space, f), tab, (0.0, 1.0), y0, 1e-8, 1e-10, a, [0.5])
    _, _, stats = integrate_adaptive(GroupProblem(space, f.py_func), tab, (0.0, 1.0), y0, 1e-8, 1e-10, b, [0.5])
    assert (sa.steps, sa.rejected) == (stats.steps, stats.rejected) and sa.steps > 5
    attempts = sa.steps + sa.rejected
    assert sa.rhs_evals == stats.rhs_evals == (tab.stages - 1) * attempts + 1
    assert len(a.y) == len(b.y) == 3
    for ya, yb in zip(a.y, b.y):
        np.testing.assert_allclose(ya, yb, rtol=0, atol=1e-12 * max(1.0, np.abs(yb).max()))


def test_compiled_adaptive_tolerance_proportionality():
    """rkmk45 through the engine: the global error at t = 1 falls with the tolerance
    (fitted slope of log error against log rtol between 0.7 and 1.2 over 1e-5..1e-9: a
    controlled error, per the local error per unit step)."""
    space, f, y0 = CASES["SO3xR3"]
    ref = integrate(f, y0, (0.0, 1.0), space=space, method="rkmk6", dt=1e-3).y_final
    tols = np.array([1e-5, 1e-6, 1e-7, 1e-8, 1e-9])
    errs = [np.abs(integrate(f, y0, (0.0, 1.0), space=space, method="rkmk45", rtol=r, atol=r * 1e-2).y_final
                   - ref).max() for r in tols]
    slope = np.polyfit(np.log(tols), np.log(errs), 1)[0]
    assert 0.7 < slope < 1.2 and max(errs) < 1e-3, (errs, slope)


@njit
def _wrong_shape(t, y):
    return np.zeros(2)


def test_a_wrong_shape_from_f_is_a_clear_error():
    with pytest.raises(ValueError, match=r"shape \(space.dim,\)"):
        integrate(_wrong_shape, np.eye(3), (0.0, 0.01), space=SO3, method="rkmk4", dt=1e-3)


@pytest.mark.parametrize("name", sorted(CASES))
def test_compiled_loop_order(name):
    """RKMK4 through the engine, errors at t = 1 against RKMK6 at h = 1e-3: slope 4 +- 0.3."""
    space, f, y0 = CASES[name]
    ref = integrate(f, y0, (0.0, 1.0), space=space, method="rkmk6", dt=1e-3).y_final
    hs = np.array([0.04, 0.02, 0.01])
    errs = [np.abs(integrate(f, y0, (0.0, 1.0), space=space, method="rkmk4", dt=h).y_final - ref).max() for h in hs]
    slope = np.polyfit(np.log(hs), np.log(errs), 1)[0]
    assert min(errs) > 1e-12 and abs(slope - 4.0) < 0.3, (errs, slope)


def test_batches_need_a_python_f():
    space, f, _ = CASES["SO3"]
    y0 = SO3.exp(np.zeros((2, 3)))
    with pytest.raises(ValueError, match="one point of shape"):
        integrate(f, y0, (0.0, 0.01), space=space, method="rkmk4", dt=1e-3)


@njit
def _matrix_result(t, y):
    return np.zeros((3, 1))


@njit
def _strided_spin(t, R):  # _spin's values as a strided view of a longer array
    out = np.zeros(6)
    w = _spin(t, R)
    for k in range(3):
        out[2 * k] = w[k]
    return out[::2]


def test_a_result_that_is_not_a_vector_is_refused_in_one_line():
    with pytest.raises(ValueError, match=r"shape \(space.dim,\), got array\(float64, 2d") as err:
        integrate(_matrix_result, np.eye(3), (0.0, 0.01), space=SO3, method="rkmk4", dt=1e-3)
    assert "\n" not in str(err.value)


def test_a_strided_result_runs_in_the_engine_like_a_contiguous_one():
    """A 1-D result that is not C-contiguous goes through the adapter: the same steps as
    the contiguous field, bit for bit (the adapter only copies)."""
    a = integrate(_strided_spin, np.eye(3), (0.0, 0.5), space=SO3, method="rkmk4", dt=1e-2).y_final
    b = integrate(_spin, np.eye(3), (0.0, 0.5), space=SO3, method="rkmk4", dt=1e-2).y_final
    np.testing.assert_array_equal(a, b)
