"""Scenes as frozen dataclasses, loaded from TOML with overrides and validated up front."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any, Callable, Mapping

from ..integrators import is_splitting, resolve_scheme
from ..tableaux import COMPOSITIONS, NAMES
from .schema import REQUIRED, Key, SceneError, flatten, non_negative, positive, read_toml, resolve_keys


@dataclass(frozen=True)
class IntegratorSpec:
    """``[integrator]``: method and either a fixed ``dt`` (number or ``"auto"``) or tolerances."""

    method: str
    dt: float | str | None
    rtol: float | None
    atol: float | None

    @property
    def adaptive(self) -> bool:
        return self.dt is None


@dataclass(frozen=True)
class OutputSpec:
    """``[output]``: record interval in simulated seconds and the recorded quantities."""

    every: float | None
    quantities: tuple[str, ...]
    hdf5: bool = True
    checkpoint_every: float = 60.0
    paraview: bool = False
    blowup_factor: float = 1e3
    plots: bool = True
    #: simulated seconds between VTU files / state snapshots (None: ``t_end / SPARSE_OUTPUTS``)
    paraview_every: float | None = None
    snapshot_every: float | None = None


@dataclass(frozen=True)
class EventSpec:
    """One ``[[events]]`` entry: the zeros of ``quantity - value`` (a history column),
    crossing in ``direction`` (-1 falling, +1 rising, 0 both); ``terminal`` stops the run
    at the first."""

    name: str
    quantity: str
    value: float = 0.0
    direction: int = 0
    terminal: bool = False


#: Keys of one ``[[events]]`` entry.
EVENT_KEYS = {
    "name": Key("name", "str", "", "name of the event (default: quantity and value)"),
    "quantity": Key("quantity", "str", REQUIRED, "a history column of a recorded quantity, e.g. tip_z or energy"),
    "value": Key("value", "float", 0.0, "the level whose crossings are the events"),
    "direction": Key("direction", "str", "both", "crossings counted", choices=("falling", "rising", "both")),
    "terminal": Key("terminal", "bool", False, "stop the run at the first event"),
}


def event_specs(source: str, entries) -> tuple[EventSpec, ...]:
    """The validated ``[[events]]`` entries (one-line :class:`SceneError` naming the entry)."""
    out = []
    for i, entry in enumerate(entries):
        v = resolve_keys(EVENT_KEYS, entry, f"{source}: events[{i}]")
        name = v["name"] or f"{v['quantity']} = {v['value']:g}"
        out.append(EventSpec(name, v["quantity"], v["value"], {"falling": -1, "rising": 1, "both": 0}[v["direction"]],
                             v["terminal"]))
    if len({e.name for e in out}) != len(out):
        raise SceneError(f"{source}: key 'events': two events share a name; give each a name")
    return tuple(out)


@dataclass(frozen=True)
class GuardSpec:
    """``[guard]``: checks before and during a run (liegroup_int/guards.py)."""

    dt: bool = True
    spectrum: bool = True
    energy_balance: float = 0.5


@dataclass(frozen=True)
class Scene:
    """A validated scene.

    Attributes
    ----------
    name : str
    kind : str
        Problem kind (a key of ``KINDS``).
    source : str
        File path or ``builtin:NAME``, used in error messages.
    t_end : float
    integrator : IntegratorSpec
    output : OutputSpec
    params : mapping
        The problem kind's own keys (read-only), by dotted name.
    raw : mapping
        All given keys after overrides, for metadata.
    """

    name: str
    kind: str
    source: str
    description: str
    t_end: float
    integrator: IntegratorSpec
    output: OutputSpec
    params: Mapping[str, Any] = field(repr=False)
    raw: Mapping[str, Any] = field(repr=False)
    guard: GuardSpec = field(default_factory=GuardSpec)
    events: tuple = ()

    def __getitem__(self, key: str):
        return self.params[key]


@dataclass(frozen=True)
class Stability:
    """What a problem kind offers the run guards (liegroup_int/guards.py).

    Attributes
    ----------
    describe : str
        The discretization in a few words, for messages ("primal collocation, p=4, n_ctrl=31").
    remedy : str
        What to try when an oscillatory mode of the discretization grows.
    remedy_real : str
        What to try when a real (non-oscillatory) mode grows at rest, which damping does
        not remove.
    spectral_radius : callable
        ``(t, y) -> |lambda|max`` of the linearized problem (cheap: power iteration).
    growth : callable
        ``(t, y, duration) -> GrowthReport`` from the dense spectrum, or ``None`` when the
        problem has more than ``max_unknowns`` unknowns.
    at_rest : callable
        ``y -> bool``: the state does not move (its spectrum should then be imaginary).
    max_unknowns : int
        Largest problem for which ``growth`` computes the dense spectrum.
    sized : object, optional
        A report of damping sized on the dense spectrum at the start (beams:
        ``DampingReport``); the start probe then reuses it instead of recomputing.
    clean : str, optional
        Why the dense spectrum at the start need not be computed (a discretization whose
        spectrum at rest is imaginary by construction); empty: compute it.
    """

    describe: str
    remedy: str
    remedy_real: str
    spectral_radius: Callable[[float, Any], float]
    growth: Callable[[float, Any, float], Any]
    at_rest: Callable[[Any], bool]
    max_unknowns: int
    sized: Any = None
    clean: str = ""


@dataclass
class Simulation:
    """What a problem kind builds from a scene: everything the runner needs.

    Attributes
    ----------
    problem : Problem
    y0 : state
    diagnostics : dict of str to callable
        ``name -> fn(t, y)`` for the recorded quantities only.
    final_state : callable
        ``fn(y) -> dict`` of named, JSON-ready fields.
    info : dict
        Extra JSON-ready facts for summary.json (discretization, stable step, ...).
    conserved : callable, optional
        ``E(y)`` whose change equals the problem's quadrature (beams: kinetic plus strain
        energy, whose change is the work of the loads): the energy balance.
    stability : Stability, optional
        Hooks of the run guards (stable step, spectrum probe, failure diagnosis).
    snapshot : callable, optional
        An observer ``(t, y)`` run at output times whose ``shapes()`` returns ``None`` or a
        dict with ``t (k,)`` and ``centreline (k, m, 3)`` (plus any arrays to keep): the
        runner draws shapes.png from it and stores the dict in shapes.npz.
    frames : callable, optional
        ``frames(y) -> (points (m, 3), frames (m, 3, 3), point_data)``: a curve with
        section frames, written as a ParaView series when the scene asks for it
        (``output.paraview``); ``None``: the problem has no such picture.
    fields : callable, optional
        ``fields(y) -> {name: array}``: quantities the scene asked for beyond the state
        (beams: ``output.fields``), stored with the state snapshots in results.h5.
    mode_shape : callable, optional
        ``mode_shape(vector) -> (points (k, 3), displacement (k, 3), rotation (k, 3))``: a
        mode of the linearized increment map (complex, increment-shaped) as complex
        displacement and rotation along the reference curve, for ``liegroup-int modes``
        (which makes them real, :func:`liegroup_int.io.modes.real_shapes`); ``None``: no
        shapes.
    """

    problem: Any
    y0: Any
    diagnostics: dict[str, Callable]
    final_state: Callable[[Any], dict]
    info: dict = field(default_factory=dict)
    snapshot: Callable[[Any], dict] | None = None
    to_arrays: Callable[[Any], dict] = lambda y: {"y": y}
    from_arrays: Callable[[dict], Any] = lambda a: a["y"]
    conserved: Callable[[Any], float] | None = None
    stability: Stability | None = None
    frames: Callable[[Any], tuple] | None = None
    mode_shape: Callable[[Any], tuple] | None = None
    fields: Callable[[Any], dict] | None = None


@dataclass(frozen=True)
class ProblemKind:
    """A problem plugin as scenes see it: its keys, its quantities and a builder."""

    name: str
    keys: Mapping[str, Key]
    quantities: tuple[str, ...]
    default_quantities: tuple[str, ...]
    build: Callable[[Scene], Simulation]
    check: Callable[[Scene], None] | None = None
    #: whether a run of the scene may compile numba kernels (the runner then says so on
    #: stderr as the first compilation starts); None: never
    compiles: Callable[[Scene], bool] | None = None
    #: ``refine(scene) -> (overrides, "")`` giving the same scene on the next finer mesh
    #: (``modes`` estimates the discretization error from it), or ``(None, why not)``
    refine: Callable[[Scene], tuple[dict | None, str]] | None = None
    #: ``constrained(problem) -> int``: degrees of freedom held by supports and joints
    #: (``modes`` tells their zero eigenvalues from rigid-body modes); None: unknown
    constrained: Callable[[Any], int] | None = None


#: Default number of ParaView files and of state snapshots of a run: their intervals
#: default to ``t_end / SPARSE_OUTPUTS`` (history rows stay at ``output.every``).
SPARSE_OUTPUTS = 100

_STRIDE_RULE = ("rounded to the nearest whole multiple of the recorded interval (output.every, in whole steps), at "
                "least one; the last output is always written")


def output_stride(interval: float | None, t_end: float, every: float) -> int:
    """Outputs from one ParaView file (or state snapshot) to the next: ``interval``
    (``None``: ``t_end / SPARSE_OUTPUTS``) as the nearest whole multiple of the record
    interval ``every`` (halves up), at least 1."""
    target = t_end / SPARSE_OUTPUTS if interval is None else interval
    return max(1, math.floor(target / every + 0.5))


def check_sparse_every(source: str, values: Mapping[str, Any]) -> None:
    """``output.paraview_every`` and ``output.snapshot_every``, when given: within
    ``[output.every, t_end]`` (``output.every`` defaulting to ``t_end / 200``); raises a
    one-line :class:`SceneError` naming the key."""
    t_end = values["t_end"]
    every = values["output.every"]
    least = every if every is not None else t_end / 200.0
    shown = "output.every" if every is not None else "output.every (default t_end/200)"
    for key in ("output.paraview_every", "output.snapshot_every"):
        v = values[key]
        if v is None:
            continue
        if v > t_end:
            raise SceneError(f"{source}: key '{key}' = {v!r}: expected <= t_end = {t_end!r}")
        if v < least * (1 - 1e-9):
            raise SceneError(f"{source}: key '{key}' = {v!r}: expected >= {shown} = {least:.6g} s (these files are "
                             f"written at output times)")


def common_keys(kind: ProblemKind) -> dict[str, Key]:
    method_names = tuple(sorted(NAMES)) + tuple(COMPOSITIONS)
    keys = [
        Key("name", "str", "", "scene name (defaults to the file name)"),
        Key("description", "str", "", "one line shown by `liegroup-int scenes`"),
        Key("problem", "str", REQUIRED, "problem kind", choices=tuple(sorted(KINDS))),
        Key("t_end", "float", REQUIRED, "simulated time span", "s", positive),
        Key("integrator.method", "str", "rkmk4", "RKMK method, or a symplectic splitting (strang, yoshida4, yoshida6: "
            "fixed steps; beams: the Galerkin formulation)", choices=method_names),
        Key("integrator.dt", "float_or_auto", None, 'fixed step; "auto" (beams: stable step); "none" to use rtol/atol', "s", positive),
        Key("integrator.rtol", "float", None, "relative tolerance (adaptive pairs)", "", positive),
        Key("integrator.atol", "float", None, "absolute tolerance (adaptive pairs)", "", positive),
        Key("output.every", "float", None, "simulated time between recorded rows (default t_end/200)", "s", positive),
        Key("output.quantities", "strs", kind.default_quantities, "recorded quantities", choices=kind.quantities),
        Key("output.hdf5", "bool", True, "also stream history and state snapshots to results.h5"),
        Key("output.blowup_factor", "float", 1e3,
            "stop when the recorded energy magnitude exceeds this factor times its largest earlier value (0: off)",
            "", non_negative),
        Key("output.paraview", "bool", False, "beams: write a VTU file every output.paraview_every and the index "
            "beam.pvd (about 1 ms per file; on in the built-in scenes whose picture is the point)"),
        Key("output.paraview_every", "float", None, "simulated time between ParaView files (default t_end/100); "
            + _STRIDE_RULE, "s", positive),
        Key("output.snapshot_every", "float", None, "simulated time between state snapshots in results.h5, which "
            "shapes.png and `plot --times` draw (default t_end/100); " + _STRIDE_RULE, "s", positive),
        Key("output.plots", "bool", True, "draw history.png (and shapes.png) after the run (about 0.5 s; `--no-plots`)"),
        Key("output.checkpoint_every", "float", 60.0, "wall-clock seconds between checkpoints (0: only at the end and on SIGINT/SIGTERM)", "s", non_negative),
        Key("events", "tables", (), "[[events]] entries: quantity (a history column of a recorded quantity, e.g. "
            "tip_z), value (default 0), direction (falling, rising, both), terminal (stop the run at the first), "
            "name; the column is compared at output times and each crossing located on the dense output of the step "
            "it falls in, listed in summary.json"),
        Key("guard.dt", "bool", True, "refuse a fixed dt beyond the stable step of the discretization at the start"),
        Key("guard.spectrum", "bool", True,
            "refuse a discretization with a growing linearized mode at rest (dense spectrum at the start; "
            "small problems)"),
        Key("guard.energy_balance", "float", 0.5,
            "stop when |E_kin + E_strain - W - E0| exceeds this fraction of the energy scale (0: off)", "",
            non_negative),
    ]
    return {k.name: k for k in keys}


KINDS: dict[str, ProblemKind] = {}

#: Most fixed steps a run may take: the step floor is ``t_end / MAX_STEPS`` (a billion
#: steps is about 20 minutes of a rigid body and far longer for a beam).
MAX_STEPS = 10**9
#: Most output times a run may record (history rows, HDF5 snapshots, VTU files).
MAX_OUTPUTS = 10**6


def check_counts(source: str, span: float, dt: float | None, every: float, given_every: float | None = None) -> None:
    """Refuse a fixed step below the floor ``span / MAX_STEPS`` and an output interval
    giving more than ``MAX_OUTPUTS`` outputs over ``span`` (the run's remaining time).

    Parameters
    ----------
    source : str
        For the message.
    span : float
        Simulated time to run [s].
    dt : float or None
        Fixed step (None: adaptive).
    every : float
        Output interval [s] (with a fixed step, a whole number of steps).
    given_every : float, optional
        The scene's ``output.every`` (None: the default ``t_end / 200``), for the message.

    Raises
    ------
    SceneError
        One line naming the key, the limit and the remedy.
    """
    if dt is not None and span / dt > MAX_STEPS:
        raise SceneError(f"{source}: key 'integrator.dt' = {dt!r}: expected >= t_end / {MAX_STEPS:.0e} = "
                         f"{span / MAX_STEPS:.3g} s (at most {MAX_STEPS:.0e} steps; {span / dt:.3g} asked); "
                         f"raise dt or shorten t_end")
    if span / every > MAX_OUTPUTS:
        shown = "t_end/200 (default)" if given_every is None else repr(given_every)
        step = f" (whole steps of {dt:.3g} s: every {every:.3g} s)" if dt is not None and every != given_every else ""
        least = span / MAX_OUTPUTS if dt is None else math.ceil(span / MAX_OUTPUTS / dt) * dt
        raise SceneError(f"{source}: key 'output.every' = {shown}{step}: {span / every:.3g} outputs over {span:g} s, "
                         f"more than {MAX_OUTPUTS:.0e}; give output.every >= {least:.3g} s or shorten t_end")


def register_kind(kind: ProblemKind) -> ProblemKind:
    KINDS[kind.name] = kind
    return kind


def build_scene(given: Mapping[str, Any], source: str, default_name: str) -> Scene:
    """Validate flat ``given`` keys into a :class:`Scene` (raises :class:`SceneError`)."""
    kind_name = given.get("problem")
    if not isinstance(kind_name, str) or kind_name not in KINDS:
        valid = ", ".join(sorted(KINDS))
        raise SceneError(f"{source}: key 'problem' = {kind_name!r}: expected one of {valid}")
    kind = KINDS[kind_name]
    keys = {**common_keys(kind), **kind.keys}
    v = resolve_keys(keys, given, source)
    method = resolve_scheme(v["integrator.method"])
    dt, rtol, atol = v["integrator.dt"], v["integrator.rtol"], v["integrator.atol"]
    if is_splitting(method) and dt is None:
        raise SceneError(f"{source}: key 'integrator.method' = {v['integrator.method']!r} is a splitting method: give "
                         "a fixed step (integrator.dt, or \"auto\"), not rtol/atol")
    if dt is None and rtol is None and atol is None:
        raise SceneError(f"{source}: key 'integrator.dt' is missing: give a step (or rtol/atol for an adaptive pair)")
    if dt is not None and (rtol is not None or atol is not None):
        raise SceneError(f"{source}: keys 'integrator.dt' and 'integrator.rtol/atol' both given: choose fixed or adaptive stepping")
    if dt is None and getattr(method, "b_hat", None) is None:
        raise SceneError(
            f"{source}: key 'integrator.method' = {v['integrator.method']!r} has no embedded pair: "
            "adaptive stepping (rtol/atol) needs rkmk32, rkmk45 or rkmk65"
        )
    if isinstance(dt, float) and dt > v["t_end"]:
        raise SceneError(f"{source}: key 'integrator.dt' = {dt!r}: expected a step <= t_end = {v['t_end']!r}")
    every = v["output.every"]
    if every is not None and every > v["t_end"]:
        raise SceneError(f"{source}: key 'output.every' = {every!r}: expected <= t_end = {v['t_end']!r}")
    check_sparse_every(source, v)
    if isinstance(dt, float):
        check_counts(source, v["t_end"], dt, max(every if every is not None else v["t_end"] / 200.0, dt), every)
    elif every is not None:
        check_counts(source, v["t_end"], None, every, every)
    params = {k: v[k] for k in kind.keys}
    scene = Scene(
        name=v["name"] or default_name,
        kind=kind.name,
        source=source,
        description=v["description"],
        t_end=v["t_end"],
        integrator=IntegratorSpec(v["integrator.method"], dt, rtol, atol),
        output=OutputSpec(every, v["output.quantities"], v["output.hdf5"], v["output.checkpoint_every"],
                          v["output.paraview"], v["output.blowup_factor"], v["output.plots"],
                          v["output.paraview_every"], v["output.snapshot_every"]),
        params=MappingProxyType(params),
        raw=MappingProxyType(dict(given)),
        guard=GuardSpec(v["guard.dt"], v["guard.spectrum"], v["guard.energy_balance"]),
        events=event_specs(source, v["events"]),
    )
    if kind.check is not None:
        kind.check(scene)
    return scene


def load_scene(path_or_name: "str | Path", overrides: Mapping[str, Any] | None = None) -> Scene:
    """Load a scene file (or a built-in by name), apply dotted overrides and validate. A
    directory named like a built-in scene (a run's output, say) does not hide it."""
    from .registry import builtin_names, builtin_path

    p = Path(path_or_name)
    if p.suffix == ".toml" or (p.exists() and not (p.is_dir() and str(path_or_name) in builtin_names())):
        source, default_name = str(p), p.stem
    else:
        p = builtin_path(str(path_or_name))
        source, default_name = f"builtin:{path_or_name}", str(path_or_name)
    given = flatten(read_toml(p))
    if overrides:
        given.update(overrides)
    return build_scene(given, source, default_name)
