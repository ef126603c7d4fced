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
    finite-difference Jacobian-vector products (two rate evaluations per iteration).

    The dominant eigenvalues of an undamped structure come in ``+-i omega`` pairs, for
    which plain power iteration oscillates; iterating with ``dG^2`` (whose dominant
    eigenvalue ``-omega^2`` is real) converges. Returns ``sqrt(|rho(dG^2)|)``.
    """
    z = problem.zero_increment(y)
    rng = np.random.default_rng(seed)
    x = rng.standard_normal(z.shape)
    x /= np.linalg.norm(x)
    g0 = problem.increment_rate(t, y, z)

    def jv(v):
        du = eps * v
        return (problem.increment_rate(t, problem.action(du, y), du) - g0) / eps

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
