"""HDF5 results streamed during a run (h5py).

Layout of ``results.h5``::

    /                 attrs: scene (JSON of the scene keys), source, version, problem
    /history/t        (m,)      output times
    /history/<name>   (m,)      one dataset per history column (tip_x, energy, ...)
    /snapshots/t      (m,)
    /snapshots/<name> (m, ...)  state arrays at output times (beams: c, v, w, R, K, K_s;
                                rigid bodies: y)

Every dataset is chunked and resizable along its first axis; the file is flushed after
each output, so a killed run keeps everything up to its last output.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Callable, Mapping

import numpy as np


class Hdf5Writer:
    """Observer writing history rows and state snapshots at output times.

    Parameters
    ----------
    path : Path
    quantities : mapping of str to callable
        History quantities ``name -> fn(t, y)`` (scalars or vectors).
    columns : mapping of str to list of str
        Column names for vector quantities (as in :class:`HistoryWriter`).
    snapshot : callable
        ``fn(y) -> dict of arrays`` saved at every output.
    attrs : mapping
        Metadata stored on the root group (JSON-encoded when not a scalar or string).
    append : bool
        Continue an existing file (resumed runs) instead of creating it.
    """

    def __init__(self, path: Path, quantities: Mapping[str, Callable], columns: Mapping[str, list],
                 snapshot: Callable[[object], dict], attrs: Mapping, append: bool = False):
        import h5py

        self.path = Path(path)
        self.quantities = dict(quantities)
        self.columns = dict(columns or {})
        self.snapshot = snapshot
        exists = append and self.path.exists()
        self.f = h5py.File(self.path, "a" if exists else "w")
        if not exists:
            for k, v in attrs.items():
                self.f.attrs[k] = v if isinstance(v, (str, int, float)) else json.dumps(v, default=str)
            self.f.create_group("history")
            self.f.create_group("snapshots")
        self.f.flush()

    def _append(self, group: str, name: str, value: np.ndarray) -> None:
        g = self.f[group]
        value = np.asarray(value, dtype=float)
        if name not in g:
            g.create_dataset(name, shape=(0,) + value.shape, maxshape=(None,) + value.shape, dtype="f8",
                             chunks=(max(1, min(256, 2**20 // max(1, value.size * 8))),) + value.shape)
        d = g[name]
        d.resize(d.shape[0] + 1, axis=0)
        d[-1] = value

    def __call__(self, t: float, y) -> None:
        self._append("history", "t", t)
        for name, fn in self.quantities.items():
            val = np.atleast_1d(np.asarray(fn(t, y), dtype=float))
            for col, x in zip(self.columns.get(name, [name]), val):
                self._append("history", col, x)
        self._append("snapshots", "t", t)
        for name, arr in self.snapshot(y).items():
            self._append("snapshots", name, arr)
        self.f.flush()

    def truncate_after(self, t: float) -> None:
        """Drop rows with time > ``t`` (a resumed run continues from its checkpoint)."""
        for group in ("history", "snapshots"):
            g = self.f[group]
            if "t" not in g:
                continue
            keep = int(np.searchsorted(g["t"][:], t, side="right"))
            for d in g.values():
                d.resize(keep, axis=0)
        self.f.flush()

    def close(self) -> None:
        self.f.close()


def read_results(path: Path) -> dict:
    """``{"attrs": {...}, "history": {name: array}, "snapshots": {name: array}}``."""
    import h5py

    with h5py.File(path, "r") as f:
        return {
            "attrs": dict(f.attrs),
            "history": {k: v[:] for k, v in f["history"].items()},
            "snapshots": {k: v[:] for k, v in f["snapshots"].items()},
        }
