"""Streaming CSV history: one row per output time, flushed as it is written.

A run that dies keeps every row written before it.
"""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Callable, Mapping

import numpy as np


class HistoryWriter:
    """Observer that evaluates named quantities at output times and appends CSV rows.

    Parameters
    ----------
    path : Path
        CSV file; created (truncated) on construction with a header ``t, names...``.
    quantities : mapping of str to callable
        ``name -> fn(t, y)``; a function may return a float or a sequence, whose entries
        become columns ``name_0, name_1, ...`` (or the names it declares, see
        ``columns``).
    columns : mapping of str to list of str, optional
        Column names for vector-valued quantities.
    """

    def __init__(self, path: Path, quantities: Mapping[str, Callable], columns: Mapping[str, list] | None = None,
                 append: bool = False):
        self.path = Path(path)
        self.quantities = dict(quantities)
        self.columns = dict(columns or {})
        header = ["t"]
        for name in self.quantities:
            header.extend(self.columns.get(name, [name]))
        self.header = header
        exists = append and self.path.exists()
        #: rows in the file: those already there (a resumed run) and the ones written here
        self.rows = max(0, sum(1 for _ in open(self.path)) - 1) if exists else 0
        self._fh = open(self.path, "a" if exists else "w", newline="")
        self._csv = csv.writer(self._fh)
        if not exists:
            self._csv.writerow(header)
            self._fh.flush()
        self.last: dict[str, float] = {}

    def __call__(self, t: float, y) -> None:
        row = [repr(float(t))]
        for name, fn in self.quantities.items():
            val = np.atleast_1d(np.asarray(fn(t, y), dtype=float))
            row.extend(repr(float(x)) for x in val)
            for col, x in zip(self.columns.get(name, [name]), val):
                self.last[col] = float(x)
        self._csv.writerow(row)
        self._fh.flush()
        self.rows += 1

    def close(self) -> None:
        self._fh.close()


def read_history(path: Path) -> dict[str, np.ndarray]:
    """Columns of a history CSV as float arrays."""
    data = np.genfromtxt(path, delimiter=",", names=True)
    data = np.atleast_1d(data)
    return {name: np.asarray(data[name], dtype=float) for name in data.dtype.names}
