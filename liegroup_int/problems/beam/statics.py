"""Static equilibrium of the Galerkin beam: Newton-Raphson with load stepping.

The residual is the generalized force of the dynamics at rest,
:meth:`GalerkinBeamProblem._forces` with zero velocities (the gyroscopic terms vanish) and
the external loads scaled by a load factor ``lambda`` (follower loads keep their
dependence on the state), so statics and dynamics share one copy of the physics. The
unknowns are the free control-value increments of position and rotation vector
(``u[0]``, ``u[1]`` of the problem's increment), applied on the Lie group with
:meth:`GalerkinBeamProblem.action`; supported rows stay fixed and the second rows of
rigid joints follow the first (:meth:`GalerkinBeamProblem.project_increment`). At a hinge
the second member's end rotation is the first's carried across the joint and turned by one
unknown angle about the axis, ``exp(Theta_b) = exp(G^T Theta_a) exp(phi axis)`` with
``G = R_a^T R_b``: the hinge stays a hinge exactly at every iterate, and the residual of
``phi`` is the couple about the axis (the virtual work of ``dTheta_b = G^T dTheta_a +
dphi axis``).

The tangent is a forward-difference Jacobian whose columns are perturbed in groups: two
control values whose residual rows do not overlap (basis supports farther apart than the
band ``2 p``) share a group, so a tangent costs ``6 (2 p + 1)`` residual evaluations
whatever the number of control points. It is factored with a sparse LU (it is not
symmetric under follower loads), and each Newton step is damped by a backtracking line
search on the residual measured through the current tangent (:func:`_line_search`).

Norms: the residual ``(F, T / L)`` (forces on positions, couples on rotations divided by
the reference length ``L``), relative to the norm of the full external load at the
reference configuration. Its round-off floor is about ``1e-16`` times the axial stiffness
over the load (measured ~3e-10 for the roll-up at 1 % of its full couple), hence the
default tolerance ``1e-8``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ...groups.so3 import exp_so3, log_so3
from .galerkin import GalerkinBeamProblem, GalerkinBeamState

#: Component index of a hinge's angle among the unknowns (after the three of a rotation).
HINGE_ANGLE = 3


class StaticDivergence(RuntimeError):
    """A load step found no equilibrium within ``max_iter`` Newton iterations (or hit a
    singular tangent). One-line message naming the load factor, the iteration and the
    residual; ``result`` is the :class:`StaticResult` up to the last converged step
    (``result.state`` its state, ``result.converged`` False)."""

    def __init__(self, message: str, result: "StaticResult"):
        super().__init__(message)
        self.result = result


@dataclass
class StaticResult:
    """Outcome of :func:`solve_static`.

    Attributes
    ----------
    state : GalerkinBeamState
        Equilibrium at the last converged load factor (zero velocities).
    load_factors : list of float
        The converged load factors, in order.
    iterations : list of int
        Newton iterations of each converged step.
    residuals : list of list of float
        Relative residual norm of each step before each iteration and after the last
        (``iterations[k] + 1`` values for step ``k``; the failed step's too when one fails).
    converged : bool
        All load steps converged.
    load_norm : float
        Norm of the full external load at the reference configuration (the scale of the
        relative residuals).
    tangents : int
        Tangents assembled; ``evaluations``: residual evaluations in all.
    tips : list of ndarray
        The tip position ``(3,)`` at each converged load step (the load path).
    """

    state: GalerkinBeamState
    load_factors: list = field(default_factory=list)
    iterations: list = field(default_factory=list)
    residuals: list = field(default_factory=list)
    converged: bool = False
    load_norm: float = 0.0
    tangents: int = 0
    evaluations: int = 0
    tips: list = field(default_factory=list)


class _Unknowns:
    """The free unknowns of a problem: ``(field, row, component)`` of each (field 0:
    position, 1: rotation vector; component :data:`HINGE_ANGLE`: a hinge's angle, on its
    first row), the column groups of the finite-difference tangent and the residual's
    reduction onto them."""

    def __init__(self, pb: GalerkinBeamProblem):
        if any(b.body.joint == "ball" for b in pb.bodies):
            raise ValueError("static: a body on a ball joint turns freely about the line of its loads through "
                             "the joint, so its equilibrium is not unique; put it on a hinge (or rigid), or run "
                             "the dynamics")
        self.pb, n = pb, pb.n
        follower = np.arange(n)  # joint rows b follow rows a: positions at every joint,
        turns = np.arange(n)  # rotations at the rigid ones and the hinges
        for j in pb.joints:
            follower[j.b] = j.a
            if j.rigid or j.kind == "hinge":
                turns[j.b] = j.a
        self.node_of = follower
        free = [(~pb.fix_position) & (follower == np.arange(n)), (~pb.fix_rotation) & (turns == np.arange(n))]
        # a roller row: its position along its axis, its bending rotations (no twist)
        kept = {(0, row): (axis,) for row, axis in pb.rollers} | {(1, row): (0, 1) for row, _ in pb.rollers}
        kept |= {(1, row): (comp,) for row, comp in pb.pins}  # a pinned row turns about its pin only
        idx = [(f, i, d) for i in range(n) for f in (0, 1) if free[f][i] for d in kept.get((f, i), range(3))]
        self.hinges = tuple(pb.hinges)
        self.n_plain = len(idx)
        idx += [(1, h.a, HINGE_ANGLE) for h in self.hinges]
        self.field, self.row, self.comp = (np.array(v, dtype=int) for v in zip(*idx)) if idx else (
            np.zeros(0, int),) * 3
        self.size = len(idx)
        #: ``(n, n)`` bool: residual node (row) depends on control node (column)
        self.pattern = _node_pattern(pb.gs.B0, pb.gs.B1, follower, turns)
        self.groups = _groups(self.pattern)
        self.length = float(pb.space.length)

    def _joint_turn(self, h, y: GalerkinBeamState) -> np.ndarray:
        """``G = R_a^T R_b`` of hinge ``h`` at ``y``."""
        return y.R[h.point].T @ y.R[h.point_b]

    def expand(self, x: np.ndarray, y: GalerkinBeamState | None = None) -> np.ndarray:
        """The increment ``(4, n, 3)`` of free values ``x`` ``(size,)``; with hinges, at the
        state ``y``: exactly on the group (``exp(Theta_b) = exp(G^T Theta_a) exp(phi axis)``),
        or linearized (``Theta_b = G^T Theta_a + phi axis``) with ``exact=False``."""
        return self._expand(x, y, exact=True)

    def linear(self, y: GalerkinBeamState | None):
        """``expand`` linearized at ``y`` (mode shapes)."""
        return lambda x: self._expand(x, y, exact=False)

    def _expand(self, x: np.ndarray, y, exact: bool) -> np.ndarray:
        u = np.zeros((4, self.pb.n, 3))
        k = self.n_plain
        u[self.field[:k], self.row[:k], self.comp[:k]] = x[:k]
        for h, phi in zip(self.hinges, x[k:]):
            carried = self._joint_turn(h, y).T @ u[1, h.a]
            u[1, h.b] = log_so3(exp_so3(carried) @ exp_so3(phi * h.axis)) if exact else carried + phi * h.axis
        return u

    def reduce(self, F: np.ndarray, T: np.ndarray, y: GalerkinBeamState | None = None) -> np.ndarray:
        """Free entries of the generalized forces ``F, T`` ``(n, 3)``, with each joint's
        second rows added to its first (virtual work of the joined increments); a hinge's
        angle takes the couple about its axis."""
        F, T = F.copy(), T.copy()
        angles = [float(h.axis @ T[h.b]) for h in self.hinges]
        for j in self.pb.joints:
            F[j.a] += F[j.b]
            if j.rigid:
                T[j.a] += j.Q @ T[j.b]
        for h in self.hinges:
            T[h.a] += self._joint_turn(h, y) @ T[h.b]
        k = self.n_plain
        return np.concatenate([np.stack([F, T])[self.field[:k], self.row[:k], self.comp[:k]], angles])

    def increment_norm(self, x: np.ndarray) -> float:
        """``|(eta / L, Theta)|`` of free increments ``x``."""
        return float(np.sqrt(np.sum(np.where(self.field == 0, x / self.length, x) ** 2)))

    def norm(self, r: np.ndarray) -> float:
        """``|(F, T / L)|``."""
        return float(np.sqrt(np.sum(np.where(self.field == 0, r, r / self.length) ** 2)))


def _node_pattern(B0: np.ndarray, B1: np.ndarray, node_of: np.ndarray, turns_of=None) -> np.ndarray:
    """``(n, n)`` bool: residual node ``k`` depends on control node ``j`` (their basis
    functions share a point), with joint rows merged onto their first rows (``node_of``
    for positions, ``turns_of`` for rotations: a ball joint's second row is its own node
    for the rotations and its first row's for the positions, so it belongs to both)."""
    A = ((B0 != 0) | (B1 != 0)).astype(float)
    P = (A.T @ A) > 0
    n = len(node_of)
    M = np.zeros((n, n))
    M[np.arange(n), node_of] = 1.0
    if turns_of is not None:
        M[np.arange(n), turns_of] = 1.0
    return (M.T @ P.astype(float) @ M) > 0


def _groups(pattern: np.ndarray) -> list[np.ndarray]:
    """Greedy colouring of the nodes: nodes in one group share no residual node."""
    n = pattern.shape[0]
    conflict = (pattern.astype(float).T @ pattern.astype(float)) > 0
    colour = -np.ones(n, dtype=int)
    for j in range(n):
        used = set(colour[conflict[j] & (colour >= 0)].tolist())
        colour[j] = next(c for c in range(n) if c not in used)
    return [np.flatnonzero(colour == c) for c in range(colour.max() + 1)] if n else []


class _System:
    """Residual and tangent of one problem at one load time ``t``."""

    def __init__(self, pb: GalerkinBeamProblem, t: float):
        self.pb, self.t, self.dofs = pb, float(t), _Unknowns(pb)
        self.zero_w = np.zeros((pb.m, 3))
        self.evaluations = self.tangents = 0
        L = self.dofs.length
        self.steps = np.where(self.dofs.field == 0, np.sqrt(np.finfo(float).eps) * L, np.sqrt(np.finfo(float).eps))

    def residual(self, y: GalerkinBeamState, lam: float) -> np.ndarray:
        """Free generalized forces at rest with the loads times ``lam``, ``(size,)``."""
        self.evaluations += 1
        F, T = self.pb._forces(self.t, y, self.zero_w, load_factor=lam)
        return self.dofs.reduce(F, T, y)

    def move(self, y: GalerkinBeamState, x: np.ndarray) -> GalerkinBeamState:
        """``y`` moved by the free increments ``x`` on the group."""
        return self.pb.action(self.dofs.expand(x, y), y)

    def tangent(self, y: GalerkinBeamState, lam: float, r0: np.ndarray, central: bool = False):
        """Sparse finite-difference Jacobian ``d r / d x`` (CSC), one residual evaluation
        per column group and unknown type (6 per group): forward differences from the
        residual ``r0`` at ``y``, or with ``central`` two-sided differences (12 per group)
        with steps :data:`CENTRAL_STEP` (truncation ``O(h^2)`` instead of ``O(h)``: the
        tangent of the eigenvalue analyses, :func:`tangent_matrix`)."""
        import scipy.sparse

        d = self.dofs
        self.tangents += 1
        steps = self.steps * (CENTRAL_STEP / np.sqrt(np.finfo(float).eps)) if central else self.steps
        rows, cols, vals = [], [], []
        for group in d.groups:
            in_group = np.isin(d.row, group)
            for f in (0, 1):
                for c in range(3 if f == 0 else 4):
                    sel = np.flatnonzero(in_group & (d.field == f) & (d.comp == c))
                    if sel.size == 0:
                        continue
                    x = np.zeros(d.size)
                    x[sel] = steps[sel]
                    if central:
                        dr = 0.5 * (self.residual(self.move(y, x), lam) - self.residual(self.move(y, -x), lam))
                    else:
                        dr = self.residual(self.move(y, x), lam) - r0
                    for j in sel:
                        hit = np.flatnonzero(d.pattern[d.row, d.row[j]])
                        rows.append(hit)
                        cols.append(np.full(hit.size, j))
                        vals.append(dr[hit] / steps[j])
        return scipy.sparse.csc_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                                       shape=(d.size, d.size))


#: Relative step of the central-difference tangent (times the reference length for
#: positions): about the cube root of the machine epsilon, which balances the truncation
#: ``h^2`` against the round-off ``eps / h``.
CENTRAL_STEP = 6e-6


@dataclass
class Tangent:
    """The tangent of the static residual at one state (:func:`tangent_matrix`).

    Attributes
    ----------
    matrix : ndarray, shape (size, size)
        ``d r / d x``: free generalized forces (``r``: forces on positions, material couples
        on rotations) by free increments ``x`` (position control values, right rotation
        increments). Minus the stiffness: negative definite at a stable equilibrium of
        conservative loads.
    expand : callable
        ``expand(x)``: the increment ``(4, n, 3)`` of free values ``x`` ``(size,)`` (rows 0
        and 1: position and rotation control values; supported rows zero).
    load_factor : float
    """

    matrix: np.ndarray
    expand: object
    load_factor: float


def tangent_matrix(problem: GalerkinBeamProblem, y: GalerkinBeamState, load_factor: float = 1.0,
                   t: float = 0.0) -> Tangent:
    """Dense tangent of the static residual of ``problem`` at ``y`` under the loads at time
    ``t`` times ``load_factor``, by central differences (:data:`CENTRAL_STEP`), in the
    unknowns of :func:`solve_static`. ``y``'s velocities are ignored."""
    _check(problem, 1, 1.0, 1)
    system = _System(problem, t)
    y = y.copy()
    y.v[:] = 0.0
    y.w[:] = 0.0
    J = system.tangent(y, load_factor, None, central=True).toarray()
    return Tangent(J, system.dofs.linear(y), float(load_factor))


def solve_static(problem: GalerkinBeamProblem, *, load_steps: int = 10, tol: float = 1e-8, max_iter: int = 30,
                 t: float = 0.0, progress=None, y0: GalerkinBeamState | None = None,
                 load_factor: float = 1.0, from_factor: float = 0.0) -> StaticResult:
    """Static equilibrium of ``problem`` under its loads at time ``t`` (profiles included)
    times ``load_factor``, applied in ``load_steps`` equal steps of the load factor from
    ``from_factor``: ``lambda = from_factor + (load_factor - from_factor) k / load_steps``.

    Parameters
    ----------
    problem : GalerkinBeamProblem
        ``space.formulation = "galerkin"``; supports without prescribed motion.
    load_steps : int
        Number of load steps (>= 1).
    tol : float
        A step has converged when the residual norm is at most ``tol`` times the norm of
        the full external load (module docstring), or when the Newton correction is at
        most :data:`XTOL` (the residual at its round-off floor).
    max_iter : int
        Newton iterations allowed per step.
    t : float
        Time at which the load profiles are evaluated.
    progress : callable, optional
        ``progress(step, load_factor, iteration, residual)`` after each residual
        evaluation of a Newton iterate (``residual`` relative).
    y0 : GalerkinBeamState, optional
        Starting configuration (default: the reference); its velocities are ignored.
    load_factor : float
        The final load factor (default 1: the loads as given).
    from_factor : float
        The load factor at which ``y0`` is in equilibrium (default 0: the reference
        configuration is unloaded); the first step goes from it.

    Returns
    -------
    StaticResult

    Raises
    ------
    ValueError
        A collocation problem, no support, a prescribed support motion, bad arguments.
    StaticDivergence
        A load step did not converge (the result up to the last converged step attached).
    """
    _check(problem, load_steps, tol, max_iter)
    if not (np.isfinite(load_factor) and np.isfinite(from_factor)):
        raise ValueError(f"static: load factors: expected finite numbers, got {from_factor!r} to {load_factor!r}")
    system = _System(problem, t)
    y = (y0 if y0 is not None else problem.initial_state()).copy()
    y.v[:] = 0.0
    y.w[:] = 0.0
    load = system.dofs.norm(system.residual(y, 1.0) - system.residual(y, 0.0))
    res = StaticResult(state=y, load_norm=load)
    scale = load if load > 0 else 1.0
    for k in range(1, load_steps + 1):
        lam = from_factor + (load_factor - from_factor) * k / load_steps
        y, hist, ok, why = _newton(system, y, lam, scale, tol, max_iter,
                                   (lambda it, r, k=k, lam=lam: progress(k, lam, it, r)) if progress else None)
        res.residuals.append(hist)
        res.tangents, res.evaluations = system.tangents, system.evaluations
        if not ok:
            last = res.load_factors[-1] if res.load_factors else from_factor
            raise StaticDivergence(f"static: no equilibrium at load factor {lam:.4g} (step {k} of {load_steps}): "
                                   f"residual {hist[-1]:.3e} after iteration {len(hist) - 1} ({why}, tol {tol:.1e}); "
                                   f"last converged load factor {last:.4g}", res)
        res.state = y
        res.load_factors.append(lam)
        res.iterations.append(len(hist) - 1)
        res.tips.append(problem.tip(y))
    res.converged = True
    return res


def _check(problem, load_steps: int, tol: float, max_iter: int) -> None:
    """One-line refusals of what :func:`solve_static` cannot solve."""
    if getattr(problem, "formulation", None) != "galerkin":
        raise ValueError(f'static needs space.formulation = "galerkin" (got {getattr(problem, "formulation", "?")!r})')
    if not np.any(problem.fix_position):
        raise ValueError("static needs a support: bc.start or bc.end clamped or hinged (a free beam has no "
                         "equilibrium under loads)")
    if problem.moving_ends or problem.translating_ends:
        raise ValueError("static: a prescribed support motion (motion.*, translation.*) is not a static load")
    if not (isinstance(load_steps, (int, np.integer)) and load_steps >= 1):
        raise ValueError(f"static: load_steps: expected a positive integer, got {load_steps!r}")
    if not (tol > 0 and np.isfinite(tol)):
        raise ValueError(f"static: tol: expected a positive tolerance, got {tol!r}")
    if not (isinstance(max_iter, (int, np.integer)) and max_iter >= 1):
        raise ValueError(f"static: max_iter: expected a positive integer, got {max_iter!r}")


def _newton(system: _System, y, lam: float, scale: float, tol: float, max_iter: int, report):
    """Newton iterations of one load step from ``y``: ``(state, relative residual norms,
    converged, why not)``."""
    import scipy.sparse.linalg

    r = system.residual(y, lam)
    hist = [system.dofs.norm(r) / scale]
    if report:
        report(0, hist[-1])
    for it in range(1, max_iter + 1):
        if hist[-1] <= tol:
            return y, hist, True, ""
        J = system.tangent(y, lam, r)
        try:
            lu = scipy.sparse.linalg.splu(J)
        except RuntimeError:
            return y, hist, False, "singular tangent"
        dx = -lu.solve(r)
        y, r = _line_search(system, y, lam, lu, dx)
        hist.append(system.dofs.norm(r) / scale)
        if report:
            report(it, hist[-1])
        if system.dofs.increment_norm(dx) <= XTOL:  # the residual is at its round-off floor
            return y, hist, True, ""
    if hist[-1] <= tol:
        return y, hist, True, ""
    return y, hist, False, f"max_iter = {max_iter} reached"


#: How much larger than the Newton step the simplified correction after it may be and the
#: step still be taken whole. After a full step of a slender beam the shear and axial
#: residuals are of order ``GA Theta^3`` and act through the bending compliance (a factor
#: ``GA L^2 / EI``, thousands), so the correction is often larger than the step although
#: Newton converges; a strict test (factor 1) halves such steps and doubles the iterations
#: of the roll-up, while without any test a large load step diverges (measured on the
#: roll-up, n_ctrl = 21: 11 iterations per quarter-circle step with 100, 21 with 1, and a
#: half circle in one step: 24 iterations with 100, divergence without the test).
MAX_GROWTH = 100.0

#: A step has also converged when the Newton correction ``|(eta / L, Theta)|`` falls to
#: ``XTOL``: the residual then sits at its round-off floor, about ``1e-16`` times the axial
#: stiffness over the load (measured 6e-8 relative for the steel cantilever of the
#: built-in scene under a 1 N tip load, where the corrections fall from 1e-9 to 1e-13 and
#: then stay at 1e-16).
XTOL = 1e-12


def _line_search(system: _System, y, lam: float, lu, dx, halvings: int = 8):
    """Backtracking: the first of ``dx, dx/2, ...`` whose residual, measured by the current
    tangent (the simplified Newton correction ``J^-1 r(alpha)``, affine-invariant: the
    plain norm of ``(F, T / L)`` is dominated by the stiff axial and shear rows), is at
    most :data:`MAX_GROWTH` times ``|dx|``; else the smallest step. ``(state, r)``."""
    size = system.dofs.increment_norm(dx)
    alpha = 1.0
    for _ in range(halvings + 1):
        yt = system.move(y, alpha * dx)
        rt = system.residual(yt, lam)
        if np.all(np.isfinite(rt)) and system.dofs.increment_norm(lu.solve(rt)) <= MAX_GROWTH * size:
            break
        alpha *= 0.5
    return yt, rt
