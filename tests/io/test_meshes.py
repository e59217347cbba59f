"""Mesh files: clothsim.load / clothsim.io.meshes (read, check, write)."""

import os
import subprocess
import sys
import time
from pathlib import Path

import meshio
import numpy as np
import pytest

from clothsim import io, load
from clothsim.errors import InputError
from clothsim.mesh import grid

from ..data_sets import assignment_dir

REPO = Path(__file__).resolve().parents[2]


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
    return assignment_dir() / f"{name}.obj"  # skips when the third-party files are absent


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


def test_import_clothsim_does_not_import_meshio():
    code = "import sys, clothsim, clothsim.mesh, clothsim.io; print('meshio' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, env={**os.environ, "PYTHONPATH": str(REPO)})
    assert out.stdout.strip() == "False"


def test_a_directory_as_mesh_path_is_named_as_such(tmp_path):
    with pytest.raises(InputError, match=r"^cloth\.mesh: is a directory, not a mesh file: "):
        load(tmp_path, field="cloth.mesh")


@pytest.mark.parametrize("content", [b"", b"solid empty\nendsolid empty\n",
                                     b"\0" * 80 + (0).to_bytes(4, "little")])
def test_an_empty_stl_has_no_triangles(tmp_path, content):
    path = tmp_path / "empty.stl"
    path.write_bytes(content)
    with pytest.raises(InputError) as info:
        load(path, field="cloth.mesh")
    text = str(info.value)
    assert text == f"cloth.mesh: {path} has no triangles (the file is empty)", text
