"""Frame files: clothsim.io.frames (FrameWriter, read_frame, read_pvd)."""

import xml.etree.ElementTree as ET
from pathlib import Path

import meshio
import numpy as np
import pytest

from clothsim import io
from clothsim.errors import InputError
from clothsim.mesh import Mesh, grid


def pvd_entries(path):
    root = ET.parse(path).getroot()  # raises if the file is not valid XML
    assert root.tag == "VTKFile" and root.get("type") == "Collection"
    return [(float(d.get("timestep")), d.get("file")) for d in root.iter("DataSet")]


def frame_data(k, n, seed=0):
    rng = np.random.default_rng(seed + k)
    return rng.standard_normal((n, 3)) / 3, rng.standard_normal((n, 3)) * 1e-7


def test_frame_writer_round_trip_bitwise(tmp_path):
    base = grid(4, 4)
    mesh = Mesh(base.vertices, base.triangles, [[0, 5]])  # a strand as a line cell
    writer = io.FrameWriter(tmp_path / "out", mesh)
    h = 1 / 30
    for k in range(3):
        x, v = frame_data(k, 16)
        path = writer.write(k, k * h, x, v)
        assert path.name == f"frame_{k:06d}.vtu"
        # after every write the collection is complete and lists exactly the frames so far
        assert pvd_entries(writer.pvd_path) == [(i * h, f"frame_{i:06d}.vtu")
                                                for i in range(k + 1)]
    for k in range(3):
        x, v = io.read_frame(tmp_path / "out" / f"frame_{k:06d}.vtu")
        x0, v0 = frame_data(k, 16)
        assert x.dtype == v.dtype == np.float64
        assert np.array_equal(x.view(np.uint64), x0.view(np.uint64))
        assert np.array_equal(v.view(np.uint64), v0.view(np.uint64))
    cells = meshio.read(tmp_path / "out" / "frame_000002.vtu").cells_dict
    assert np.array_equal(cells["triangle"], mesh.triangles)
    assert cells["line"].tolist() == [[0, 5]]
    assert [t for t, _ in io.read_pvd(writer.pvd_path)] == [0.0, h, 2 * h]
    assert [i for i, _, _ in writer.frames()] == [0, 1, 2]
    leftovers = sorted(p.name for p in (tmp_path / "out").iterdir())
    assert leftovers == ["frame_000000.vtu", "frame_000001.vtu", "frame_000002.vtu",
                         "trajectory.pvd"]  # no temporary files


def test_frame_writer_interrupted_mid_write_leaves_valid_files(tmp_path, monkeypatch):
    mesh = grid(3, 3)
    writer = io.FrameWriter(tmp_path, mesh)
    for k in range(2):
        writer.write(k, 0.1 * k, *frame_data(k, 9))
    from clothsim.io.vtufile import VtuTemplate

    real_write = VtuTemplate.write

    def write_half_then_interrupt(self, path, *args, **kwargs):
        Path(path).write_text("<VTKFile")  # a truncated file under the temporary name
        raise KeyboardInterrupt

    monkeypatch.setattr(VtuTemplate, "write", write_half_then_interrupt)
    with pytest.raises(KeyboardInterrupt):
        writer.write(2, 0.2, *frame_data(2, 9))
    monkeypatch.setattr(VtuTemplate, "write", real_write)
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "frame_000000.vtu", "frame_000001.vtu", "trajectory.pvd"]
    assert [f for _, f in pvd_entries(tmp_path / "trajectory.pvd")] == [
        "frame_000000.vtu", "frame_000001.vtu"]
    for _t, path in io.read_pvd(tmp_path / "trajectory.pvd"):
        assert io.read_frame(path)[0].shape == (9, 3)


def test_frame_writer_resume_keeps_earlier_entries(tmp_path):
    mesh = grid(3, 3)
    first = io.FrameWriter(tmp_path, mesh)
    for k in range(4):
        first.write(k, 0.5 * k, *frame_data(k, 9))
    # the run stopped after frame 3; resume from frame 2 (frames 2, 3 are recomputed)
    resumed = io.FrameWriter(tmp_path, mesh)
    resumed.write(2, 1.0, *frame_data(2, 9, seed=100))
    assert pvd_entries(tmp_path / "trajectory.pvd") == [
        (0.0, "frame_000000.vtu"), (0.5, "frame_000001.vtu"), (1.0, "frame_000002.vtu")]
    assert np.array_equal(io.read_frame(tmp_path / "frame_000002.vtu")[0],
                          frame_data(2, 9, seed=100)[0])
    # a fresh run (first index 0) starts a new collection
    fresh = io.FrameWriter(tmp_path, mesh)
    fresh.write(0, 0.0, *frame_data(0, 9))
    assert pvd_entries(tmp_path / "trajectory.pvd") == [(0.0, "frame_000000.vtu")]


def test_frame_writer_and_reader_errors(tmp_path):
    mesh = grid(3, 3)
    writer = io.FrameWriter(tmp_path, mesh)
    with pytest.raises(InputError, match=r"^velocities: expected shape \(9, 3\), got \(8, 3\)$"):
        writer.write(0, 0.0, np.zeros((9, 3)), np.zeros((8, 3)))
    with pytest.raises(InputError, match=r"^index: must be a non-negative integer"):
        writer.write(-1, 0.0, np.zeros((9, 3)), np.zeros((9, 3)))
    with pytest.raises(InputError, match=r"^basename: only letters"):
        io.FrameWriter(tmp_path, mesh, basename="a/b")
    io.write_mesh(tmp_path / "plain.vtu", mesh)
    with pytest.raises(InputError, match=r"plain\.vtu: point data 'velocity' missing$"):
        io.read_frame(tmp_path / "plain.vtu")
    with pytest.raises(InputError, match=r"^frame: file not found"):
        io.read_frame(tmp_path / "frame_000009.vtu")
