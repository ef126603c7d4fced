"""Scene kind ``beam``: geometrically exact beams by explicit RKMK IGA-C."""

from __future__ import annotations

import math

import numpy as np

from ..iga import CollocationSpace, NurbsCurve, arc_length, arc_nurbs_quadratic, helix_quarter, k_refine, straight
from ..iga.patches import JOINT_KINDS, PatchedSpace, split_curve
from ..iga.quadrature import DEFAULT_RULE, RULES
from ..problems.beam import (
    BeamProblem,
    BeamState,
    BoundaryConditions,
    EndBody,
    EndLoad,
    InitialConditions,
    Loads,
    Material,
    Profile,
    Section,
    SectionConstants,
    SupportMotion,
)
from ..problems.beam.damping import size_kelvin_voigt
from ..problems.beam.inertia_scaling import MAX_UNKNOWNS, given_scale_report, size_rotary_inertia
from ..problems.beam.formulations import beam_problem
from ..problems.beam.model import END_TYPES, PROFILE_KINDS
from ..problems.beam.problem import SECTION_FIELDS
from ..problems.errors import ParameterError
from .scene import ProblemKind, Scene, Simulation, Stability, register_kind
from .schema import Key, SceneError, flatten, non_negative, positive, resolve_keys

ZERO = (0.0, 0.0, 0.0)


def _int_between(lo, hi):
    return lambda v: None if lo <= v <= hi else f"an integer from {lo} to {hi}"


def _at_least_one(v):
    return None if v == "auto" or v >= 1 else 'a factor >= 1 or "auto"'


def _end_keys(end: str) -> list[Key]:
    at = "s = 0" if end == "start" else "s = L"
    return [
        Key(f"motion.{end}.kind", "str", "none", f"prescribed rotation of the clamped end at {at}: spin_up "
            "(Simo & Vu-Quoc 1986, rest to motion.rate over motion.time) or harmonic (amplitude "
            "sin(2 pi t / time); it starts at full speed, an impulsive start whose shock converges slowly in dt)",
            choices=("none", "spin_up", "harmonic")),
        Key(f"motion.{end}.axis", "vec3", (0.0, 0.0, 1.0), f"axis of the prescribed rotation (through the end at {at})"),
        Key(f"motion.{end}.rate", "float", 0.0, "final angular speed of a spin_up", "rad/s"),
        Key(f"motion.{end}.amplitude", "float", 0.0, "amplitude of a harmonic rotation", "rad"),
        Key(f"motion.{end}.time", "float", 1.0, "spin-up duration, or period of the harmonic rotation", "s", positive),
        Key(f"translation.{end}.kind", "str", "none", f"prescribed displacement d(t) of the clamped or hinged end at "
            f"{at} along translation.{end}.axis: speed_up (from rest to translation.{end}.rate over "
            f"translation.{end}.time, zero acceleration at both ends) or harmonic (amplitude sin(2 pi t / time); "
            "it starts at full speed, an impulsive start whose shock converges slowly in dt); base excitation",
            choices=("none", "speed_up", "harmonic")),
        Key(f"translation.{end}.axis", "vec3", (0.0, 0.0, 1.0), "direction of the prescribed displacement"),
        Key(f"translation.{end}.rate", "float", 0.0, "final speed of a speed_up", "m/s"),
        Key(f"translation.{end}.amplitude", "float", 0.0, "amplitude of a harmonic displacement", "m"),
        Key(f"translation.{end}.time", "float", 1.0, "speed-up duration, or period of the harmonic displacement", "s",
            positive),
        Key(f"loads.{end}.force", "vec3", ZERO, f"force at {at} (spatial, dead load; material frame if follower)",
            "N"),
        Key(f"loads.{end}.couple", "vec3", ZERO, f"couple at {at} (spatial; material frame if follower)", "N m"),
        Key(f"loads.{end}.follower", "bool", False, f"the force and couple at {at} turn with the end section "
            "(components in its frame d1, d2, d3; non-conservative)"),
        Key(f"loads.{end}.profile", "str", "constant", f"time profile of the {end} loads",
            choices=PROFILE_KINDS),
        Key(f"loads.{end}.t_on", "float", 0.0, "profile switch-on time (step, ramp)", "s", non_negative),
        Key(f"loads.{end}.t_off", "float", float("inf"), "profile switch-off time (step, ramp)", "s", positive),
        Key(f"loads.{end}.ramp", "float", 1.0, "ramp duration (ramp)", "s", positive),
        Key(f"loads.{end}.table", "table", ((0.0, 1.0), (1.0, 1.0)), "[t, factor] points (table)"),
    ]


def _fractions(values) -> str | None:
    """``output.points``: fractions of the length in [0, 1]."""
    return None if all(0.0 <= v <= 1.0 for v in values) else "fractions of the length in [0, 1]"


KEYS = {
    k.name: k
    for k in [
        Key("geometry.kind", "str", "straight", "reference centreline", choices=("straight", "arch", "helix", "nurbs")),
        Key("geometry.length", "float", 1.0, "length of a straight beam", "m", positive),
        Key("geometry.direction", "vec3", (1.0, 0.0, 0.0), "axis direction of a straight beam"),
        Key("geometry.origin", "vec3", ZERO, "position of s = 0 of a straight beam", "m"),
        Key("geometry.degree", "int", 2, "degree of a given NURBS (kind = nurbs; 1 to 10)", "", _int_between(1, 10)),
        Key("geometry.control_points", "floats", (0.0,), "flat list of x, y, z of the NURBS control points", "m"),
        Key("geometry.weights", "floats", (1.0,), "NURBS weights (default all 1)"),
        Key("geometry.knots", "floats", (0.0,), "NURBS knot vector (default open uniform)"),
        Key("geometry.reference_vector", "vec3", ZERO,
            "vector defining the section axis d1 (projected normal to the tangent); 0 = automatic"),
        Key("integrator.backend", "str", "numba", "stage kernels: compiled (numba) or plain NumPy",
            choices=("numba", "numpy")),
        Key("space.degree", "int", 4, "spline degree p (2 to 10)", "", _int_between(2, 10)),
        Key("space.formulation", "str", "galerkin",
            "balance laws: the weak form (galerkin, the default: energy-conserving, locking-free, no spurious "
            "growing mode), or the paper's primal collocation (primal)",
            choices=("primal", "galerkin")),
        Key("space.quadrature", "str", DEFAULT_RULE,
            "quadrature rule of the galerkin stiffness (auto: gauss-spline-reduced for p = 3..6, else "
            "gauss-spline for p = 3..7, where found and determining the basis, else gauss-p, and gauss on a piece "
            "of one or two knot intervals; gauss-spline-reduced: the Gaussian rule of the products N_i' N_j', "
            "about p / 2 points per knot interval; gauss-spline: of the products N_i' N_j, about (p + 1) / 2; "
            "gauss-p: p Gauss points per knot interval; the three integrate the straight beam's bending and "
            "axial stiffness at rest exactly)",
            choices=tuple(RULES)),
        Key("space.n_ctrl", "int", 31, "number of control points (the paper's n + 1; 4 to 2001)", "", _int_between(4, 2001)),
        Key("material.E", "float", None, "Young's modulus", "Pa", positive),
        Key("material.nu", "float", 0.3, "Poisson's ratio (G = E / (2 (1 + nu)))"),
        Key("material.G", "float", None, "shear modulus (overrides nu)", "Pa", positive),
        Key("material.rho", "float", None, "density", "kg/m^3", positive),
        Key("material.kelvin_voigt", "number_or_auto", 0.0,
            "Kelvin-Voigt retardation time tau (strain-rate damping, ratio tau omega / 2; 0 = none; \"auto\" = "
            "the least that leaves no growing mode at t = 0, from the dense spectrum)", "s", non_negative),
        Key("section.shape", "str", "circle", "cross-section", choices=("circle", "square", "rectangle", "explicit")),
        Key("section.d", "float", None, "diameter (circle)", "m", positive),
        Key("section.t", "float", None, "side (square)", "m", positive),
        Key("section.b", "float", None, "width along d1 (rectangle)", "m", positive),
        Key("section.h", "float", None, "height along d2 (rectangle)", "m", positive),
        Key("section.shear_factor", "float", 1.0, "shear correction factor k (G A_s = k G A)", "", positive),
        Key("section.rotary_inertia_scale", "number_or_auto", 1.0,
            "factor >= 1 on the bending rotary inertia rho I1, rho I2 (1 = the exact model; a larger factor lowers "
            "the shear-rotation branch that bounds the stable step; \"auto\" = the largest that moves the lowest "
            "section.rotary_inertia_modes frequencies by at most section.rotary_inertia_tol, capped where the "
            "top frequency stops falling; galerkin; reported in summary.json)", "", _at_least_one),
        Key("section.rotary_inertia_modes", "int", 6, "lowest distinct modes checked by rotary_inertia_scale",
            "", _int_between(1, 50)),
        Key("section.rotary_inertia_tol", "float", 1e-3,
            "relative frequency shift of those modes allowed by rotary_inertia_scale = \"auto\"", "", positive),
        Key("section.EA", "float", None, "axial stiffness (explicit)", "N", positive),
        Key("section.GA", "float", None, "shear stiffness (explicit)", "N", positive),
        Key("section.EI1", "float", None, "bending stiffness about d1 (explicit)", "N m^2", positive),
        Key("section.EI2", "float", None, "bending stiffness about d2 (explicit)", "N m^2", positive),
        Key("section.GJ", "float", None, "torsional stiffness (explicit)", "N m^2", positive),
        Key("section.rhoA", "float", None, "mass per length (explicit)", "kg/m", positive),
        Key("section.rhoI1", "float", None, "rotational inertia per length about d1 (explicit)", "kg m", positive),
        Key("section.rhoI2", "float", None, "rotational inertia per length about d2 (explicit)", "kg m", positive),
        Key("section.rhoJ", "float", None, "polar inertia per length (explicit; default rhoI1 + rhoI2)", "kg m", positive),
        Key("bc.start", "str", "clamped", "end condition at s = 0 (roller: slides along its tangent, a coordinate "
            "axis, without twisting; pinned: held, turning about bc.pin_axis only; both static and buckle only)",
            choices=END_TYPES),
        Key("bc.end", "str", "free", "end condition at s = L (as bc.start)", choices=END_TYPES),
        Key("bc.pin_axis", "vec3", [0.0, 0.0, 1.0], "axis a pinned end turns about (along an axis of its section: "
            "the normal of a frame's plane)"),
        Key("loads.gravity", "vec3", ZERO, "gravitational acceleration (adds rho A g per length)", "m/s^2"),
        Key("loads.distributed_force", "vec3", ZERO, "force per length, spatial", "N/m"),
        Key("loads.distributed_couple", "vec3", ZERO, "couple per length, spatial", "N m/m"),
        Key("loads.profile", "str", "constant", "time profile of the distributed loads (and gravity)",
            choices=PROFILE_KINDS),
        Key("loads.t_on", "float", 0.0, "distributed-load profile switch-on time", "s", non_negative),
        Key("loads.t_off", "float", float("inf"), "distributed-load profile switch-off time", "s", positive),
        Key("loads.ramp", "float", 1.0, "distributed-load ramp duration (ramp, smooth)", "s", positive),
        Key("loads.table", "table", ((0.0, 1.0), (1.0, 1.0)), "distributed-load [t, factor] points (table)"),
        *_end_keys("start"),
        *_end_keys("end"),
        Key("initial.velocity", "vec3", ZERO, "uniform initial velocity", "m/s"),
        Key("initial.omega", "vec3", ZERO, "initial rigid angular velocity (spatial)", "rad/s"),
        Key("initial.axis_point", "vec3", ZERO, "point on the axis of the initial rigid rotation", "m"),
        Key("initial.state", "str", "reference", 'initial configuration: the unstressed reference geometry, or '
            '"static": the static equilibrium under the loads at t = 0, at rest (galerkin; Newton with load steps, '
            'as `liegroup-int static`)', choices=("reference", "static")),
        Key("initial.static_steps", "int", 10, 'load steps of the static solve of initial.state = "static"', "",
            _int_between(1, 10000)),
        Key("beams", "tables", (), "a frame: [[beams]] entries (members), each a patch with the keys of "
            "[geometry] (kind, length, direction, origin, ...), a name, optionally its own n_ctrl and its own section "
            "([beams.section], [beams.material]: the scene's keys fill in the rest); without [[joints]] they form a "
            "chain, each member's end joined rigidly to the next one's start (equal position and rotation, balance "
            "of resultants); bc.start is the first member's start and bc.end the last member's end; replaces "
            "[geometry]"),
        Key("joints", "tables", (), "[[joints]] entries: joints between any member ends instead of the chain (T and "
            "X junctions, closed rings, trees; galerkin): ends, the coinciding member ends joined at one point "
            "(\"<name>.start\" or \"<name>.end\" of named [[beams]] entries, or \"<name>@<fraction>\", an interior "
            "point of a member at that fraction of its length, where the member stays continuous; two or more; "
            "each end in one joint at most, and not a supported end: support a frame through an end of its own), "
            "and kind: rigid (equal "
            "position and rotation, the default), ball (equal position, rotations free: no couple transmitted) "
            "or hinge (equal position, relative rotation about axis only: no couple about the axis but that of "
            "its rotational spring and damper, stiffness and damping)"),
        Key("point_loads", "tables", (), "[[point_loads]] entries: s (fraction of the reference length, inside "
            "(0, 1); members in [[beams]] order), force and couple (spatial, dead), and a time profile (profile, "
            "t_on, t_off, ramp, table); a beam is split at s into two patches joined rigidly, where the load acts "
            "(with [[joints]]: inside a member only)"),
        Key("bodies", "tables", (), "[[bodies]] entries: rigid bodies fixed to an end of the beam (galerkin): at "
            "(\"start\" or \"end\"; in a frame \"<member>.start\", \"<member>.end\" or an interior point "
            "\"<member>@<fraction>\"), mass [kg], inertia (principal moments about the centre of mass along the end "
            "section's d1, d2, d3 [kg m^2]), offset (centre of mass from the end point, section frame [m]), force "
            "and couple on the body with a time profile, joint (rigid; ball or hinge with axis, stiffness, "
            "damping: the body turns on its own) (a tip mass, a hub, a payload)"),
        Key("output.points", "floats", (), "history of the centreline at these fractions of the reference length "
            "(columns s0p5_x, s0p5_y, s0p5_z for 0.5), e.g. [0.5, 1.0]", "", _fractions),
        Key("output.fields", "strs", (), "section quantities at the collocation points, in results.h5 snapshots "
            "(section_<name>) and ParaView point data: strains Gamma, K; resultants N, M (material), n, m (spatial); "
            "velocity, angular_velocity", choices=SECTION_FIELDS),
    ]
}

QUANTITIES = ("tip", "energy", "kinetic", "strain", "momentum", "angular_momentum", "orth_error", "energy_balance",
              "work", "reactions", "joint_reactions", "bodies")
COLUMNS = {
    "tip": ["tip_x", "tip_y", "tip_z"],
    "momentum": ["p_x", "p_y", "p_z"],
    "angular_momentum": ["h_x", "h_y", "h_z"],
}


def _err(scene: Scene, key: str, expected: str):
    raise SceneError(f"{scene.source}: key '{key}': expected {expected}")


def _need(scene: Scene, key: str, why: str):
    if scene[key] is None:
        raise SceneError(f"{scene.source}: missing key '{key}' ({why})")
    return scene[key]


def geometry(scene: Scene) -> NurbsCurve:
    """Reference centreline at the scene's ``(space.degree, space.n_ctrl)`` (one beam)."""
    return _curve(scene, lambda k: scene[f"geometry.{k}"], "geometry.", scene["space.n_ctrl"])


def _base_curve(scene: Scene, get, pre: str) -> NurbsCurve | None:
    """The given NURBS of ``kind = nurbs`` (before refinement), None for built-in kinds."""
    if get("kind") != "nurbs":
        return None
    pts = np.asarray(get("control_points"), float)
    if pts.size < 6 or pts.size % 3:
        _err(scene, f"{pre}control_points", "a flat list of x, y, z triples (at least two points)")
    pts = pts.reshape(-1, 3)
    deg = get("degree")
    w = np.asarray(get("weights"), float)
    if w.size == 1 and w[0] == 1.0:
        w = np.ones(len(pts))
    if w.size != len(pts) or np.any(w <= 0):
        _err(scene, f"{pre}weights", f"{len(pts)} positive weights")
    kv = np.asarray(get("knots"), float)
    if kv.size == 1:
        from ..iga import open_uniform_knots

        kv = open_uniform_knots(deg, len(pts))
    if scene["space.degree"] < deg:
        _err(scene, "space.degree", f"at least the NURBS degree {deg}")
    return NurbsCurve(deg, kv, pts, w)


def _curve(scene: Scene, get, pre: str, n: int, base: NurbsCurve | None = None) -> NurbsCurve:
    """A centreline of ``n`` control points at degree ``space.degree`` from geometry keys
    ``get(name)`` (``pre`` names them in errors); ``base`` replaces the described curve."""
    kind, p = get("kind"), scene["space.degree"]
    if n < p + 1:
        _err(scene, "space.n_ctrl", f"at least space.degree + 1 = {p + 1} control points, got {n}")
    try:
        if base is not None:
            return k_refine(base, p, n)
        if kind == "straight":
            if not np.any(get("direction")):
                _err(scene, f"{pre}direction", "a non-zero vector")
            return straight(get("length"), get("direction"), p, n, get("origin"))
        if kind == "arch":
            return arc_nurbs_quadratic(p, n)
        if kind == "helix":
            return helix_quarter(p, n)
        return k_refine(_base_curve(scene, get, pre), p, n)
    except ValueError as exc:
        raise SceneError(f"{scene.source}: {pre.rstrip('.') or 'geometry'}: {exc}") from None


#: Keys of one ``[[beams]]`` entry: those of ``[geometry]`` plus a name and its own n_ctrl.
BEAM_KEYS = {
    "name": Key("name", "str", "", "name of the beam (errors and docs)"),
    "n_ctrl": Key("n_ctrl", "int", 0, "control points of this patch (0: space.n_ctrl)", "", lambda v: None if v >= 0 else
                  "an integer >= 0"),
}
#: The time-profile keys of a load entry ([[point_loads]], [[joints]]).
PROFILE_KEYS = {
    "profile": Key("profile", "str", "constant", "time profile of the force and couple", choices=PROFILE_KINDS),
    "t_on": Key("t_on", "float", 0.0, "profile switch-on time", "s", non_negative),
    "t_off": Key("t_off", "float", float("inf"), "profile switch-off time", "s", positive),
    "ramp": Key("ramp", "float", 1.0, "ramp duration", "s", positive),
}
#: Keys of one ``[[joints]]`` entry.
JOINT_KEYS = {
    "ends": Key("ends", "strs", (), "the joined member ends, \"<name>.start\" or \"<name>.end\", or interior "
                "points, \"<name>@<fraction>\" (the fraction of the member's length, in (0, 1): the member stays "
                "continuous there); two or more"),
    "kind": Key("kind", "str", "rigid", "rigid (position and rotation), ball (position only) or hinge "
                "(position, and rotation but for a turn about the axis)", choices=JOINT_KINDS),
    "axis": Key("axis", "vec3", ZERO, "hinge axis (spatial, reference configuration; kind = \"hinge\" only)"),
    "stiffness": Key("stiffness", "float", 0.0, "rotational spring about the hinge axis: couple k phi, phi the "
                     "relative rotation angle (|phi| < pi; kind = \"hinge\" only)", "N m/rad", non_negative),
    "damping": Key("damping", "float", 0.0, "rotational damper about the hinge axis: couple c dphi/dt "
                   "(kind = \"hinge\" only)", "N m s/rad", non_negative),
    "force": Key("force", "vec3", ZERO, "force at the joint (spatial, dead load, on its first end)", "N"),
    "couple": Key("couple", "vec3", ZERO, "couple at the joint (spatial, dead load, on its first end)", "N m"),
    **PROFILE_KEYS,
}
#: Keys of one ``[[bodies]]`` entry.
BODY_KEYS = {
    "at": Key("at", "str", "end", "the end the body is fixed to: \"start\" or \"end\" of the beam (or chain), "
              "\"<member>.start\" / \"<member>.end\" of a named [[beams]] member (a frame's joint included), or "
              "an interior point \"<member>@<fraction>\" (the member split there, its pieces joined rigidly)"),
    "mass": Key("mass", "float", 0.0, "mass", "kg", non_negative),
    "inertia": Key("inertia", "vec3", ZERO, "principal moments of inertia about the centre of mass, along the "
                   "end section's d1, d2, d3", "kg m^2"),
    "offset": Key("offset", "vec3", ZERO, "centre of mass from the end point, along the end section's d1, d2, d3 "
                  "(it turns with the end)", "m"),
    "force": Key("force", "vec3", ZERO, "force on the body at its centre of mass (spatial, dead; material with "
                 "follower)", "N"),
    "couple": Key("couple", "vec3", ZERO, "couple on the body (spatial, dead; material with follower)", "N m"),
    "follower": Key("follower", "bool", False, "the force and couple turn with the body"),
    "joint": Key("joint", "str", "rigid", "rigid (fixed to the end section), ball (turning freely about the end "
                 "point) or hinge (turning about axis): on a ball or hinge the body has its own rotation, its "
                 "offset and axes from the joint point in the end section's reference frame", choices=JOINT_KINDS),
    "axis": Key("axis", "vec3", ZERO, "hinge axis (spatial, reference configuration; joint = \"hinge\" only)"),
    "stiffness": Key("stiffness", "float", 0.0, "rotational spring about the hinge axis (joint = \"hinge\" only)",
                     "N m/rad", non_negative),
    "damping": Key("damping", "float", 0.0, "rotational damper about the hinge axis (joint = \"hinge\" only)",
                   "N m s/rad", non_negative),
    **PROFILE_KEYS,
    "table": Key("table", "table", ((0.0, 1.0), (1.0, 1.0)), "[t, factor] points (table)"),
}
#: Keys of one ``[[point_loads]]`` entry.
POINT_LOAD_KEYS = {
    "s": Key("s", "float", None, "position as a fraction of the reference length, in (0, 1)", "",
             lambda v: None if 0.0 < v < 1.0 else "a fraction in (0, 1) (use loads.start / loads.end at the ends)"),
    "force": Key("force", "vec3", ZERO, "force (spatial, dead load)", "N"),
    "couple": Key("couple", "vec3", ZERO, "couple (spatial, dead load)", "N m"),
    **PROFILE_KEYS,
    "table": Key("table", "table", ((0.0, 1.0), (1.0, 1.0)), "[t, factor] points (table)"),
}


def _pieces(scene: Scene):
    """The beams of the scene before splitting: ``[(get, pre, n_ctrl, section)]`` with
    ``get(key)`` its geometry keys, ``pre`` its name in errors and ``section`` its own
    :class:`SectionConstants` (None: the scene's)."""
    if not scene["beams"]:
        return [(lambda k: scene[f"geometry.{k}"], "geometry.", scene["space.n_ctrl"], None)]
    given = [k for k in scene.raw if k.startswith("geometry.")]
    if given:
        raise SceneError(f"{scene.source}: key '{given[0]}': a frame takes its geometry from [[beams]]; "
                         "remove [geometry]")
    geo_keys = {k.split(".", 1)[1]: Key(k.split(".", 1)[1], v.kind, v.default, v.doc, v.unit, v.check, v.choices)
                for k, v in KEYS.items() if k.startswith("geometry.")}
    section_keys = {k: v for k, v in KEYS.items() if k.startswith(SECTION_PREFIXES) and k not in SCENE_WIDE}
    out = []
    for i, entry in enumerate(scene["beams"]):
        where = f"beams[{i}]"
        flat = flatten(entry)
        own = {k: flat.pop(k) for k in list(flat) if k.startswith(SECTION_PREFIXES)}
        v = resolve_keys({**geo_keys, **BEAM_KEYS}, flat, f"{scene.source}: {where}")
        label = f"{where}." if not v["name"] else f"beams[{i}] ({v['name']})."
        if own:  # its own section: the given keys, the scene's for the rest
            if not set(own) <= set(section_keys):
                _unknown_section_key(scene, where, own, section_keys)
            given = resolve_keys({k: section_keys[k] for k in own}, own, f"{scene.source}: {where}")
            section = constants(scene, lambda k, g=given: g[k] if k in g else scene[k], label)
        else:
            section = None
        out.append((v.get, label, v["n_ctrl"] or scene["space.n_ctrl"], section))
    return out


#: Key prefixes a ``[[beams]]`` entry may set for itself (its section).
SECTION_PREFIXES = ("section.", "material.")
#: Keys under those prefixes set once for the whole scene.
SCENE_WIDE = ("material.kelvin_voigt", "section.rotary_inertia_scale", "section.rotary_inertia_modes",
              "section.rotary_inertia_tol")


def _unknown_section_key(scene: Scene, where: str, own: dict, section_keys: dict):
    bad = sorted(set(own) - set(section_keys))[0]
    hint = f" ({bad.split('.')[1]} is set once, in [{bad.split('.')[0]}])" if bad in SCENE_WIDE else ""
    raise SceneError(f"{scene.source}: {where}: unknown key '{bad}'{hint}")


def _exact_base(scene: Scene, get, pre: str) -> NurbsCurve | None:
    """The described centreline in its exact coarsest form (degree 1 line, quadratic NURBS
    arc, the given NURBS), or None for the helix (an interpolant)."""
    kind = get("kind")
    if kind == "straight":
        return straight(get("length"), get("direction"), 1, 2, get("origin"))
    if kind == "arch":
        return arc_nurbs_quadratic(2, 3)
    return _base_curve(scene, get, pre) if kind == "nurbs" else None


def _split_at(base: NurbsCurve, frac: float):
    """The two exact pieces of a centreline split at the fraction ``frac`` of its length."""
    length = float(arc_length(base, [1.0])[0])
    lo, hi = 0.0, 1.0
    for _ in range(60):  # bisection on the arc length
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if float(arc_length(base, [mid])[0]) < frac * length else (lo, mid)
    return split_curve(base, 0.5 * (lo + hi))


def _point_load_list(scene: Scene) -> list:
    """``[(s, index, EndLoad)]`` of the scene's ``[[point_loads]]``, sorted by ``s``."""
    loads = []
    for i, entry in enumerate(scene["point_loads"]):
        v = resolve_keys(POINT_LOAD_KEYS, entry, f"{scene.source}: point_loads[{i}]")
        if v["s"] is None:
            raise SceneError(f"{scene.source}: point_loads[{i}]: missing key 's' ({POINT_LOAD_KEYS['s'].doc})")
        try:
            prof = Profile(kind=v["profile"], t_on=v["t_on"], t_off=v["t_off"], ramp=v["ramp"], table=v["table"])
        except ParameterError as exc:
            raise SceneError(f"{scene.source}: point_loads[{i}]: key '{exc.field}': {exc.reason}") from None
        loads.append((v["s"], i, EndLoad(force=v["force"], couple=v["couple"], force_profile=prof,
                                         couple_profile=prof)))
    loads.sort(key=lambda x: x[0])
    return loads


def _split_pieces(scene: Scene, frame: dict, s: float, what: str, load: EndLoad | None) -> None:
    """Split the piece of ``frame`` (lists ``pieces, sections, spaces, members,
    joint_loads``) at the fraction ``s`` of the total length, where the point load ``load``
    acts (``what``: ``"point_loads[i]"``) or a joint takes an interior point of a member
    (``load`` None, ``what``: ``"joints[i]"``); at an existing piece end a load goes on the
    joint there."""
    p, spaces, joint_loads = scene["space.degree"], frame["spaces"], frame["joint_loads"]
    edges = np.concatenate([[0.0], np.cumsum([sp.length for sp in spaces])])
    edges /= edges[-1]
    at = int(np.argmin(np.abs(edges - s)))
    if abs(edges[at] - s) <= 1e-9:  # at a joint
        if scene["joints"] and frame["members"][at - 1] != frame["members"][at]:
            if load is not None:
                raise SceneError(f"{scene.source}: {what}: s = {s!r} is a member end; with [[joints]] a point load "
                                 "acts inside a member")
            raise SceneError(f"{scene.source}: {what}: the point at {s:.6g} of the total length is a member's end, "
                             "not an interior point: name it \"<member>.start\" or \"<member>.end\"")
        if load is not None and joint_loads[at - 1] is not None:
            raise SceneError(f"{scene.source}: {what}: another point load acts at s = {s!r}")
        if load is not None:
            joint_loads[at - 1] = load
        return
    k = int(np.searchsorted(edges, s) - 1)
    get, pre, _, n, exact = frame["pieces"][k]
    exact = exact if exact is not None else _exact_base(scene, get, pre)
    if exact is None:
        raise SceneError(f"{scene.source}: {what}: a {'point load' if load is not None else 'joint'} inside a helix "
                         "beam is not supported; describe the helix as a NURBS (kind = nurbs)")
    frac = (s - edges[k]) / (edges[k + 1] - edges[k])
    left, right = _split_at(exact, frac)
    n_left = max(p + 1, int(round(frac * (n - 1))) + 1)
    n_right = max(p + 1, n + 1 - n_left)
    a, b = _curve(scene, get, pre, n_left, left), _curve(scene, get, pre, n_right, right)
    frame["pieces"][k:k + 1] = [(get, pre, a, n_left, left), (get, pre, b, n_right, right)]
    for name in ("sections", "members"):
        frame[name][k:k + 1] = [frame[name][k]] * 2
    spaces[k:k + 1] = [_space(scene, get, pre, a), _space(scene, get, pre, b)]
    joint_loads.insert(k, load)


def frame_space(scene: Scene):
    """The collocation space of the scene, the joint point loads, and one section per patch
    when a ``[[beams]]`` entry has its own (else None): ``(space, joint_loads, sections)``;
    one :class:`CollocationSpace` for a single beam without point loads or joints, else a
    :class:`PatchedSpace` (beams of ``[[beams]]``, split where ``[[point_loads]]`` act;
    the two pieces of a split share its control points by length, one shared; joined in a
    chain, or as ``[[joints]]`` says: :func:`_graph`)."""
    beams = _pieces(scene)
    frame = {"pieces": [(get, pre, _curve(scene, get, pre, n), n, None) for get, pre, n, _ in beams],
             "sections": [sec for *_, sec in beams], "members": list(range(len(beams)))}
    loads = _point_load_list(scene)
    if len(beams) == 1 and not loads and not scene["joints"] and not any("@" in p for *_, p in _interior_places(scene)):
        get, pre, curve, _, _ = frame["pieces"][0]
        return _space(scene, get, pre, curve), (), frame["sections"][0]
    frame["spaces"] = [_space(scene, get, pre, c) for get, pre, c, _, _ in frame["pieces"]]
    frame["joint_loads"] = [None] * (len(beams) - 1)
    for s, what in _interior_split_points(scene, frame):
        _split_pieces(scene, frame, s, what, None)
    for s, i, load in loads:
        _split_pieces(scene, frame, s, f"point_loads[{i}]", load)
    joint_loads, graph = frame["joint_loads"], {}
    if scene["joints"]:
        pairs, kinds, axes, springs, joint_loads = _graph(scene, frame)
        graph = {"joints": pairs, "kinds": kinds, "axes": axes, "springs": springs}
    try:
        space = PatchedSpace(frame["spaces"], **graph)
    except ValueError as exc:
        raise SceneError(f"{scene.source}: key '{'joints' if graph else 'beams'}': {exc}") from None
    space.members = tuple(frame["members"])  # the [[beams]] entry of each patch (bodies at member ends)
    sections = frame["sections"]
    if any(sec is not None for sec in sections):
        shared = constants(scene) if any(sec is None for sec in sections) else None
        sections = tuple(sec if sec is not None else shared for sec in sections)
    else:
        sections = None
    return space, tuple(ld if ld is not None else EndLoad() for ld in joint_loads), sections


def _interior_point(where: str, end: str, names: list, key: str = "ends") -> tuple[int, float] | None:
    """``(member, fraction)`` of a joint end or a body's place ``"<name>@<fraction>"`` (an
    interior point of a member, the fraction of its length in (0, 1)), or None for a
    member end; ``key`` names the scene key in errors."""
    if "@" not in end:
        return None
    name, _, frac = end.rpartition("@")
    if name not in names:
        raise SceneError(f"{where}: key '{key}': {end!r}: no [[beams]] entry named {name!r}"
                         + (f" (members: {', '.join(names)})" if any(names) else ""))
    try:
        f = float(frac)
    except ValueError:
        f = math.nan
    if not 0.0 < f < 1.0:
        raise SceneError(f"{where}: key '{key}': {end!r}: expected \"<member>@<fraction>\" with a fraction of the "
                         "member's length strictly between 0 and 1 (its ends are \"<member>.start\" and "
                         "\"<member>.end\")")
    return names.index(name), f


def _canonical_end(where: str, end: str, names: list) -> str:
    """``end`` with an interior point's fraction written as a float (``"a@0.50"`` and
    ``"a@0.5"`` are one point)."""
    point = _interior_point(where, end, names)
    return end if point is None else f"{names[point[0]]}@{point[1]!r}"


def _member_fractions(frame: dict, m: int) -> tuple[list, np.ndarray]:
    """The pieces of member ``m`` and the fractions of its length where they end."""
    pieces = [k for k, mm in enumerate(frame["members"]) if mm == m]
    lengths = np.array([frame["spaces"][k].length for k in pieces])
    return pieces, np.cumsum(lengths) / lengths.sum()


def _interior_places(scene: Scene) -> list:
    """``[(what, key, place)]``: every place that ``[[joints]]`` entries (``ends``) and
    ``[[bodies]]`` entries (``at``) name, member ends and interior points
    ``"<name>@<fraction>"`` alike."""
    out = [(f"joints[{i}]", "ends", e) for i, entry in enumerate(scene["joints"])
           for e in resolve_keys(JOINT_KEYS, entry, f"{scene.source}: joints[{i}]")["ends"]]
    return out + [(f"bodies[{i}]", "at", resolve_keys(BODY_KEYS, entry, f"{scene.source}: bodies[{i}]")["at"])
                  for i, entry in enumerate(scene["bodies"])]


def _interior_split_points(scene: Scene, frame: dict) -> list:
    """``[(s, what)]`` (``what``: ``"joints[i]"`` or ``"bodies[i]"``): the interior member
    points that ``[[joints]]`` and ``[[bodies]]`` entries name (:func:`_interior_point`),
    as fractions ``s`` of the total length,
    where the member is split (its pieces joined rigidly) so that a joint or a body takes a
    piece end there."""
    places = [p for p in _interior_places(scene) if "@" in p[2]]
    if not places:
        return []
    names, out = _member_names(scene), []
    total = sum(sp.length for sp in frame["spaces"])
    for what, key, place in places:
        m, f = _interior_point(f"{scene.source}: {what}", place, names, key)
        pieces, _ = _member_fractions(frame, m)
        start = sum(sp.length for sp in frame["spaces"][:pieces[0]])
        length = sum(frame["spaces"][k].length for k in pieces)
        out.append(((start + f * length) / total, what))
    return out


def _member_names(scene: Scene) -> list:
    """Names of the ``[[beams]]`` entries, checked distinct and given (``[[joints]]``,
    interior points)."""
    if not scene["beams"]:
        what = "joints" if scene["joints"] else "bodies"
        raise SceneError(f"{scene.source}: key '{what}': {what} at members' ends or interior points need the frame's "
                         "members in [[beams]]")
    names = [str(flatten(e).get("name", "")) for e in scene["beams"]]
    for i, name in enumerate(names):
        if not name or names.index(name) != i:
            raise SceneError(f"{scene.source}: beams[{i}]: key 'name' = {name!r}: [[joints]] needs a distinct name "
                             "for every member")
    return names


def _graph(scene: Scene, frame: dict) -> tuple:
    """Joint pairs ``((piece, side), (piece, side))``, their kinds, hinge axes, springs and
    point loads: the pieces of each split member in a rigid chain, and each ``[[joints]]``
    entry's ends joined to one end of it (:func:`_join`; one-line errors naming the entry
    and key)."""
    names, members = _member_names(scene), frame["members"]
    supported = {f"{names[0]}.start": "bc.start", f"{names[-1]}.end": "bc.end"}
    used: dict = {}
    entries = [_joint_entry(scene, frame, i, entry, names, used, supported) for i, entry in enumerate(scene["joints"])]
    taken = {k for *_, interior in entries for k in interior}  # split points a joint takes over
    out: tuple = ([], [], [], [], [])

    def add(a, b, kind="rigid", axis=None, spring=(0.0, 0.0), load=None):
        for lst, x in zip(out, ((a, b), kind, axis, spring, load)):
            lst.append(x)

    for k in range(len(members) - 1):
        if members[k] == members[k + 1] and k not in taken:
            add((k, "end"), (k + 1, "start"), load=frame["joint_loads"][k])
    for where, v, ends, interior in entries:
        _join(where, v, ends, interior, add, frame["joint_loads"])
    return out


def _joint_entry(scene: Scene, frame: dict, i: int, entry, names: list, used: dict, supported: dict) -> tuple:
    """``(where, keys, member_ends, interior)`` of ``[[joints]]`` entry ``i``: its member ends
    ``(piece, side)`` and, for its interior points, the piece ending there; checked to
    coincide."""
    where = f"{scene.source}: joints[{i}]"
    v = resolve_keys(JOINT_KEYS, entry, where)
    if len(v["ends"]) < 2:
        raise SceneError(f"{where}: key 'ends': expected two or more member ends, e.g. [\"a.end\", \"b.start\"]")
    places = []
    for e in v["ends"]:
        places.append(_joint_end(scene, where, e, names, frame, used, supported))
        used[_canonical_end(where, e, names)] = i
    spaces = frame["spaces"]
    pos = [np.asarray(spaces[k].c0[0 if side == "start" else -1]) for k, side in places]
    total = sum(sp.length for sp in spaces)
    for e, x in zip(v["ends"][1:], pos[1:]):
        gap = float(np.linalg.norm(x - pos[0]))
        if gap > 1e-9 * total:
            raise SceneError(f"{where}: key 'ends': {e!r} at {np.round(x, 6).tolist()} is {gap:.3g} m from "
                             f"{v['ends'][0]!r} at {np.round(pos[0], 6).tolist()}; joined ends must coincide")
    inside = [_interior_point(where, e, names) is not None for e in v["ends"]]
    return (where, v, [p for p, q in zip(places, inside) if not q], [p[0] for p, q in zip(places, inside) if q])


def _join(where: str, v: dict, ends: list, interior: list, add, joint_loads: list) -> None:
    """The pairs of one ``[[joints]]`` entry, all from one first end (the hub): its first
    interior point's piece end if it has one (the member's two pieces there joined
    rigidly), else its first member end. Another interior point joins both of its pieces to
    the hub rigidly, so only a rigid joint takes more than one; the entry's load goes on
    one of its pairs (loads act on the hub)."""
    kind, axis, spring, load = v["kind"], _hinge_axis(where, v), (v["stiffness"], v["damping"]), _joint_load(where, v)
    if len(interior) > 1 and kind != "rigid":
        raise SceneError(f"{where}: key 'kind' = {kind!r}: a {kind} joint takes one interior point (\"<member>@"
                         "<fraction>\"); join the other members at their ends, or make the joint rigid")
    pairs = []  # (a, b, kind, axis, spring, load)
    if interior:
        hub = (interior[0], "end")
        pairs.append([hub, (interior[0] + 1, "start"), "rigid", None, (0.0, 0.0), joint_loads[interior[0]]])
        for k in interior[1:]:
            pairs.append([hub, (k, "end"), "rigid", None, (0.0, 0.0), joint_loads[k]])
            pairs.append([hub, (k + 1, "start"), "rigid", None, (0.0, 0.0), None])
    else:
        hub, ends = ends[0], ends[1:]
    pairs += [[hub, e, kind, axis, spring, None] for e in ends]
    if load is not None:
        next(p for p in pairs if p[5] is None)[5] = load
    for p in pairs:
        add(*p)


def _joint_load(where: str, v: dict):
    """The dead force and couple of a ``[[joints]]`` entry (on its first pair), or None."""
    if not (np.any(v["force"]) or np.any(v["couple"])):
        return None
    try:
        prof = Profile(kind=v["profile"], t_on=v["t_on"], t_off=v["t_off"], ramp=v["ramp"])
    except ParameterError as exc:
        raise SceneError(f"{where}: key '{exc.field}': {exc.reason}") from None
    return EndLoad(force=v["force"], couple=v["couple"], force_profile=prof, couple_profile=prof)


def _hinge_axis(where: str, v: dict):
    """The axis of a ``[[joints]]`` entry: given and non-zero for a hinge, absent otherwise
    (as its spring and damper)."""
    a = np.asarray(v["axis"], dtype=float)
    if v["kind"] != "hinge":
        for key in ("axis", "stiffness", "damping"):
            if np.any(v[key]):
                raise SceneError(f"{where}: key '{key}': only a hinge has an axis, a spring and a damper "
                                 f"(kind = {v['kind']!r})")
        return None
    if not np.all(np.isfinite(a)) or not np.any(a):
        raise SceneError(f"{where}: key 'axis' = {a.tolist()}: a hinge needs a finite non-zero axis [x, y, z]")
    return a


def _joint_end(scene: Scene, where: str, end: str, names: list, frame: dict, used: dict, supported: dict):
    """``(piece, side)`` of a member end ``"<name>.start"`` or ``"<name>.end"``, or of an
    interior point ``"<name>@<fraction>"`` (the end of the piece that ends there)."""
    key = _canonical_end(where, end, names)
    if key in used:
        raise SceneError(f"{where}: key 'ends': {end!r} is already joined (joints[{used[key]}]); "
                         "list all the ends of one point in one joint")
    point = _interior_point(where, end, names)
    if point is not None:
        pieces, ends = _member_fractions(frame, point[0])
        return pieces[int(np.argmin(np.abs(ends - point[1])))], "end"
    members = frame["members"]
    name, _, side = end.rpartition(".")
    if side not in ("start", "end") or not name:
        raise SceneError(f"{where}: key 'ends': {end!r}: expected \"<member>.start\", \"<member>.end\" or "
                         "\"<member>@<fraction>\" (an interior point)")
    if name not in names:
        raise SceneError(f"{where}: key 'ends': {end!r}: no [[beams]] entry named {name!r} (members: "
                         f"{', '.join(names)})")
    bc = supported.get(end)
    if bc is not None and scene[bc] != "free":
        raise SceneError(f"{where}: key 'ends': {end!r} is supported ({bc} = {scene[bc]!r}); a joint takes free "
                         "ends only: support the frame through a member end of its own")
    m = names.index(name)
    pieces = [k for k, mm in enumerate(members) if mm == m]
    return (pieces[0], "start") if side == "start" else (pieces[-1], "end")


def _space(scene: Scene, get, pre: str, curve: NurbsCurve) -> CollocationSpace:
    a = get("reference_vector")
    try:
        return CollocationSpace(curve, reference_vector=None if not np.any(a) else a)
    except ValueError as exc:
        raise SceneError(f"{scene.source}: key '{pre}reference_vector': {exc}") from None


def constants(scene: Scene, get=None, pre: str = "") -> SectionConstants:
    """The section of the scene, or of a ``[[beams]]`` entry: ``get(key)`` reads its
    ``section.*`` and ``material.*`` keys (``pre`` names the entry in errors)."""
    get = get or (lambda k: scene[k])

    def need(key, why):
        if get(key) is None:
            raise SceneError(f"{scene.source}: missing key '{pre}{key}' ({why})")
        return get(key)

    shape = get("section.shape")
    try:
        if shape == "explicit":
            vals = {k: need(f"section.{k}", "explicit section") for k in
                    ("EA", "GA", "EI1", "EI2", "GJ", "rhoA", "rhoI1", "rhoI2")}
            rhoJ = get("section.rhoJ") if get("section.rhoJ") is not None else vals["rhoI1"] + vals["rhoI2"]
            return SectionConstants(CN=(vals["GA"], vals["GA"], vals["EA"]), CM=(vals["EI1"], vals["EI2"], vals["GJ"]),
                                    mu=vals["rhoA"], Jm=(vals["rhoI1"], vals["rhoI2"], rhoJ))
        E = need("material.E", f"{shape} section")
        rho = need("material.rho", f"{shape} section")
        material = Material(E=E, rho=rho, nu=get("material.nu"), G=get("material.G"))
        k = get("section.shear_factor")
        if shape == "circle":
            section = Section.circle(need("section.d", "circle"), k)
        elif shape == "square":
            section = Section.square(need("section.t", "square"), k)
        else:
            section = Section.rectangle(need("section.b", "rectangle"), need("section.h", "rectangle"), k)
        return SectionConstants.from_material(material, section)
    except ParameterError as exc:
        prefix = "material" if exc.field in ("E", "rho", "nu", "G") else "section"
        raise SceneError(f"{scene.source}: key '{pre}{prefix}.{exc.field}': {exc.reason}") from None


def _profile(scene: Scene, pre: str) -> Profile:
    try:
        return Profile(kind=scene[f"{pre}.profile"], t_on=scene[f"{pre}.t_on"], t_off=scene[f"{pre}.t_off"],
                       ramp=scene[f"{pre}.ramp"], table=scene[f"{pre}.table"])
    except ParameterError as exc:
        raise SceneError(f"{scene.source}: key '{pre}.{exc.field}': {exc.reason}") from None


def _motion(scene: Scene, end: str) -> SupportMotion | None:
    pre = f"motion.{end}"
    if scene[f"{pre}.kind"] == "none":
        return None
    try:
        return SupportMotion(scene[f"{pre}.kind"], scene[f"{pre}.axis"], scene[f"{pre}.rate"], scene[f"{pre}.amplitude"],
                             scene[f"{pre}.time"])
    except ParameterError as exc:
        raise SceneError(f"{scene.source}: key '{pre}.{exc.field}': {exc.reason}") from None


def _translation(scene: Scene, end: str) -> SupportMotion | None:
    pre = f"translation.{end}"
    kind = scene[f"{pre}.kind"]
    if kind == "none":
        return None
    try:
        return SupportMotion("spin_up" if kind == "speed_up" else kind, scene[f"{pre}.axis"], scene[f"{pre}.rate"],
                             scene[f"{pre}.amplitude"], scene[f"{pre}.time"])
    except ParameterError as exc:
        raise SceneError(f"{scene.source}: key '{pre}.{exc.field}': {exc.reason}") from None


def _end_load(scene: Scene, end: str) -> EndLoad:
    pre = f"loads.{end}"
    prof = _profile(scene, pre)
    return EndLoad(force=scene[f"{pre}.force"], couple=scene[f"{pre}.couple"], force_profile=prof, couple_profile=prof,
                   follower=scene[f"{pre}.follower"])


def problem(scene: Scene, size_damping: bool = False) -> BeamProblem:
    """The :class:`BeamProblem` of a validated beam scene.

    With ``material.kelvin_voigt = "auto"`` and ``size_damping=True`` (what a run does,
    :func:`build`) the retardation time of a collocation formulation is sized from the dense
    linearized spectrum at the initial state (:func:`~liegroup_int.problems.beam.damping.size_kelvin_voigt`) and the
    report kept as ``damping_report``; without it the problem is built undamped, at no
    cost (scene checks, tests). The Galerkin weak form needs no damping ("auto" is 0 and no
    spectrum is computed: :data:`GALERKIN_CLEAN`).
    """
    pb = _checked[1] if _checked[0] is scene else _undamped(scene)
    kv = scene["material.kelvin_voigt"]
    if kv == "auto" and size_damping and pb.formulation != "galerkin":
        pb = _sized(scene, pb)
    return pb


#: The problem built by the last :func:`check` and its scene: a run validates the scene
#: (check) and then builds it; the second build reuses the first.
_checked: tuple = (None, None)


def _undamped(scene: Scene) -> BeamProblem:
    """The problem with ``kelvin_voigt = "auto"`` taken as 0 (sized by :func:`_sized`)."""
    space, joint_loads, sections = frame_space(scene)
    loads = Loads(distributed_force=scene["loads.distributed_force"], gravity=scene["loads.gravity"],
                  distributed_couple=scene["loads.distributed_couple"],
                  distributed_profile=_profile(scene, "loads"), start=_end_load(scene, "start"),
                  end=_end_load(scene, "end"), joints=joint_loads)
    try:
        bcs = BoundaryConditions(scene["bc.start"], scene["bc.end"], _motion(scene, "start"), _motion(scene, "end"),
                                 _translation(scene, "start"), _translation(scene, "end"), scene["bc.pin_axis"])
    except ParameterError as exc:
        if exc.field == "pin_axis":
            raise SceneError(f"{scene.source}: key 'bc.pin_axis': {exc.reason}") from None
        end = "start" if exc.field.startswith("start") else "end"
        table = "translation" if exc.field.endswith("translation") else "motion"
        raise SceneError(f"{scene.source}: key '{table}.{end}.kind': {exc.reason}") from None
    ic = InitialConditions(scene["initial.velocity"], scene["initial.omega"], scene["initial.axis_point"])
    kv = scene["material.kelvin_voigt"]
    section = sections if sections is not None else constants(scene)  # one-line errors, named by key
    bodies = _bodies(scene, space)
    if bodies and scene["space.formulation"] != "galerkin":
        raise SceneError(f"{scene.source}: key 'bodies': end bodies need space.formulation = \"galerkin\"")

    def make(scale):
        scaled = section if scale == 1.0 else (section.with_rotary_inertia_scale(scale) if not isinstance(
            section, tuple) else tuple(sec.with_rotary_inertia_scale(scale) for sec in section))
        try:
            return beam_problem(space, scaled, bcs, loads, ic, backend=scene["integrator.backend"],
                                kelvin_voigt=0.0 if kv == "auto" else kv, formulation=scene["space.formulation"],
                                quadrature=scene["space.quadrature"], bodies=bodies)
        except ValueError as exc:
            raise SceneError(f"{scene.source}: {exc}") from None

    return _rotary_inertia(scene, make)


def _rotary_inertia(scene: Scene, make) -> BeamProblem:
    """The problem ``make(scale)`` with ``section.rotary_inertia_scale`` applied (``"auto"``
    sized by :func:`~liegroup_int.problems.beam.inertia_scaling.size_rotary_inertia`) and its
    report as ``rotary_inertia_report`` (Galerkin; None where the modal check does not apply)."""
    given, key = scene["section.rotary_inertia_scale"], "section.rotary_inertia_scale"
    modes = scene["section.rotary_inertia_modes"]
    if given != "auto":
        pb = make(given)
        if given != 1.0 and pb.formulation == "galerkin" and 6 * pb.n <= MAX_UNKNOWNS and _modal_plain(pb):
            pb.rotary_inertia_report = given_scale_report(pb, given, modes)
        return pb
    if scene["space.formulation"] != "galerkin":
        raise SceneError(f"{scene.source}: key '{key}' = 'auto' needs space.formulation = \"galerkin\" (its modal "
                         "analysis); give a number")
    pb = make(1.0)
    if not _modal_plain(pb):
        raise SceneError(f"{scene.source}: key '{key}' = 'auto': the modal check covers a beam with supports only "
                         "(no bodies, joints or hinges); give a number")
    cache = (scene.kind, repr(sorted(scene.params.items())))
    try:
        rep = _RI_SIZED[cache] if cache in _RI_SIZED else size_rotary_inertia(pb, modes,
                                                                                scene["section.rotary_inertia_tol"])
    except ValueError as exc:
        raise SceneError(f"{scene.source}: key '{key}' = 'auto': {exc}") from None
    if len(_RI_SIZED) >= 32:
        _RI_SIZED.pop(next(iter(_RI_SIZED)))
    _RI_SIZED[cache] = rep
    pb = make(rep.scale) if rep.scale != 1.0 else pb
    pb.rotary_inertia_report = rep
    return pb


def _modal_plain(pb) -> bool:
    """Whether the Galerkin modal analysis at rest describes ``pb`` (no bodies, joints, hinges)."""
    return not (pb.bodies or pb.joints or pb.hinges)


#: Rotary-inertia factors sized in this process, by the scene's keys (as :data:`_SIZED`).
_RI_SIZED: dict = {}


def _sized(scene: Scene, pb: BeamProblem) -> BeamProblem:
    """``pb`` with the retardation time of ``kelvin_voigt = "auto"`` sized at the initial
    state (:func:`~liegroup_int.problems.beam.damping.size_kelvin_voigt`)."""
    try:
        y0 = pb.initial_state()
    except ValueError as exc:
        raise SceneError(f"{scene.source}: {exc}") from None
    key = (scene.kind, repr(sorted(scene.params.items())))
    try:
        rep = _SIZED[key] if key in _SIZED else size_kelvin_voigt(pb.with_kelvin_voigt, y0)
    except ValueError as exc:
        raise SceneError(f"{scene.source}: key 'material.kelvin_voigt' = 'auto': {exc} in this discretization "
                         f"({describe_formulation(pb.formulation)}, p={scene['space.degree']}, "
                         f"n_ctrl={scene['space.n_ctrl']}); try "
                         + ('space.formulation = "galerkin" (no spurious growing mode), or '
                            if pb.formulation != "galerkin" else "")
                         + "another space.n_ctrl or degree, or give an explicit retardation time") from None
    if len(_SIZED) >= 32:
        _SIZED.pop(next(iter(_SIZED)))
    _SIZED[key] = rep
    pb = pb.with_kelvin_voigt(rep.tau)
    pb.damping_report = rep
    return pb


#: Damping sized in this process, by the scene's own keys (everything that defines the
#: problem; not dt, t_end or outputs): a study, a resume or a rerun of the same beam sizes
#: it once (each sizing is one or more dense spectra).
_SIZED: dict = {}


def check(scene: Scene) -> None:
    global _checked
    pb = _undamped(scene)
    try:
        pb.initial_state()
    except ValueError as exc:
        raise SceneError(f"{scene.source}: {exc}") from None
    if "reactions" in scene.output.quantities and not pb.supports():
        raise SceneError(f"{scene.source}: key 'output.quantities': 'reactions' needs a clamped or hinged end "
                         f"(bc.start = {scene['bc.start']!r}, bc.end = {scene['bc.end']!r})")
    if "joint_reactions" in scene.output.quantities and not (pb.formulation == "galerkin" and pb.joints):
        raise SceneError(f"{scene.source}: key 'output.quantities': 'joint_reactions' needs a frame's joints "
                         "([[beams]] or [[joints]]) and space.formulation = \"galerkin\"")
    if "bodies" in scene.output.quantities and not getattr(pb, "bodies", ()):
        raise SceneError(f"{scene.source}: key 'output.quantities': 'bodies' needs [[bodies]] entries")
    _check_splitting(scene, pb)
    _checked = (scene, pb)


def _check_splitting(scene: Scene, pb) -> None:
    """A splitting method (kick-drift-kick) needs the Galerkin formulation's compiled
    kernels."""
    from ..integrators import is_splitting, resolve_scheme

    method = scene.integrator.method
    if not is_splitting(resolve_scheme(method)):
        return
    where = f"{scene.source}: key 'integrator.method' = {method!r}"
    if pb.formulation != "galerkin":
        raise SceneError(f"{where}: splitting methods need space.formulation = \"galerkin\" (a constant mass matrix; "
                         f"this is {pb.formulation!r}): use an RKMK method (rkmk4) here")
    if scene["integrator.backend"] != "numba":
        raise SceneError(f"{where}: splitting methods run the compiled kernels: use integrator.backend = \"numba\"")
    if pb.tau > 0.0 or scene["material.kelvin_voigt"] not in ("auto", 0.0):
        raise SceneError(f"{where}: splitting methods are for undamped problems (material.kelvin_voigt = "
                         f"{scene['material.kelvin_voigt']!r}): use an RKMK method (rkmk4) with damping")


def _point_rows(pb: BeamProblem, y0: BeamState, fractions) -> np.ndarray:
    """Rows of basis values ``(k, n)`` at the parameters where the reference centreline
    (the initial state's) reaches the given fractions of its length (by chord lengths on
    a grid of 64 n_ctrl intervals, then linear interpolation of the parameter)."""
    sp = pb.space
    if not getattr(sp, "chain", True):  # members apart: chords within each member only
        parts = [_chords(sp.patches[k].point_matrix, np.asarray(y0.c, float)[sp.offsets[k]:sp.offsets[k + 1]],
                         64 * p.n_ctrl, sp._u_edges[k], sp._u_edges[k + 1]) for k, p in enumerate(sp.patches)]
        s0 = np.cumsum([0.0] + [s[-1] for s, _ in parts])
        s, u = np.concatenate([s + s0[k] for k, (s, _) in enumerate(parts)]), np.concatenate([u for _, u in parts])
    else:
        s, u = _chords(sp.point_matrix, np.asarray(y0.c, float)[:sp.n_ctrl], 64 * pb.n, 0.0, 1.0)
    return _state_rows(pb, sp.point_matrix(np.interp(np.asarray(fractions, float) * s[-1], s, u)))


def _state_rows(pb: BeamProblem, P: np.ndarray) -> np.ndarray:
    """Basis rows ``P`` ``(k, n_ctrl)`` of the members as rows on the state's control values
    ``(k, n)``: zero on the nodes of a Galerkin state's bodies on joints, which follow."""
    return np.hstack([P, np.zeros((P.shape[0], pb.n - P.shape[1]))])


def _chords(point_matrix, c: np.ndarray, intervals: int, u0: float, u1: float):
    """Cumulative chord length ``(k,)`` of the centreline with control values ``c`` on a grid of
    ``intervals`` over the local parameter, and the global parameters ``(k,)`` of the grid
    (``[u0, u1]``)."""
    ul = np.linspace(0.0, 1.0, intervals + 1)
    x = point_matrix(ul) @ c
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(x, axis=0), axis=1))])
    return s, u0 + (u1 - u0) * ul


def point_columns(fractions) -> list[str]:
    """History columns of ``output.points``: ``s0p5_x`` for the fraction 0.5 (no dots in
    column names: CSV readers such as ``numpy.genfromtxt`` drop them)."""
    return [f"s{f:g}_{a}".replace(".", "p") for f in fractions for a in "xyz"]


def reaction_columns(pb: BeamProblem) -> list[str]:
    return [f"reaction_{end}_{q}" for end in pb.supports() for q in ("fx", "fy", "fz", "cx", "cy", "cz")]


def joint_columns(pb: BeamProblem) -> list[str]:
    """``joint<k>_fx .. cz``: the force and couple (spatial) the first end of joint pair ``k``
    exerts on the second (:meth:`GalerkinBeamProblem.joint_reactions`)."""
    return [f"joint{k}_{q}" for k in range(len(getattr(pb, "joints", ()))) for q in ("fx", "fy", "fz", "cx", "cy", "cz")]


def body_columns(pb: BeamProblem) -> list[str]:
    """``body<k>_x .. z`` and ``body<k>_wx .. wz``: the centre of mass and the spatial angular
    velocity of body ``k`` (:meth:`GalerkinBeamProblem.body_motion`)."""
    return [f"body{k}_{q}" for k in range(len(getattr(pb, "bodies", ()))) for q in ("x", "y", "z", "wx", "wy", "wz")]


def diagnostics(pb: BeamProblem, names, points=None) -> dict:
    """Quantities computed from the state; ``energy_balance`` and ``work`` need the run's
    work of the loads and are added by the runner (liegroup_int/guards.py). ``points``:
    basis rows of ``output.points`` (quantity ``points``, recorded when given)."""
    table = {
        "tip": lambda t, y: pb.tip(y),
        "energy": lambda t, y: pb.energy(y, t),
        "kinetic": lambda t, y: pb.energy_parts(y, t)["kinetic"],
        "strain": lambda t, y: pb.energy_parts(y, t)["strain"],
        "momentum": lambda t, y: pb.momentum(y)[0],
        "angular_momentum": lambda t, y: pb.momentum(y)[1],
        "orth_error": lambda t, y: pb.orth_error(y),
        "reactions": lambda t, y: np.concatenate([np.concatenate(fc) for fc in pb.reactions(y, t).values()]),
        "joint_reactions": lambda t, y: np.concatenate([np.concatenate(fc) for fc in pb.joint_reactions(y, t)]),
        "bodies": lambda t, y: np.concatenate([np.concatenate(xw) for xw in pb.body_motion(y)]),
    }
    out = {q: table[q] for q in names if q in table}
    if points is not None:
        out["points"] = lambda t, y: (points @ y.c).ravel()
    return out


class ShapeRecorder:
    """Deformed shapes for the shape plot and shapes.npz: from the state snapshots a run
    stored in results.h5 (:meth:`from_snapshots`), or, for runs without HDF5 output, from
    the control points it keeps as an observer at output times.

    Parameters
    ----------
    space : CollocationSpace, optional
        Evaluates the centreline in :meth:`shapes` (without one, only the control points).
    bodies : sequence of (int, int, (3,) array)
        The row, point and offset of each rigid body (``GalerkinBeamProblem.bodies``): their
        joint points and centres join the shapes.
    """

    def __init__(self, space=None, n_points: int = 101, bodies=()):
        self.space = space
        self.n_points = n_points
        self.bodies = tuple((int(r), int(p), np.asarray(c, float)) for r, p, c in bodies)
        self.t: list[float] = []
        self.c: list[np.ndarray] = []
        self.R: list[np.ndarray] = []

    def __call__(self, t, y):
        self.t.append(float(t))
        self.c.append(y.c.copy())
        self.R.append(y.R[[p for _, p, _ in self.bodies]].copy())

    def shapes(self) -> dict | None:
        """``{"t", "control_points", "u", "centreline"}`` of the recorded outputs, with
        ``"body_joint"`` and ``"body_centre"`` ``(m, k, 3)`` when there are bodies
        (``Simulation.snapshot``: the runner plots ``centreline`` against ``t`` and stores
        all in shapes.npz); ``None`` before two outputs."""
        return self._shapes(np.asarray(self.t), np.asarray(self.c), np.asarray(self.R))

    def from_snapshots(self, t: np.ndarray, snapshots: dict) -> dict | None:
        """:meth:`shapes` from stored snapshots: ``t`` ``(m,)`` and the state arrays of
        ``BeamSimulation.to_arrays`` stacked over outputs (control points ``c``
        ``(m, n, 3)``), as arrays or HDF5 datasets."""
        ctrl = snapshots.get("c")
        if len(t) < 2 or self.space is None or ctrl is None:
            return None
        R = snapshots.get("R")
        points = [p for _, p, _ in self.bodies]
        R = np.asarray(R[...], dtype=float)[:, points] if R is not None and points else None
        return self._shapes(np.asarray(t), np.asarray(ctrl[...], dtype=float), R)

    def _shapes(self, t: np.ndarray, ctrl: np.ndarray, R) -> dict | None:
        if len(t) < 2 or self.space is None:
            return None
        u = np.linspace(0.0, 1.0, self.n_points)
        P = self.space.point_matrix(u)
        line = np.einsum("uj,mjk->muk", P, ctrl[:, :P.shape[1]])  # the members' control values
        if not getattr(self.space, "chain", True):  # members apart: a NaN point between them
            patch = np.searchsorted(self.space._u_edges[1:-1], u, side="right")
            members = getattr(self.space, "members", None)  # the pieces of a split member stay one line
            member = np.asarray(members)[patch] if members is not None else patch
            line = np.insert(line, np.flatnonzero(np.diff(member)) + 1, np.nan, axis=1)
        out = {"t": np.asarray(t), "control_points": ctrl, "u": u, "centreline": line}
        if self.bodies and R is not None and R.size:
            joint = ctrl[:, [r for r, _, _ in self.bodies]]
            arms = np.array([c for _, _, c in self.bodies])
            out.update(body_joint=joint, body_centre=joint + np.einsum("mkij,kj->mki", R, arms))
        return out


def auto_step(scene: Scene, pb: BeamProblem, y0) -> dict:
    """``integrator.dt = "auto"``: spectral radius at the initial state times the method's
    imaginary-axis stability limit (a splitting method's kick-drift-kick limit), with a
    safety factor (integrators/stepsize.py)."""
    import sys

    from ..integrators import resolve_scheme, spectral_radius, stable_step

    lam = spectral_radius(pb, 0.0, y0)
    step = stable_step(resolve_scheme(scene.integrator.method), lam, scene.t_end)
    if step.warning:
        print(f"warning: {scene.source}: {step.warning}", file=sys.stderr)
    return {"dt_auto": step.dt, "lambda_max": lam, "lambda_dt": step.y, "dt_rule": step.rule}


def _body_end(scene: Scene, where: str, at: str, space) -> tuple[str, int]:
    """``(side, patch)`` of a body's ``at``: the beam's own end (patch -1) or a member's."""
    if at in ("start", "end"):
        return at, -1
    if "@" in at:  # an interior point: the end of the piece ending there (the member is split there)
        names = [str(flatten(e).get("name", "")) for e in scene["beams"]]
        m, f = _interior_point(where, at, names, "at")
        pieces = [k for k, mm in enumerate(getattr(space, "members", ())) if mm == m]
        ends = np.cumsum([space.patches[k].length for k in pieces])
        return "end", pieces[int(np.argmin(np.abs(ends / ends[-1] - f)))]
    name, _, side = at.rpartition(".")
    if side not in ("start", "end") or not name:
        raise SceneError(f"{where}: key 'at' = {at!r}: expected \"start\", \"end\", \"<member>.start\" / "
                         "\"<member>.end\" or \"<member>@<fraction>\" (an interior point)")
    names = [str(flatten(e).get("name", "")) for e in scene["beams"]]
    if name not in names:
        raise SceneError(f"{where}: key 'at' = {at!r}: no [[beams]] entry named {name!r}"
                         + (f" (members: {', '.join(n for n in names if n)})" if any(names) else ""))
    pieces = [k for k, m in enumerate(getattr(space, "members", ())) if m == names.index(name)]
    return side, (pieces[0] if side == "start" else pieces[-1]) if pieces else names.index(name)


def _bodies(scene: Scene, space=None) -> tuple:
    """The scene's ``[[bodies]]`` as :class:`EndBody` objects (one-line errors)."""
    out = []
    for i, entry in enumerate(scene["bodies"]):
        where = f"{scene.source}: bodies[{i}]"
        v = resolve_keys(BODY_KEYS, entry, where)
        side, patch = _body_end(scene, where, v["at"], space)
        try:
            prof = Profile(kind=v["profile"], t_on=v["t_on"], t_off=v["t_off"], ramp=v["ramp"], table=v["table"])
            load = EndLoad(force=v["force"], couple=v["couple"], force_profile=prof, couple_profile=prof,
                           follower=v["follower"])
            out.append(EndBody(at=side, mass=v["mass"], inertia=tuple(v["inertia"]), patch=patch,
                               offset=tuple(v["offset"]), load=load, joint=v["joint"], axis=tuple(v["axis"]),
                               stiffness=v["stiffness"], damping=v["damping"]))
        except ParameterError as exc:
            raise SceneError(f"{where}: key '{exc.field}': {exc.reason}") from None
    return tuple(out)


def _static_start(scene: Scene, pb: BeamProblem) -> tuple:
    """``initial.state = "static"``: the equilibrium under the loads at t = 0, at rest, and
    what the solve took (for summary.json); one-line SceneErrors."""
    from ..problems.beam.statics import StaticDivergence, solve_static

    where = f"{scene.source}: key 'initial.state' = 'static'"
    if any(np.any(scene[f"initial.{k}"]) for k in ("velocity", "omega")):
        raise SceneError(f"{where}: starts at rest; remove initial.velocity and initial.omega")
    steps = scene["initial.static_steps"]
    try:
        res = solve_static(pb, load_steps=steps, t=0.0)
    except ValueError as exc:
        raise SceneError(f"{where}: {exc}") from None
    except StaticDivergence as exc:
        raise SceneError(f"{where}: {exc}; try more initial.static_steps (`liegroup-int static` shows the "
                         "residuals)") from None
    return res.state, {"initial_static": {"load_steps": steps, "iterations": sum(res.iterations),
                                          "residual": res.residuals[-1][-1]}}


def _quadrature_used(pb) -> dict:
    """The Galerkin stiffness rule as run (``"auto"`` resolved per member) and its point count."""
    used = sorted(set(pb.gs.rules_used))
    return {"rule": pb.quadrature, "used": used[0] if len(used) == 1 else used,
            "points": int(np.count_nonzero(pb.gs.w_full + pb.gs.w_axial))}


def build(scene: Scene) -> Simulation:
    pb = problem(scene, size_damping=True)
    if getattr(pb, "rollers", ()) or getattr(pb, "pins", ()):
        end = "start" if scene["bc.start"] in ("roller", "pinned") else "end"
        raise SceneError(f"{scene.source}: key 'bc.{end}' = '{scene[f'bc.{end}']}' is for `liegroup-int static` "
                         "and `buckle`; use hinged or clamped ends to run")
    y0, static = (pb.initial_state(), {}) if scene["initial.state"] == "reference" else _static_start(scene, pb)

    def final_state(y):
        return {"tip": pb.tip(y).tolist(), "energy": pb.energy(y, scene.t_end), "orth_error": pb.orth_error(y)}

    info = {}
    if scene.integrator.dt == "auto" or scene.integrator.adaptive:
        # adaptive pairs are capped by the same stable step (their error estimate does not
        # see the weak growth of unresolved high modes)
        info.update(auto_step(scene, pb, y0))
    info = {
        **info,
        **static,
        "discretization": {"formulation": pb.formulation, "degree": scene["space.degree"],
                           "n_ctrl": scene["space.n_ctrl"],
                           "length": pb.space.length,
                           **({"quadrature": _quadrature_used(pb)} if pb.formulation == "galerkin"
                              else {"C_star": 4.0}),
                           "kelvin_voigt": pb.tau},
        **({"kelvin_voigt_auto": pb.damping_report.as_dict()} if pb.damping_report is not None else {}),
        **({"rotary_inertia": pb.rotary_inertia_report.as_dict()} if pb.rotary_inertia_report is not None
           else {"rotary_inertia": {"scale": scene["section.rotary_inertia_scale"]}}
           if scene["section.rotary_inertia_scale"] != 1.0 else {}),
        **({"kelvin_voigt_auto": f"0 ({GALERKIN_CLEAN})"}
           if scene["material.kelvin_voigt"] == "auto" and pb.formulation == "galerkin" else {}),
        "columns": {**{k: v for k, v in COLUMNS.items() if k in scene.output.quantities},
                    **({"reactions": reaction_columns(pb)} if "reactions" in scene.output.quantities else {}),
                    **({"joint_reactions": joint_columns(pb)} if "joint_reactions" in scene.output.quantities else {}),
                    **({"bodies": body_columns(pb)} if "bodies" in scene.output.quantities else {}),
                    **({"points": point_columns(scene["output.points"])} if scene["output.points"] else {})},
    }
    fields = tuple(scene["output.fields"])
    points = _point_rows(pb, y0, scene["output.points"]) if scene["output.points"] else None
    shapes = ShapeRecorder(pb.space, bodies=[(b.row, b.point, b.c) for b in getattr(pb, "bodies", ())])
    sim = Simulation(problem=pb, y0=y0, diagnostics=diagnostics(pb, scene.output.quantities, points),
                     final_state=final_state, info=info, snapshot=shapes,
                     to_arrays=lambda y: y.arrays(), from_arrays=lambda a: type(y0)(**a),
                     conserved=pb.mechanical_energy, stability=stability(scene, pb),
                     frames=_frames(pb, fields), mode_shape=mode_shape(pb, y0),
                     fields=(lambda y: {f"section_{k}": v for k, v in pb.section_fields(y, fields).items()})
                     if fields else None)
    return sim


def mode_shape(pb: BeamProblem, y0, n_points: int = 101):
    """``Simulation.mode_shape``: a mode's position and rotation increments (control values,
    ``vector[0]`` and ``vector[1]``, complex) on the centreline of the state ``y0`` (the
    initial state; an equilibrium for modes about it) at ``n_points`` parameters."""
    P = _state_rows(pb, pb.space.point_matrix(np.linspace(0.0, 1.0, n_points)))
    ref = P @ np.asarray(y0.c, dtype=float)
    return lambda vec: (ref, P @ np.asarray(vec[0]), P @ np.asarray(vec[1]))


def _frames(pb: BeamProblem, fields=()):
    """Centreline at the collocation points, their section frames, arc lengths and the
    requested section ``fields`` (``Simulation.frames``, the ParaView series)."""
    _, N0, s_c = pb.frame_points
    N0, s_c = np.asarray(N0), np.asarray(s_c, dtype=float)
    base = {"s": s_c}
    if not getattr(pb.space, "chain", True):  # a frame that is not a chain: no cell between members
        base["member"] = np.asarray(pb.gs.point_patch[:len(N0)], dtype=float)
    if fields:
        return lambda y: (N0 @ y.c, y.R[:len(N0)], {**base, **pb.section_fields(y, fields)})
    return lambda y: (N0 @ y.c, y.R[:len(N0)], base)


#: Largest number of unknowns (12 n_ctrl) for which the guards compute the dense spectrum
#: (n_ctrl = 125; ~1 s for the eigenvalues on one core).
PROBE_MAX_UNKNOWNS = 1500

#: Why a Galerkin run computes no dense spectrum at the start (no damping sizing, no probe):
#: its semi-discretization is Hamiltonian, so the linearized spectrum at rest is imaginary.
GALERKIN_CLEAN = "galerkin: energy-conserving weak form, imaginary spectrum at rest by construction"

#: What to try when a collocation run grows a mode: the weak form first (it finishes the runs
#: collocation cannot), then the least damping, then another mesh.
REMEDY = ('try space.formulation = "galerkin" (energy-conserving weak form: no spurious growing mode, no locking), '
          'or material.kelvin_voigt = "auto" (the least damping that removes growth at the start) or a larger '
          'value, or another space.n_ctrl (docs/verification.md, "Stability maps")')
#: The same for the weak form, whose spectrum at rest is clean: what grows is the motion itself
#: or a step the mesh's top modes do not allow.
REMEDY_GALERKIN = ("try a finer space.n_ctrl (to resolve the motion), a smaller integrator.dt, or "
                   'material.kelvin_voigt > 0 to damp the top modes (docs/verification.md, "Stability maps")')


def describe_formulation(formulation: str) -> str:
    """``"primal collocation"`` or ``"galerkin"``."""
    return formulation if formulation == "galerkin" else f"{formulation} collocation"


def stability(scene: Scene, pb: BeamProblem) -> Stability:
    """Guard hooks of a beam: power-iteration spectral radius, dense growth check (up to
    :data:`PROBE_MAX_UNKNOWNS` unknowns), rest test."""
    from ..integrators import growth_check, spectral_radius

    kv = f", kelvin_voigt = {pb.tau:.3g} s" if pb.tau > 0 else ""
    describe = (f"{describe_formulation(pb.formulation)}, p={scene['space.degree']}, n_ctrl={scene['space.n_ctrl']}{kv}")

    def growth(t, y, duration):
        if 12 * pb.n > PROBE_MAX_UNKNOWNS:
            return None
        return growth_check(pb, t, y, duration)

    def at_rest(y):
        return not (np.any(y.v) or np.any(y.w))

    galerkin = pb.formulation == "galerkin"
    remedy_real = ("strain-rate damping does not act on a real mode: try "
                   + ("another" if galerkin else 'space.formulation = "galerkin" (locking-free), or another')
                   + " space.degree or space.n_ctrl")
    return Stability(describe=describe, remedy=REMEDY_GALERKIN if galerkin else REMEDY, remedy_real=remedy_real, spectral_radius=lambda t, y: spectral_radius(pb, t, y),
                     growth=growth, at_rest=at_rest, max_unknowns=PROBE_MAX_UNKNOWNS, sized=pb.damping_report,
                     clean=GALERKIN_CLEAN if galerkin else "")


def refine(scene: Scene) -> tuple[dict | None, str]:
    """The scene on the next finer mesh: knot spans halved, ``n_ctrl -> 2 n_ctrl - p``
    (uniform knots), or ``(None, why not)``."""
    if any("n_ctrl" in entry for entry in scene["beams"]):
        return None, "a [[beams]] entry sets its own n_ctrl"
    p, n = scene["space.degree"], scene["space.n_ctrl"]
    fine = 2 * n - p
    if fine > 2001:
        return None, f"the finer mesh (n_ctrl = {fine}) is beyond the largest n_ctrl, 2001"
    return {"space.n_ctrl": fine}, ""


def constrained(pb: BeamProblem) -> int:
    """Degrees of freedom held by the supports (3 per held position or rotation) and the
    joints (6 per rigid pair, 5 per hinge, 3 per ball pair)."""
    ends = sum(3 * (bool(e.fix_position) + bool(e.fix_rotation)) for e in pb.ends)
    rotations = {"rigid": 3, "hinge": 2, "ball": 0}
    return ends + sum(3 + rotations[getattr(j, "kind", "rigid")] for j in getattr(pb, "joints", ()))


KIND = register_kind(ProblemKind(
    name="beam",
    keys=KEYS,
    quantities=QUANTITIES,
    default_quantities=("tip", "energy"),
    build=build,
    check=check,
    compiles=lambda scene: scene["integrator.backend"] == "numba",
    refine=refine,
    constrained=constrained,
))
