"""Linear analyses about a static equilibrium of the Galerkin beam: prestressed modes and
buckling loads.

**Prestressed modes** (:func:`prestressed_modes`): the modal analysis of
:func:`~liegroup_int.integrators.spectrum.modal_analysis` about the equilibrium that
:func:`~.statics.solve_static` finds under the loads, instead of about the reference: the
stresses of the equilibrium enter the linearized increment map (geometric stiffness), so
an axial compression lowers the bending frequencies and a tension raises them.

**Buckling loads** (:func:`buckling_loads`): the load factors ``lambda`` at which the
tangent ``K(lambda) = d r / d x`` of the static residual about the equilibrium under
``lambda`` times the loads (:func:`~.statics.tangent_matrix`, central differences) becomes
singular.

1. Linear buckling: with ``K_0`` the tangent at the unloaded reference and ``K_1`` the
   tangent at the equilibrium of the first load step ``lambda_1 = 1 / load_steps``,
   ``K(lambda) ~ K_0 + lambda K_G`` with ``K_G = (K_1 - K_0) / lambda_1``; the critical
   factors are the real positive eigenvalues of ``(K_0 + lambda K_G) phi = 0`` (dense
   generalized eigenproblem, :func:`scipy.linalg.eig`). For a structure whose equilibrium
   path is linear (a straight column under an axial load) ``K`` is affine in ``lambda``
   up to the axial shortening, and this is the classical Euler analysis.
2. Nonlinear refinement of the lowest factor: from the last equilibrium ``lambda_j`` the
   eigenproblem ``(K_j + mu (K_j - K_{j-1}) / (lambda_j - lambda_{j-1})) phi = 0`` (the
   secant of the tangent along the load path) predicts ``lambda_{j+1} = lambda_j + mu``;
   the equilibrium is followed there in load steps of at most ``1 / load_steps`` and the
   prediction repeated until it moves by less than ``rtol`` (a secant iteration on the
   singularity of ``K`` along the path: superlinear), or until the last predictions agree
   to the tangents' round-off (:data:`FLOOR_BAND`; ``BucklingResult.accuracy``). Beyond a limit point the static
   solver finds no equilibrium: the step is halved, and after :data:`HALVINGS` halvings the
   refinement stops at the last equilibrium (``BucklingResult.note`` says so).

``K_G`` here is the secant of the whole tangent, not only its stress part: when the loads
turn the beam's stiff axial and shear directions before it buckles (a bending-dominated
structure such as the 45-degree bend under its transverse load), ``K_G`` carries terms of
order ``EA`` times the rotation, and the linear factors are small spurious values that the
refinement does not confirm; a refined factor is only reported as critical when the
tangent is singular there (:data:`SINGULAR`).

The higher factors come from the secant of the tangent between the reference and the
first critical state (:func:`_higher_factors`), extrapolated linearly in the load from there. Only real factors are reported: follower loads make ``K`` unsymmetric
and can lose stability by flutter instead (complex pairs), which a static analysis does
not see.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ...integrators.spectrum import ModalReport, modal_analysis
from .galerkin import GalerkinBeamProblem, GalerkinBeamState
from .statics import StaticDivergence, StaticResult, solve_static, tangent_matrix


@dataclass
class PrestressedModes:
    """Modes about a static equilibrium (:func:`prestressed_modes`).

    Attributes
    ----------
    report : ModalReport
        The modal analysis about ``static.state``.
    static : StaticResult
        The equilibrium.
    """

    report: ModalReport
    static: StaticResult


def prestressed_modes(problem: GalerkinBeamProblem, n: int, static_result: StaticResult | None = None, *,
                      t: float = 0.0, load_steps: int = 10, tol: float = 1e-8, max_iter: int = 30,
                      duration: float | None = None) -> PrestressedModes:
    """The ``n`` lowest modes of ``problem`` about its static equilibrium under the loads at
    time ``t``: ``static_result``'s state, or the one :func:`~.statics.solve_static` finds
    with ``load_steps``, ``tol``, ``max_iter``. ``duration`` as in
    :func:`~liegroup_int.integrators.spectrum.modal_analysis`.

    Raises ValueError (what :func:`~.statics.solve_static` or the modal analysis refuse)
    and :class:`~.statics.StaticDivergence`."""
    if static_result is None:
        static_result = solve_static(problem, load_steps=load_steps, tol=tol, max_iter=max_iter, t=t)
    elif not static_result.converged:
        raise ValueError("prestressed_modes: the static result did not converge")
    return PrestressedModes(modal_analysis(problem, t, static_result.state, n, duration=duration), static_result)


#: Times the refinement halves a load step that finds no equilibrium before it stops.
HALVINGS = 5

#: Largest stiffness of the buckling mode at the refined factor, relative to its stiffness
#: unloaded (:func:`_stiffness_ratio`), for the tangent to count as singular there. At the
#: column's Euler load it is ~1e-8 (the secant iteration's tolerance); a structure whose
#: tangent never becomes singular on its load path (a bending-dominated one) can still let
#: the secant prediction stall where the tangent is regular, which this rejects.
SINGULAR = 1e-4


#: The refinement's predictions have reached the tangents' round-off when the last
#: :data:`FLOOR_COUNT` of them and the equilibrium of the last lie within this relative band
#: without converging to ``rtol``
#: (the secant over steps that short divides the central differences' noise by the step:
#: Argyris' frame at n_ctrl 21 jitters by 1e-6 about its critical load).
FLOOR_BAND = 1e-5
FLOOR_COUNT = 3


def _noise_floor(history: list, factor: float, lam: float) -> float:
    """The relative spread of the last :data:`FLOOR_COUNT` refined predictions and the
    equilibrium ``lam`` they were made at, if it is within :data:`FLOOR_BAND` (the
    refinement has reached the tangents' round-off), else 0. The linear prediction
    (``history[0]``) does not count."""
    last = history[1:][-FLOOR_COUNT:]
    if len(last) < FLOOR_COUNT:
        return 0.0
    spread = (max(last + [lam]) - min(last + [lam])) / abs(factor)
    return spread if spread <= FLOOR_BAND else 0.0


def _stiffness_ratio(K: np.ndarray, K0: np.ndarray, phi: np.ndarray) -> float:
    """``|phi.K phi| / |phi.K0 phi|``: the stiffness of the mode ``phi`` under the load
    (``K``) relative to its stiffness unloaded (``K0``)."""
    return float(abs(phi @ K @ phi) / max(abs(phi @ K0 @ phi), 1e-300))


@dataclass
class BucklingResult:
    """Critical load factors (:func:`buckling_loads`).

    Attributes
    ----------
    load_factors : ndarray, shape (k,)
        Critical load factors, lowest first (``k <= n``): the first refined along the load
        path (when ``refined``), the others from the secant between the reference and the
        critical state.
    linear : ndarray, shape (k,)
        The linear buckling factors (about the reference, step 1 of the module docstring).
    vectors : list of ndarray, each (4, n_ctrl, 3)
        The buckling modes as increments (rows 0 and 1: position and right rotation
        increments of the control values), real, unit 2-norm; ``linear_vectors`` those of
        the linear analysis.
    state : GalerkinBeamState
        The equilibrium of the last linearization, at load factor ``at_factor``.
    refined : bool
        The first factor converged to ``rtol`` along the load path and the tangent is
        singular there (``singularity <= SINGULAR``).
    singularity : float
        The first mode's stiffness at the refined factor relative to unloaded
        (:func:`_stiffness_ratio`; NaN when not refined).
    history : list of float
        The lowest factor predicted at each equilibrium of the refinement.
    iterations : int
        Refinement iterations (equilibria solved after the first load step).
    newton : int
        Newton iterations in all.
    note : str
        Why the refinement stopped early ("" when refined or not asked).
    accuracy : float
        The relative spread of the last refined predictions when the refinement stopped at
        the tangents' round-off before reaching ``rtol`` (:func:`_noise_floor`), else 0.
    """

    load_factors: np.ndarray
    linear: np.ndarray
    vectors: list
    linear_vectors: list
    state: GalerkinBeamState
    at_factor: float
    refined: bool = False
    iterations: int = 0
    newton: int = 0
    note: str = ""
    singularity: float = float("nan")
    history: list = field(default_factory=list)
    accuracy: float = 0.0


def critical_factors(K: np.ndarray, KG: np.ndarray, base: float, n: int, rtol_imag: float = 1e-6):
    """The ``n`` lowest real load factors ``base + mu > 0`` with ``(K + mu KG) phi = 0``
    (``K, KG`` ``(m, m)``), and their vectors ``phi`` ``(m, k)`` (real, unit 2-norm).
    Eigenvalues with ``|Im mu| > rtol_imag |mu|`` (finite-difference noise splits a
    degenerate real pair by about ``1e-8``) and infinite ones (directions without
    geometric stiffness) are left out."""
    import scipy.linalg

    with np.errstate(divide="ignore", invalid="ignore"):
        mu, vec = scipy.linalg.eig(K, -KG)
    ok = np.isfinite(mu) & (np.abs(mu.imag) <= rtol_imag * np.abs(mu)) & (base + mu.real > 0)
    idx = np.flatnonzero(ok)[np.argsort(base + mu.real[ok], kind="stable")][:n]
    vectors = []
    for k in idx:
        v = vec[:, k]
        j = int(np.argmax(np.abs(v)))
        v = np.real(v * (abs(v[j]) / v[j]))
        vectors.append(v / np.linalg.norm(v))
    return base + mu.real[idx], np.array(vectors).T.reshape(K.shape[0], len(idx))


def buckling_loads(problem: GalerkinBeamProblem, n: int = 3, *, t: float = 0.0, load_steps: int = 10,
                   refine: bool = True, rtol: float = 1e-7, max_refine: int = 20, tol: float = 1e-8,
                   max_iter: int = 30) -> BucklingResult:
    """The ``n`` lowest critical load factors of ``problem`` under its loads at time ``t``
    (module docstring): linear buckling from the tangents at the reference and at the
    load factor ``1 / load_steps``, then (``refine``) the lowest factor followed along the
    load path in steps of at most ``1 / load_steps`` until it moves by less than ``rtol``
    (at most ``max_refine`` equilibria). ``tol``, ``max_iter``: the Newton solver's
    (:func:`~.statics.solve_static`).

    Raises ValueError: what :func:`~.statics.solve_static` refuses, a bad ``n`` or
    ``load_steps``, no positive critical factor, or no equilibrium at the first load step."""
    if not (isinstance(n, (int, np.integer)) and n >= 1):
        raise ValueError(f"buckling: n: expected at least one mode, got {n!r}")
    if not (isinstance(load_steps, (int, np.integer)) and load_steps >= 1):
        raise ValueError(f"buckling: load_steps: expected a positive integer, got {load_steps!r}")
    T0 = tangent_matrix(problem, problem.initial_state(), 0.0, t)
    lam1 = 1.0 / load_steps
    try:
        first = solve_static(problem, load_steps=1, load_factor=lam1, t=t, tol=tol, max_iter=max_iter)
    except StaticDivergence as exc:
        raise ValueError(f"buckling: no equilibrium at the first load step: {exc}") from None
    K1 = tangent_matrix(problem, first.state, lam1, t).matrix
    linear, phi = critical_factors(T0.matrix, (K1 - T0.matrix) / lam1, 0.0, n)
    if linear.size == 0:
        raise ValueError("buckling: no positive critical load factor (the tangent stays regular under every "
                         "positive multiple of the loads in the linear analysis)")
    lin_vectors = [T0.expand(v) for v in phi.T]
    res = BucklingResult(linear, linear, lin_vectors, lin_vectors, first.state, lam1,
                         newton=sum(first.iterations))
    if refine:
        _refine(problem, res, (0.0, T0.matrix), (lam1, K1), n, t, load_steps, rtol, max_refine, tol, max_iter,
                T0.expand)
    return res


def _higher_factors(res: BucklingResult, K: np.ndarray, K0: np.ndarray, lam: float, n: int, expand) -> None:
    """Factors 2.. of ``res`` from the secant of the tangent between the reference (``K0``)
    and the critical state (``K`` at ``lam``). The last step's secant, over a step that the
    iteration shrinks to ``rtol``, divides the tangents' finite-difference noise by that
    step: the lowest factor it predicts converges, the higher ones do not (a portal frame's
    sway mode came out 6 % low from it)."""
    factors, phi = critical_factors(K, (K - K0) / lam, lam, n)
    if factors.size > 1 and res.load_factors.size > 1:
        res.load_factors = np.concatenate([res.load_factors[:1], factors[1:]])
        res.vectors = res.vectors[:1] + [expand(v) for v in phi.T[1:]]


def _refine(problem, res: BucklingResult, prev, cur, n, t, load_steps, rtol, max_refine, tol, max_iter, expand):
    """The secant iteration of the module docstring, from the equilibrium ``res.state`` at
    ``cur = (lambda, K)`` with the previous tangent ``prev``; updates ``res``."""
    (lam_p, K_p), (lam, K) = prev, cur
    K0 = prev[1]
    y = res.state
    for it in range(max_refine + 1):
        factors, phi = critical_factors(K, (K - K_p) / (lam - lam_p), lam, n)
        if factors.size == 0:
            res.note = f"no positive critical factor in the linearization at load factor {lam:.6g}"
            return
        res.load_factors, res.vectors, res.state, res.at_factor = factors, [expand(v) for v in phi.T], y, lam
        res.history.append(float(factors[0]))
        floor = _noise_floor(res.history, factors[0], lam)
        if abs(factors[0] - lam) <= rtol * abs(factors[0]) or floor:
            if floor:
                res.accuracy = floor
            _higher_factors(res, K, K0, lam, n, expand)
            res.singularity = _stiffness_ratio(K, K0, phi[:, 0])
            res.refined = res.singularity <= SINGULAR
            if not res.refined:
                res.note = (f"the prediction converged at load factor {lam:.6g} but the tangent is regular there "
                            f"(mode stiffness {res.singularity:.2g} of the unloaded one)")
            return
        if it == max_refine:
            res.note = f"not converged to rtol {rtol:g} in {max_refine} equilibria"
            return
        target = float(factors[0])
        for _ in range(HALVINGS + 1):
            steps = max(1, math.ceil(abs(target - lam) * load_steps))
            try:
                st = solve_static(problem, load_steps=steps, load_factor=target, from_factor=lam, t=t, y0=y,
                                  tol=tol, max_iter=max_iter)
                break
            except StaticDivergence as exc:
                res.newton += sum(exc.result.iterations)
                why = str(exc)
                target = lam + 0.5 * (target - lam)
        else:
            res.note = f"refinement stopped at load factor {lam:.6g}: {why}"
            return
        res.iterations += 1
        res.newton += sum(st.iterations)
        lam_p, K_p, lam, y = lam, K, target, st.state
        K = tangent_matrix(problem, y, lam, t).matrix
