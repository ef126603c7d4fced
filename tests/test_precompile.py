"""``liegroup-int compile``: the kernel sets it warms cover the built-in scenes, so that a
first run after it compiles nothing."""

from __future__ import annotations

import pytest
from numba.core import event

from liegroup_int.cli import main
from liegroup_int.precompile import DEFAULT_SETS, KERNEL_SETS, compile_sets, warm_scene
from liegroup_int.scenes import builtin_descriptions, load_scene, parse_override


class _Compiles(event.Listener):
    """Names of the functions numba compiles (or loads from its disk cache) while installed."""

    def __init__(self):
        self.names = []

    def on_start(self, ev):
        self.names.append(ev.data["dispatcher"].py_func.__qualname__)

    def on_end(self, ev):
        pass


def _family(scene_name: str) -> str:
    scene = load_scene(scene_name)
    if scene.kind != "beam":
        return "rigid_body"
    return f"beam_{scene['space.formulation']}"


@pytest.mark.parametrize("scene_name", sorted(builtin_descriptions()))
def test_default_sets_cover_every_builtin_scene(scene_name, tmp_path):
    """After its family's set is warm, a built-in scene's start-up checks and first step
    compile nothing: ``compile`` with the default sets leaves no compilation to a first run
    of any built-in scene as shipped."""
    family = _family(scene_name)
    assert family in DEFAULT_SETS
    ks = KERNEL_SETS[family]
    warm_scene(ks.scene, ks.overrides)
    rec = _Compiles()
    with event.install_listener("numba:compile", rec):
        warm_scene(scene_name)
    assert rec.names == [], f"{scene_name} compiled {rec.names} after the {family!r} set was warmed"


@pytest.mark.parametrize("scene_name", ["spinning_helix", "cantilever"])
def test_the_split_set_covers_a_leapfrog_run_of_another_scene(scene_name):
    """``beam_galerkin_split`` (``compile --all``) warms the compiled leapfrog of every
    Galerkin scene: after it, a ``strang`` run of another scene compiles nothing."""
    ks = KERNEL_SETS["beam_galerkin_split"]
    warm_scene(ks.scene, ks.overrides)
    rec = _Compiles()
    with event.install_listener("numba:compile", rec):
        warm_scene(scene_name, ("integrator.method=strang", "integrator.dt=auto"))
    assert rec.names == [], f"{scene_name} compiled {rec.names}"


def test_the_leapfrog_calls_the_stage_rate_s_compiled_entries():
    """The compiled leapfrog calls the Galerkin stage rate and action through the addresses of
    their entries ``call_rates`` and ``call_action`` (the first-class functions of the
    engine's data), so it compiles none of their code and runs the machine code
    ``liegroup-int compile`` cached for them (its first call after the default sets: 7.9 s of
    CPU against 9.7 s with their code linked in, measured). Checked: the data it runs on hold
    those two entries, its compiled signature types them as first-class functions, and a
    leapfrog run adds no compiled copy of either entry (a second copy, for other argument
    types, would be compiled code the default sets do not cache)."""
    import numpy as np
    from numba.core import types

    from liegroup_int.integrators.engine import FunctionValue
    from liegroup_int.problems.beam.kernels import galerkin
    from liegroup_int.scenes import KINDS
    from liegroup_int.tableaux import COMPOSITIONS

    ks = KERNEL_SETS["beam_galerkin"]
    warm_scene(ks.scene, ks.overrides)
    entries = (galerkin.call_rates, galerkin.call_action)
    before = [set(e.signatures) for e in entries]
    scene = load_scene("pendulum", dict(parse_override(s) for s in KERNEL_SETS["beam_galerkin_split"].overrides))
    pb = KINDS[scene.kind].build(scene).problem
    y = pb.split_steps(pb.initial_state(), 1e-6, COMPOSITIONS["strang"].gammas_f, 2)
    assert np.all(np.isfinite(y.c))
    fns = [x.fn for x in pb._split_data.data if isinstance(x, FunctionValue)]
    assert fns == list(entries)
    data_type = galerkin.call_split_steps.signatures[0][0]
    assert sum(isinstance(t, types.FunctionType) for t in data_type) == 2, data_type
    assert [set(e.signatures) for e in entries] == before


_PARTS_THEN_WARM = """
import sys
from numba.core import event
from liegroup_int.precompile import KERNEL_SETS, PARTS, warm_scene
ks = KERNEL_SETS[sys.argv[1]]
for part in ks.parts:
    PARTS[part](ks)
names = []
class Rec(event.Listener):
    def on_start(self, ev):
        names.append(ev.data["dispatcher"].py_func.__qualname__)
    def on_end(self, ev):
        pass
with event.install_listener("numba:compile", Rec()):
    warm_scene(ks.scene, ks.overrides)
print(repr(names))
"""


@pytest.mark.parametrize("name", sorted(n for n, ks in KERNEL_SETS.items() if ks.parts))
def test_a_set_s_parts_leave_its_warm_up_nothing_to_compile(name):
    """The pieces ``compile`` runs side by side (the stage rate; the action and the engine's
    loop, compiled without running it) are all a first run of the set's scene needs: in a
    fresh process that ran them, its warm-up compiles (or loads) nothing more."""
    import subprocess
    import sys

    out = subprocess.run([sys.executable, "-c", _PARTS_THEN_WARM, name], capture_output=True, text=True, check=True)
    assert out.stdout.strip().splitlines()[-1] == "[]", f"{name}: {out.stdout[-2000:]}"


@pytest.mark.parametrize("name", sorted(n for n, ks in KERNEL_SETS.items() if ks.warm is None))
def test_every_kernel_set_names_a_valid_scene(name):
    ks = KERNEL_SETS[name]
    scene = load_scene(ks.scene, dict(parse_override(o) for o in ks.overrides))
    assert scene.integrator.adaptive == name.endswith("_adaptive")
    assert (scene.raw.get("space.formulation") == "primal") == ("primal" in name)


def test_the_user_field_set_leaves_a_new_field_only_its_own_compilation():
    """After ``user_field`` is warm, a new ``numba.njit`` field on SO(3) (fixed step and
    adaptive) and on the sphere compiles only itself (and nothing of the engine)."""
    import numpy as np
    from numba import njit

    from liegroup_int import SO3, Sphere, integrate

    assert KERNEL_SETS["user_field"].scene is None
    KERNEL_SETS["user_field"].warm()

    @njit
    def spin(t, y):
        return np.array([0.0, 0.0, 1.0 + t])

    rec = _Compiles()
    with event.install_listener("numba:compile", rec):
        integrate(spin, np.eye(3), (0.0, 0.01), space=SO3, method="rkmk4", dt=1e-3)
        integrate(spin, np.eye(3), (0.0, 0.01), space=SO3, method="rkmk45", rtol=1e-8, atol=1e-8)
        integrate(spin, np.array([1.0, 0.0, 0.0]), (0.0, 0.01), space=Sphere(), method="rkmk4", dt=1e-3)
    # the field itself and numba's implementations of what it calls (np.array), nothing else
    assert any(n.endswith("<locals>.spin") for n in rec.names), rec.names
    assert all(n.endswith("<locals>.spin") or n.endswith("<locals>.impl") for n in rec.names), rec.names


def test_compile_command_in_process(capsys):
    assert main(["compile", "rigid_body", "--jobs", "1"]) == 0
    err = capsys.readouterr().err
    assert "compiling 1 kernel set(s): rigid_body" in err and "rigid_body:" in err and "compiled in" in err


def test_compile_command_lists_and_refuses(capsys):
    assert main(["compile", "--list"]) == 0
    out = capsys.readouterr().out
    assert all(name in out for name in KERNEL_SETS)
    assert main(["compile", "beam_primel"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "unknown kernel set 'beam_primel'" in err and "did you mean 'beam_primal'" in err
    assert main(["compile", "--jobs", "0"]) == 2
    assert "--jobs 0" in capsys.readouterr().err
    with pytest.raises(ValueError, match="unknown kernel set"):
        compile_sets(["nope"])


def test_compile_sets_in_worker_processes():
    """Two sets side by side in spawned processes (the command's default on 2 cores)."""
    done = compile_sets(["rigid_body", "rigid_body_adaptive"], jobs=2)
    assert sorted(done) == ["rigid_body", "rigid_body_adaptive"] and all(s > 0 for s in done.values())


def test_compile_notice_says_so_once_when_numba_compiles(capsys):
    """A run that compiles prints one line as the first compilation starts; nothing when
    nothing compiles, and nothing when disabled (quiet runs)."""
    from numba import njit

    from liegroup_int.runner import CompileNotice

    @njit(cache=False)
    def fresh(x):
        return x + 1.0

    @njit(cache=False)
    def other(x):
        return x * 2.0

    with CompileNotice(enabled=False):
        fresh(1.0)
    assert capsys.readouterr().err == ""
    with CompileNotice(enabled=True):
        fresh(1.0)  # compiled already: no notice
    assert capsys.readouterr().err == ""
    with CompileNotice(enabled=True):
        other(1.0)
        other(2)  # a second specialization: still one line
    assert capsys.readouterr().err == CompileNotice.MESSAGE + "\n"


def test_a_slow_set_up_says_so(monkeypatch, tmp_path, capsys):
    """A set-up longer than SETUP_NOTICE_S prints one line on stderr while it runs (here
    the threshold lowered to 0.05 s and the build slowed by 0.3 s); a quick one, or a quiet
    run, prints nothing."""
    import time

    import liegroup_int.runner as runner
    from liegroup_int.scenes import KINDS, load_scene

    kind = KINDS["rigid_body"]
    slow = lambda scene, build=kind.build: (time.sleep(0.3), build(scene))[1]  # noqa: E731
    monkeypatch.setattr(runner, "SETUP_NOTICE_S", 0.05)
    scene = load_scene("heavy_top", {"t_end": 0.01, "output.every": 0.01, "output.plots": False})
    runner.run_scene(scene, tmp_path / "quick", quiet=False)
    assert "setting up" not in capsys.readouterr().err
    import dataclasses

    monkeypatch.setitem(KINDS, "rigid_body", dataclasses.replace(kind, build=slow))
    runner.run_scene(scene, tmp_path / "slow", quiet=False)
    err = capsys.readouterr().err
    assert err.count("setting up heavy_top (more than 0.05 s") == 1
    runner.run_scene(scene, tmp_path / "slow_quiet", quiet=True)
    assert "setting up" not in capsys.readouterr().err


def test_a_slow_scene_check_says_so_and_counts_as_set_up(monkeypatch, tmp_path, capsys):
    """Loading a scene checks it (a large beam mesh builds its discretization there, 4.5 s
    at n_ctrl = 2001): `run` prints the set-up line during a slow load too (threshold lowered
    to 0.05 s, the check slowed by 0.3 s), and summary.json's `timing.setup_s` includes it."""
    import dataclasses
    import json
    import time

    import liegroup_int.runner as runner
    from liegroup_int.cli import main
    from liegroup_int.scenes import KINDS

    kind = KINDS["rigid_body"]
    slow = lambda scene, check=kind.check: (time.sleep(0.3), check(scene) if check else None)[1]  # noqa: E731
    monkeypatch.setattr(runner, "SETUP_NOTICE_S", 0.05)
    monkeypatch.setitem(KINDS, "rigid_body", dataclasses.replace(kind, check=slow))
    out = tmp_path / "slow_check"
    assert main(["run", "heavy_top", "--set", "t_end=0.01", "--set", "output.every=0.01", "--no-plots",
                 "--out", str(out)]) == 0
    assert capsys.readouterr().err.count("setting up heavy_top (more than 0.05 s") == 1
    assert json.loads((out / "summary.json").read_text())["timing"]["setup_s"] >= 0.3


def test_compile_writes_the_package_bytecode():
    """``compile`` writes each module's bytecode where Python reads it (``__pycache__``), so
    that no process compiles the package's sources again, even where Python would not
    write it (an editable install with ``PYTHONDONTWRITEBYTECODE``)."""
    import importlib.util
    from pathlib import Path

    import liegroup_int
    from liegroup_int.precompile import write_bytecode

    root = Path(liegroup_int.__file__).parent
    own = Path(importlib.util.cache_from_source(str(root / "precompile.py")))
    own.unlink(missing_ok=True)  # imported already: nothing reads it again here
    assert write_bytecode()
    sources = sorted(root.rglob("*.py"))
    assert len(sources) > 50
    missing = [p for p in sources if not Path(importlib.util.cache_from_source(str(p))).exists()]
    assert missing == []
