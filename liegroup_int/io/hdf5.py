"""HDF5 results streamed during a run (h5py).

Layout of ``results.h5``::

    /                 attrs: scene (JSON of the scene keys), source, version, problem
    /history/t        (m,)      output times
    /history/<name>   (m,)      one dataset per history column (tip_x, energy, ...)
    /snapshots/t      (k,)
    /snapshots/<name> (k, ...)  state arrays at the output times a run selects (every output,
                                or every few: ``output.snapshot_every``; beams: c, v, w, R,
                                K, K_s; rigid bodies: y)

Every dataset is chunked (about 64 KiB per chunk, :func:`chunk_rows`) and resizable along
its first axis. Outputs are buffered in memory and written in blocks: when
``flush_outputs`` outputs are pending, when the last write is older than ``flush_s``
seconds, at every checkpoint of the run and at the end. A killed run therefore keeps
everything up to its last block: it loses at most the outputs of the last ``flush_s``
seconds (2 s by default), and never more than ``flush_outputs`` (256) of them.
"""

from __future__ import annotations

import errno
import json
import shutil
import time
from pathlib import Path
from typing import Callable, Mapping

import numpy as np


#: Bytes kept free beyond a block's own on the disk of results.h5 (HDF5 metadata).
HEADROOM = 2**20
#: Target bytes of a dataset's chunk: HDF5 allocates whole chunks, so a dataset's file
#: space exceeds its values by less than one chunk (a few snapshots of a beam, not hundreds).
CHUNK_BYTES = 2**16


def chunk_rows(row_bytes: int) -> int:
    """Rows per chunk of a dataset whose rows take ``row_bytes``: ``CHUNK_BYTES`` worth, 1
    to 256."""
    return max(1, min(256, CHUNK_BYTES // max(1, row_bytes)))


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
    flush_outputs : int
        Largest number of buffered outputs.
    flush_s : float
        Longest time [s] an output stays in the buffer (checked at each output).
    snapshot_due : callable, optional
        ``fn(t) -> bool``: whether the output at ``t`` also stores a state snapshot
        (default: every output does).

    Attributes
    ----------
    snapshots : int
        State snapshots in the file and its buffer.
    """

    def __init__(self, path: Path, quantities: Mapping[str, Callable], columns: Mapping[str, list],
                 snapshot: Callable[[object], dict], attrs: Mapping, append: bool = False,
                 flush_outputs: int = 256, flush_s: float = 2.0, snapshot_due: Callable[[float], bool] | None = None):
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
        self.snapshot_due = snapshot_due
        self.snapshots = self._stored("snapshots")
        self.flush_outputs, self.flush_s = int(flush_outputs), float(flush_s)
        self._pending: dict[tuple[str, str], list] = {}
        self._n_pending = 0
        self._last_write = time.perf_counter()

    def _stored(self, group: str) -> int:
        """Rows of ``group`` in the file."""
        g = self.f[group]
        return int(g["t"].shape[0]) if "t" in g else 0

    def _buffer(self, group: str, name: str, value) -> None:
        self._pending.setdefault((group, name), []).append(np.array(value, dtype=float))

    def _write(self, group: str, name: str, values: list) -> None:
        g = self.f[group]
        block = np.stack(values)
        shape = block.shape[1:]
        if name not in g:
            size = int(np.prod(shape)) if shape else 1
            g.create_dataset(name, shape=(0,) + shape, maxshape=(None,) + shape, dtype="f8",
                             chunks=(chunk_rows(8 * size),) + shape)
        d = g[name]
        n = d.shape[0]
        d.resize(n + block.shape[0], axis=0)
        d[n:] = block

    def _check_room(self) -> None:
        """Raise ``OSError(ENOSPC)`` naming the file when its disk cannot take the pending
        block (its values, a chunk per dataset and :data:`HEADROOM`): HDF5 itself does not
        survive a full disk (a failed write leaves the file's cache in a state where the
        next flush crashes the interpreter), so the block is not handed to it."""
        need = HEADROOM
        for (group, name), values in self._pending.items():
            row = np.asarray(values[0]).nbytes or 8
            need += row * len(values) + row * chunk_rows(row)
        free = shutil.disk_usage(self.path.parent).free
        if free < need:
            raise OSError(errno.ENOSPC, f"No space left on device ({free} bytes free, {need} needed for the next "
                          f"block)", str(self.path))

    def flush(self) -> None:
        """Write the buffered outputs and flush the file; ``OSError(ENOSPC)`` before any
        write when the disk cannot take them (the file then keeps its earlier blocks)."""
        if self._n_pending:
            self._check_room()
            for (group, name), values in self._pending.items():
                self._write(group, name, values)
            self._pending, self._n_pending = {}, 0
        self.f.flush()
        self._last_write = time.perf_counter()

    def __call__(self, t: float, y) -> None:
        self._buffer("history", "t", t)
        for name, fn in self.quantities.items():
            val = np.atleast_1d(np.asarray(fn(t, y), dtype=float))
            for col, x in zip(self.columns.get(name, [name]), val):
                self._buffer("history", col, x)
        if self.snapshot_due is None or self.snapshot_due(t):
            self._buffer("snapshots", "t", t)
            for name, arr in self.snapshot(y).items():
                self._buffer("snapshots", name, arr)
            self.snapshots += 1
        self._n_pending += 1
        if self._n_pending >= self.flush_outputs or time.perf_counter() - self._last_write > self.flush_s:
            self.flush()

    def truncate_after(self, t: float) -> None:
        """Drop rows with time > ``t`` (a resumed run continues from its checkpoint)."""
        self.flush()
        for group in ("history", "snapshots"):
            g = self.f[group]
            if "t" not in g:
                continue
            keep = int(np.searchsorted(g["t"][:], t, side="right"))
            for d in g.values():
                d.resize(keep, axis=0)
        self.f.flush()
        self.snapshots = self._stored("snapshots")

    def close(self) -> None:
        """Write what is buffered and close the file. When the buffer cannot be written
        (``OSError``), the file is closed without it and the error raised."""
        try:
            self.flush()
        finally:
            self._pending, self._n_pending = {}, 0
            if self.f.id.valid:
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
