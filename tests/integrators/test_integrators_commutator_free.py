"""Commutator-free and Crouch-Grossman schemes: checked data, orders on SO(3) and on an
isospectral flow, and their reduction to Runge-Kutta on R^n."""

from __future__ import annotations

import functools
from fractions import Fraction

import numpy as np
import pytest

from liegroup_int import SO3, Isospectral, Rn, integrate
from liegroup_int.tableaux import CF_REGISTRY, ButcherTableau, CommutatorFreeTableau
from liegroup_int.tableaux.lie_order import lie_order, local_error_orders

ORDERS = {"cf3": 3, "cf4": 4, "cg3": 3, "cg4a": 4}


def test_checks_refuse_broken_schemes():
    with pytest.raises(ValueError, match="not explicit"):
        CommutatorFreeTableau("x", "x", ("0", "1"), ((), (("0", "1"),)), (("1/2", "1/2"),), 2)
    with pytest.raises(ValueError, match="sum to 1/2, not c\\[1\\] = 1"):
        CommutatorFreeTableau("x", "x", ("0", "1"), ((), (("1/2", "0"),)), (("1/2", "1/2"),), 2)
    # CF3 with its two final exponentials swapped: the collapsed tableau is unchanged
    # (classical order 3), but the h^3 Magnus term is missed
    with pytest.raises(ValueError, match="miss the h\\^3 Magnus term"):
        CommutatorFreeTableau("x", "x", ("0", "1/3", "2/3"), ((), (("1/3", "0", "0"),), (("0", "2/3", "0"),)),
                              (("-1/12", "0", "3/4"), ("1/3", "0", "0")), 3)
    with pytest.raises(ValueError, match="claimed order 4 but the collapsed tableau fails the order-4"):
        CommutatorFreeTableau("x", "x", ("0", "1/3", "2/3"), ((), (("1/3", "0", "0"),), (("0", "2/3", "0"),)),
                              (("1/3", "0", "0"), ("-1/12", "0", "3/4")), 4)


def test_a_scheme_that_passes_the_collapsed_and_magnus_checks_but_not_order_4_is_refused():
    """CF4 with the two exponentials of its fourth stage swapped: the collapsed tableau and
    the final exponentials are unchanged (classical order 4, the h^3 Magnus condition), but
    the stage value is wrong at h^2 by a commutator, which enters the step at h^4."""
    stages = ((), (("1/2", "0", "0", "0"),), (("0", "1/2", "0", "0"),),
              (("-1/2", "0", "1", "0"), ("1/2", "0", "0", "0")))
    final = (("1/4", "1/6", "1/6", "-1/12"), ("-1/12", "1/6", "1/6", "1/4"))
    with pytest.raises(ValueError, match="on a Lie group its local error has an h\\^4 term"):
        CommutatorFreeTableau("x", "x", ("0", "1/2", "1/2", "1"), stages, final, 4)
    # claimed as order 3 it is accepted, and it is order 3
    assert lie_order(CommutatorFreeTableau("x", "x", ("0", "1/2", "1/2", "1"), stages, final, 3)) == 3


@pytest.mark.parametrize("name", sorted(CF_REGISTRY))
def test_lie_group_order_from_the_local_error_expansion(name):
    """The local error on the generic GL(3) problem vanishes through h^p (below 1e-14 relative
    for the rational schemes, 2e-15 measured for the 16-digit CG4a) and not at h^(p+1)
    (measured 0.045 for cf4, 0.24 for cg4a, 0.12 for cf3, 0.26 for cg3): the order is exact."""
    cf = CF_REGISTRY[name]
    defect = local_error_orders(cf, 5)
    p = ORDERS[name]
    assert np.all(defect[1:p + 1] < 1e-14) and defect[p + 1] > 1e-2
    assert lie_order(cf) == p


def test_the_series_are_those_of_the_flow_and_of_the_step():
    """The machinery of the check against direct evaluation at h = 0.01: the flow's series
    (to h^5) against scipy's DOP853 at tolerance 1e-13, the step's series against CF4's step
    computed with scipy's expm. Both differ by the truncation at h^6 (measured 1e-11 at
    h = 0.01, 6e-10 at 0.02: the factor 2^6), asserted below 1e-10, while the h^5 terms
    are 6.5e-10: a wrong coefficient up to h^5 would show."""
    from scipy.integrate import solve_ivp
    from scipy.linalg import expm

    from liegroup_int.tableaux import lie_order as L

    prob, h, P = L._problem(), 0.01, 5
    powers = h ** np.arange(P + 1)[:, None, None]
    field = lambda y: L._field(y[None], prob)[0]  # noqa: E731  (a constant series: A(y))
    flow = solve_ivp(lambda t, x: (field(x.reshape(3, 3)) @ x.reshape(3, 3)).ravel(), (0.0, h),
                     prob["y0"].ravel(), method="DOP853", rtol=1e-13, atol=1e-15).y[:, -1].reshape(3, 3)
    assert np.max(np.abs((L.exact_flow(prob, P) * powers).sum(axis=0) - flow)) < 1e-10
    cf = CF_REGISTRY["cf4"]
    F, Y = [], []
    for i in range(cf.stages):
        y = prob["y0"]
        for r in cf.stage_rows_f[i]:
            y = expm(sum(x * F[j] for j, x in enumerate(r[:i]))) @ y if i else y
        Y.append(y)
        F.append(h * field(y))
    y1 = prob["y0"]
    for r in cf.final_rows_f:
        y1 = expm(sum(x * F[j] for j, x in enumerate(r))) @ y1
    assert np.max(np.abs((L.scheme_step(cf, prob, P) * powers).sum(axis=0) - y1)) < 1e-10


@pytest.mark.parametrize("name", sorted(CF_REGISTRY))
def test_on_rn_a_scheme_is_its_collapsed_runge_kutta_method(name):
    """Translations commute: the scheme equals RK with A = sum of stage rows, b = sum of
    final rows (to round-off), on a non-autonomous nonlinear system; the collapsed
    tableau of a rational scheme is itself a checked ButcherTableau."""
    cf = CF_REGISTRY[name]
    f = lambda t, y: np.array([np.sin(t) * y[1], -y[0] ** 2 + y[1]])  # noqa: E731
    h, y = 0.1, np.array([1.0, 0.5])
    y_rk = y.copy()
    for n in range(10):  # classical RK with the collapsed coefficients, by hand
        k = np.zeros((cf.stages, 2))
        for i in range(cf.stages):
            k[i] = f(n * h + cf.c_f[i] * h, y_rk + h * cf.A_f[i] @ k)
        y_rk = y_rk + h * cf.b_f @ k
    y_cf = integrate(f, y, (0.0, 1.0), space=Rn(2), method=cf, dt=h).y_final
    assert np.allclose(y_cf, y_rk, rtol=0, atol=1e-14)
    if cf.exact:
        assert ButcherTableau("collapsed", cf.A, cf.b, cf.c, cf.order).order == cf.order


def _toda():
    rng = np.random.default_rng(0)
    a, b = rng.standard_normal(5), rng.uniform(0.5, 1.5, 4)
    M = Isospectral(5)
    return M, np.diag(a) + np.diag(b, 1) + np.diag(b, -1), lambda t, L: M.group.vee(np.triu(L, 1) - np.tril(L, -1))


def _so3_problem():
    return SO3, np.eye(3), lambda t, R: R @ np.array([np.sin(t), 1.0, R[0, 2]])


def _heavy_top():
    """The non-symmetric heavy top of benchmarks/rigid_body_work_precision.py, as a plugin
    problem (its own action and vector field; the scheme drives them)."""
    from liegroup_int.problems import RigidBody

    top = RigidBody(inertia=(1.0, 0.8, 0.5), mass=1.0, com=(0.0, 0.0, 0.5))
    return top.problem(), top.state(SO3.exp(np.array([0.5, 0.0, 0.0])), np.array([0.4, -0.2, 6.0]))


def _order_problem(problem):
    """(f, y0, space, T, dts, dt of the RKMK6 reference) of one problem of test_measured_orders."""
    if problem == "heavy_top":
        f, y0 = _heavy_top()
        return f, y0, None, 1.0, np.array([0.02, 0.01, 0.005]), 1.25e-3
    space, y0, f = _toda() if problem == "toda" else _so3_problem()
    return f, y0, space, (1.0 if problem == "toda" else 2.0), np.array([0.1, 0.05, 0.025]), 1e-2


@functools.lru_cache(maxsize=None)
def _order_reference(problem):
    """RKMK6 final state at the reference dt, and its distance to the RKMK6 run at twice that
    dt: a bound on the reference's own error (the coarser run's error is 2^6 times larger)."""
    f, y0, space, T, _, dt = _order_problem(problem)
    ref, coarse = (integrate(f, y0, (0.0, T), space=space, method="rkmk6", dt=h).y_final for h in (dt, 2 * dt))
    return ref, np.max(np.abs(ref - coarse))


@pytest.mark.parametrize("problem", ["toda", "so3", "heavy_top"])
@pytest.mark.parametrize("name", sorted(CF_REGISTRY))
def test_measured_orders(name, problem):
    """Least-squares slope of the final-state error against RKMK6 over three steps: within 0.3
    of the nominal order. Measured: Toda (Isospectral(5), T = 1, dt = 0.1, 0.05, 0.025) cf3
    2.87, cf4 3.92, cg3 2.92, cg4a 4.06; SO(3) (non-autonomous, T = 2) 2.98, 4.02, 3.03,
    4.08; heavy top (T = 1, dt = 0.02, 0.01, 0.005) 3.02, 4.07, 3.00, 4.00 (over T = 2 with
    the same steps cf4's slope is 3.70, its error falling 13x per halving, while the other
    three stay within 0.02 of their orders: the span is chosen where the leading terms show).
    The reference is RKMK6 at dt = 0.01 (Toda, SO(3)) and 1.25e-3 (heavy top); its distance to
    the run at twice its dt, measured 3.9e-12, 1.1e-14 and 2.8e-14 (the heavy top's within
    6.5e-14 of RKMK6 at dt = 1.25e-4), is asserted below 1e-3 of the smallest error fitted
    (1.8e-7, 8.8e-9, 4.4e-9), so that it moves the slope by less than 1e-3."""
    f, y0, space, T, dts, _ = _order_problem(problem)
    ref, ref_err = _order_reference(problem)
    err = [np.max(np.abs(integrate(f, y0, (0.0, T), space=space, method=name, dt=dt).y_final - ref)) for dt in dts]
    assert ref_err < 1e-3 * min(err), (ref_err, err)
    slope = np.polyfit(np.log(dts), np.log(err), 1)[0]
    assert slope == pytest.approx(ORDERS[name], abs=0.3), (err, slope)


def test_commutator_free_keeps_the_spectrum():
    M, L0, f = _toda()
    L = integrate(f, L0, (0.0, 20.0), space=M, method="cf4", dt=0.02).y_final
    assert np.max(np.abs(np.linalg.eigvalsh(L) - np.linalg.eigvalsh(L0))) <= 1e-12


def test_adaptive_stepping_is_refused_in_one_line():
    with pytest.raises(ValueError, match="method 'cf4' has no embedded pair; give a fixed dt"):
        integrate(lambda t, R: np.ones(3), np.eye(3), (0.0, 1.0), space=SO3, method="cf4", rtol=1e-6)


def test_a_perturbed_coefficient_is_refused():
    """CF4 with 1e-6 moved between its two final exponentials in its second column (the
    collapsed tableau, hence the classical order 4, and the h^3 Magnus term unchanged):
    refused by the Lie-group expansion, its h^4 term 1.6e-7 relative; CG4a with one stage
    weight moved by 1e-6 (16-digit coefficients): refused."""
    cf = CF_REGISTRY["cf4"]
    f0, f1 = list(cf.final_rows[0]), list(cf.final_rows[1])
    f0[1], f1[1] = f0[1] + Fraction(1, 10**6), f1[1] - Fraction(1, 10**6)
    with pytest.raises(ValueError, match="local error has an h\\^4 term \\(relative size 1.6e-07"):
        CommutatorFreeTableau("x", "x", cf.c, cf.stage_rows, (tuple(f0), tuple(f1)), 4)
    cg = CF_REGISTRY["cg4a"]

    def text(x):  # the stored 16-digit floats as the strings the constructor takes
        if isinstance(x, (tuple, list)):
            return tuple(text(v) for v in x)
        return x if isinstance(x, (str, Fraction, int)) else repr(float(x))

    stages = [list(stage) for stage in text(cg.stage_rows)]
    first = list(stages[2][0])
    first[0] = repr(float(first[0]) + 1e-6)
    stages[2][0] = tuple(first)
    CommutatorFreeTableau("x", "x", text(cg.c), text(cg.stage_rows), text(cg.final_rows), 4)  # as stored: accepted
    with pytest.raises(ValueError, match="claimed order 4|sum to"):
        CommutatorFreeTableau("x", "x", text(cg.c), tuple(tuple(st) for st in stages), text(cg.final_rows), 4)
