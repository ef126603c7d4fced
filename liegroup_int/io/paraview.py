"""ParaView output: beam centrelines and section frames as VTK XML files.

One time step is an UnstructuredGrid (``.vtu``): the centreline points joined by
``VTK_LINE`` segments, with point data arrays. The section frames are stored as three
vector arrays ``d1, d2, d3`` (the columns of ``R``), so ParaView's *Glyph* filter
(orientation array ``d1``, ``d2`` or ``d3``) draws them. A time series is indexed by a
collection file (``.pvd``) that ParaView opens as one animated dataset.

The files are plain XML written by this module (no VTK dependency), each through a
temporary file and a rename, so a reader never sees half a file and a killed run
leaves a valid index of the steps written so far.
"""

from __future__ import annotations

import base64
import os
import time
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

#: VTK cell type of a two-point line segment.
VTK_LINE = 3

ENCODINGS = ("ascii", "base64")
FRAME_NAMES = ("d1", "d2", "d3")


# ---------------------------------------------------------------------- low level
def _atomic_write(path: Path, text: str) -> None:
    """Write ``text`` through a temporary file and rename it onto ``path`` (a failed write
    removes the temporary file and leaves ``path`` as it was)."""
    tmp = path.with_name(path.name + ".tmp")
    try:
        with open(tmp, "w", encoding="utf-8") as fh:
            fh.write(text)
        os.replace(tmp, path)
    except OSError:
        tmp.unlink(missing_ok=True)
        raise


def _ascii_values(a: np.ndarray) -> str:
    """Values of ``a`` (any shape) as text; floats with ``repr`` (round-trip) precision."""
    # tolist() gives Python floats and ints, whose str is their shortest round-trip repr
    return " ".join(map(str, a.ravel().tolist()))


def _base64_values(a: np.ndarray) -> str:
    """VTK XML inline ``binary`` format: base64 of a UInt64 byte count + the raw data."""
    raw = np.ascontiguousarray(a).tobytes()
    header = np.array([len(raw)], dtype="<u8").tobytes()
    return base64.b64encode(header + raw).decode("ascii")


def _data_array(name: str, a: np.ndarray, encoding: str) -> str:
    """One ``<DataArray>`` element.

    Parameters
    ----------
    name : str
    a : numpy.ndarray, shape (m,) or (m, k)
        Float arrays are written as Float64, integer arrays as Int64, ``uint8`` as UInt8.
    encoding : {"ascii", "base64"}
    """
    if a.dtype == np.uint8:
        vtk_type, a = "UInt8", a.astype("u1")
    elif a.dtype.kind in "iu":
        vtk_type, a = "Int64", a.astype("<i8")
    else:
        vtk_type, a = "Float64", a.astype("<f8")
    # scalars: no NumberOfComponents (VTK's default is 1; readers then return shape (m,))
    ncomp = "" if a.ndim == 1 else f' NumberOfComponents="{a.shape[1]}"'
    fmt = "ascii" if encoding == "ascii" else "binary"
    values = _ascii_values(a) if encoding == "ascii" else _base64_values(a)
    return (f'<DataArray type="{vtk_type}" Name={quoteattr(name)}{ncomp} format="{fmt}">\n{values}\n</DataArray>\n')


# ---------------------------------------------------------------------- validation
def _check_points(points) -> np.ndarray:
    pts = np.asarray(points, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 3 or pts.shape[0] < 2:
        raise ValueError(f"points: expected an array of shape (m, 3) with m >= 2, got shape {pts.shape}")
    return pts


def _check_frames(frames, m: int) -> np.ndarray | None:
    if frames is None:
        return None
    R = np.asarray(frames, dtype=float)
    if R.shape != (m, 3, 3):
        raise ValueError(f"frames: expected shape ({m}, 3, 3), got {R.shape}")
    return R


def _check_point_data(point_data, m: int, reserved: tuple[str, ...]) -> dict[str, np.ndarray]:
    out: dict[str, np.ndarray] = {}
    for name, values in (point_data or {}).items():
        a = np.asarray(values)
        if not isinstance(name, str) or not name:
            raise ValueError(f"point_data: array names must be non-empty strings, got {name!r}")
        if name in reserved:
            raise ValueError(f"point_data: name {name!r} is taken by the frame vectors {reserved}")
        if a.ndim not in (1, 2) or a.shape[0] != m:
            raise ValueError(f"point_data[{name!r}]: expected shape ({m},) or ({m}, k), got {a.shape}")
        if a.dtype.kind not in "biuf":
            raise ValueError(f"point_data[{name!r}]: expected numbers, got dtype {a.dtype}")
        out[name] = a.astype(float) if a.dtype.kind == "b" else a
    return out


# ---------------------------------------------------------------------- public API
def write_beam_vtu(path, points, frames=None, point_data=None, encoding: str = "ascii") -> Path:
    """Write one beam configuration as a VTK XML UnstructuredGrid (``.vtu``).

    Parameters
    ----------
    path : str or Path
        Output file (conventionally ``*.vtu``); parent directories must exist.
    points : array_like, shape (m, 3)
        Centreline points, in order along the beam (``m >= 2``); consecutive points are
        joined by line cells (``m - 1``, or fewer: see ``point_data["member"]``).
    frames : array_like, shape (m, 3, 3), optional
        Section frames at the points; written as point vectors ``d1, d2, d3`` (the
        columns ``R[:, :, 0]``, ``R[:, :, 1]``, ``R[:, :, 2]``).
    point_data : dict of str to array_like, optional
        Extra point arrays, each of shape ``(m,)`` (scalars) or ``(m, k)`` (k components).
        An array ``"member"`` (the member of each point, a frame's patch) also keeps the
        cells within members: consecutive points of two members are not joined.
    encoding : {"ascii", "base64"}
        ``"ascii"``: text with ``repr`` (round-trip) precision; ``"base64"``: VTK's
        inline binary format (little endian, UInt64 byte-count headers). Both are exact.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    ValueError
        Wrong shapes, a point array named like a frame vector, an unknown encoding.
    """
    if encoding not in ENCODINGS:
        raise ValueError(f"encoding: expected one of {ENCODINGS}, got {encoding!r}")
    pts = _check_points(points)
    m = pts.shape[0]
    R = _check_frames(frames, m)
    arrays: dict[str, np.ndarray] = {}
    if R is not None:
        arrays.update({name: R[:, :, j] for j, name in enumerate(FRAME_NAMES)})
    arrays.update(_check_point_data(point_data, m, FRAME_NAMES if R is not None else ()))
    first = np.arange(m - 1, dtype=np.int64)
    if "member" in arrays:
        first = first[arrays["member"][:-1] == arrays["member"][1:]]
    connectivity = np.stack([first, first + 1], axis=1).ravel()
    offsets = 2 * np.arange(1, first.size + 1, dtype=np.int64)
    types = np.full(first.size, VTK_LINE, dtype=np.uint8)
    vectors = ' Vectors="d1"' if R is not None else ""
    body = [
        '<?xml version="1.0"?>\n',
        '<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" header_type="UInt64">\n',
        "<UnstructuredGrid>\n",
        f'<Piece NumberOfPoints="{m}" NumberOfCells="{first.size}">\n',
        f"<PointData{vectors}>\n",
        *(_data_array(name, a, encoding) for name, a in arrays.items()),
        "</PointData>\n",
        "<Points>\n",
        _data_array("Points", pts, encoding),
        "</Points>\n",
        "<Cells>\n",
        _data_array("connectivity", connectivity, encoding),
        _data_array("offsets", offsets, encoding),
        _data_array("types", types, encoding),
        "</Cells>\n",
        "</Piece>\n",
        "</UnstructuredGrid>\n",
        "</VTKFile>\n",
    ]
    path = Path(path)
    _atomic_write(path, "".join(body))
    return path


def write_pvd(path, entries) -> Path:
    """Write a ParaView collection (``.pvd``) indexing a time series of files.

    Parameters
    ----------
    path : str or Path
        Output file (conventionally ``*.pvd``).
    entries : sequence of (float, str)
        ``(time, filename)`` pairs, ``filename`` relative to the directory of ``path``
        (ParaView resolves it from there), in time order.

    Returns
    -------
    Path
        ``path``.
    """
    lines = ['<?xml version="1.0"?>\n',
             '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">\n',
             "<Collection>\n"]
    for t, name in entries:
        lines.append(f'<DataSet timestep="{float(t)!r}" group="" part="0" file={quoteattr(str(name))}/>\n')
    lines += ["</Collection>\n", "</VTKFile>\n"]
    path = Path(path)
    _atomic_write(path, "".join(lines))
    return path


def interpolate_frames(u_c: np.ndarray, R_c: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Frames at parameters ``u`` by geodesic interpolation between neighbouring
    collocation frames (for display; exact at ``u = u_c``).

    Parameters
    ----------
    u_c : numpy.ndarray, shape (n,)
        Increasing collocation parameters covering ``[u[0], u[-1]]``.
    R_c : numpy.ndarray, shape (n, 3, 3)
        Rotations at ``u_c``.
    u : numpy.ndarray, shape (m,)
        Parameters in ``[u_c[0], u_c[-1]]``.

    Returns
    -------
    numpy.ndarray, shape (m, 3, 3)
        ``exp(tau log(R_{i+1} R_i^T)) R_i`` with ``tau`` the position of ``u`` in
        ``[u_c[i], u_c[i+1]]``.
    """
    from ..groups.so3 import exp_so3, log_so3

    i = np.clip(np.searchsorted(u_c, u, side="right") - 1, 0, len(u_c) - 2)
    tau = (u - u_c[i]) / (u_c[i + 1] - u_c[i])
    rel = log_so3(R_c[i + 1] @ np.swapaxes(R_c[i], -1, -2))
    return exp_so3(tau[:, None] * rel) @ R_c[i]


class FrameSeriesWriter:
    """Observer ``(t, y)`` writing a curve with frames as a ParaView time series.

    Each call writes ``out_dir/paraview/{stem}_{k:05d}.vtu`` (:func:`write_beam_vtu`) and
    then rewrites ``out_dir/{stem}.pvd`` listing every file written so far, so the index is
    valid at any time (a killed run keeps the steps it reached). With ``index_every_s > 0``
    the index is rewritten only when it is older than that many wall seconds, and at
    :meth:`flush` / :meth:`close`: a run of many files then does not rewrite a growing index
    per file (quadratic cost), and a killed run's index lacks at most the files of its last
    ``index_every_s`` seconds (it always lists whole files). It knows no model: the arrays
    come from ``geometry``.

    Parameters
    ----------
    out_dir : str or Path
        Run directory; ``paraview/`` is created in it.
    geometry : callable
        ``geometry(y) -> (points (m, 3), frames (m, 3, 3), point_data dict of (m,) arrays)``.
    every_output : bool
        ``True``: one file per call (a time series). ``False``: every call overwrites
        ``{stem}_00000.vtu`` and the index lists only the latest time (last state only).
    encoding : {"ascii", "base64"}
        Passed to :func:`write_beam_vtu`.
    stem : str
        File name stem.
    index_every_s : float
        Longest wall time [s] the index may lag behind the files written (0: rewritten
        at every call).

    Attributes
    ----------
    entries : list of (float, str)
        ``(t, "paraview/{stem}_XXXXX.vtu")`` of the files in the index.
    pvd : Path
        The index file, ``out_dir/{stem}.pvd``.
    """

    def __init__(self, out_dir, geometry, every_output: bool = True, encoding: str = "ascii", stem: str = "beam",
                 index_every_s: float = 0.0):
        if encoding not in ENCODINGS:
            raise ValueError(f"encoding: expected one of {ENCODINGS}, got {encoding!r}")
        self.out_dir = Path(out_dir)
        self.dir = self.out_dir / "paraview"
        self.dir.mkdir(parents=True, exist_ok=True)
        self.stem = stem
        self.pvd = self.out_dir / f"{stem}.pvd"
        self.frames_of, self.every_output, self.encoding = geometry, every_output, encoding
        self.entries: list[tuple[float, str]] = []
        self.index_every_s = float(index_every_s)
        self._indexed, self._index_wall = 0, time.perf_counter()

    def resume_after(self, t: float) -> None:
        """Continue the series of an existing index from the entries up to ``t``; the
        series' files past them (written after ``t`` by the run resumed) are removed."""
        import xml.etree.ElementTree as ET

        if self.pvd.exists():
            root = ET.parse(self.pvd).getroot()
            self.entries = [(float(d.get("timestep")), d.get("file")) for d in root.iter("DataSet")
                            if float(d.get("timestep")) <= t]
        self._indexed = -1  # the index on disk may list later files: rewrite it at the next flush
        if self.every_output:
            kept = {Path(f).name for _, f in self.entries}
            for path in self.dir.glob(f"{self.stem}_[0-9][0-9][0-9][0-9][0-9].vtu"):
                if path.name not in kept:
                    path.unlink()

    def __call__(self, t: float, y) -> None:
        k = len(self.entries) if self.every_output else 0
        name = f"{self.stem}_{k:05d}.vtu"
        points, frames, data = self.frames_of(y)
        write_beam_vtu(self.dir / name, points, frames, data, self.encoding)
        entry = (float(t), f"{self.dir.name}/{name}")
        if self.every_output:
            self.entries.append(entry)
        else:
            self.entries = [entry]
            self._indexed = -1
        if self.index_every_s <= 0 or time.perf_counter() - self._index_wall >= self.index_every_s:
            self.flush()

    def flush(self) -> None:
        """Rewrite the index when it lacks files written since its last write."""
        if self._indexed != len(self.entries):
            write_pvd(self.pvd, self.entries)
            self._indexed = len(self.entries)
        self._index_wall = time.perf_counter()

    def close(self) -> None:
        """Write the index of every file written (:meth:`flush`)."""
        self.flush()


class BeamParaViewWriter(FrameSeriesWriter):
    """:class:`FrameSeriesWriter` of a beam's centreline and section frames.

    Parameters
    ----------
    out_dir : str or Path
        Run directory; ``paraview/`` is created in it.
    problem : BeamProblem
        Supplies the points that carry its rotations (``frame_points``: parameters,
        basis values, reference arc lengths) and ``space.point_matrix``.
    every_output : bool
        As :class:`FrameSeriesWriter`.
    n_points : int, optional
        ``None`` (default): points at the ``n_ctrl`` collocation points,
        ``N0 @ y.c``, with the exact frames ``y.R`` there. An integer ``>= 2``:
        ``n_points`` points at uniformly spaced parameters (smoother lines), with
        frames interpolated along geodesics between the collocation frames.
    encoding : {"ascii", "base64"}
        Passed to :func:`write_beam_vtu`.

    Notes
    -----
    Point data: ``d1, d2, d3`` (frame columns) and ``s`` (reference arc length).
    """

    def __init__(self, out_dir, problem, every_output: bool = True, n_points: int | None = None,
                 encoding: str = "ascii"):
        if n_points is not None and (int(n_points) != n_points or n_points < 2):
            raise ValueError(f"n_points: expected None or an integer >= 2, got {n_points!r}")
        super().__init__(out_dir, self._arrays, every_output, encoding, "beam")
        self.problem = problem
        space = problem.space
        u_pts, basis, s_pts = problem.frame_points
        self._u_c = np.asarray(u_pts, dtype=float)
        if n_points is None:
            self._u, self._B, self._s = None, np.asarray(basis), np.asarray(s_pts, dtype=float)
        else:
            u = np.linspace(0.0, 1.0, int(n_points))
            self._u, self._B, self._s = u, space.point_matrix(u), np.asarray(space.arc_length(u), dtype=float)

    def geometry(self, y) -> tuple[np.ndarray, np.ndarray]:
        """Points ``(m, 3)`` and frames ``(m, 3, 3)`` of a :class:`BeamState`."""
        points = self._B @ y.c[:self._B.shape[1]]
        R = np.asarray(y.R)[:len(self._u_c)]  # the centreline's points (a Galerkin state's nodes follow)
        frames = R if self._u is None else interpolate_frames(self._u_c, R, self._u)
        return points, frames

    def _arrays(self, y):
        points, frames = self.geometry(y)
        return points, frames, {"s": self._s}
