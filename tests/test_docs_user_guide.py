"""docs/user-guide.md walked end to end: every command it shows runs, in order, in a fresh
directory, with short spans (``t_end``) so the walk takes seconds; commands shown with their
output (``$ ...`` lines) give that output.

What is changed from the page, and why:

* every ``run`` gets ``--set t_end=0.02`` (the resume extends to 0.04, the page's ``t_end=2``),
  the cantilever's (dt = 1e-6 s) ``t_end=0.002``, the sweep ``t_end=0.01``: the commands and
  their files are under test, not the physics, which have their own tests (the cantilever's
  event, at 0.0207 s, is located in ``tests/scenes/test_scenes_events.py``);
* ``--no-plots`` on the runs whose plots would be of the kind ``runs/pendulum`` draws and
  this test checks (tip and energy columns, one member); the runs with other plots (more
  columns, a frame) draw theirs;
* ``bench`` (named in the prose, a minute even with ``--quick``) is left to
  ``tests/bench``;
* studies run with ``--serial`` (the Dask path has its own test in ``tests/test_studies.py``).
"""

from __future__ import annotations

import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from liegroup_int.cli import main

ROOT = Path(__file__).resolve().parents[1]
GUIDE = ROOT / "docs" / "user-guide.md"


def _steps(text: str) -> list[tuple[str, list[str]]]:
    """``(command, expected output lines)`` in page order: the lines of ```bash blocks
    (continuations joined), and the ``$ `` lines of plain blocks with the lines under them
    (lines of a plain block before its first ``$`` show a message, not a command)."""
    steps: list[tuple[str, list[str]]] = []
    for lang, body in re.findall(r"```(\w*)\n(.*?)```", text, flags=re.S):
        lines = body.replace("\\\n", " ").splitlines()
        if lang == "bash":
            steps += [(ln.strip(), []) for ln in lines if ln.strip()]
            continue
        current = None
        for ln in lines:
            if ln.startswith("$ "):
                current = (ln[2:].strip(), [])
                steps.append(current)
            elif current is not None and ln.strip():
                current[1].append(ln.rstrip())
    return steps


#: runs whose plots are of the kind runs/pendulum draws, which are checked (about 0.2 s a run)
SAME_PLOTS = {"runs/pendulum61", "runs/pendulum_primal", "runs/pendulum_adaptive", "runs/cantilever_event"}


def _shorten(argv: list[str]) -> list[str]:
    if argv[:2] == ["liegroup-int", "run"]:
        if "--resume" in argv:
            return [a.replace("t_end=2", "t_end=0.04") for a in argv]
        out = argv[argv.index("--out") + 1] if "--out" in argv else None
        span = "0.002" if argv[2] == "cantilever" else "0.02"
        return argv + ["--set", f"t_end={span}"] + (["--no-plots"] if out in SAME_PLOTS else [])
    if argv[:2] == ["liegroup-int", "sweep"]:
        return argv + ["--set", "t_end=0.01", "--serial"]
    if argv[:2] == ["liegroup-int", "converge"]:
        return argv + ["--serial"]
    return argv


def test_the_page_shows_the_commands_this_test_runs():
    cmds = [c for c, _ in _steps(GUIDE.read_text())]
    assert cmds[0] == "liegroup-int run pendulum --out runs/pendulum"
    assert any(c.startswith("liegroup-int run pendulum --resume runs/pendulum") for c in cmds)
    assert any(c.startswith("liegroup-int converge heavy_top") for c in cmds)
    assert any(c.startswith("liegroup-int sweep pendulum") for c in cmds)
    assert any(c.startswith("liegroup-int plot runs/pendulum") for c in cmds)


def test_user_guide_end_to_end(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    text = GUIDE.read_text()
    ran = []
    for cmd, expected in _steps(text):
        argv = _shorten(shlex.split(cmd))
        want_error = bool(expected) and expected[0].startswith("error:")
        capsys.readouterr()
        rc = main(argv[1:])
        out, err = capsys.readouterr()
        if want_error:
            assert rc == 2, f"{cmd}: rc {rc}, expected the documented error"
            assert err.strip() == expected[0], f"{cmd}: printed {err.strip()!r}"
        else:
            assert rc == 0, f"{cmd}: rc {rc}: {err.strip()[-300:]}"
            for line in expected:  # the documented output, up to noise-level figures
                if "Re lambda" in line:
                    continue  # the largest real part at rest is at finite-difference noise
                assert line.strip() in out, f"{cmd}: missing {line.strip()!r} in\n{out}"
        ran.append(argv[1])
    # prose-only commands
    assert main(["scenes", "--reference"]) == 0 and "integrator.dt" in capsys.readouterr().out
    res = subprocess.run([sys.executable, str(ROOT / "examples" / "render_pvd.py"), "runs/pendulum", "pendulum.png"],
                         capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr[-500:]
    assert (tmp_path / "pendulum.png").stat().st_size > 10000
    # what the page says the commands wrote
    run = tmp_path / "runs" / "pendulum"
    for name in ("history.csv", "results.h5", "beam.pvd", "checkpoint.npz", "summary.json", "history.png",
                 "shapes.png", "shapes.npz", "plot_history.png", "plot_history.pdf", "plot_shapes.png"):
        assert (run / name).exists(), name
    assert list((run / "paraview").glob("beam_*.vtu"))
    for d in ("runs/pendulum61", "runs/pendulum_primal", "runs/pendulum_adaptive"):
        assert (tmp_path / d / "summary.json").exists(), d
    assert list(tmp_path.glob("studies/heavy_top-converge/study.csv"))
    assert list(tmp_path.glob("studies/pendulum-sweep/study.csv"))
    assert ran.count("run") >= 5 and {"validate", "plot", "converge", "sweep"} <= set(ran)


@pytest.mark.parametrize("cmd", ["liegroup-int run pendulum --set space.n_ctrl=3"])
def test_parser_keeps_documented_errors(cmd):
    steps = dict(_steps(GUIDE.read_text()))
    assert steps[cmd] and steps[cmd][0].startswith("error:")
