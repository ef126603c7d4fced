"""Dense output and events: the continuous extensions' exact conditions, the interpolant's
measured order on SO(3) x R^3, output times that do not change the steps, and events located
on the dense output (against the analytic time and against scipy's ``solve_ivp``)."""

from fractions import Fraction

import numpy as np
import pytest
from numba import njit
from scipy.integrate import solve_ivp

from liegroup_int import SO3, Product, Rn, integrate
from liegroup_int.integrators import GroupProblem, StateRecorder, integrate_adaptive, integrate_fixed, resolve_method
from liegroup_int.bench.free_body import f_njit  # the README's body as a numba.njit field
from liegroup_int.problems import RigidBody
from liegroup_int.problems.rigid_body_se3 import FreeBody
from liegroup_int.tableaux import REGISTRY, RK4
from liegroup_int.tableaux.continuous import continuous_extension, continuous_residuals, weights_at

TOP = RigidBody(inertia=(1.0, 0.8, 0.5), mass=1.0, com=(0.0, 0.0, 0.5))
Y0 = TOP.state(SO3.exp(np.array([0.5, 0.1, 0.0])), np.array([0.3, -0.2, 8.0]))

# the README's free body flipping about its intermediate axis (benchmarks/free_body_case.py)
INERTIA = np.array([1.0, 2.0, 3.0])
FB_SPACE = Product(SO3, Rn(3))
FB_Y0 = FB_SPACE.join(np.eye(3), np.array([0.01, 5.0, 0.01]))


def free_body(t, y):
    R, W = FB_SPACE.split(y)
    return np.concatenate([R @ W, np.cross(INERTIA * W, W) / INERTIA])


@pytest.mark.parametrize("name", sorted(REGISTRY))
def test_continuous_extension_is_exact(name):
    """Order p for the embedded pairs, p - 1 (at least 1) for the others, every continuous
    order condition exactly zero, b(1) = b; the stages bootstrapped where the method's own
    cannot carry it."""
    tab = REGISTRY[name]
    ext = continuous_extension(tab)
    assert ext.order == (tab.order if tab.b_hat is not None else max(1, tab.order - 1))
    A = [list(r) for r in ext.A]
    assert all(r == 0 for _, _, r in continuous_residuals(A, [list(w) for w in ext.W]))
    assert weights_at([list(w) for w in ext.W], Fraction(1)) == list(tab.b) + [Fraction(0)] * ext.extra
    assert ext.extra == {"verner65": 4, "dp54": 2, "rk6": 2}.get(name, 0)


def test_perturbed_continuous_weight_fails_a_condition():
    ext = continuous_extension(REGISTRY["dp54"], 4)
    W = [list(w) for w in ext.W]
    W[2][3] += Fraction(1, 10**6)
    bad = [(m, r) for _, m, r in continuous_residuals([list(r) for r in ext.A], W) if r != 0]
    assert bad and all(m == 3 for m, _ in bad)


def test_rk4_weights_are_the_textbook_ones():
    """Hairer-Norsett-Wanner I, II.6: b1 = theta - 3/2 theta^2 + 2/3 theta^3, b2 = b3 =
    theta^2 - 2/3 theta^3, b4 = -1/2 theta^2 + 2/3 theta^3."""
    F = Fraction
    assert continuous_extension(RK4).W == ((1, 0, 0, 0), (F(-3, 2), 1, 1, F(-1, 2)), (F(2, 3), F(-2, 3), F(-2, 3), F(2, 3)))


def _reference(times):
    """The heavy top landing on ``times`` (rkmk65, dt = 2e-4: error below 1e-15 here)."""
    rec = StateRecorder()
    integrate_fixed(TOP.problem(), resolve_method("rkmk65"), (0.0, 1.0), Y0, 2e-4, rec, times)
    return np.array(rec.y[1:len(times) + 1])


@pytest.mark.parametrize("method, dts", [("rkmk4", (0.1, 0.05, 0.025, 0.0125)),
                                         ("rkmk45", (0.1, 0.05, 0.025, 0.0125)),
                                         ("rkmk65", (0.1, 0.05, 0.025))])
@pytest.mark.parametrize("q", ["p - 1", "p"])
def test_dense_output_order_on_so3(method, dts, q):
    """Fixed steps over 1 s of the heavy top; largest error of sol.sol at the mid-step points
    against a landing reference. An interpolant of order q (local error h^(q+1)) on a method
    of order p has a global error O(h^p) between steps when q >= p - 1: measured slopes
    3.99, 5.18, 6.12 for p = 4, 5, 6 at q = p - 1; the bound p - 0.3 leaves room for the fit
    and is above the required p - 1. The interpolated attitudes are rotations to round-off.

    Error between the steps over that at the steps: with q = p it is 0.9-1.0 for all three
    (bound 1.5); with q = p - 1 at most 1.3 (rkmk4) and 1.7 (rkmk45), bound 2, but 2.8, 4.9,
    10.4 for rkmk65 at dt = 0.1, 0.05, 0.025, bound 12: Verner's pair converges like h^7 at
    the step ends on this problem, faster than the h^6 of its order-5 interpolant."""
    p = resolve_method(method).order
    order = p if q == "p" else p - 1
    errs, ratios = [], []
    for dt in dts:
        n = round(1.0 / dt)
        times = (np.arange(2 * n) + 1) * (dt / 2)  # mid-steps (even indices) and step ends (odd)
        sol = integrate(TOP.problem(), Y0, (0.0, 1.0), method=method, dt=dt, dense_output=True, dense_order=order)
        err = np.abs(sol.sol(times) - _reference(times)).max(axis=1)
        errs.append(err[0::2].max())
        ratios.append(err[0::2].max() / err[1::2].max())
        R = TOP.split(sol.sol(times[0::2]))[0]
        assert np.abs(np.einsum("nji,njk->nik", R, R) - np.eye(3)).max() < 1e-14
    slope = np.polyfit(np.log(dts), np.log(errs), 1)[0]
    assert slope > p - 0.3, (slope, errs)
    bound = 1.5 if q == "p" else {"rkmk4": 2.0, "rkmk45": 2.0, "rkmk65": 12.0}[method]
    assert max(ratios) < bound, ratios


@pytest.mark.parametrize("method", ["rkmk4", "rkmk45", "rkmk65"])
@pytest.mark.parametrize("dq", [-1, 0])
def test_interpolant_local_order(method, dq):
    """One step of h = 0.2, 0.1, 0.05 from the heavy top's initial state: the interpolant's
    error at mid-step is its local error, O(h^(q+1)). Measured slopes for q = p - 1, p: rkmk4
    4.03, 4.90; rkmk45 4.93, 6.22; rkmk65 6.15, 6.86; bound q + 1 - 0.3. (Rotation per step up
    to 1.6 rad: the guard is raised to 2 rad, far from dexpinv's pole at 2 pi.)"""
    q = resolve_method(method).order + dq
    hs, errs = np.array([0.2, 0.1, 0.05]), []
    for h in hs:
        rec = StateRecorder()
        integrate_fixed(TOP.problem(), resolve_method("rkmk65"), (0.0, h / 2), Y0, 1e-4, rec)
        sol = integrate(TOP.problem(), Y0, (0.0, h), method=method, dt=h, dense_output=True, dense_order=q,
                        max_increment_angle=2.0)
        errs.append(np.abs(sol.sol(h / 2) - rec.y[-1]).max())
    slope = np.polyfit(np.log(hs), np.log(errs), 1)[0]
    assert slope > q + 1 - 0.3, (slope, errs)


def test_output_times_do_not_change_the_steps():
    """rkmk45 at rtol = atol = 1e-9 over 20 s: 817 steps and 4903 evaluations with 201
    output times as without, the same final state bit for bit, FSAL carried across them
    (with the order-4 interpolant, which needs no extra stage, the same evaluations; the
    default order 5 adds its 2 bootstrapped stages on each step with an output time inside);
    landing on them (the driver's t_out) takes 1228 steps and 7369 evaluations."""
    kw = dict(space=FB_SPACE, method="rkmk45", rtol=1e-9, atol=1e-9)
    ends = [0.0]
    bare = integrate(free_body, FB_Y0, (0.0, 20.0), monitor=lambda t, y, s: ends.append(t), **kw)
    t_eval = np.linspace(0.0, 20.0, 201)
    q4 = integrate(free_body, FB_Y0, (0.0, 20.0), t_eval=t_eval, dense_order=4, **kw)
    q5 = integrate(free_body, FB_Y0, (0.0, 20.0), t_eval=t_eval, **kw)
    assert (q4.stats.steps, q4.stats.rhs_evals) == (bare.stats.steps, bare.stats.rhs_evals) == (817, 4903)
    inside = np.unique(np.searchsorted(ends, t_eval[~np.isin(t_eval, ends)]))
    assert q5.stats.steps == 817 and q5.stats.rhs_evals == 4903 + 2 * inside.size
    assert q4.stats.rejected == q5.stats.rejected == bare.stats.rejected
    np.testing.assert_array_equal(q5.y_final, bare.y_final)
    np.testing.assert_array_equal(q5.t, t_eval)
    _, _, landing = integrate_adaptive(GroupProblem(FB_SPACE, free_body), resolve_method("rkmk45"), (0.0, 20.0),
                                       FB_Y0, 1e-9, 1e-9, None, t_eval)
    assert landing.steps > 1.4 * bare.stats.steps, landing.steps


def test_output_times_do_not_change_the_compiled_steps():
    """The same run with a ``numba.njit`` field: the steps run in the compiled engine, which
    hands Python only the steps with an output time inside. 817 steps and 4903 evaluations
    with and without the 201 output times (order 4), the final state bit for bit; with
    order 5 the bootstrapped stages on the steps with an output inside, as the Python loop
    counts them. The outputs equal those of the same field through the Python loop to
    round-off, which the flow near the separatrix amplifies: 1e-15 at t = 1, 2e-11 at t = 20,
    4.6e-9 at most near a flip (asserted 1e-13 up to t = 1 and 5e-8 over the run)."""
    kw = dict(space=FB_SPACE, method="rkmk45", rtol=1e-9, atol=1e-9)
    t_eval = np.linspace(0.0, 20.0, 201)
    bare = integrate(f_njit, FB_Y0, (0.0, 20.0), **kw)
    q4 = integrate(f_njit, FB_Y0, (0.0, 20.0), t_eval=t_eval, dense_order=4, **kw)
    q5 = integrate(f_njit, FB_Y0, (0.0, 20.0), t_eval=t_eval, **kw)
    generic = integrate(f_njit, FB_Y0, (0.0, 20.0), t_eval=t_eval, monitor=lambda t, y, s: None, **kw)
    assert (q4.stats.steps, q4.stats.rhs_evals) == (bare.stats.steps, bare.stats.rhs_evals) == (817, 4903)
    assert (q5.stats.steps, q5.stats.rhs_evals) == (generic.stats.steps, generic.stats.rhs_evals)
    assert q5.stats.rhs_evals > 4903
    np.testing.assert_array_equal(q4.y_final, bare.y_final)
    np.testing.assert_array_equal(q5.y_final, bare.y_final)
    np.testing.assert_array_equal(q5.t, generic.t)
    diff = np.array([np.abs(a - b).max() for a, b in zip(q5.y, generic.y)])
    assert diff[q5.t <= 1.0].max() < 1e-13 and diff.max() < 5e-8, diff.max()


def test_compiled_events_and_dense_output_match_the_python_loop():
    """With a ``numba.njit`` field, ``events`` and ``dense_output`` take every step from the
    compiled engine: the README's flip at the same time as through the Python loop (to
    1e-12 s), the same steps, and ``sol(t)`` between the steps equal to round-off."""
    def flip(t, y):
        return y[10]

    flip.terminal, flip.direction = True, -1
    kw = dict(space=FB_SPACE, method="rkmk45", rtol=1e-9, atol=1e-9, events=flip, dense_output=True)
    a = integrate(f_njit, FB_Y0, (0.0, 20.0), **kw)
    b = integrate(f_njit, FB_Y0, (0.0, 20.0), monitor=lambda t, y, s: None, **kw)
    assert a.status == b.status == 1 and a.stats.steps == b.stats.steps > 50
    assert abs(a.t_events[0][0] - b.t_events[0][0]) < 1e-12 and abs(a.t_events[0][0] - 2.741068) < 1e-6
    ts = np.linspace(0.0, min(a.sol.t_max, b.sol.t_max), 37)
    np.testing.assert_allclose(a.sol(ts), b.sol(ts), rtol=0, atol=1e-12)


def _thrown_body():
    body = FreeBody(2.0, (1.0, 2.0, 3.0))
    R0 = SO3.exp(np.array([0.3, -0.2, 0.5]))
    x0, v0 = np.array([0.0, 0.0, 1.5]), np.array([1.0, 0.5, 6.0])
    y0 = body.state(R0, x0, R0.T @ v0, np.array([0.4, 3.0, 0.2]))
    t_hit = (v0[2] + np.sqrt(v0[2] ** 2 + 2 * 9.81 * x0[2])) / 9.81  # x_z(t) = 1.5 + 6 t - g t^2 / 2
    return body, y0, t_hit


def test_thrown_body_meets_the_ground_at_the_analytic_time():
    """A tumbling body in SE(3) x R^6 thrown upward: its centre of mass reaches z = 0 at the
    analytic time within 1e-10 at rtol = atol = 1e-10 (measured 1.3e-11); the terminal
    event ends the run there, on the group."""
    body, y0, t_hit = _thrown_body()

    def ground(t, y):
        return body.split(y)[1][2]

    ground.terminal, ground.direction = True, -1
    sol = integrate(body.problem(), y0, (0.0, 5.0), method="rkmk45", rtol=1e-10, atol=1e-10, events=ground)
    assert sol.status == 1 and len(sol.t_events[0]) == 1
    assert abs(sol.t_events[0][0] - t_hit) < 1e-10
    assert sol.t_final == sol.t_events[0][0] and sol.t[-1] == sol.t_final
    np.testing.assert_array_equal(sol.y_events[0][0], sol.y_final)
    assert abs(body.split(sol.y_final)[1][2]) < 1e-12
    R = body.split(sol.y_final)[0]
    assert np.abs(R.T @ R - np.eye(3)).max() < 1e-14


def _oscillator(t, y):
    return np.array([y[1], -y[0]])


@pytest.mark.parametrize("direction", [1.0, -1.0, 0.0])
def test_direction_filtering_matches_solve_ivp(direction):
    """y'' = -y, y(0) = (1, 0) over 20 s; zeros of y0 - 0.5 (3 rising, 4 falling): the same events
    as solve_ivp (RK45), times within 1e-7 (both runs at rtol = atol = 1e-10)."""

    def g(t, y):
        return y[0] - 0.5

    g.direction = direction
    ours = integrate(_oscillator, np.array([1.0, 0.0]), (0.0, 20.0), method="rkmk45", rtol=1e-10, atol=1e-10,
                     events=g)
    ref = solve_ivp(_oscillator, (0.0, 20.0), [1.0, 0.0], rtol=1e-10, atol=1e-10, events=g)
    assert len(ours.t_events[0]) == len(ref.t_events[0]) == {1.0: 3, -1.0: 4, 0.0: 7}[direction]
    np.testing.assert_allclose(ours.t_events[0], ref.t_events[0], atol=1e-7)
    np.testing.assert_allclose(ours.y_events[0], ref.y_events[0], atol=1e-7)


@njit
def _oscillator_njit(t, y):
    return np.array([y[1], -y[0]])


@njit
def _level(t, y):
    return y[0] - 0.5


@njit
def _level_int(t, y):  # an integer result: through the engine's adapter
    return 1 if y[0] > 0.5 else -1


@pytest.fixture
def handovers(monkeypatch):
    """The steps the compiled engine hands back to Python (dense output, events)."""
    import liegroup_int.integrators.drivers as drivers

    calls = []
    original = drivers._hand_over

    def counted(*args):
        calls.append(args[2].t)
        return original(*args)

    monkeypatch.setattr(drivers, "_hand_over", counted)
    return calls


@pytest.mark.parametrize("direction", [1.0, -1.0, 0.0])
def test_compiled_events_are_watched_in_the_engine(direction, handovers):
    """With a ``numba.njit`` field and a ``numba.njit`` event the compiled loop checks the
    sign after every step and hands back only the steps over which it changes (and the last):
    the same 3 / 4 / 7 zeros of y0 - 0.5 as the same event in Python, which takes every one
    of the 812 steps through Python, at the same times to 1e-12 (measured equal). Sign
    changes the direction filters out (across skipped steps) do not hide the next one."""
    kw = dict(method="rkmk45", rtol=1e-10, atol=1e-12)
    _level.direction = direction
    ours = integrate(_oscillator_njit, np.array([1.0, 0.0]), (0.0, 20.0), events=_level, **kw)
    watched = len(handovers)
    handovers.clear()

    def g(t, y):
        return y[0] - 0.5

    g.direction = direction
    python = integrate(_oscillator_njit, np.array([1.0, 0.0]), (0.0, 20.0), events=g, **kw)
    n = {1.0: 3, -1.0: 4, 0.0: 7}[direction]
    assert len(ours.t_events[0]) == len(python.t_events[0]) == n
    np.testing.assert_allclose(ours.t_events[0], python.t_events[0], rtol=0, atol=1e-12)
    assert watched == n + 1 and len(handovers) == python.stats.steps > 500
    _level_int.direction = direction
    coarse = integrate(_oscillator_njit, np.array([1.0, 0.0]), (0.0, 20.0), events=_level_int, **kw)
    assert len(coarse.t_events[0]) == n  # the same crossings, located on a step function


def test_terminal_count_and_t_eval_stop_at_the_event():
    """terminal = 2 stops at the second zero; output times after it are not recorded, and the
    run ends there (status 1)."""

    def g(t, y):
        return y[0]

    g.terminal = 2
    sol = integrate(_oscillator, np.array([1.0, 0.0]), (0.0, 20.0), method="rkmk4", dt=0.05, events=g,
                    t_eval=np.arange(1.0, 20.0, 1.0), dense_output=True)
    np.testing.assert_allclose(sol.t_events[0], [np.pi / 2, 3 * np.pi / 2], atol=1e-6)
    assert sol.status == 1 and sol.t_final == sol.t_events[0][1]
    np.testing.assert_array_equal(sol.t, [0.0, 1.0, 2.0, 3.0, 4.0, sol.t_final])
    assert sol.sol.t_max == sol.t_final
    with pytest.raises(ValueError, match="outside the integrated interval"):
        sol.sol(5.0)


def test_dense_output_refuses_commutator_free_and_bad_events():
    with pytest.raises(ValueError, match="need an RKMK method"):
        integrate(_oscillator, np.ones(2), (0.0, 1.0), method="cf4", dt=0.1, dense_output=True)
    with pytest.raises(TypeError, match="expected callables"):
        integrate(_oscillator, np.ones(2), (0.0, 1.0), dt=0.1, events=[1.0])


def test_bad_output_times_and_dense_order_are_refused():
    with pytest.raises(ValueError, match="t_eval must be sorted"):
        integrate(_oscillator, np.ones(2), (0.0, 1.0), dt=0.1, t_eval=[0.5, 0.2])
    with pytest.raises(ValueError, match="continuous order must be in"):
        integrate(_oscillator, np.ones(2), (0.0, 1.0), dt=0.1, dense_output=True, dense_order=5)


def test_dense_output_on_the_sphere_stays_on_it():
    """A homogeneous space (the action of SO(3) on S^2): interpolated points between steps of
    a coarse rkmk45 run have unit length to round-off (1e-15 measured)."""
    from liegroup_int.manifolds import Sphere

    w = np.array([0.3, -1.0, 2.0])
    sol = integrate(lambda t, y: np.cos(t) * w + np.cross(y, w), np.array([1.0, 0.0, 0.0]), (0.0, 3.0),
                    space=Sphere(), method="rkmk45", rtol=1e-4, atol=1e-4, dense_output=True)
    ts = np.linspace(0.0, sol.t_final, 301)
    assert sol.stats.steps < 100
    assert np.abs(np.linalg.norm(sol.sol(ts), axis=1) - 1.0).max() < 1e-14


@njit
def _vector_event(t, y):
    return y[:1]


def test_an_event_that_is_not_a_number_is_refused_in_one_line():
    with pytest.raises(ValueError, match="event g\\(t, y\\) must return a number, got ndarray of shape \\(1,\\)") as err:
        integrate(_oscillator_njit, np.array([1.0, 0.0]), (0.0, 1.0), method="rkmk45", rtol=1e-8, atol=1e-8,
                  events=_vector_event)
    assert "\n" not in str(err.value)
