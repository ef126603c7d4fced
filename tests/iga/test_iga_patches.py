"""PatchedSpace (chains of collocation patches) and split_curve."""

import numpy as np
import pytest

from liegroup_int.iga import CollocationSpace, arc_nurbs_quadratic, k_refine, straight
from liegroup_int.iga.patches import PatchedSpace, split_curve


def _frame():
    return PatchedSpace([CollocationSpace(straight(10.0, (1, 0, 0), 4, 9)),
                         CollocationSpace(straight(5.0, (0, 1, 0), 3, 7, origin=(10, 0, 0)))])


def test_blocks_joints_and_solve():
    sp = _frame()
    assert sp.n_ctrl == 16 and sp.offsets == (0, 9, 16) and sp.joints == ((8, 9),)
    assert sp.length == pytest.approx(15.0, rel=1e-12)
    # block-diagonal: no coupling between the patches' rows and columns
    assert not np.any(sp.N0[:9, 9:]) and not np.any(sp.N1[9:, :9])
    rhs = np.random.default_rng(0).standard_normal((16, 4))
    assert np.allclose(sp.N0 @ sp.solve(rhs), rhs, atol=1e-13)
    # the joint appears in both patches at the same place
    assert np.allclose(sp.c0[8], sp.c0[9], atol=1e-14)
    assert sp.s_c[8] == pytest.approx(10.0) and sp.s_c[9] == pytest.approx(10.0)


def test_global_parameter_follows_length():
    sp = _frame()
    u = np.linspace(0.0, 1.0, 31)
    x = sp.point_matrix(u) @ sp.control_points
    s = sp.arc_length(u)
    assert np.allclose(s, 15.0 * u, atol=1e-10)  # straight patches parametrized by length
    expect = np.where(u[:, None] <= 2 / 3, np.outer(15 * u, [1, 0, 0]), [10, 0, 0] + np.outer(15 * u - 10, [0, 1, 0]))
    assert np.allclose(x, expect, atol=1e-12)


def test_patches_must_meet():
    with pytest.raises(ValueError, match="joined ends must coincide"):
        PatchedSpace([CollocationSpace(straight(1.0, (1, 0, 0), 3, 6)),
                      CollocationSpace(straight(1.0, (0, 1, 0), 3, 6, origin=(1.0, 0.1, 0)))])


@pytest.mark.parametrize("u", [0.3, 0.5, 0.77])
def test_split_curve_reproduces_the_curve(u):
    curve = k_refine(arc_nurbs_quadratic(2, 3), 4, 12)
    left, right = split_curve(curve, u)
    t = np.linspace(0.0, 1.0, 41)
    assert np.allclose(left.evaluate(t, 0)[0], curve.evaluate(u * t, 0)[0], atol=1e-13)
    assert np.allclose(right.evaluate(t, 0)[0], curve.evaluate(u + (1 - u) * t, 0)[0], atol=1e-13)
    with pytest.raises(ValueError, match="split parameter"):
        split_curve(curve, 1.0)


def test_explicit_joints_any_ends():
    """A T of three patches: explicit joints to one first end (rows of each pair, kinds),
    the chain-contact check skipped, and one-line errors for ends that do not meet, an end
    joined twice and an unknown kind."""
    post = CollocationSpace(straight(1.0, (0, 0, 1), 3, 6))
    left = CollocationSpace(straight(0.5, (-1, 0, 0), 3, 5, origin=(0, 0, 1)))
    right = CollocationSpace(straight(0.5, (1, 0, 0), 3, 5, origin=(0, 0, 1)))
    pairs = [((0, "end"), (1, "start")), ((0, "end"), (2, "start"))]
    sp = PatchedSpace([post, left, right], joints=pairs, kinds=["rigid", "ball"])
    assert not sp.chain and sp.joints == ((5, 6), (5, 11)) and sp.joint_kinds == ("rigid", "ball")
    with pytest.raises(ValueError, match="joined ends must coincide"):  # the chain: left's end is not right's start
        PatchedSpace([post, left, right])
    with pytest.raises(ValueError, match=r"patch end \(1, 'end'\) at \[-0.5, 0.0, 1.0\] and \(2, 'end'\) .* must coincide"):
        PatchedSpace([post, left, right], joints=[((1, "end"), (2, "end"))])
    with pytest.raises(ValueError, match=r"joint 2: patch end \(1, 'start'\) is joined twice"):
        PatchedSpace([post, left, right], joints=[pairs[0], ((2, "start"), (1, "start"))])
    with pytest.raises(ValueError, match="kinds: one of rigid, ball, hinge per joint"):
        PatchedSpace([post, left, right], joints=pairs, kinds=["rigid", "slider"])
    with pytest.raises(ValueError, match=r"joint 2: a hinge needs a finite non-zero axis"):
        PatchedSpace([post, left, right], joints=pairs, kinds=["rigid", "hinge"])
    sp = PatchedSpace([post, left, right], joints=pairs, kinds=["rigid", "hinge"], axes=[None, (0, 2, 0)],
                      springs=[(0, 0), (3.0, 0.5)])
    assert sp.joint_axes[0] is None and np.array_equal(sp.joint_axes[1], [0.0, 1.0, 0.0])
    assert sp.joint_springs == ((0.0, 0.0), (3.0, 0.5))
    with pytest.raises(ValueError, match=r"joint 2: spring stiffness and damping must be finite and >= 0"):
        PatchedSpace([post, left, right], joints=pairs, kinds=["rigid", "hinge"], axes=[None, (0, 1, 0)],
                     springs=[(0, 0), (-1.0, 0.0)])
