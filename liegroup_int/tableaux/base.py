"""Explicit Butcher tableaux as exact, self-checking data."""

from __future__ import annotations

import numbers
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Sequence

import numpy as np

from .order_conditions import first_failed_condition, tree_to_str


def _to_fraction(value, name: str, what: str) -> Fraction:
    """Convert an exact rational (Fraction, int or ``'p/q'`` string) to Fraction."""
    if isinstance(value, bool):
        raise ValueError(f"ButcherTableau {name!r}: {what} entry {value!r} is a bool")
    if isinstance(value, numbers.Integral):
        return Fraction(int(value))
    if isinstance(value, numbers.Rational):
        return Fraction(value.numerator, value.denominator)
    if isinstance(value, str):
        try:
            return Fraction(value)
        except ValueError:
            pass
    raise ValueError(
        f"ButcherTableau {name!r}: {what} entry {value!r} is not an exact rational "
        "(use int, Fraction or a 'p/q' string)")


def _vector(values, name: str, what: str) -> tuple[Fraction, ...]:
    return tuple(_to_fraction(v, name, what) for v in values)


def _readonly(array: np.ndarray) -> np.ndarray:
    array.setflags(write=False)
    return array


@dataclass(frozen=True)
class ButcherTableau:
    """Explicit Runge-Kutta tableau with exact rational coefficients.

    Construction validates the data and raises :class:`ValueError` (one-line
    message naming the tableau and the failed check) unless: ``A`` is square
    and strictly lower triangular, ``b``/``c``/``b_hat`` have ``s`` entries,
    ``c_i == sum_j A_ij`` exactly, ``sum(b) == 1``, every order condition up to
    ``order`` holds exactly for ``b`` and up to ``order_hat`` for ``b_hat``,
    and (if ``fsal``) the last row of ``A`` equals ``b``.

    Parameters
    ----------
    name : str
        Registry name.
    A : sequence of sequences
        ``(s, s)`` coefficients; entries Fraction, int or ``'p/q'`` strings
        (floats are rejected: they are not exact).  Stored as a tuple of
        tuples of Fractions.
    b : sequence
        ``(s,)`` weights of the propagated solution.
    c : sequence
        ``(s,)`` nodes.
    order : int
        Claimed order of ``b``.
    b_hat : sequence, optional
        Embedded weights (error estimator).
    order_hat : int, optional
        Claimed order of ``b_hat``; required iff ``b_hat`` is given.
    fsal : bool, default False
        First-same-as-last property (last stage equals the next first stage).
    description : str
        One line, including the literature source.
    method : str, optional
        The RKMK method name that scenes, the CLI and ``integrate`` use for this tableau
        (``"rkmk4"``); the tableau's own ``name`` is accepted too (``resolve``).

    Attributes
    ----------
    A_f, b_f, c_f : numpy.ndarray
        Read-only float64 copies of ``A`` ``(s, s)``, ``b`` and ``c`` ``(s,)``.
    b_hat_f : numpy.ndarray or None
        Float embedded weights.
    e_f : numpy.ndarray or None
        Error weights ``b_f - b_hat_f``.
    """

    name: str
    A: tuple[tuple[Fraction, ...], ...]
    b: tuple[Fraction, ...]
    c: tuple[Fraction, ...]
    order: int
    b_hat: tuple[Fraction, ...] | None = None
    order_hat: int | None = None
    fsal: bool = False
    description: str = ""
    method: str = ""
    A_f: np.ndarray = field(init=False, repr=False, compare=False)
    b_f: np.ndarray = field(init=False, repr=False, compare=False)
    c_f: np.ndarray = field(init=False, repr=False, compare=False)
    b_hat_f: np.ndarray | None = field(init=False, repr=False, compare=False)
    e_f: np.ndarray | None = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        name = self.name
        A = tuple(_vector(row, name, "A") for row in self.A)
        b = _vector(self.b, name, "b")
        c = _vector(self.c, name, "c")
        b_hat = None if self.b_hat is None else _vector(self.b_hat, name, "b_hat")
        object.__setattr__(self, "A", A)
        object.__setattr__(self, "b", b)
        object.__setattr__(self, "c", c)
        object.__setattr__(self, "b_hat", b_hat)
        self._check()
        object.__setattr__(self, "A_f", _readonly(np.array(
            [[float(x) for x in row] for row in A], dtype=float).reshape(len(b), len(b))))
        object.__setattr__(self, "b_f", _readonly(np.array([float(x) for x in b])))
        object.__setattr__(self, "c_f", _readonly(np.array([float(x) for x in c])))
        if b_hat is None:
            object.__setattr__(self, "b_hat_f", None)
            object.__setattr__(self, "e_f", None)
        else:
            b_hat_f = _readonly(np.array([float(x) for x in b_hat]))
            e_f = _readonly(np.array([float(x - y) for x, y in zip(b, b_hat)]))
            object.__setattr__(self, "b_hat_f", b_hat_f)
            object.__setattr__(self, "e_f", e_f)

    @property
    def stages(self) -> int:
        """Number of stages ``s``."""
        return len(self.b)

    @property
    def has_embedded(self) -> bool:
        """Whether embedded weights ``b_hat`` are present."""
        return self.b_hat is not None

    def _fail(self, message: str) -> None:
        raise ValueError(f"ButcherTableau {self.name!r}: {message}")

    def _check(self) -> None:
        """Run all structural and order checks (see class docstring)."""
        A, b, c, s = self.A, self.b, self.c, len(self.b)
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"ButcherTableau name must be a non-empty str, got {self.name!r}")
        if "\n" in self.description:
            self._fail("description must be a single line")
        if s == 0:
            self._fail("empty tableau (b has no entries)")
        if len(A) != s or any(len(row) != s for row in A):
            self._fail(f"A must be square ({s}x{s}) to match len(b)={s}, "
                       f"got row lengths {[len(row) for row in A]}")
        if len(c) != s:
            self._fail(f"len(c)={len(c)} does not match stages s={s}")
        if self.b_hat is not None and len(self.b_hat) != s:
            self._fail(f"len(b_hat)={len(self.b_hat)} does not match stages s={s}")
        if (self.b_hat is None) != (self.order_hat is None):
            self._fail("b_hat and order_hat must be given together")
        for i in range(s):
            for j in range(i, s):
                if A[i][j] != 0:
                    self._fail(f"not explicit: A[{i}][{j}] = {A[i][j]} (A must be "
                               "strictly lower triangular)")
        for i in range(s):
            if sum(A[i]) != c[i]:
                self._fail(f"row-sum condition fails at stage {i}: "
                           f"c[{i}] = {c[i]} but sum_j A[{i}][j] = {sum(A[i])}")
        if sum(b) != 1:
            self._fail(f"sum(b) = {sum(b)} != 1 (not consistent)")
        self._check_order(b, self.order, "b", "order")
        if self.b_hat is not None:
            self._check_order(self.b_hat, self.order_hat, "b_hat", "order_hat")
        if self.fsal and (A[-1] != b or c[-1] != 1):
            self._fail("fsal=True requires the last row of A to equal b and c[-1] = 1")

    def _check_order(self, weights, order, label: str, order_label: str) -> None:
        if isinstance(order, bool) or not isinstance(order, numbers.Integral) or order < 1:
            self._fail(f"{order_label} must be a positive int, got {order!r}")
        failed = first_failed_condition(self.A, weights, int(order))
        if failed is not None:
            tree, tree_ord, residual = failed
            self._fail(f"claimed {order_label}={order} but weights {label} fail the "
                       f"order-{tree_ord} condition for tree {tree_to_str(tree)} "
                       f"(Phi - 1/gamma = {residual})")

    def summary(self) -> str:
        """Multi-line human-readable tableau ``c | A`` over ``b`` (and ``b_hat``)."""
        def fmt(values: Sequence[Fraction]) -> str:
            return " ".join(f"{str(x):>12}" for x in values)

        lines = [f"{self.name}: order {self.order}, {self.stages} stages"]
        for i, row in enumerate(self.A):
            lines.append(f"{str(self.c[i]):>8} | {fmt(row[:i])}")
        lines.append(f"{'b':>8} | {fmt(self.b)}")
        if self.b_hat is not None:
            lines.append(f"{'b_hat':>8} | {fmt(self.b_hat)}")
        return "\n".join(lines)
