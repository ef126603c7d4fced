"""Spectrum of the linearized increment map, for stable step sizes.

For a state ``y`` the map ``G(u) = increment_rate(t, Lambda(u, y), u)`` sends an
increment to its rate; RKMK applied near ``y`` behaves like RK applied to
``du/dt = G(u)``, so the eigenvalues of ``dG/du`` at ``u = 0`` decide stability:
a step ``h`` is stable when ``h * lambda`` lies in the method's stability region for
every eigenvalue ``lambda``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .problem import Problem


def jacobian(problem: Problem, t: float, y, eps: float | None = None) -> np.ndarray:
    """Dense ``dG/du`` at ``u = 0`` by central differences, ``(m, m)`` with ``m`` the
    increment size. Each column costs two rate evaluations; use for small problems."""
    z = problem.zero_increment(y)
    m = z.size
    scale = np.maximum(problem.increment_scale(y).ravel(), 1.0)
    eps = eps if eps is not None else 1e-6
    J = np.empty((m, m))
    for j in range(m):
        e = np.zeros(m)
        e[j] = eps * scale[j]
        du = e.reshape(z.shape)
        gp = problem.increment_rate(t, problem.action(du, y), du).ravel()
        gm = problem.increment_rate(t, problem.action(-du, y), -du).ravel()
        J[:, j] = (gp - gm) / (2.0 * e[j])
    return J


def eigenvalues(problem: Problem, t: float, y) -> np.ndarray:
    """All eigenvalues of the linearized increment map (dense; small problems)."""
    return np.linalg.eigvals(jacobian(problem, t, y))


def spectral_radius(problem: Problem, t: float, y, iterations: int = 200, seed: int = 0,
                    eps: float = 1e-7, rtol: float = 1e-7) -> float:
    """Largest ``|lambda|`` of the linearized increment map by power iteration on
    finite-difference Jacobian-vector products (four rate evaluations per iteration).

    The dominant eigenvalues of an undamped structure come in ``+-i omega`` pairs, for
    which plain power iteration oscillates; iterating with ``dG^2`` (whose dominant
    eigenvalue ``-omega^2`` is real) converges. Returns ``sqrt(|rho(dG^2)|)``.

    The products are central differences, as :func:`jacobian`'s: a one-sided difference
    carries the rate's round-off divided by ``eps``, which on a stiff frame (the built-in
    portal, EA / EI = 1e7 per m^2) exceeds the product itself and left the iteration at a
    third of the largest ``|lambda|`` (the run at that step blew up from rest).
    """
    z = problem.zero_increment(y)
    rng = np.random.default_rng(seed)
    x = rng.standard_normal(z.shape)
    x /= np.linalg.norm(x)

    def jv(v):
        du = eps * v
        return (problem.increment_rate(t, problem.action(du, y), du)
                - problem.increment_rate(t, problem.action(-du, y), -du)) / (2.0 * eps)

    rho = 0.0
    for _ in range(iterations):
        x2 = jv(jv(x))
        rho_new = float(np.linalg.norm(x2))
        if rho_new == 0.0:
            return 0.0
        x = x2 / rho_new
        if abs(rho_new - rho) <= rtol * rho_new:
            rho = rho_new
            break
        rho = rho_new
    return float(np.sqrt(rho))


@dataclass(frozen=True)
class GrowthReport:
    """Largest real part of the linearized spectrum at a state.

    Attributes
    ----------
    lam_max : float
        Largest ``|lambda|`` [1/s].
    max_real : float
        Largest ``Re lambda`` [1/s].
    at_imag : float
        ``|Im lambda|`` of that eigenvalue.
    growing : bool
        ``max_real`` is above the finite-difference noise (``noise * lam_max``) and a mode
        grows by more than ``e`` over the duration (``max_real * duration > 1``).
    size : int
        Number of unknowns (the Jacobian is ``size x size``).
    """

    lam_max: float
    max_real: float
    at_imag: float
    growing: bool
    size: int


#: Real part [1/s] above which a linearized mode counts as growing (guards, damping sizing).
GROWTH_THRESHOLD = 1e-2

#: Largest increment size for which :func:`growth_check` forms the dense Jacobian.
MAX_DENSE = 3000


def growth_check(problem: Problem, t: float, y, duration: float, noise: float = 1e-6) -> GrowthReport:
    """Dense eigenvalues of the linearized increment map at ``(t, y)``: does a mode grow?

    An undamped structure has a purely imaginary spectrum; a collocation scheme need not
    (docs/verification.md, "Stability of the semi-discretization"). Central differences
    leave real parts of about ``1e-9 |lambda|max``; ``noise`` sets the level above which a
    real part counts. Costs ``2 m`` rate evaluations and an ``m x m`` eigenvalue problem.
    """
    m = int(problem.zero_increment(y).size)
    if m > MAX_DENSE:
        raise ValueError(f"{m} unknowns: too many for a dense spectrum (at most {MAX_DENSE})")
    lam = eigenvalues(problem, t, y)
    k = int(np.argmax(lam.real))
    lam_max = float(np.max(np.abs(lam)))
    re = float(lam.real[k])
    growing = re > noise * lam_max and re * duration > 1.0
    return GrowthReport(lam_max, re, float(abs(lam.imag[k])), bool(growing), m)


@dataclass(frozen=True)
class Mode:
    """One mode of the linearized increment map (:func:`modal_analysis`).

    Attributes
    ----------
    lam : complex
        Eigenvalue [1/s]; oscillatory modes are listed once, with ``Im lam > 0``.
    freq_hz : float
        Natural frequency ``|lam| / 2 pi`` [Hz].
    damping_ratio : float
        ``-Re lam / |lam|`` (0 undamped or ``|Re lam|`` at the noise level, negative for a
        growing mode).
    growing : bool
        ``Re lam`` above the finite-difference noise (and, given a duration, growth by more
        than ``e`` over it).
    vector : ndarray, complex, increment-shaped
        The eigenvector (unit 2-norm, phase chosen so that its largest entry is real).
    """

    lam: complex
    freq_hz: float
    damping_ratio: float
    growing: bool
    vector: np.ndarray


@dataclass(frozen=True)
class ModalReport:
    """The lowest modes at a state, and what was left out.

    Attributes
    ----------
    modes : list of Mode
        By increasing ``|lam|``.
    size : int
        Unknowns (the Jacobian is ``size x size``).
    lam_max : float
        Largest ``|lambda|`` [1/s].
    zero_modes : int
        Eigenvalues with ``|lambda|`` at the noise level (rigid-body and constraint modes).
    growing_real : int
        Real eigenvalues above the noise (non-oscillatory growth, listed among the modes).
    """

    modes: list
    size: int
    lam_max: float
    zero_modes: int
    growing_real: int


def modal_analysis(problem: Problem, t: float, y, n: int, noise: float = 1e-9,
                   duration: float | None = None) -> ModalReport:
    """The ``n`` lowest modes of the linearized increment map at ``(t, y)`` (dense).

    Eigenvalues of ``dG/du`` (:func:`jacobian`) come in pairs ``lambda = -zeta omega +- i
    omega sqrt(1 - zeta^2)`` for a damped oscillator; each pair is one mode of natural
    frequency ``|lambda| / 2 pi`` and damping ratio ``-Re lambda / |lambda|``. Eigenvalues
    with ``|lambda| <= noise |lambda|max`` are rigid-body or constraint modes (counted, not
    listed); real eigenvalues above the noise are non-oscillatory (a growing one is
    listed and flagged). The default ``noise`` is the central differences' level (about
    ``1e-10 |lambda|max`` with relative steps of ``1e-6``), not :func:`growth_check`'s
    ``1e-6``: stiff sections have ``|lambda|max`` six orders above the first mode. With a
    ``duration``, a mode counts as growing only if it also grows by more than ``e`` over it
    (the rule of :func:`growth_check`): near-zero eigenvalues of rigid-body motion carry
    finite-difference noise of either sign.
    """
    if n < 1:
        raise ValueError(f"n: expected at least one mode, got {n}")
    z = problem.zero_increment(y)
    m = int(z.size)
    if m > MAX_DENSE:
        raise ValueError(f"{m} unknowns: too many for a dense modal analysis (at most {MAX_DENSE})")
    lam, vec = np.linalg.eig(jacobian(problem, t, y))
    lam_max = float(np.max(np.abs(lam)))
    floor = noise * lam_max
    mag = np.abs(lam)
    zero = mag <= floor
    real = np.abs(lam.imag) <= floor
    keep = ~zero & ((lam.imag > floor) | (real & (lam.real > floor)))
    order = np.flatnonzero(keep)[np.argsort(mag[keep], kind="stable")][:n]
    modes = []
    for k in order:
        v = vec[:, k]
        j = int(np.argmax(np.abs(v)))
        v = v * (abs(v[j]) / v[j]) / np.linalg.norm(v)
        zeta = 0.0 if abs(lam[k].real) <= floor else float(-lam[k].real / mag[k])
        grows = lam[k].real > floor and (duration is None or lam[k].real * duration > 1.0)
        modes.append(Mode(complex(lam[k]), float(mag[k] / (2 * np.pi)), zeta, bool(grows), v.reshape(z.shape)))
    return ModalReport(modes, m, lam_max, int(np.count_nonzero(zero)),
                       int(np.count_nonzero(~zero & real & (lam.real > floor))))
