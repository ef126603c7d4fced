"""Markdown tables and the command line every benchmark script shares.

Every script in ``benchmarks/`` takes ``--quick`` (tiny sizes and short spans: a smoke
run of a few seconds that still prints its tables) and ``--out DIR`` (where figures go;
in quick mode a temporary directory unless given), through :func:`parser` and
:func:`figure_dir`, and prints its results with :func:`markdown` as Markdown tables.
"""

from __future__ import annotations

import argparse
import math
import tempfile
from collections.abc import Iterable, Sequence
from pathlib import Path

#: What a script prints when PyElastica (the ``[peers]`` extra) is not installed.
PEER_ABSENT = "PyElastica not installed (pip install -e \".[peers]\"): the peer column is absent"


def parser(doc: str | None, quick_help: str = "tiny sizes and short spans (a smoke run of a few seconds)"):
    """An argument parser with ``--quick`` and ``--out``; its description is the first
    line of ``doc``."""
    ap = argparse.ArgumentParser(description=(doc or "").strip().splitlines()[0] if doc else None)
    ap.add_argument("--quick", action="store_true", help=quick_help)
    ap.add_argument("--out", type=Path, default=None,
                    help="directory for figures and files (default: docs/img; a temporary one with --quick)")
    return ap


def figure_dir(args, default: Path) -> Path:
    """Where a script writes its figures: ``--out``, else a new temporary directory in
    quick mode, else ``default``. Created if missing."""
    if args.out is not None:
        out = Path(args.out)
    elif args.quick:
        out = Path(tempfile.mkdtemp(prefix="bench_quick_"))
    else:
        out = Path(default)
    out.mkdir(parents=True, exist_ok=True)
    return out


def cell(x, spec: str = ".3g") -> str:
    """A table cell: floats formatted with ``spec`` (``-`` for None or a non-finite
    float), anything else as ``str``."""
    if x is None:
        return "-"
    if isinstance(x, float) and not math.isfinite(x):
        return "-"
    if isinstance(x, float):
        return format(x, spec)
    return str(x)


def markdown(head: Sequence[str], rows: Iterable[Sequence]) -> str:
    """A Markdown table; cells that are not strings go through :func:`cell`."""
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        if len(r) != len(head):
            raise ValueError(f"table row has {len(r)} cells, header {len(head)}")
        lines.append("| " + " | ".join(c if isinstance(c, str) else cell(c) for c in r) + " |")
    return "\n".join(lines)


def peer_available() -> bool:
    """Whether PyElastica can be imported."""
    import importlib.util

    return importlib.util.find_spec("elastica") is not None
