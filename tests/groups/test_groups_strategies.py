"""Hypothesis strategies and helpers shared by the ``tests/groups`` property tests.

(Modelled on jaxlie's ``tests/utils.py``.) The module also tests the strategies
themselves, so a broken sampler cannot make the property tests pass vacuously.

Algebra elements are drawn in *regimes* that control the rotation angle of every
rotational sub-block (SO(3): the whole 3-vector; SE(3): the last 3 entries of
``(rho, theta)``; R^n: none; Product/Power: per factor, found with ``split_algebra``):

``generic``      angle in (1e-3, 3)
``small``        angle in 1e-8 .. 1e-6 (log-uniform); translations either O(1) or ~1e-7
``near_pi``      angle = pi - delta, delta in 1e-9 .. 1e-6 (log-uniform)
``pi``           angle exactly pi (up to the rounding of ``pi * unit vector``)
``near_pi_log``  angle = pi - delta, delta in 1e-4 .. 1e-3
``fd``           angle in (0.1, 3)        (finite-difference checks)
``series``       angle in [0, 1.99]       (Bernoulli series converge for |xi| < 2 pi)
``dexpinv``      angle in [0, pi - 0.1]
``mixed``        each block independently ``generic``, ``small`` or ``near_pi``

Translational entries (SE(3) ``rho``, R^n) are uniform in [-3, 3].
"""

from __future__ import annotations

import math

import hypothesis.extra.numpy as hnp
import hypothesis.strategies as st
import numpy as np
import pytest
from hypothesis import given, settings

from liegroup_int.groups import SE3, SO3, Power, Product, Rn
from liegroup_int.groups.base import LieGroup

# ---------------------------------------------------------------------------- groups
GROUPS: list[LieGroup] = [
    SO3,
    SE3,
    Rn(1),
    Rn(3),
    Product(SO3, Rn(3)),
    Product(SE3, SO3, Rn(2)),
    Power(SO3, 4),
    Power(SE3, 2),
]
GROUP_IDS = [G.name.replace(" ", "") for G in GROUPS]
MATRIX_GROUPS = [SO3, SE3]
MATRIX_GROUP_IDS = ["SO3", "SE3"]

BATCH = (2, 3)


def rotation_blocks(G: LieGroup) -> list[np.ndarray]:
    """Integer index arrays (length 3) of the rotation vectors inside G's flat algebra."""
    if G is SO3 or isinstance(G, type(SO3)):
        return [np.arange(3)]
    if G is SE3 or isinstance(G, type(SE3)):
        return [np.arange(3, 6)]
    if isinstance(G, Rn):
        return []
    if isinstance(G, Product):
        parts, factors = G.split_algebra(np.arange(G.dim, dtype=float)), G.factors
    elif isinstance(G, Power):
        parts, factors = list(G.split_algebra(np.arange(G.dim, dtype=float))), [G.group] * G.n
    else:  # pragma: no cover - new group types must be added here
        raise TypeError(f"no rotation-block rule for {G!r}")
    out = []
    for part, f in zip(parts, factors):
        idx = np.asarray(part).astype(int)
        out.extend(idx[b] for b in rotation_blocks(f))
    return out


def translation_indices(G: LieGroup) -> np.ndarray:
    blocks = rotation_blocks(G)
    rot = np.concatenate(blocks) if blocks else np.zeros(0, dtype=int)
    return np.setdiff1d(np.arange(G.dim), rot)


def block_angles(G: LieGroup, xi: np.ndarray) -> np.ndarray:
    """Norms of the rotation blocks, shape ``(..., n_blocks)``."""
    xi = np.asarray(xi)
    blocks = rotation_blocks(G)
    if not blocks:
        return np.zeros(xi.shape[:-1] + (0,))
    return np.stack([np.linalg.norm(xi[..., b], axis=-1) for b in blocks], axis=-1)


# ------------------------------------------------------------------------ strategies
def _log_uniform(lo: float, hi: float) -> st.SearchStrategy[float]:
    return st.floats(math.log10(lo), math.log10(hi)).map(lambda e: 10.0**e)


ANGLES: dict[str, st.SearchStrategy[float]] = {
    "generic": st.floats(1e-3, 3.0),
    "small": _log_uniform(1e-8, 1e-6),
    "near_pi": _log_uniform(1e-9, 1e-6).map(lambda d: math.pi - d),
    "pi": st.just(math.pi),
    "near_pi_log": _log_uniform(1e-4, 1e-3).map(lambda d: math.pi - d),
    "fd": st.floats(0.1, 3.0),
    "series": st.floats(0.0, 1.99),
    "dexpinv": st.floats(0.0, math.pi - 0.1),
}
MIXABLE = ("generic", "small", "near_pi")

unit_vectors = (
    st.tuples(*[st.floats(-1.0, 1.0)] * 3)
    .map(np.array)
    .filter(lambda v: np.linalg.norm(v) > 0.1)
    .map(lambda v: v / np.linalg.norm(v))
)


@st.composite
def algebra(draw, G: LieGroup, regime: str = "generic", batch_shape: tuple[int, ...] = ()):
    """Algebra elements of G, shape ``batch_shape + (G.dim,)``, in the given regime."""
    n = int(np.prod(batch_shape, dtype=int))
    blocks = rotation_blocks(G)
    trans = translation_indices(G)
    out = np.empty((n, G.dim))
    for i in range(n):
        tscale = draw(st.sampled_from([1.0, 1e-7])) if regime == "small" else 1.0
        out[i, trans] = tscale * np.array(
            draw(st.lists(st.floats(-3.0, 3.0), min_size=len(trans), max_size=len(trans))), dtype=float
        )
        for b in blocks:
            reg = draw(st.sampled_from(MIXABLE)) if regime == "mixed" else regime
            out[i, b] = draw(ANGLES[reg]) * draw(unit_vectors)
    return out.reshape(tuple(batch_shape) + (G.dim,))


def points(G: LieGroup, batch_shape: tuple[int, ...] = (), regimes=("generic", "small", "near_pi", "pi")):
    """Group elements ``exp(xi)`` with xi drawn in one of ``regimes``."""
    return st.sampled_from(regimes).flatmap(lambda r: algebra(G, r, batch_shape)).map(G.exp)


def tangents(G: LieGroup, batch_shape: tuple[int, ...] = ()):
    """Arbitrary algebra directions, entries in [-1, 1] (no regime structure)."""
    return hnp.arrays(float, tuple(batch_shape) + (G.dim,), elements=st.floats(-1.0, 1.0))


def act_points(G: LieGroup, batch_shape: tuple[int, ...] = ()):
    """Points of the space G acts on (``G.act_shape``): 3-vectors for SO3/SE3, n-vectors
    for R^n, ``(N, *)`` stacks for ``Power`` and flat concatenations for ``Product``."""
    if isinstance(G, Product):
        return hnp.arrays(float, tuple(batch_shape) + G.act_shape, elements=st.floats(-3.0, 3.0))
    if isinstance(G, Power):
        return act_points(G.group, tuple(batch_shape) + (G.n,))
    n = G.n if isinstance(G, Rn) else 3
    return hnp.arrays(float, tuple(batch_shape) + (n,), elements=st.floats(-3.0, 3.0))


# --------------------------------------------------------------------------- helpers
def flat(x) -> np.ndarray:
    """Concatenate a (possibly nested) tuple of arrays into one 1-D array."""
    if isinstance(x, tuple):
        return np.concatenate([flat(p) for p in x]) if x else np.zeros(0)
    return np.ravel(np.asarray(x, dtype=float))


def index(x, i):
    """``x[i]`` for an array or a tuple of arrays (as ``Product.act`` uses)."""
    if isinstance(x, tuple):
        return tuple(index(p, i) for p in x)
    return np.asarray(x)[i]


def max_error(actual, expected, scale: float | None = None) -> float:
    """``max|actual - expected| / max(1, max|expected|)`` (mixed abs/rel error).

    Points and algebra elements mix O(1) rotation entries with translations up to
    ~5; dividing by ``max(1, |expected|)`` makes one tolerance mean "so many ulps of
    the largest entry" for both.
    """
    a, e = flat(actual), flat(expected)
    assert a.shape == e.shape, (np.shape(actual), np.shape(expected))
    if a.size == 0:
        return 0.0
    s = max(1.0, float(np.max(np.abs(e)))) if scale is None else scale
    return float(np.max(np.abs(a - e))) / s


def assert_close(actual, expected, tol: float, scale: float | None = None, msg: str = ""):
    assert np.shape(flat(actual)) == np.shape(flat(expected))
    if not isinstance(actual, tuple):
        assert np.shape(actual) == np.shape(expected), (np.shape(actual), np.shape(expected))
    err = max_error(actual, expected, scale)
    assert np.all(np.isfinite(flat(actual))), f"non-finite result {msg}"
    assert err <= tol, f"error {err:.3e} > tol {tol:.1e} {msg}"


# ------------------------------------------------------------- tests of the samplers
group_params = pytest.mark.parametrize("G", GROUPS, ids=GROUP_IDS)

EXPECTED_BLOCKS = {
    "SO3": [[0, 1, 2]],
    "SE3": [[3, 4, 5]],
    "R1": [],
    "R3": [],
    "SO3xR3": [[0, 1, 2]],
    "SE3xSO3xR2": [[3, 4, 5], [6, 7, 8]],
    "SO3^4": [[0, 1, 2], [3, 4, 5], [6, 7, 8], [9, 10, 11]],
    "SE3^2": [[3, 4, 5], [9, 10, 11]],
}


@group_params
def test_rotation_blocks_found_through_split_algebra(G):
    gid = G.name.replace(" ", "")
    assert [list(b) for b in rotation_blocks(G)] == EXPECTED_BLOCKS[gid]


BOUNDS = {
    "generic": (1e-3, 3.0),
    "small": (1e-8, 1e-6),
    "near_pi": (math.pi - 1e-6, math.pi - 1e-9),
    "pi": (math.pi, math.pi),
    "near_pi_log": (math.pi - 1e-3, math.pi - 1e-4),
    "fd": (0.1, 3.0),
    "series": (0.0, 1.99),
    "dexpinv": (0.0, math.pi - 0.1),
}


@group_params
@pytest.mark.parametrize("regime", list(BOUNDS))
@settings(max_examples=max(5, settings.default.max_examples // 4))  # 64 cheap parametrizations
@given(data=st.data())
def test_algebra_strategy_respects_regime(G, regime, data):
    xi = data.draw(algebra(G, regime, BATCH))
    assert xi.shape == BATCH + (G.dim,)
    lo, hi = BOUNDS[regime]
    ang = block_angles(G, xi)
    # 1e-15 relative: the angle is |angle * unit vector| up to a few ulps
    assert np.all(ang >= lo * (1 - 1e-15)) and np.all(ang <= hi * (1 + 1e-15)), ang
    # rotation_angle() is the largest rotation block (0 without rotations)
    expected = ang.max(axis=-1) if ang.shape[-1] else np.zeros(BATCH)
    np.testing.assert_allclose(G.rotation_angle(xi), expected, rtol=1e-15, atol=0)
