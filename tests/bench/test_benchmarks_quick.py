"""Every script in ``benchmarks/`` runs in ``--quick`` mode and prints a Markdown table.

The scripts are found by glob, so a new script is covered without editing this file.
Each runs in a subprocess (``sys.executable``, a temporary working directory, figures
into ``--out``) and must exit 0 and print at least one Markdown table with a data row in
which no number is ``nan`` or ``inf`` (``nan``/``inf`` in a table means a
run failed). Scripts with a PyElastica peer must, without PyElastica, say that the peer
column is absent rather than skip. A script that draws figures writes them into ``--out``.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from liegroup_int.bench.table import PEER_ABSENT, peer_available

ROOT = Path(__file__).resolve().parents[2]
SCRIPTS = sorted((ROOT / "benchmarks").glob("*.py"))
NON_FINITE = re.compile(r"(?<![\w.])[-+]?(nan|inf)(?![\w.])", re.IGNORECASE)
# a quick run finishes within this many seconds even on an empty numba cache (compilation
# included): a guard against a script whose quick mode stopped being quick, not a
# performance claim
TIMEOUT_S = 300


def tables(text: str) -> list[list[list[str]]]:
    """The Markdown tables in ``text``: lists of data rows (header and rule dropped)."""
    out, cur = [], None
    lines = text.splitlines()
    for i, line in enumerate(lines):
        s = line.strip()
        if s.startswith("|") and i + 1 < len(lines) and re.match(r"^\|(\s*:?-+:?\s*\|)+$", lines[i + 1].strip()):
            cur = []
            out.append(cur)
        elif cur is not None and s.startswith("|") and not re.match(r"^\|(\s*:?-+:?\s*\|)+$", s):
            cur.append([c.strip() for c in s.strip("|").split("|")])
        elif not s.startswith("|"):
            cur = None
    return out


def test_table_parser_reads_rows_and_numbers():
    text = "x\n| a | b |\n|---|---|\n| 1.5e-3 | nan |\n| 2 | - |\n\n| c |\n|---|\n| 3 |\n"
    found = tables(text)
    assert found == [[["1.5e-3", "nan"], ["2", "-"]], [["3"]]]
    assert [bool(NON_FINITE.search(c)) for c in ("nan", "1.0 (-inf)", "2.5e-3", "info", "-", "n/a")] == \
        [True, True, False, False, False, False]


@pytest.mark.parametrize("script", SCRIPTS, ids=[s.stem for s in SCRIPTS])
def test_script_quick_mode(script, tmp_path):
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")])),
               MPLBACKEND="Agg")
    proc = subprocess.run([sys.executable, str(script), "--quick", "--out", str(tmp_path / "out")], cwd=tmp_path,
                          env=env, capture_output=True, text=True, timeout=TIMEOUT_S)
    assert proc.returncode == 0, f"{script.name} --quick exited {proc.returncode}:\n{proc.stderr[-3000:]}"
    found = [t for t in tables(proc.stdout) if t]
    assert found, f"{script.name} --quick printed no Markdown table with a data row:\n{proc.stdout[-2000:]}"
    for table in found:
        for row in table:
            bad = [c for c in row if NON_FINITE.search(c)]
            assert not bad, f"{script.name}: non-finite cell in table row {row}"
    source = script.read_text()
    if "pyelastica_peer" in source and not peer_available():
        assert PEER_ABSENT in proc.stdout, f"{script.name}: no note that the peer column is absent"
    if "savefig" in source:
        assert list((tmp_path / "out").glob("*.png")), f"{script.name}: draws figures but wrote none into --out"
    assert not list(tmp_path.glob("docs")), f"{script.name}: wrote into docs/ of its working directory"
