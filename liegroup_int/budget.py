"""What a run's outputs will cost, checked before anything is written.

A run records ``n`` outputs: a history row at each, a state snapshot (HDF5) and a VTU file
at every few of them (``output.snapshot_every``, ``output.paraview_every``). Before its
first file, the runner refuses, with one line naming the key to change:

* a fixed step below ``span / MAX_STEPS`` and more than ``MAX_OUTPUTS`` outputs
  (:func:`liegroup_int.scenes.scene.check_counts`);
* outputs whose in-memory part (the output times, the history read back for the plots,
  shapes kept for the shape plot) would exceed half the memory available;
* outputs whose files would exceed the free space of the output directory's disk.

The sizes are estimates from one output of the initial state (:func:`output_sizes`).
"""

from __future__ import annotations

import math
import os
import shutil
from pathlib import Path
from typing import NamedTuple

import numpy as np

from .scenes import SceneError
from .scenes.scene import check_counts

#: Fraction of the available memory the outputs may hold.
MEMORY_FRACTION = 0.5
#: Bytes of one float in history.csv and in an ASCII VTU file (``repr`` precision, separator).
TEXT_FLOAT_BYTES = 24


class OutputSizes(NamedTuple):
    """Bytes of one output of each kind of a run.

    Attributes
    ----------
    row_memory : int
        Held in memory per history row until the end of the run (output time, the row
        read back for the plots).
    snapshot_memory : int
        Held in memory per state snapshot (shapes kept, or read back, for the shape plot).
    row_disk : int
        Written per history row (CSV row, HDF5 history row).
    snapshot_disk : int
        Written per state snapshot (HDF5).
    paraview_disk : int
        Written per ParaView file (VTU file and its index entry).
    """

    row_memory: int
    snapshot_memory: int
    row_disk: int
    snapshot_disk: int
    paraview_disk: int

    def memory(self, rows: int, snapshots: int) -> int:
        """Bytes held in memory by ``rows`` history rows and ``snapshots`` snapshots."""
        return rows * self.row_memory + snapshots * self.snapshot_memory

    def disk(self, rows: int, snapshots: int, files: int) -> int:
        """Bytes written by ``rows`` history rows, ``snapshots`` snapshots and ``files``
        ParaView files."""
        return rows * self.row_disk + snapshots * self.snapshot_disk + files * self.paraview_disk


def _nbytes(arrays: dict) -> int:
    return int(sum(np.asarray(a).nbytes for a in arrays.values()))


def output_sizes(scene, sim, y0) -> OutputSizes:
    """:class:`OutputSizes` of ``scene`` run as ``sim`` (a ``Simulation``) from ``y0``."""
    columns = sim.info.get("columns") or {}
    wanted = set(scene.output.quantities) | set(sim.diagnostics)
    n_cols = 1 + sum(len(columns.get(q, [q])) for q in wanted)
    snap = _nbytes(sim.to_arrays(y0))
    if sim.fields is not None:
        snap += _nbytes(sim.fields(y0))
    keeps_shapes = sim.snapshot is not None and (scene.output.plots or not scene.output.hdf5)
    row_memory = 8 + (8 * n_cols if scene.output.plots else 0)
    row_disk = TEXT_FLOAT_BYTES * n_cols + (8 * n_cols if scene.output.hdf5 else 0)
    paraview = 0
    if scene.output.paraview and sim.frames is not None:
        points, frames, point_data = sim.frames(y0)
        n_float = np.size(points) + np.size(frames) + sum(np.size(a) for a in (point_data or {}).values())
        paraview = TEXT_FLOAT_BYTES * int(n_float) + 1024  # values, XML and the .pvd entry
    return OutputSizes(row_memory, snap if keeps_shapes else 0, row_disk, snap if scene.output.hdf5 else 0, paraview)


def sparse_count(n: int, stride: int) -> int:
    """Snapshots (or ParaView files) among ``n`` outputs when every ``stride``-th one and
    the last are written: ``ceil(n / stride)``."""
    return -(-n // stride)


def available_memory() -> int:
    """Bytes of memory available to a new allocation (``MemAvailable`` on Linux, else the
    physical memory)."""
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")


def free_disk(out_dir: Path) -> int:
    """Free bytes on the disk of ``out_dir`` (of its nearest existing parent)."""
    p = Path(out_dir).resolve()
    while not p.exists() and p != p.parent:
        p = p.parent
    return shutil.disk_usage(p).free


def _gib(n: float) -> str:
    """Bytes in the largest binary unit below them (``1.5 MiB``, ``745 GiB``)."""
    for unit, size in (("TiB", 2**40), ("GiB", 2**30), ("MiB", 2**20), ("KiB", 2**10)):
        if n >= size:
            return f"{n / size:.3g} {unit}"
    return f"{n:.0f} B"


def check_budget(scene, sim, y0, t0: float, dt: float | None, every: float, out_dir: Path,
                 memory: int | None = None, disk: int | None = None, snapshot_stride: int = 1,
                 paraview_stride: int = 1) -> int:
    """Refuse a run whose outputs exceed the counts, the memory or the disk; return their number.

    Parameters
    ----------
    scene : Scene
    sim : Simulation
    y0 : state
        The initial (or resumed) state, for the sizes of one output.
    t0 : float
        Start time (a resumed run's checkpoint time).
    dt : float or None
        The resolved fixed step (None: adaptive).
    every : float
        The output interval the run uses.
    out_dir : Path
    memory, disk : int, optional
        Available memory and free disk [bytes] (default: measured).
    snapshot_stride, paraview_stride : int
        Outputs from one state snapshot (ParaView file) to the next.

    Raises
    ------
    SceneError
        One line with the estimate, the limit and the key to change.
    """
    span = scene.t_end - t0
    check_counts(scene.source, span, dt, every, scene.output.every)
    n = math.ceil(span / every - 1e-9)
    snapshots, files = sparse_count(n, snapshot_stride), sparse_count(n, paraview_stride)
    sizes = output_sizes(scene, sim, y0)
    memory = available_memory() if memory is None else memory
    held = sizes.memory(n, snapshots)
    if held > MEMORY_FRACTION * memory:
        raise SceneError(f"{scene.source}: {n} outputs (every {every:g} s over {span:g} s) would hold "
                         f"{_gib(held)} in memory, more than half the {_gib(memory)} available; raise "
                         f"output.every or output.snapshot_every, or set output.plots=false")
    disk = free_disk(out_dir) if disk is None else disk
    written = sizes.disk(n, snapshots, files)
    if written > disk:
        raise SceneError(f"{scene.source}: {n} outputs (every {every:g} s over {span:g} s) would write "
                         f"{_gib(written)}, more than the {_gib(disk)} free in {out_dir}; raise output.every "
                         f"(or output.snapshot_every / output.paraview_every), or set output.hdf5=false / "
                         f"output.paraview=false")
    return n
