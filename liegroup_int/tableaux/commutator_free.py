"""Commutator-free and Crouch-Grossman schemes: several exponentials per stage, no dexpinv.

A scheme with ``s`` stages is given by nodes ``c``, for each stage ``i`` a sequence of
weight rows ``alpha_i^1, ..., alpha_i^{J_i}`` (each ``(s,)``, zero from column ``i`` on), and
final rows ``beta^1, ..., beta^J``. With ``F_j = h f(t + c_j h, Y_j)``:

    Y_i     = exp(sum_j alpha_i^{J_i}_j F_j) ... exp(sum_j alpha_i^1_j F_j) . y_n
    y_{n+1} = exp(sum_j beta^J_j F_j) ... exp(sum_j beta^1_j F_j) . y_n

(row 1 is applied first). Crouch-Grossman methods are the case of one ``F_j`` per
exponential; on R^n every such scheme is the Runge-Kutta method with the *collapsed*
coefficients ``A_ij = sum_k alpha_i^k_j`` and ``b_j = sum_k beta^k_j``.

Checks on construction (``ValueError`` naming the scheme and the failed check):
explicitness and shapes; ``c_i = sum_j A_ij``; every classical order condition of the
collapsed tableau up to the claimed order (exactly for rational coefficients, to 1e-14
for coefficients given in decimals); from order 3 on, the condition that makes the
product of the final exponentials match the Magnus expansion at ``h^3`` for
``y' = (A_0 + t A_1) y`` (non-commuting ``A_0, A_1``):
``sum_{k < l} (beta^l . 1)(beta^k . c) - (beta^k . 1)(beta^l . c) = -1/6``; then the
order on Lie groups up to 4, from the local error's expansion in ``h`` on a generic
problem on GL(3) (:mod:`.lie_order`: equivalent to Owren's conditions on ordered trees up
to order 4). Orders above 4 rest on the classical conditions and measured slopes
(``tests/integrators/test_integrators_commutator_free.py``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np

from .lie_order import lie_order, local_error_orders
from .order_conditions import order_condition_residuals, tree_to_str

#: Tolerance of the checks for schemes given in decimals (CG4a: 16 digits).
DECIMAL_TOL = 1e-14


def _num(x):
    """Exact Fraction from an int, Fraction or ``'p/q'`` string; float from a decimal string."""
    if isinstance(x, (int, Fraction)):
        return Fraction(x)
    if isinstance(x, str) and ("." in x or "e" in x.lower()):
        return float(x)
    if isinstance(x, str):
        return Fraction(x)
    raise ValueError(f"coefficient {x!r}: expected an int, a Fraction or a string")


@dataclass(frozen=True)
class CommutatorFreeTableau:
    """A commutator-free (or Crouch-Grossman) Lie group scheme, checked on construction.

    Parameters
    ----------
    name, method : str
        Registry name and the method name scenes, the CLI and ``integrate`` use.
    c : sequence
        ``(s,)`` nodes.
    stage_rows : sequence of sequences of sequences
        For each stage, its exponentials' weight rows (each ``(s,)``), first applied first;
        the first stage has none.
    final_rows : sequence of sequences
        The final exponentials' weight rows, first applied first.
    order : int
        Claimed order.
    description : str
        One line with the literature source.
    """

    name: str
    method: str
    c: tuple
    stage_rows: tuple
    final_rows: tuple
    order: int
    description: str = ""
    #: the collapsed Runge-Kutta coefficients ``sum_k alpha_i^k_j`` and ``sum_k beta^k_j``
    #: (Fractions; decimals as the exact value of their float): the scheme's linear
    #: stability, since on R^n it is this Runge-Kutta method
    A: tuple = field(init=False, repr=False, compare=False)
    b: tuple = field(init=False, repr=False, compare=False)
    #: the same as floats, ``(s, s)`` and ``(s,)``
    A_f: np.ndarray = field(init=False, repr=False, compare=False)
    b_f: np.ndarray = field(init=False, repr=False, compare=False)
    c_f: np.ndarray = field(init=False, repr=False, compare=False)
    #: float weight rows: per stage ``(J_i, s)``, final ``(J, s)``
    stage_rows_f: tuple = field(init=False, repr=False, compare=False)
    final_rows_f: np.ndarray = field(init=False, repr=False, compare=False)

    kind = "commutator_free"
    b_hat = None
    order_hat = None
    fsal = False

    def __post_init__(self):
        conv = lambda rows: tuple(tuple(_num(x) for x in r) for r in rows)  # noqa: E731
        c = tuple(_num(x) for x in self.c)
        stages = tuple(conv(rows) for rows in self.stage_rows)
        final = conv(self.final_rows)
        object.__setattr__(self, "c", c)
        object.__setattr__(self, "stage_rows", stages)
        object.__setattr__(self, "final_rows", final)
        A_raw, b_raw = self._check()
        A = tuple(tuple(Fraction(x) for x in row) for row in A_raw)
        b = tuple(Fraction(x) for x in b_raw)
        object.__setattr__(self, "A", A)
        object.__setattr__(self, "b", b)
        for name, arr in (("A_f", np.array([[float(x) for x in row] for row in A])),
                          ("b_f", np.array([float(x) for x in b])), ("c_f", np.array([float(x) for x in c]))):
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)
        rows_f = tuple(np.array([[float(x) for x in r] for r in rows]).reshape(len(rows), len(c)) for rows in stages)
        object.__setattr__(self, "stage_rows_f", rows_f)
        object.__setattr__(self, "final_rows_f", np.array([[float(x) for x in r] for r in final]))

    @property
    def stages(self) -> int:
        return len(self.c)

    @property
    def exact(self) -> bool:
        every = [*self.c, *(x for rows in self.stage_rows for r in rows for x in r),
                 *(x for r in self.final_rows for x in r)]
        return all(isinstance(x, Fraction) for x in every)

    @property
    def exponentials(self) -> int:
        """Exponentials (actions) per step, the final ones included."""
        return sum(len(rows) for rows in self.stage_rows) + len(self.final_rows)

    def _fail(self, message: str):
        raise ValueError(f"CommutatorFreeTableau {self.name!r}: {message}")

    def _close(self, residual) -> bool:
        return residual == 0 if isinstance(residual, Fraction) else abs(residual) <= DECIMAL_TOL

    def _check(self):
        """Run the checks (see the module docstring); return the collapsed ``A, b`` as given
        (Fractions, or floats for decimal coefficients)."""
        c, stages, final = self.c, self.stage_rows, self.final_rows
        s = len(c)
        if s == 0 or len(stages) != s:
            self._fail(f"expected stage rows for each of the {s} stages, got {len(stages)}")
        if stages[0]:
            self._fail("the first stage is y_n itself: it takes no exponentials")
        for i, rows in enumerate(stages):
            for r in rows:
                if len(r) != s:
                    self._fail(f"stage {i}: a row has {len(r)} weights, expected {s}")
                if any(x != 0 for x in r[i:]):
                    self._fail(f"stage {i}: not explicit (weights on stages >= {i})")
            if not self._close(sum((sum(r) for r in rows), Fraction(0)) - c[i]):
                self._fail(f"stage {i}: the weights sum to {sum(sum(r) for r in rows)}, not c[{i}] = {c[i]}")
        if not final or any(len(r) != s for r in final):
            self._fail(f"final rows: expected one or more rows of {s} weights")
        A = [[sum((r[j] for r in stages[i]), Fraction(0)) for j in range(s)] for i in range(s)]
        b = [sum((r[j] for r in final), Fraction(0)) for j in range(s)]
        if not (isinstance(self.order, int) and self.order >= 1):
            self._fail(f"order must be a positive int, got {self.order!r}")
        for tree, k, res in order_condition_residuals(A, b, self.order):
            if not self._close(res):
                self._fail(f"claimed order {self.order} but the collapsed tableau fails the order-{k} condition "
                           f"for tree {tree_to_str(tree)} (residual {res})")
        if self.order >= 3:
            ones = [sum(r) for r in final]
            cs = [sum(x * cj for x, cj in zip(r, c)) for r in final]
            comm = sum(ones[l2] * cs[k] - ones[k] * cs[l2] for k in range(len(final)) for l2 in range(k + 1, len(final)))
            if not self._close(comm - Fraction(-1, 6)):
                self._fail(f"claimed order {self.order} but the final exponentials miss the h^3 Magnus term "
                           f"(sum = {comm}, expected -1/6)")
        self._check_lie_order(min(self.order, 4))
        return A, b

    def _check_lie_order(self, order: int) -> None:
        """The local error on a generic Lie-group problem vanishes through ``h^order``."""
        p = lie_order(self, order)
        if p < order:
            size = local_error_orders(self, order)[p + 1]
            self._fail(f"claimed order {self.order} but on a Lie group its local error has an h^{p + 1} term "
                       f"(relative size {size:.2g} on the generic GL(3) problem): it fails the order-{p + 1} "
                       "conditions of commutator-free schemes, though its collapsed tableau passes")


def _cg(name, method, c, A_rows, b, order, description):
    """A Crouch-Grossman scheme from its Butcher-like data: stage ``i`` takes the
    exponentials of ``a_ij F_j`` for ``j = 1 .. i-1`` in turn, the step those of ``b_j F_j``."""
    s = len(c)

    def unit(j, w):
        r = ["0"] * s
        r[j] = w
        return tuple(r)

    stages = [()] + [tuple(unit(j, w) for j, w in enumerate(row)) for row in A_rows]
    final = tuple(unit(j, w) for j, w in enumerate(b))
    return CommutatorFreeTableau(name, method, tuple(c), tuple(stages), final, order, description)


CF3 = CommutatorFreeTableau(
    name="cf3", method="cf3", c=("0", "1/3", "2/3"),
    stage_rows=((), (("1/3", "0", "0"),), (("0", "2/3", "0"),)),
    final_rows=(("1/3", "0", "0"), ("-1/12", "0", "3/4")),
    order=3,
    description="Commutator-free method of order 3, 3 stages, 2 final exponentials "
                "(Celledoni, Marthinsen & Owren 2003, Future Gener. Comput. Syst. 19).",
)

CF4 = CommutatorFreeTableau(
    name="cf4", method="cf4", c=("0", "1/2", "1/2", "1"),
    stage_rows=((), (("1/2", "0", "0", "0"),), (("0", "1/2", "0", "0"),),
                (("1/2", "0", "0", "0"), ("-1/2", "0", "1", "0"))),
    final_rows=(("1/4", "1/6", "1/6", "-1/12"), ("-1/12", "1/6", "1/6", "1/4")),
    order=4,
    description="Commutator-free method of order 4 on the classical RK4 nodes, 2 final "
                "exponentials (Celledoni, Marthinsen & Owren 2003, Future Gener. Comput. Syst. 19).",
)

CG3 = _cg("cg3", "cg3", ("0", "3/4", "17/24"), [("3/4",), ("119/216", "17/108")],
          ("13/51", "-2/3", "24/17"), 3,
          "Crouch-Grossman method of order 3, 3 stages (Owren & Marthinsen 1999, BIT 39, table 6.1).")

CG4A = _cg("cg4a", "cg4a",
           ("0", "0.8177227988124852", "0.3859740639032449", "0.3242290522866937", "0.8768903263420429"),
           [("0.8177227988124852",),
            ("0.3199876375476427", "0.0659864263556022"),
            ("0.9214417194464946", "0.4997857776773573", "-1.0969984448371582"),
            ("0.3552358559023322", "0.2390958372307326", "1.3918565724203246", "-1.1092979392113465")],
           ("0.1370831520630755", "-0.0183698531564020", "0.7397813985370780", "-0.1907142565505889",
            "0.3322195591068374"), 4,
           "Crouch-Grossman method of order 4, 5 stages (Jackiewicz, Marthinsen & Owren 2000, Adv. "
           "Comput. Math. 13, example 1; coefficients to 16 digits).")

#: The commutator-free schemes by registry name.
CF_REGISTRY: dict[str, CommutatorFreeTableau] = {t.name: t for t in (CF3, CF4, CG3, CG4A)}
