"""Symmetric compositions of a symmetric second-order method, checked on construction.

A composition with coefficients ``gamma_1 .. gamma_s`` (a palindrome) steps by
``Phi_{gamma_s h} o ... o Phi_{gamma_1 h}``, with ``Phi`` a symmetric method of order 2 (for
mechanical systems a Strang splitting into exactly integrable flows: symplectic, and so is
the composition). Its order is that of the coefficients (Yoshida 1990; McLachlan 1995).

The check does not enumerate the conditions. A symmetric method's step is the exponential
of ``h A + h^3 B + h^5 C + O(h^7)`` with ``A`` the exact vector field; for generic
non-commuting ``A, B, C`` (random 3 x 3 matrices, fixed seed) the composition's error
against ``exp(h A)`` vanishes through ``h^p`` if and only if the coefficients satisfy the
order-``p`` conditions of symmetric compositions (through order 6 they involve ``A``,
``B``, ``C`` and their commutators only). The expansion runs on truncated matrix series
(:mod:`.series`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np

from .series import series_exp, series_mul

#: Relative size of an error coefficient that counts as zero: coefficients given to 15 digits
#: leave up to 4e-11 (Yoshida6 at h^6); a coefficient off by 1e-6 leaves 3e-5.
TOL = 1e-9
#: Highest order the generic check can confirm (the base method's log is generic through h^5).
MAX_CHECKED_ORDER = 6
_SEED = 20261202


def _coefficient(x) -> float:
    if isinstance(x, str) and "/" in x:
        return float(Fraction(x))
    return float(x)


def composition_error(gammas, order: int) -> np.ndarray:
    """Relative size of the coefficients of ``h^0 .. h^(order+1)`` of the composition's error
    against ``exp(h A)``, for the generic symmetric base method of the module docstring."""
    P = order + 1
    rng = np.random.default_rng(_SEED)
    A, B, C = (rng.standard_normal((3, 3)) / np.sqrt(3) for _ in range(3))
    step = np.eye(3)[None].repeat(P + 1, axis=0) * (np.arange(P + 1) == 0)[:, None, None]
    for g in gammas:
        log = np.zeros((P + 1, 3, 3))
        for k, M in ((1, A), (3, B), (5, C)):
            if k <= P:
                log[k] = g**k * M
        step = series_mul(series_exp(log), step)
    log = np.zeros((P + 1, 3, 3))
    log[1] = A
    exact = series_exp(log)
    scale = np.maximum(np.abs(exact).max(axis=(1, 2)), 1e-300)
    return np.abs(step - exact).max(axis=(1, 2)) / scale


@dataclass(frozen=True)
class Composition:
    """A symmetric composition ``gamma_1 .. gamma_s`` of a symmetric second-order method.

    Parameters
    ----------
    name : str
        Registry name, the ``method=`` of :func:`~liegroup_int.integrate`.
    gammas : sequence
        The coefficients (ints, ``'p/q'`` strings or decimals): a palindrome summing to 1.
    order : int
        Claimed order (even, at most :data:`MAX_CHECKED_ORDER`).
    description : str
        One line with the literature source.
    """

    name: str
    gammas: tuple
    order: int
    description: str = ""
    #: the coefficients as floats ``(s,)``
    gammas_f: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        g = np.array([_coefficient(x) for x in self.gammas])
        g.setflags(write=False)
        object.__setattr__(self, "gammas_f", g)
        self._check()

    @property
    def stages(self) -> int:
        """Base steps per step."""
        return len(self.gammas)

    def _fail(self, message: str):
        raise ValueError(f"Composition {self.name!r}: {message}")

    def _check(self) -> None:
        g = self.gammas_f
        if g.size == 0:
            self._fail("no coefficients")
        if not np.allclose(g, g[::-1], rtol=0.0, atol=1e-15):
            self._fail("the coefficients are not a palindrome (the composition would not be symmetric)")
        if abs(g.sum() - 1.0) > 1e-14:
            self._fail(f"the coefficients sum to {g.sum()!r}, not 1")
        if not (isinstance(self.order, int) and self.order >= 2 and self.order % 2 == 0
                and self.order <= MAX_CHECKED_ORDER):
            self._fail(f"order must be 2, 4 or 6 (symmetric compositions have even order), got {self.order!r}")
        err = composition_error(g, self.order)
        bad = [k for k in range(1, self.order + 1) if err[k] > TOL]
        if bad:
            self._fail(f"claimed order {self.order} but its error has an h^{bad[0]} term (relative size "
                       f"{err[bad[0]]:.2g}): the coefficients miss the order-{bad[0]} conditions")


_Y4 = 1.0 / (2.0 - 2.0 ** (1.0 / 3.0))
STRANG = Composition("strang", (1,), 2, "The symmetric splitting itself (Strang 1968): order 2.")
YOSHIDA4 = Composition(
    "yoshida4", (repr(_Y4), repr(1.0 - 2.0 * _Y4), repr(_Y4)), 4,
    "Triple jump: gamma = 1 / (2 - 2^(1/3)) (Yoshida 1990, Phys. Lett. A 150; Suzuki 1990): order 4.")
_W = (-1.17767998417887, 0.235573213359357, 0.784513610477560)
YOSHIDA6 = Composition(
    "yoshida6", tuple(repr(x) for x in (*_W[::-1], 1.0 - 2.0 * sum(_W), *_W)), 6,
    "Seven stages, solution A of Yoshida (1990, Phys. Lett. A 150, table 1): order 6.")

#: The compositions by name.
COMPOSITIONS: dict[str, Composition] = {c.name: c for c in (STRANG, YOSHIDA4, YOSHIDA6)}
