"""Order of a commutator-free or Crouch-Grossman scheme on a Lie group, from its local error.

The classical conditions of the collapsed tableau are necessary, not sufficient: on a
non-commutative group the products of exponentials must also reproduce the commutator
terms of the exact flow (Owren's conditions on ordered trees). Instead of enumerating the
trees, the local error is expanded in powers of ``h`` for one generic problem on ``GL(3)``,

    y' = A(y) y,   A(y) = D + (u . y) C1 + (v . y)^2 C2 + (w . y)^3 C3,

with fixed random matrices ``D, C1, C2, C3`` and vectors ``u, v, w`` (``y`` flattened), and a
random ``y0``. ``A`` has non-zero derivatives up to the third in generic directions and its
values do not commute, so every elementary differential of order <= 4 (the trees with
three branches included) enters the expansion with a generic coefficient: the scheme has
order ``p`` on Lie groups (up to 4) if and only if the coefficients of ``h^1 .. h^p`` of
the local error vanish (here: below :data:`TOL` relative to the solution's own
coefficients, which round-off of 16-digit coefficients respects by 4 orders).

Truncated power series in ``h`` with matrix coefficients, ``(P + 1, 3, 3)``, carry every
quantity: the exact flow by Picard iteration (exact to ``h^P`` after ``P`` sweeps), the
scheme's stages and step by the series of ``exp``.
"""

from __future__ import annotations

import numpy as np

from .series import series_exp as _exp
from .series import series_mul as _mul
from .series import series_scalar_mul as _scalar_mul

#: Relative size of a local-error coefficient that counts as zero.
TOL = 1e-10
#: Dimension of the test group GL(N) and the seed of its problem.
N, SEED = 3, 20240611


def _field(y: np.ndarray, prob: dict) -> np.ndarray:
    """``A(y)`` of a state series ``y``: a matrix series."""
    flat = y.reshape(y.shape[0], -1)
    lin, sq, cu = flat @ prob["u"], flat @ prob["v"], flat @ prob["w"]
    sq2 = _scalar_mul(sq, sq)
    cu3 = _scalar_mul(_scalar_mul(cu, cu), cu)
    out = lin[:, None, None] * prob["C"][0] + sq2[:, None, None] * prob["C"][1] + cu3[:, None, None] * prob["C"][2]
    out[0] += prob["D"]
    return out


def _h_times(a: np.ndarray) -> np.ndarray:
    """``h a``: the series shifted by one order."""
    out = np.zeros_like(a)
    out[1:] = a[:-1]
    return out


def _problem() -> dict:
    rng = np.random.default_rng(SEED)
    g = lambda *shape: rng.standard_normal(shape) / np.sqrt(N)  # noqa: E731
    return {"D": g(N, N), "C": g(3, N, N), "u": g(N * N), "v": g(N * N), "w": g(N * N),
            "y0": np.eye(N) + 0.3 * g(N, N)}


def exact_flow(prob: dict, order: int) -> np.ndarray:
    """Taylor series of ``y(h)`` to ``h^order``: Picard sweeps ``y <- y0 + int A(y) y``."""
    y = np.zeros((order + 1, N, N))
    y[0] = prob["y0"]
    for _ in range(order):
        rate = _mul(_field(y, prob), y)
        new = np.zeros_like(y)
        new[0] = prob["y0"]
        for k in range(order):
            new[k + 1] = rate[k] / (k + 1)
        y = new
    return y


def scheme_step(tab, prob: dict, order: int) -> np.ndarray:
    """Series of the scheme's step ``y1(h)`` (exponentials applied first row first)."""
    y0 = np.zeros((order + 1, N, N))
    y0[0] = prob["y0"]

    def apply(rows, F):
        y = y0
        for r in rows:
            e = sum(float(x) * F[j] for j, x in enumerate(r) if x != 0)
            if not isinstance(e, np.ndarray):
                continue
            y = _mul(_exp(e), y)
        return y

    F = []
    for i in range(len(tab.c)):
        F.append(_h_times(_field(apply(tab.stage_rows[i], F), prob)))
    return apply(tab.final_rows, F)


def local_error_orders(tab, order: int) -> np.ndarray:
    """Relative size of the local error's coefficients of ``h^0 .. h^order``: the largest
    entry of ``y1 - y(h)`` at each power over the largest of ``y(h)``'s at that power."""
    prob = _problem()
    exact = exact_flow(prob, order)
    diff = scheme_step(tab, prob, order) - exact
    scale = np.maximum(np.abs(exact).max(axis=(1, 2)), 1e-300)
    return np.abs(diff).max(axis=(1, 2)) / scale


def lie_order(tab, up_to: int = 4) -> int:
    """The order on Lie groups (at most ``up_to``): the largest ``p`` such that the local
    error's coefficients of ``h^1 .. h^p`` vanish."""
    defect = local_error_orders(tab, up_to)
    p = 0
    while p < up_to and defect[p + 1] <= TOL:
        p += 1
    return p
