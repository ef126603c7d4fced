"""Facts typed in the docs that the code or another page owns, checked so that they cannot
drift apart: the built-in scene list, the default kernel sets, the compile and first-run
figures (one measurement, quoted in three places), the history columns of the user guide's
run, and the scene key reference (generated; tests/scenes/test_scenes_cli.py)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from liegroup_int.precompile import DEFAULT_SETS, KERNEL_SETS
from liegroup_int.scenes import builtin_descriptions, load_scene

ROOT = Path(__file__).resolve().parents[1]
CLI = (ROOT / "docs" / "cli.md").read_text()
README = (ROOT / "README.md").read_text()
START = (ROOT / "docs" / "getting-started.md").read_text()
GUIDE = (ROOT / "docs" / "user-guide.md").read_text()


def test_the_builtin_scene_list_is_complete():
    """docs/cli.md names every built-in scene, and no other."""
    para = CLI[CLI.index("Built-in scenes ("):CLI.index("## First run")]
    named = set(re.findall(r"`([a-z0-9_]+)`", para)) - {"buckle"}
    assert named == set(builtin_descriptions())


def test_the_default_kernel_sets_are_the_documented_ones():
    row = next(line for line in CLI.splitlines() if line.startswith("| `liegroup-int compile [SET"))
    assert f"default sets `{DEFAULT_SETS[0]}` and `{DEFAULT_SETS[1]}`" in row and len(DEFAULT_SETS) == 2
    assert all(name in KERNEL_SETS for name in DEFAULT_SETS)


def _seconds(pattern: str, text: str) -> float:
    m = re.search(pattern, text)
    assert m, pattern
    return float(m.group(1))


def test_the_compile_and_first_run_figures_agree():
    """docs/cli.md's "First run" table is the measurement; the README quotes it exactly and
    getting-started rounded to the second."""
    compile_s = _seconds(r"\| `liegroup-int compile` \(sets [^|]*\| ([0-9.]+) s \|", CLI)
    first_s = _seconds(r"\| `liegroup-int run cantilever` with an empty cache \| ([0-9.]+) s \|", CLI)
    assert _seconds(r"separate processes \(([0-9.]+) s on\s+2 cores", README) == compile_s
    assert _seconds(r"\(([0-9.]+) s for the cantilever\) and says so", README) == first_s
    assert abs(_seconds(r"ahead of the first run \(about ([0-9.]+) s, once\)", START) - compile_s) <= 0.5


@pytest.mark.parametrize("page, text", [("user-guide.md", GUIDE), ("getting-started.md", START)])
def test_the_pendulum_history_columns_are_the_scene_s(page, text):
    """The columns the pages list for the pendulum's history.csv are those its recorded
    quantities give (tip -> tip_x, tip_y, tip_z)."""
    from liegroup_int.scenes.beam import COLUMNS

    quantities = load_scene("pendulum").output.quantities
    columns = ["t"] + [c for q in quantities for c in COLUMNS.get(q, [q])]
    listed = ", ".join(columns[1:])
    assert listed in text, (page, listed)
