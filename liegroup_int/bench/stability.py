"""Stability maps of beam discretizations: the linearized spectrum over (p, n_ctrl).

For a scene, a formulation and a damping setting, each map entry is the dense spectrum of
the linearized increment map (:func:`liegroup_int.integrators.eigenvalues`) at one state:

* ``rest``: the scene's initial state;
* ``half_circle`` / ``full_circle``: the ``rollup`` beam bent statically into a half or a
  full circle by its end couple ``M = k EI`` (``k L = pi`` or ``2 pi``), built
  analytically (:func:`circle_state`), linearized with the couple applied;
* ``t=T``: the state a run of the scene reaches at ``T`` (the paper's pendulum at 2 s).

With ``kelvin_voigt = "auto"`` the entry reports the retardation time sized at the
initial state (:func:`liegroup_int.problems.beam.damping.size_kelvin_voigt`) and the
spectrum with that damping.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..groups.so3 import exp_so3
from ..integrators import eigenvalues, integrate_fixed, resolve_method, spectral_radius, stable_step
from ..integrators.spectrum import GROWTH_THRESHOLD
from ..problems.beam import BeamState
from ..scenes import load_scene
from ..scenes.beam import problem
from .beam_internals import first_frequency, size_kelvin_voigt


@dataclass
class MapEntry:
    """One (scene, state, formulation, damping, p, n_ctrl) entry of a stability map."""

    scene: str
    state: str
    formulation: str
    damping: str
    degree: int
    n_ctrl: int
    max_real: float = float("nan")
    at_imag: float = float("nan")
    lam_max: float = float("nan")
    omega1: float = float("nan")
    tau: float = 0.0
    zeta1: float = 0.0
    max_real_undamped: float = float("nan")
    seconds: float = 0.0
    note: str = ""

    @property
    def growing(self) -> bool:
        return bool(self.max_real > GROWTH_THRESHOLD)

    def as_dict(self) -> dict:
        return dict(self.__dict__)


def circle_state(pb, k: float) -> BeamState:
    """The beam bent statically into an arc of uniform curvature ``k`` about the spatial
    direction ``a`` of its material axis ``d1`` at ``s = 0``: the exact equilibrium of a
    straight, isotropic beam under the end couple ``M = k EI a`` (a circular arc).

    Rotations ``R = exp(k s a) R0`` at the collocation points, material curvature
    ``K = K0 + k R0^T a``, and a centreline integrating ``R e3`` (fine trapezoidal rule,
    then interpolated through the collocation matrix).
    """
    sp = pb.space
    axis = sp.R0[0][:, 0]  # d1 at s = 0: bending about d1 (a straight reference keeps it)
    u = np.linspace(0.0, 1.0, 8001)
    s_f = sp.arc_length(u)
    r0_f, _, _ = sp.frame(u)
    tangents = (exp_so3(np.outer(k * s_f, axis)) @ r0_f)[:, :, 2]
    c_f = np.concatenate([[sp.c0[0]], sp.c0[0] + np.cumsum(0.5 * (tangents[1:] + tangents[:-1])
                                                           * np.diff(s_f)[:, None], axis=0)])
    c_pts = np.stack([np.interp(sp.s_c, s_f, c_f[:, j]) for j in range(3)], axis=1)
    R = exp_so3(np.outer(k * sp.s_c, axis)) @ sp.R0
    K = np.array(sp.K0) + k * np.einsum("nji,j->ni", sp.R0, axis)
    z = np.zeros((pb.n, 3))
    return BeamState(sp.solve(c_pts), z.copy(), z.copy(), R, K, np.array(sp.K0_s))


def _state_at(pb, t_state: float):
    """The scene's state at ``t_state`` (RKMK4 at 0.8 of its stable step)."""
    y0 = pb.initial_state()
    lam = spectral_radius(pb, 0.0, y0)
    dt = stable_step(resolve_method("rkmk4"), lam, t_state).dt
    _, y, _ = integrate_fixed(pb, resolve_method("rkmk4"), (0.0, t_state), y0, dt)
    return y


def map_entry(scene: str, state: str, formulation: str, damping: str, p: int, n: int,
              overrides: dict | None = None) -> MapEntry:
    """Compute one entry (see the module docstring for ``state`` and ``damping``)."""
    start = time.perf_counter()
    e = MapEntry(scene, state, formulation, damping, p, n)
    keys = {"space.degree": p, "space.n_ctrl": n, "space.formulation": formulation, "integrator.backend": "numba",
            "material.kelvin_voigt": 0.0, **(overrides or {})}
    if state in ("half_circle", "full_circle"):
        keys.update({"loads.end.profile": "constant"})
    sc = load_scene(scene, keys)
    pb = problem(sc)
    y0 = pb.initial_state()
    if damping == "auto":
        try:
            rep = size_kelvin_voigt(pb.with_kelvin_voigt, y0)
        except ValueError as exc:  # refused: the growth needs more than light damping
            e.note = f"refused: {exc}"[:200]
            e.seconds = time.perf_counter() - start
            return e
        e.tau, e.zeta1 = rep.tau, rep.zeta1
        pb = pb.with_kelvin_voigt(rep.tau)
    elif damping not in ("none", "0"):
        e.tau = float(damping)
        pb = pb.with_kelvin_voigt(e.tau)
    t_lin = 0.0
    try:
        if state == "rest":
            y = y0
        elif state in ("half_circle", "full_circle"):
            k = (np.pi if state == "half_circle" else 2.0 * np.pi) / pb.space.length
            EI = pb.CM[0]
            pb = pb.__class__(pb.space, pb.constants, pb.bcs, _couple_loads(pb, k * EI), pb.initial,
                              backend=pb.backend, kelvin_voigt=pb.tau, formulation=pb.formulation)
            y = circle_state(pb, k)
        elif state.startswith("t="):
            t_lin = float(state[2:])
            y = _state_at(pb, t_lin)
        else:
            raise ValueError(f"unknown state {state!r}")
        lam = eigenvalues(pb, t_lin, y)
    except Exception as exc:  # a run that blows up before the state is reached
        e.note = f"{type(exc).__name__}: {exc}"[:160]
        e.seconds = time.perf_counter() - start
        return e
    i = int(np.argmax(lam.real))
    e.max_real, e.at_imag, e.lam_max = float(lam.real[i]), float(abs(lam.imag[i])), float(np.max(np.abs(lam)))
    e.omega1 = first_frequency(lam)
    if damping == "auto" and e.tau > 0 and state != "rest":  # at rest: the sizing's own ratio
        e.zeta1 = 0.5 * e.tau * e.omega1
    e.seconds = time.perf_counter() - start
    return e


def _couple_loads(pb, couple: float):
    """The problem's loads with the end couple ``couple`` about the bending axis."""
    from dataclasses import replace

    axis = pb.space.R0[0][:, 0]
    end = replace(pb.loads.end, couple=tuple(float(x) for x in couple * axis))
    return replace(pb.loads, end=end)
