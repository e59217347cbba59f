"""Mesh files, frame files and matrix export (clothsim.io, clothsim.mesh.load)."""

import os
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import meshio
import numpy as np
import pytest
import scipy.sparse

from clothsim import io
from clothsim.errors import InputError
from clothsim.mesh import Mesh, grid, load

REPO = Path(__file__).resolve().parents[1]
JACOBSON = REPO.parent / "shared" / "data" / "jacobson-a8"


def quad_mesh():
    """3 × 2 vertices, 2 quads, awkward float64 coordinates."""
    u, v = np.meshgrid(np.arange(3) / 3.0, np.arange(2) * np.pi)
    points = np.column_stack([u.ravel(), v.ravel(), np.full(6, 1e-17)])
    return points, np.array([[0, 1, 4, 3], [1, 2, 5, 4]])


# --------------------------------------------------------------------------- reading


@pytest.mark.parametrize("ext", ["ply", "vtu", "obj", "vtk"])
def test_quads_written_by_meshio_read_back(tmp_path, ext):
    points, quads = quad_mesh()
    path = tmp_path / f"quads.{ext}"
    meshio.write(path, meshio.Mesh(points, [("quad", quads)]))
    mesh = load(path)
    assert mesh.triangle_count == 2 * len(quads)
    assert np.array_equal(mesh.vertices, points)
    # the two triangles of each quad cover it exactly: total area = 2/3 × π
    assert mesh.triangle_areas().sum() == pytest.approx(2 / 3 * np.pi, rel=1e-14)


def test_line_cells_become_strands(tmp_path):
    points = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]], float)
    path = tmp_path / "chain.vtu"
    meshio.write(path, meshio.Mesh(points, [("line", [[0, 1], [1, 2], [2, 3]]),
                                            ("vertex", [[0], [3]])]))
    mesh = load(path)
    assert mesh.strands.tolist() == [[0, 1], [1, 2], [2, 3]] and mesh.triangle_count == 0


def test_obj_reader_index_forms_negative_indices_and_lines(tmp_path):
    path = tmp_path / "forms.obj"
    path.write_text(
        "# comment\nmtllib x.mtl\no thing\n"
        "v 0 0 0\nv 1 0 0\nv 1 1 0 1.0\nv 0 1 0 0.5 0.5 0.5\n"  # w and colour ignored
        "vt 0 0\nvn 0 0 1\ng group\ns off\n"
        "f 1/1/1 2/1/1 3//1\n"               # v/vt/vn and v//vn
        "f -4/1 -2 -1\n"                     # relative: vertices 1, 3, 4
        "v 2 0 0\nv 3 0 0\nv 4 0 0\n"
        "l 2 5 6 -1\n"                        # polyline: 3 strands 2-5, 5-6, 6-7
        "f 6 7\n"                            # 2-vertex face: a strand (repeats 6-7: dropped)
        "f 1 4 3 7 6\n")                     # pentagon after strands: 3 fan triangles
    mesh = load(path, check=False)
    assert mesh.vertex_count == 7
    assert mesh.vertices[3].tolist() == [0, 1, 0]
    assert mesh.triangles.tolist() == [[0, 1, 2], [0, 2, 3], [0, 3, 2], [0, 2, 6], [0, 6, 5]]
    assert mesh.strands.tolist() == [[1, 4], [4, 5]]  # (5, 6) is a pentagon edge: dropped


@pytest.mark.parametrize("text, message", [
    ("v 0 0 0\nv 1 0 0\nf 1 0\n",
     "mesh: line 3: vertex index 0 out of range (1..2 defined so far)"),
    ("v 0 0 0\nf 1 2 3\nv 1 0 0\nv 0 1 0\n", "mesh: line 2: vertex index 2 out of range"),
    ("v 0 0 0\nv 1 0 0\nf -3 1\n", "mesh: line 3: vertex index -3 out of range"),
    ("v 0 0\n", "mesh: line 1: a vertex needs 3 coordinates"),
    ("v 0 0 0\nv 1 0 0\nf 1\n", "mesh: line 3: 'f' needs at least 2 vertices"),
    ("v 0 0 0\nv a 0 0\nl 1 2\n", "mesh: bad vertex coordinate"),
    ("v 0 0 0\nv 0 1 0\n", "mesh: no triangles and no lines in the file (cell types found: none)"),
])
def test_obj_reader_errors(tmp_path, text, message):
    path = tmp_path / "bad.obj"
    path.write_text(text)
    with pytest.raises(InputError) as info:
        load(path)
    assert str(info.value).startswith(message), str(info.value)


def test_read_errors_are_one_line_and_name_the_field(tmp_path):
    with pytest.raises(InputError, match=r"^cloth\.mesh: file not found: .*nowhere\.obj$"):
        load(tmp_path / "nowhere.obj", field="cloth.mesh")
    unknown = tmp_path / "cloth.xyz"
    unknown.write_text("1 2 3\n")
    with pytest.raises(InputError) as info:
        load(unknown)
    text = str(info.value)
    assert text.startswith("mesh: unknown mesh format '.xyz' of ") and "\n" not in text
    for ext in (".obj", ".ply", ".stl", ".msh", ".vtu"):
        assert ext in text.split("supported formats:")[1].split()
    broken = tmp_path / "broken.ply"
    broken.write_bytes(b"ply\nformat nonsense\n\x00\x01")
    with pytest.raises(InputError, match=r"^mesh: cannot read .*broken\.ply \(.*\); supported"):
        load(broken)
    points = meshio.Mesh(np.eye(3), [("vertex", [[0], [1], [2]])])
    only_points = tmp_path / "points.vtu"
    meshio.write(only_points, points)
    with pytest.raises(InputError, match=r"^mesh: no triangles and no lines .*: vertex\)$"):
        load(only_points)


def test_load_runs_the_checks(tmp_path):
    path = tmp_path / "fan.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\n"
                    "f 1 2 3\nf 2 1 4\nf 1 2 5\n")
    with pytest.raises(InputError, match=r"^cloth: 1 non-manifold edges .*: \(0, 1\)$"):
        load(path, field="cloth")
    assert load(path, check=False).triangle_count == 3


def jacobson(name):
    path = JACOBSON / f"{name}.obj"
    if not path.exists():
        pytest.skip(f"assignment data not found at {JACOBSON}")
    return path


@pytest.mark.parametrize("name, vertices, triangles, strands", [
    ("single-spring-horizontal", 2, 0, 1),
    ("horizontal-chain", 10, 0, 9),
    ("net", 61, 0, 156),
    ("flag", 3200, 2 * 3081, 0),
])
def test_jacobson_files(name, vertices, triangles, strands):
    mesh = load(jacobson(name))
    assert (mesh.vertex_count, mesh.triangle_count, len(mesh.strands)) == \
        (vertices, triangles, strands)


def test_jacobson_chain_geometry():
    mesh = load(jacobson("horizontal-chain"))
    assert mesh.strands.tolist() == [[i, i + 1] for i in range(9)]
    assert np.allclose(mesh.vertices[:, 0], np.round(np.arange(10) / 9, 6), atol=0)


def test_jacobson_skirt_loads_fast():
    path = jacobson("skirt")  # 1.2 MB, 9840 vertices, 9600 quads
    load(path)  # warm up imports
    start = time.perf_counter()
    mesh = load(path)
    seconds = time.perf_counter() - start
    assert (mesh.vertex_count, mesh.triangle_count) == (9840, 19200)
    assert seconds < 1.0  # measured ≈ 0.07 s including the checks (meshio alone: 0.1 s)


# --------------------------------------------------------------------------- writing meshes


def test_write_mesh_obj_round_trip_is_exact(tmp_path):
    base = grid(4, 3, size=(1 / 3, np.e), center=(0.1, 0.2, 0.3))
    mesh = Mesh(np.vstack([base.vertices, [[7 / 3, 1e-300, -0.0]]]), base.triangles,
                [[11, 12]])
    io.write_mesh(tmp_path / "m.obj", mesh)
    back = load(tmp_path / "m.obj", check=False)
    assert np.array_equal(back.vertices, mesh.vertices)
    assert np.array_equal(back.triangles, mesh.triangles)
    assert np.array_equal(back.strands, mesh.strands)


def test_write_mesh_vtu_with_positions_and_point_data(tmp_path):
    mesh = grid(3, 3)
    x = mesh.vertices + [0, 1 / 3, 0]
    io.write_mesh(tmp_path / "m.vtu", mesh, positions=x, point_data={"mass": np.arange(9.0)})
    back = meshio.read(tmp_path / "m.vtu")
    assert np.array_equal(back.points, x)
    assert np.array_equal(back.point_data["mass"], np.arange(9.0))
    assert np.array_equal(back.cells_dict["triangle"], mesh.triangles)
    with pytest.raises(InputError, match=r"^positions: expected shape \(9, 3\)"):
        io.write_mesh(tmp_path / "m.vtu", mesh, positions=x[:4])


# --------------------------------------------------------------------------- frames


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
    real_write = meshio.write

    def write_half_then_interrupt(path, *args, **kwargs):
        Path(path).write_text("<VTKFile")  # a truncated file under the temporary name
        raise KeyboardInterrupt

    monkeypatch.setattr(meshio, "write", write_half_then_interrupt)
    with pytest.raises(KeyboardInterrupt):
        writer.write(2, 0.2, *frame_data(2, 9))
    monkeypatch.setattr(meshio, "write", real_write)
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


# --------------------------------------------------------------------------- matrices


def test_matrix_and_vector_round_trip_exact(tmp_path):
    rng = np.random.default_rng(3)
    A = scipy.sparse.random(30, 20, density=0.2, random_state=rng, format="csr")
    A.data = A.data / 3 + np.pi * 1e-300
    io.write_matrix(tmp_path / "A.mtx", A)
    B = io.read_matrix(tmp_path / "A.mtx")
    assert scipy.sparse.issparse(B) and B.shape == (30, 20)
    assert (B != A).nnz == 0
    assert np.array_equal(B.toarray(), A.toarray())
    D = rng.standard_normal((4, 5)) / 7
    io.write_matrix(tmp_path / "D.mtx", D)
    assert np.array_equal(io.read_matrix(tmp_path / "D.mtx"), D)
    v = rng.standard_normal(12) * 1e10 / 3
    io.write_vector(tmp_path / "v.txt", v)
    assert np.array_equal(io.read_vector(tmp_path / "v.txt"), v)
    assert len((tmp_path / "v.txt").read_text().splitlines()) == 12


def test_import_clothsim_does_not_import_meshio():
    code = "import sys, clothsim, clothsim.mesh, clothsim.io; print('meshio' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, env={**os.environ, "PYTHONPATH": str(REPO)})
    assert out.stdout.strip() == "False"
