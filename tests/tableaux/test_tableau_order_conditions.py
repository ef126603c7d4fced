"""Order conditions, tableau validation, registry and the paper's errata."""

from __future__ import annotations

import dataclasses
import math
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from liegroup_int.tableaux import (
    KNOWN_TREE_COUNTS,
    LEAF,
    REGISTRY,
    RK3,
    RK4,
    RK6,
    ButcherTableau,
    achieved_order,
    canonical,
    density,
    elementary_weight,
    first_failed_condition,
    order_condition_residuals,
    resolve,
    tree_order,
    tree_to_str,
    trees_of_order,
    trees_up_to,
)
from liegroup_int.tableaux.methods import _lower, _vec

NAMES = sorted(REGISTRY)

# ---------------------------------------------------------------- the paper's printed tables
# Ferri & Marino, Appendix A, exactly as printed (rows of A below the diagonal).
PRINTED_RK3_A = _lower("1/2", "-1 1/2")
PRINTED_RK3_B = _vec("1/6 2/3 1/6")
PRINTED_RK3_C = _vec("0 1/2 1")

PRINTED_RK6_A = _lower("1/3",
                       "0 2/3",
                       "1/12 1/3 -1/12",
                       "-1/16 9/8 -3/16 -3/8",
                       "9/8 -3/8 -3/4 1/2 0",          # row 6 shifted left in print
                       "9/44 -9/11 63/44 18/11 0 -16/11")
PRINTED_RK6_B = _vec("11/120 0 27/40 27/40 -4/15 -4/15 11/120")
PRINTED_RK6_C = _vec("0 1/3 2/3 1/3 1/2 1/2 1")


def _exact(rows):
    return [[Fraction(x) for x in row] for row in rows]


def _exact_vec(values):
    return [Fraction(x) for x in values]


# ---------------------------------------------------------------- trees

@pytest.mark.parametrize("order,count", list(enumerate(KNOWN_TREE_COUNTS, start=1)))
def test_tree_counts(order, count):
    trees = trees_of_order(order)
    assert len(trees) == count
    assert len(set(trees)) == count
    assert all(tree_order(t) == order for t in trees)
    assert all(canonical(t) == t for t in trees)


def test_trees_up_to_eight():
    assert len(trees_up_to(8)) == sum(KNOWN_TREE_COUNTS) == 200


def test_density_tall_and_bushy():
    tall = LEAF
    for n in range(2, 8):
        tall = (tall,)
        bushy = (LEAF,) * (n - 1)
        assert density(tall) == math.factorial(n)
        assert density(bushy) == n
    assert tree_to_str(((), ((),))) == "[t,[t]]"


def test_canonical_form_dedupes_child_order():
    t1 = (((),), ())
    t2 = ((), ((),))
    assert canonical(t1) == canonical(t2)
    assert elementary_weight(RK4.A, RK4.b, t1) == elementary_weight(RK4.A, RK4.b, t2)


def test_elementary_weights_rk4_match_direct_formulas():
    A, b, c = RK4.A, RK4.b, RK4.c
    s = len(b)
    assert elementary_weight(A, b, ((),)) == sum(b[i] * c[i] for i in range(s))
    assert elementary_weight(A, b, (((),),)) == sum(
        b[i] * A[i][j] * c[j] for i in range(s) for j in range(s))
    assert elementary_weight(A, b, ((), (), ())) == sum(b[i] * c[i] ** 3 for i in range(s))


# ---------------------------------------------------------------- registry: exact orders

@pytest.mark.parametrize("name", NAMES)
def test_registry_order_exact_and_sharp(name):
    tab = REGISTRY[name]
    assert tab.name == name
    assert achieved_order(tab.A, tab.b, max_order=tab.order + 1) == tab.order
    residuals = order_condition_residuals(tab.A, tab.b, tab.order + 1)
    assert all(r == 0 for _, p, r in residuals if p <= tab.order)
    assert any(r != 0 for _, p, r in residuals if p == tab.order + 1)
    assert all(isinstance(r, Fraction) for _, _, r in residuals)


@pytest.mark.parametrize("name", NAMES)
def test_integer_residuals_equal_the_fraction_recursion(name):
    """The exact residuals are computed in integers over a common denominator; they equal,
    tree by tree, Phi(t) - 1/gamma(t) from elementary weights in Fractions, up to order 7."""
    tab = REGISTRY[name]
    for w in [tab.b] + ([tab.b_hat] if tab.b_hat is not None else []):
        fast = order_condition_residuals(tab.A, w, 7)
        slow = [elementary_weight(tab.A, w, t) - Fraction(1, density(t)) for t in trees_up_to(7)]
        assert [r for _, _, r in fast] == slow


@pytest.mark.parametrize("name", [n for n in NAMES if REGISTRY[n].b_hat is not None])
def test_registry_embedded_order_exact_and_sharp(name):
    tab = REGISTRY[name]
    assert achieved_order(tab.A, tab.b_hat, max_order=tab.order_hat + 1) == tab.order_hat
    failed = first_failed_condition(tab.A, tab.b_hat, tab.order_hat + 1)
    assert failed is not None and failed[1] == tab.order_hat + 1


@pytest.mark.parametrize("name", NAMES)
def test_registry_float_arrays(name):
    tab = REGISTRY[name]
    s = tab.stages
    assert tab.A_f.shape == (s, s) and tab.b_f.shape == (s,) and tab.c_f.shape == (s,)
    assert not tab.A_f.flags.writeable
    np.testing.assert_allclose(tab.A_f.sum(axis=1), tab.c_f, rtol=0, atol=1e-13)
    assert np.all(np.triu(tab.A_f) == 0)
    # the float path of the order check agrees (default float tolerance 1e-10)
    assert achieved_order(tab.A_f, tab.b_f, max_order=tab.order + 1) == tab.order
    if tab.b_hat is None:
        assert tab.b_hat_f is None and tab.e_f is None
    else:
        # e_f is rounded from the exact difference, not a difference of rounded floats
        np.testing.assert_array_equal(tab.e_f, [float(x - y) for x, y in zip(tab.b, tab.b_hat)])
        np.testing.assert_allclose(tab.e_f, tab.b_f - tab.b_hat_f, rtol=0, atol=1e-13)
        assert sum(x - y for x, y in zip(tab.b, tab.b_hat)) == 0
        assert abs(tab.e_f.sum()) < 1e-13
    if tab.fsal:
        assert tab.A[-1] == tab.b and tab.c[-1] == 1


def test_registry_expected_orders_and_stages():
    table = {n: (t.order, t.stages, t.order_hat) for n, t in REGISTRY.items()}
    assert table == {
        "euler": (1, 1, None), "rk2": (2, 2, None), "rk3": (3, 3, None),
        "rk4": (4, 4, None), "rk6": (6, 7, None), "bs32": (3, 4, 2),
        "dp54": (5, 7, 4), "verner65": (6, 9, 5),
    }


def test_tableau_is_frozen_and_hashable():
    with pytest.raises(dataclasses.FrozenInstanceError):
        RK4.order = 5
    assert hash(RK4) == hash(dataclasses.replace(RK4))
    assert dataclasses.replace(RK4) == RK4


def test_resolve():
    assert resolve("rk4") is RK4
    assert resolve(" RK4 ") is RK4
    assert resolve(RK6) is RK6
    assert resolve("rkmk4") is RK4 and resolve("RKMK6") is RK6  # method names too
    for exc in (KeyError, ValueError):
        with pytest.raises(exc, match="expected one of: bs32, cf3, cf4, cg3, cg4a, dp54, euler, rk2"):
            resolve("rk5")
    with pytest.raises(TypeError):
        resolve(4)


# ---------------------------------------------------------------- errata of Appendix A

def test_printed_rk3_misprint():
    A, b = _exact(PRINTED_RK3_A), _exact_vec(PRINTED_RK3_B)
    # the printed third row sums to -1/2, not c3 = 1
    assert sum(A[2]) == Fraction(-1, 2)
    with pytest.raises(ValueError, match="row-sum condition fails at stage 2"):
        ButcherTableau("rk3_printed", PRINTED_RK3_A, PRINTED_RK3_B, PRINTED_RK3_C, 3)
    # with the implied c = A 1 the printed method has order 1 only
    assert achieved_order(A, b) == 1
    tree, order, residual = first_failed_condition(A, b, 3)
    assert (tree, order, residual) == (((),), 2, Fraction(-1, 4))
    # the corrected entry A32 = 2 is Kutta's method: order exactly 3
    assert RK3.A[2] == (Fraction(-1), Fraction(2), Fraction(0))
    assert achieved_order(RK3.A, RK3.b) == 3


def test_printed_rk6_misprint():
    A, b = _exact(PRINTED_RK6_A), _exact_vec(PRINTED_RK6_B)
    # the shift keeps every row sum, so only the order conditions catch it
    assert [sum(row) for row in A] == _exact_vec(PRINTED_RK6_C)
    assert achieved_order(A, b) == 2
    tree, order, residual = first_failed_condition(A, b, 7)
    assert (tree_to_str(tree), order, residual) == ("[[t]]", 3, Fraction(7, 45))
    with pytest.raises(ValueError, match=r"fail the order-3 condition for tree \[\[t\]\]"):
        ButcherTableau("rk6_printed", PRINTED_RK6_A, PRINTED_RK6_B, PRINTED_RK6_C, 6)
    # corrected row 6 = (0, 9/8, -3/8, -3/4, 1/2, 0): order exactly 6 (not 4 as the
    # caption says, and not 7)
    assert RK6.A[5][:6] == tuple(_exact_vec(_vec("0 9/8 -3/8 -3/4 1/2 0")))
    assert achieved_order(RK6.A, RK6.b, max_order=8) == 6


# ---------------------------------------------------------------- construction rejects bad input

GOOD = dict(name="t", A=_lower("1/2"), b=_vec("0 1"), c=_vec("0 1/2"), order=2)


def _make(**changes):
    return ButcherTableau(**{**GOOD, **changes})


@pytest.mark.parametrize("changes,pattern", [
    (dict(A=(("0", "1/2"), ("1/2", "0"))), "not explicit"),
    (dict(A=(("1/2", "0"), ("0", "1/2")), c=_vec("1/2 1/2")), "not explicit"),
    (dict(c=_vec("0 1")), "row-sum condition fails at stage 1"),
    (dict(order=3), "claimed order=3 .* order-3 condition"),
    (dict(b=_vec("1/2 1/4")), r"sum\(b\) = 3/4 != 1"),
    (dict(A=(("0", "0"),)), "A must be square"),
    (dict(c=_vec("0 1/2 1")), "len\\(c\\)=3"),
    (dict(b=(0.0, 1.0)), "not an exact rational"),
    (dict(b_hat=_vec("1 0")), "b_hat and order_hat must be given together"),
    (dict(b_hat=_vec("1 0"), order_hat=2), "claimed order_hat=2"),
    (dict(b_hat=_vec("1 0 0"), order_hat=1), "len\\(b_hat\\)=3"),
    (dict(fsal=True), "fsal=True"),
    (dict(order=0), "order must be a positive int"),
    (dict(description="two\nlines"), "single line"),
])
def test_construction_rejects(changes, pattern):
    with pytest.raises(ValueError, match=pattern) as info:
        _make(**changes)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith("ButcherTableau 't'")


def test_construction_rejects_claimed_order_too_high_for_rk4():
    with pytest.raises(ValueError, match="order-5 condition"):
        dataclasses.replace(RK4, order=5)


def test_construction_accepts_mixed_exact_inputs():
    tab = _make(A=((0, 0), (Fraction(1, 2), 0)), b=(0, 1), c=(0, "1/2"),
                b_hat=("1", 0), order_hat=1)
    assert tab.A[1][0] == Fraction(1, 2) and tab.c == (0, Fraction(1, 2))
    np.testing.assert_array_equal(tab.e_f, [-1.0, 1.0])


# ---------------------------------------------------------------- float path vs exact path

_small_rationals = st.fractions(min_value=-2, max_value=2, max_denominator=12)


@settings(max_examples=25, deadline=None)
@given(st.integers(min_value=1, max_value=4).flatmap(
    lambda s: st.tuples(st.just(s), st.lists(_small_rationals, min_size=s * s + s,
                                             max_size=s * s + s))))
def test_float_residuals_match_exact(data):
    s, values = data
    A = [[values[i * s + j] if j < i else Fraction(0) for j in range(s)] for i in range(s)]
    b = values[s * s:]
    exact = order_condition_residuals(A, b, 5)
    floats = order_condition_residuals([[float(x) for x in row] for row in A],
                                       [float(x) for x in b], 5)
    for (t1, p1, r1), (t2, p2, r2) in zip(exact, floats):
        assert t1 == t2 and p1 == p2
        assert abs(float(r1) - r2) <= 1e-12 * (1 + abs(float(r1)))
