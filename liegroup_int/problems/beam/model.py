"""Beam data: material, cross-section, boundary conditions and loads (frozen dataclasses).

Units are SI throughout. The beam axis is the third material axis, so

* ``C_N = diag(k G A, k G A, E A)``   (shear, shear, axial; ``k`` = shear factor),
* ``C_M = diag(E I1, E I2, G J_t)``  (bending about d1, d2; torsion),
* mass per length ``mu = rho A`` and inertia per length ``J = rho diag(I1, I2, I1 + I2)``.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from math import isfinite, pi

import numpy as np

from ...iga.patches import JOINT_KINDS
from ..errors import ParameterError

#: End conditions. ``roller``: the end moves along its reference tangent only and does not
#: twist (a fork support); ``pinned``: the end does not move and turns only about
#: ``BoundaryConditions.pin_axis`` (a pin, for frames in a plane); both for static and
#: buckling analyses of the Galerkin beam only.
END_TYPES = ("clamped", "hinged", "free", "roller", "pinned")


@dataclass(frozen=True)
class Material:
    """Linear elastic, isotropic material.

    Parameters
    ----------
    E : float
        Young's modulus [Pa], > 0.
    rho : float
        Density [kg/m^3], > 0.
    nu : float, optional
        Poisson's ratio (``G = E / (2 (1 + nu))``); ignored when ``G`` is given.
    G : float, optional
        Shear modulus [Pa].
    """

    E: float
    rho: float
    nu: float = 0.3
    G: float | None = None

    def __post_init__(self):
        if not self.E > 0:
            raise ParameterError("E", f"expected a positive Young's modulus, got {self.E!r}")
        if not self.rho > 0:
            raise ParameterError("rho", f"expected a positive density, got {self.rho!r}")
        if self.G is None and not (-1.0 < self.nu <= 0.5):
            raise ParameterError("nu", f"expected -1 < nu <= 0.5, got {self.nu!r}")
        if self.G is not None and not self.G > 0:
            raise ParameterError("G", f"expected a positive shear modulus, got {self.G!r}")

    @property
    def shear_modulus(self) -> float:
        return self.G if self.G is not None else self.E / (2.0 * (1.0 + self.nu))


def _sized(field: str, make):
    """``make()``, with a float overflow of the section constants reported against ``field``."""
    try:
        return make()
    except OverflowError:
        raise ParameterError(field, "too large: the section constants overflow") from None


@dataclass(frozen=True)
class Section:
    """Cross-section constants.

    Parameters
    ----------
    A : float
        Area [m^2].
    I1, I2 : float
        Second moments about the material axes d1 and d2 [m^4].
    J : float
        Torsion constant [m^4] (stiffness ``G J``).
    shear_factor : float
        Shear correction factor ``k`` (``G A_s = k G A``); 1 by default, as in the paper.
    """

    A: float
    I1: float
    I2: float
    J: float
    shear_factor: float = 1.0

    def __post_init__(self):
        for name in ("A", "I1", "I2", "J", "shear_factor"):
            v = getattr(self, name)
            if not (v > 0 and isfinite(v)):
                raise ParameterError(name, f"expected a positive, finite section constant, got {v!r}")

    @staticmethod
    def circle(d: float, shear_factor: float = 1.0) -> "Section":
        """Solid circle of diameter ``d``: ``A = pi d^2/4``, ``I = pi d^4/64``, ``J = pi d^4/32``."""
        if not d > 0:
            raise ParameterError("d", f"expected a positive diameter, got {d!r}")
        return _sized("d", lambda: Section(pi * d**2 / 4, pi * d**4 / 64, pi * d**4 / 64, pi * d**4 / 32,
                                           shear_factor))

    @staticmethod
    def square(t: float, shear_factor: float = 1.0) -> "Section":
        """Solid square of side ``t``: ``I = t^4/12``, torsion constant ``0.1406 t^4``."""
        if not t > 0:
            raise ParameterError("t", f"expected a positive side, got {t!r}")
        return _sized("t", lambda: Section(t**2, t**4 / 12, t**4 / 12, 0.1406 * t**4, shear_factor))

    @staticmethod
    def rectangle(b: float, h: float, shear_factor: float = 1.0) -> "Section":
        """Solid rectangle, width ``b`` along d1 and height ``h`` along d2.

        ``I1 = b h^3/12`` (bending about d1), ``I2 = h b^3/12``; torsion constant of
        Saint-Venant's series approximation ``a c^3 (1/3 - 0.21 (c/a)(1 - (c/a)^4/12))``
        with ``a = max(b, h)``, ``c = min(b, h)``.
        """
        if not (b > 0 and h > 0):
            raise ParameterError("b, h", f"expected positive sides, got {b!r}, {h!r}")
        a, c = max(b, h), min(b, h)

        def make():
            J = a * c**3 * (1.0 / 3.0 - 0.21 * (c / a) * (1.0 - (c / a) ** 4 / 12.0))
            return Section(b * h, b * h**3 / 12, h * b**3 / 12, J, shear_factor)

        return _sized("b, h", make)


@dataclass(frozen=True)
class SectionConstants:
    """Stiffness and inertia per unit length, in the material frame (axis 3 = beam axis).

    Parameters
    ----------
    CN : (3,) tuple
        ``(G A_1, G A_2, E A)`` [N].
    CM : (3,) tuple
        ``(E I_1, E I_2, G J)`` [N m^2].
    mu : float
        Mass per length ``rho A`` [kg/m].
    Jm : (3,) tuple
        Rotational inertia per length ``rho (I_1, I_2, I_p)`` [kg m].
    """

    CN: tuple
    CM: tuple
    mu: float
    Jm: tuple

    def __post_init__(self):
        for name in ("CN", "CM", "Jm"):
            v = getattr(self, name)
            if len(v) != 3 or not all(x > 0 and isfinite(x) for x in v):
                raise ParameterError(name, f"expected three positive, finite constants, got {v!r}")
        if not (self.mu > 0 and isfinite(self.mu)):
            raise ParameterError("mu", f"expected a positive, finite mass per length, got {self.mu!r}")

    def with_rotary_inertia_scale(self, scale: float) -> "SectionConstants":
        """The section with its bending rotary inertia ``rho I_1, rho I_2`` multiplied by
        ``scale`` (>= 1); the polar inertia is kept (torsional waves run no faster than axial
        ones, so it does not bound the stable step)."""
        scale = float(scale)
        if not (isfinite(scale) and scale >= 1.0):
            raise ParameterError("rotary_inertia_scale", f"expected a factor >= 1, got {scale!r}")
        return replace(self, Jm=(scale * self.Jm[0], scale * self.Jm[1], self.Jm[2]))

    @staticmethod
    def from_material(material: "Material", section: "Section") -> "SectionConstants":
        """``C_N = diag(k G A, k G A, E A)``, ``C_M = diag(E I1, E I2, G J)``,
        ``mu = rho A``, ``J = rho diag(I1, I2, I1 + I2)``."""
        E, G, rho, s = material.E, material.shear_modulus, material.rho, section
        return SectionConstants(
            CN=(s.shear_factor * G * s.A, s.shear_factor * G * s.A, E * s.A),
            CM=(E * s.I1, E * s.I2, G * s.J),
            mu=rho * s.A,
            Jm=(rho * s.I1, rho * s.I2, rho * (s.I1 + s.I2)),
        )


#: Kinds of :class:`Profile`.
PROFILE_KINDS = ("constant", "step", "ramp", "smooth", "table", "raised_cosine", "sine")


@dataclass(frozen=True)
class Profile:
    """Scalar time profile multiplying a load vector.

    Parameters
    ----------
    kind : {"constant", "step", "ramp", "smooth", "table", "raised_cosine", "sine"}
        ``constant``: 1; ``step``: 1 for ``t_on <= t < t_off``, else 0; ``ramp``: rises
        linearly from 0 at ``t_on`` to 1 at ``t_on + ramp``, then stays (and drops to 0 at
        ``t_off``); ``smooth``: like ``ramp`` but ``sin^2(pi/2 x)`` with
        ``x = (t - t_on)/ramp`` (zero slope at both ends, so it hardly excites the top of
        the spectrum); ``table``: piecewise linear through ``table`` points
        ``(t, factor)``, constant beyond its ends; ``raised_cosine``: ``1 - cos(2 pi x)``
        for ``0 <= x < 1`` with ``x = (t - t_on)/ramp``, else 0 (a smooth pulse; the
        angular acceleration of a spin-up); ``sine``: ``sin(2 pi (t - t_on)/ramp)`` for
        ``t_on <= t < t_off`` (period ``ramp``).
    """

    kind: str = "constant"
    t_on: float = 0.0
    t_off: float = np.inf
    ramp: float = 0.0
    table: tuple = ()

    def __post_init__(self):
        if self.kind not in PROFILE_KINDS:
            raise ParameterError("profile", f"expected one of {', '.join(PROFILE_KINDS)}, got {self.kind!r}")
        if self.kind in ("ramp", "smooth", "raised_cosine", "sine") and not self.ramp > 0:
            raise ParameterError("ramp", f"expected a positive ramp duration, got {self.ramp!r}")
        if self.kind == "table" and len(self.table) < 2:
            raise ParameterError("table", "expected at least two (t, factor) points")
        if not self.t_off > self.t_on:
            raise ParameterError("t_off", f"expected t_off > t_on, got t_on={self.t_on!r}, t_off={self.t_off!r}")

    def __call__(self, t: float) -> float:
        if self.kind == "constant":
            return 1.0
        if self.kind == "table":
            tt, ff = np.asarray(self.table, dtype=float).T
            return float(np.interp(t, tt, ff))
        if t < self.t_on or t >= self.t_off:
            return 0.0
        if self.kind == "step":
            return 1.0
        if self.kind == "sine":
            return float(np.sin(2 * np.pi * (t - self.t_on) / self.ramp))
        if self.kind == "raised_cosine":
            x = (t - self.t_on) / self.ramp
            return float(1.0 - np.cos(2 * np.pi * x)) if x < 1.0 else 0.0
        x = min(1.0, (t - self.t_on) / self.ramp)
        return x if self.kind == "ramp" else float(np.sin(0.5 * np.pi * x) ** 2)

    @property
    def is_constant(self) -> bool:
        return self.kind == "constant"


@dataclass(frozen=True)
class EndLoad:
    """Force and couple applied at one end with a time profile: dead loads (spatial
    components, fixed in space) or, with ``follower``, loads that turn with the end section
    (components in the section's material frame ``d1, d2, d3``: the spatial load is
    ``R(end) (force, couple)``, non-conservative)."""

    force: tuple = (0.0, 0.0, 0.0)
    couple: tuple = (0.0, 0.0, 0.0)
    force_profile: Profile = field(default_factory=Profile)
    couple_profile: Profile = field(default_factory=Profile)
    follower: bool = False

    @property
    def active(self) -> bool:
        return bool(np.any(self.force) or np.any(self.couple))


@dataclass(frozen=True)
class EndBody:
    """A rigid body fixed to one end of the beam (a tip mass, a hub, a payload): its centre
    of mass at ``offset`` from the end point and its principal axes along the end section's
    ``d1, d2, d3``, optionally loaded.

    Parameters
    ----------
    at : {"start", "end"}
        The end it is fixed to: of the beam, or of patch ``patch`` of a frame.
    mass : float
        Mass [kg] (>= 0).
    inertia : (3,) tuple
        Principal moments of inertia about the centre of mass, along ``d1, d2, d3`` [kg m^2]
        (>= 0).
    patch : int
        A frame's patch (member piece) whose end it is; -1: the end of the whole beam or
        chain.
    offset : (3,) tuple
        The centre of mass from the end point, components along the end section's ``d1, d2,
        d3`` [m] (it turns with the section).
    load : EndLoad
        Force and couple on the body, the force acting at its centre of mass (dead, or with
        ``follower`` turning with the body).
    joint : {"rigid", "ball", "hinge"}
        How it is attached at the end point: fixed to the end section (``rigid``), or turning
        freely about the point (``ball``) or about ``axis`` (``hinge``) with its own rotation;
        then ``offset`` and the principal axes are from the joint point, in the end section's
        reference frame, and the inertia about the joint must be positive in every direction.
    axis : (3,) tuple
        The hinge's axis (spatial, reference configuration; ``joint = "hinge"`` only).
    stiffness, damping : float
        The hinge's rotational spring [N m/rad] and damper [N m s/rad] (``"hinge"`` only).
    """

    at: str = "end"
    mass: float = 0.0
    inertia: tuple = (0.0, 0.0, 0.0)
    patch: int = -1
    offset: tuple = (0.0, 0.0, 0.0)
    load: EndLoad = field(default_factory=EndLoad)
    joint: str = "rigid"
    axis: tuple = (0.0, 0.0, 0.0)
    stiffness: float = 0.0
    damping: float = 0.0

    def __post_init__(self):
        if self.at not in ("start", "end"):
            raise ParameterError("at", f"expected 'start' or 'end', got {self.at!r}")
        if not (np.isfinite(self.mass) and self.mass >= 0.0):
            raise ParameterError("mass", f"expected a mass >= 0, got {self.mass!r}")
        J = np.asarray(self.inertia, dtype=float)
        if J.shape != (3,) or not np.all(np.isfinite(J)) or np.any(J < 0.0):
            raise ParameterError("inertia", f"expected three moments of inertia >= 0, got {self.inertia!r}")
        object.__setattr__(self, "inertia", tuple(float(x) for x in J))
        c = np.asarray(self.offset, dtype=float)
        if c.shape != (3,) or not np.all(np.isfinite(c)):
            raise ParameterError("offset", f"expected three finite components, got {self.offset!r}")
        object.__setattr__(self, "offset", tuple(float(x) for x in c))
        self._check_joint()

    def _check_joint(self) -> None:
        if self.joint not in JOINT_KINDS:
            raise ParameterError("joint", f"expected one of {', '.join(JOINT_KINDS)}, got {self.joint!r}")
        a = np.asarray(self.axis, dtype=float)
        if a.shape != (3,) or not np.all(np.isfinite(a)):
            raise ParameterError("axis", f"expected three finite components, got {self.axis!r}")
        object.__setattr__(self, "axis", tuple(float(x) for x in a))
        for name in ("stiffness", "damping"):
            if not (np.isfinite(getattr(self, name)) and getattr(self, name) >= 0.0):
                raise ParameterError(name, f"expected a value >= 0, got {getattr(self, name)!r}")
        if self.joint != "hinge":
            for name in ("axis", "stiffness", "damping"):
                if np.any(getattr(self, name)):
                    raise ParameterError(name, f"only a body on a hinge has an axis, a spring and a damper "
                                               f"(joint = {self.joint!r})")
        elif not np.any(a):
            raise ParameterError("axis", "a body on a hinge needs a non-zero axis [x, y, z]")
        if self.joint != "rigid":
            J = np.linalg.eigvalsh(self.end_inertia)
            if self.mass <= 0.0 or J[0] <= 1e-12 * max(J[-1], 1e-300):
                raise ParameterError("inertia", f"a body on a {self.joint} turns on its own: it needs a mass > 0 "
                                                "and an inertia about the joint that is positive in every "
                                                f"direction (principal values {np.round(J, 12).tolist()})")

    @property
    def end_inertia(self) -> np.ndarray:
        """The inertia about the end point in the section frame, ``(3, 3)``: ``diag(inertia)
        + mass (|c|^2 I - c c^T)`` (parallel axes)."""
        c = np.asarray(self.offset)
        return np.diag(self.inertia) + self.mass * (float(c @ c) * np.eye(3) - np.outer(c, c))


@dataclass(frozen=True)
class Loads:
    """External loads.

    Parameters
    ----------
    distributed_force : (3,) tuple
        Force per length [N/m], constant in time and space (spatial frame).
    gravity : (3,) tuple
        Acceleration [m/s^2]; adds ``mu * gravity`` to the distributed force.
    distributed_couple : (3,) tuple
        Couple per length [N m/m], spatial frame.
    distributed_profile : Profile
        Time profile of the distributed force, gravity and couple.
    start, end : EndLoad
        Loads at ``s = 0`` and ``s = L`` (only where that end is not clamped).
    joints : tuple of EndLoad
        Point loads at the joints of a chain of patches (:class:`~liegroup_int.iga.PatchedSpace`),
        one per joint in chain order (dead loads: ``follower`` is refused); empty: none.
    """

    distributed_force: tuple = (0.0, 0.0, 0.0)
    gravity: tuple = (0.0, 0.0, 0.0)
    distributed_couple: tuple = (0.0, 0.0, 0.0)
    distributed_profile: Profile = field(default_factory=Profile)
    start: EndLoad = field(default_factory=EndLoad)
    end: EndLoad = field(default_factory=EndLoad)
    joints: tuple = ()


@dataclass(frozen=True)
class SupportMotion:
    """A prescribed rotation ``theta(t)`` of a clamped end about a fixed spatial ``axis``
    through the end's position: ``R(end, t) = exp(theta(t) hat(a)) R(end, 0)``, angular
    velocity ``theta'(t) a`` and acceleration ``theta''(t) a`` (``a = axis / |axis|``).

    Kinds:

    * ``spin_up`` (Simo & Vu-Quoc 1986): ``theta = (rate / time) (t^2 / 2 + (time / 2 pi)^2
      (cos(2 pi t / time) - 1))`` for ``t < time``, then ``rate (t - time / 2)``: from rest
      to the angular speed ``rate`` [rad/s] with zero angular acceleration at both ends of
      the spin-up;
    * ``harmonic``: ``theta = amplitude sin(2 pi t / time)`` [rad].
    """

    kind: str = "spin_up"
    axis: tuple = (0.0, 0.0, 1.0)
    rate: float = 0.0
    amplitude: float = 0.0
    time: float = 1.0

    def __post_init__(self):
        if self.kind not in ("spin_up", "harmonic"):
            raise ParameterError("kind", f"expected 'spin_up' or 'harmonic', got {self.kind!r}")
        if not np.linalg.norm(self.axis) > 0:
            raise ParameterError("axis", "expected a non-zero vector")
        if not self.time > 0:
            raise ParameterError("time", f"expected a positive duration, got {self.time!r}")

    @property
    def unit_axis(self) -> np.ndarray:
        a = np.asarray(self.axis, dtype=float)
        return a / np.linalg.norm(a)

    def angle(self, t: float) -> float:
        """``theta(t)`` [rad]."""
        T = self.time
        if self.kind == "harmonic":
            return self.amplitude * np.sin(2 * pi * t / T)
        if t < T:
            return self.rate / T * (0.5 * t * t + (T / (2 * pi)) ** 2 * (np.cos(2 * pi * t / T) - 1.0))
        return self.rate * (t - 0.5 * T)

    def velocity(self, t: float) -> float:
        """``theta'(t)`` [rad/s]."""
        T = self.time
        if self.kind == "harmonic":
            return self.amplitude * (2 * pi / T) * np.cos(2 * pi * t / T)
        if t < T:
            return self.rate / T * (t - T / (2 * pi) * np.sin(2 * pi * t / T))
        return self.rate

    def acceleration_profile(self) -> tuple[float, "Profile"]:
        """``theta''(t) = scale * profile(t)``: ``rate / time`` times a raised cosine over
        the spin-up, or ``-amplitude (2 pi / time)^2`` times a sine."""
        if self.kind == "harmonic":
            return -self.amplitude * (2 * pi / self.time) ** 2, Profile("sine", ramp=self.time)
        return self.rate / self.time, Profile("raised_cosine", ramp=self.time)

    def acceleration(self, t: float) -> float:
        """``theta''(t)`` [rad/s^2]."""
        scale, prof = self.acceleration_profile()
        return scale * prof(t)


@dataclass(frozen=True)
class BoundaryConditions:
    """End conditions: ``clamped`` (position and rotation fixed), ``hinged`` (position
    fixed, moment-free), ``free`` (force- and moment-free, or loaded); a clamped end may
    follow a prescribed rotation (``start_motion``, ``end_motion``: :class:`SupportMotion`),
    and a clamped or hinged end a prescribed displacement (``start_translation``,
    ``end_translation``: a :class:`SupportMotion` read as a displacement ``d(t)`` [m]
    along its axis, e.g. base excitation)."""

    start: str = "clamped"
    end: str = "free"
    start_motion: SupportMotion | None = None
    end_motion: SupportMotion | None = None
    start_translation: SupportMotion | None = None
    end_translation: SupportMotion | None = None
    pin_axis: tuple = (0.0, 0.0, 1.0)

    def __post_init__(self):
        axis = np.asarray(self.pin_axis, dtype=float)
        if axis.shape != (3,) or not np.all(np.isfinite(axis)) or not np.linalg.norm(axis) > 0:
            raise ParameterError("pin_axis", f"expected a nonzero 3-vector, got {self.pin_axis!r}")
        object.__setattr__(self, "pin_axis", tuple(float(x) for x in axis / np.linalg.norm(axis)))
        for name in ("start", "end"):
            if getattr(self, name) not in END_TYPES:
                raise ParameterError(name, f"expected one of {', '.join(END_TYPES)}, got {getattr(self, name)!r}")
            if getattr(self, f"{name}_motion") is not None and getattr(self, name) != "clamped":
                raise ParameterError(f"{name}_motion", f"a prescribed rotation needs a clamped end, not "
                                                       f"{getattr(self, name)!r}")
            if getattr(self, f"{name}_translation") is not None and getattr(self, name) in ("free", "roller", "pinned"):
                raise ParameterError(f"{name}_translation", "a prescribed displacement needs a clamped or hinged "
                                                            "end, not 'free'")


@dataclass(frozen=True)
class InitialConditions:
    """Initial motion of the reference configuration.

    ``velocity`` is a uniform translational velocity; ``omega`` a rigid angular velocity
    about the point ``axis_point``: ``v(s) = velocity + omega x (c0(s) - axis_point)``,
    ``w(s) = omega`` (spatial).
    """

    velocity: tuple = (0.0, 0.0, 0.0)
    omega: tuple = (0.0, 0.0, 0.0)
    axis_point: tuple = (0.0, 0.0, 0.0)
