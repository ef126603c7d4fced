"""ParaView output: .vtu files read back with meshio, the .pvd index parsed with ElementTree."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pytest

from liegroup_int.integrators import integrate_fixed, resolve_method
from liegroup_int.io.paraview import BeamParaViewWriter, interpolate_frames, write_beam_vtu, write_pvd
from liegroup_int.scenes.beam import problem as beam_problem
from liegroup_int.scenes.scene import load_scene

import meshio

DT = 1e-6
N_STEPS = 20
OUT_STEPS = (5, 10, 15, 20)


def _orthonormal(mesh, tol=1e-12):
    D = np.stack([mesh.point_data[n] for n in ("d1", "d2", "d3")], axis=-1)  # columns
    err = np.swapaxes(D, -1, -2) @ D - np.eye(3)
    return float(np.max(np.abs(err))) < tol and bool(np.all(np.linalg.det(D) > 0))


def _pvd_entries(path):
    root = ET.parse(path).getroot()
    assert root.get("type") == "Collection"
    return [(float(d.get("timestep")), d.get("file")) for d in root.iter("DataSet")]


class Recorder:
    def __init__(self, pb):
        self.pb, self.t, self.points, self.R = pb, [], [], []

    def __call__(self, t, y):
        self.t.append(float(t))
        self.points.append(self.pb.frame_points[1] @ y.c)  # the points that carry the rotations
        self.R.append(y.R.copy())


@pytest.fixture(scope="module")
def cantilever_series(tmp_path_factory):
    """A 20-step cantilever run (default formulation: Galerkin, whose rotations live at the
    quadrature points, 110 of them at p = 4, n_ctrl = 31) observed by the writer and by a
    plain recorder."""
    out = tmp_path_factory.mktemp("pv_run")
    scene = load_scene("cantilever", {"t_end": N_STEPS * DT, "integrator.dt": DT, "output.every": 5 * DT})
    pb = beam_problem(scene)
    writer, rec = BeamParaViewWriter(out, pb), Recorder(pb)

    def observer(t, y):
        writer(t, y)
        rec(t, y)

    t_out = DT * np.array(OUT_STEPS, dtype=float)
    integrate_fixed(pb, resolve_method("rkmk4"), (0.0, scene.t_end), pb.initial_state(), DT, observer, t_out)
    return out, pb, writer, rec


def test_series_read_back(cantilever_series):
    out, pb, writer, rec = cantilever_series
    entries = _pvd_entries(out / "beam.pvd")
    assert len(entries) == 1 + len(OUT_STEPS)  # t0 and every output time
    np.testing.assert_allclose([t for t, _ in entries], [0.0] + [k * DT for k in OUT_STEPS], rtol=1e-12, atol=0)
    assert [t for t, _ in entries] == rec.t  # repr-exact in the index
    moved = False
    for (t, name), pts, R in zip(entries, rec.points, rec.R):
        mesh = meshio.read(out / name)
        u_pts, _, s_pts = pb.frame_points
        m = len(u_pts)
        assert mesh.points.shape == (m, 3)
        np.testing.assert_allclose(mesh.points, pts, rtol=1e-12, atol=1e-12 * np.max(np.abs(pts)))
        assert np.array_equal(mesh.points, pts)  # repr round-trips exactly
        for j, n in enumerate(("d1", "d2", "d3")):
            assert np.array_equal(mesh.point_data[n], R[:, :, j])
        assert _orthonormal(mesh)
        np.testing.assert_array_equal(mesh.point_data["s"], s_pts)
        lines = mesh.cells_dict["line"]
        assert lines.shape == (m - 1, 2)
        assert np.array_equal(lines[:, 1] - lines[:, 0], np.ones(m - 1))
        moved |= not np.array_equal(pts, rec.points[0])
    assert moved  # the tip load moved the beam
    assert writer.entries == entries


@pytest.mark.parametrize("encoding", ["ascii", "base64"])
def test_write_beam_vtu_exact(tmp_path, encoding):
    rng = np.random.default_rng(1)
    pts = rng.normal(size=(7, 3)) * 10.0 ** rng.integers(-8, 8, size=(7, 1))
    Q, _ = np.linalg.qr(rng.normal(size=(7, 3, 3)))
    scalars, vecs = rng.normal(size=7), rng.normal(size=(7, 3))
    path = write_beam_vtu(tmp_path / f"b_{encoding}.vtu", pts, Q, {"s": scalars, "v": vecs}, encoding=encoding)
    mesh = meshio.read(path)
    assert np.array_equal(mesh.points, pts)
    assert np.array_equal(mesh.point_data["s"], scalars)
    assert np.array_equal(mesh.point_data["v"], vecs)
    assert np.array_equal(mesh.point_data["d3"], Q[:, :, 2])
    assert mesh.cells_dict["line"].shape == (6, 2)


def test_write_beam_vtu_without_frames(tmp_path):
    pts = np.array([[0.0, 0, 0], [1.0, 0, 0]])
    mesh = meshio.read(write_beam_vtu(tmp_path / "b.vtu", pts))
    assert np.array_equal(mesh.points, pts) and "d1" not in mesh.point_data


@pytest.mark.parametrize("bad", [
    dict(points=np.zeros((4, 2))),
    dict(points=np.zeros((1, 3))),
    dict(points=np.zeros((4, 3)), frames=np.zeros((3, 3, 3))),
    dict(points=np.zeros((4, 3)), point_data={"s": np.zeros(3)}),
    dict(points=np.zeros((4, 3)), frames=np.tile(np.eye(3), (4, 1, 1)), point_data={"d1": np.zeros(4)}),
    dict(points=np.zeros((4, 3)), encoding="raw"),
])
def test_write_beam_vtu_rejects(tmp_path, bad):
    with pytest.raises(ValueError):
        write_beam_vtu(tmp_path / "x.vtu", **bad)
    assert not (tmp_path / "x.vtu").exists()


def test_write_pvd(tmp_path):
    entries = [(0.0, "paraview/a.vtu"), (0.1 + 0.2, 'paraview/b "q".vtu')]
    got = _pvd_entries(write_pvd(tmp_path / "x.pvd", entries))
    assert got == entries


def test_last_state_only_and_dense(tmp_path):
    scene = load_scene("cantilever", {"t_end": 4 * DT, "integrator.dt": DT, "output.every": DT, "space.n_ctrl": 9})
    pb = beam_problem(scene)
    writer = BeamParaViewWriter(tmp_path, pb, every_output=False, n_points=25, encoding="base64")
    integrate_fixed(pb, resolve_method("rkmk4"), (0.0, scene.t_end), pb.initial_state(), DT, writer,
                    DT * np.arange(1.0, 5.0))
    assert _pvd_entries(tmp_path / "beam.pvd") == [(4 * DT, "paraview/beam_00000.vtu")]
    assert sorted(p.name for p in (tmp_path / "paraview").iterdir()) == ["beam_00000.vtu"]
    mesh = meshio.read(tmp_path / "paraview" / "beam_00000.vtu")
    assert mesh.points.shape == (25, 3) and _orthonormal(mesh)
    np.testing.assert_allclose(mesh.point_data["s"][[0, -1]], [0.0, pb.space.length], atol=1e-12)


def test_interpolate_frames_exact_at_nodes():
    rng = np.random.default_rng(2)
    Q, _ = np.linalg.qr(rng.normal(size=(5, 3, 3)))
    Q[np.linalg.det(Q) < 0, :, 0] *= -1
    u_c = np.array([0.0, 0.1, 0.4, 0.7, 1.0])
    np.testing.assert_allclose(interpolate_frames(u_c, Q, u_c), Q, atol=1e-14)
    mid = interpolate_frames(u_c, Q, np.array([0.05]))[0]
    np.testing.assert_allclose(mid.T @ mid, np.eye(3), atol=1e-14)
