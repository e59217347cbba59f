"""Frames written zlib-compressed or raw ([output] frame_compression): both read back bit for
bit with meshio and clothsim's readers (compare, resume), and run.json says which and why."""

import json

import meshio
import numpy as np
import pytest

import clothsim as cs
from clothsim.cli import main
from clothsim.io.frames import ZLIB_UP_TO, FrameWriter, choose_frame_compression, read_frame
from clothsim.scene.schema import spec


def test_auto_compresses_small_cloths_only():
    assert choose_frame_compression(21 * 21)[0] == "zlib"
    assert choose_frame_compression(ZLIB_UP_TO)[0] == "zlib"
    mode, why = choose_frame_compression(513 * 513)
    assert mode == "none" and "263169 vertices" in why and str(ZLIB_UP_TO) in why
    assert choose_frame_compression(513 * 513, "zlib") == (
        "zlib", "zlib: requested by output.frame_compression")
    assert choose_frame_compression(10, "none")[0] == "none"
    with pytest.raises(cs.InputError, match="output.frame_compression: must be one of"):
        choose_frame_compression(10, "gzip")
    # the scene reference states the same threshold
    assert f"{ZLIB_UP_TO:,}".replace(",", " ") in spec("output", "frame_compression").meaning


@pytest.mark.parametrize("compression", ["none", "zlib"])
def test_frame_reads_back_with_meshio_bit_for_bit(tmp_path, compression):
    mesh = cs.grid(7, 5)
    rng = np.random.default_rng(4)
    x = mesh.vertices + rng.normal(scale=1e-3, size=mesh.vertices.shape)
    v = rng.normal(size=x.shape)
    writer = FrameWriter(tmp_path, mesh, compression=compression)
    assert writer.compression == compression
    path = writer.write(0, 0.0, x, v)
    head = path.read_bytes()[:400].decode("ascii", "replace")
    assert ("vtkZLibDataCompressor" in head) == (compression == "zlib")
    m = meshio.read(path)
    assert np.array_equal(m.points, x)
    assert np.array_equal(m.point_data["velocity"], v)
    assert np.array_equal(m.cells_dict["triangle"], mesh.triangles)
    xr, vr = read_frame(path)
    assert np.array_equal(xr, x) and np.array_equal(vr, v)


def test_run_uncompressed_then_resume_compressed_equals_a_fresh_run(tmp_path):
    out, fresh = tmp_path / "run", tmp_path / "fresh"
    assert main(["run", "hanging", "--set", "output.frame_compression=none", "--frames", "2",
                 "--out", str(out), "--no-preview"]) == 0
    info = json.loads((out / "run.json").read_text())
    assert info["frame_compression"] == "none: requested by output.frame_compression"
    assert b"vtkZLibDataCompressor" not in (out / "frame_000002.vtu").read_bytes()[:400]
    # compare reads the raw frames through trajectory.pvd: they equal the trajectory
    assert main(["compare", str(out / "trajectory.pvd"), str(out / "trajectory.npz"),
                 "--no-table"]) == 0
    # resume reads the last raw frame back; the compression is not part of the scene hash
    assert main(["run", "hanging", "--frames", "4", "--out", str(out), "--resume",
                 "--no-preview"]) == 0
    info = json.loads((out / "run.json").read_text())
    assert info["resumed_from"] == 2 and info["frame_compression"].startswith("zlib: 441 ")
    assert b"vtkZLibDataCompressor" in (out / "frame_000004.vtu").read_bytes()[:400]
    assert main(["run", "hanging", "--frames", "4", "--out", str(fresh), "--no-preview"]) == 0
    with np.load(out / "trajectory.npz") as a, np.load(fresh / "trajectory.npz") as b:
        assert np.array_equal(a["positions"], b["positions"])
        assert np.array_equal(a["velocities"], b["velocities"])


def test_bad_compression_is_a_scene_error():
    with pytest.raises(cs.InputError, match="output.frame_compression: must be one of"):
        cs.load_scene("hanging", ["output.frame_compression=gzip"])
    with pytest.raises(cs.InputError, match="output.compression: unknown key"):
        cs.load_scene("hanging", ["output.compression=none"])
