"""Wavefront OBJ: clothsim's own reader and writer (clothsim.io.obj)."""


import numpy as np
import pytest

from clothsim import io, load
from clothsim.errors import InputError
from clothsim.mesh import Mesh, grid


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


def test_write_mesh_obj_round_trip_is_exact(tmp_path):
    base = grid(4, 3, size=(1 / 3, np.e), center=(0.1, 0.2, 0.3))
    mesh = Mesh(np.vstack([base.vertices, [[7 / 3, 1e-300, -0.0]]]), base.triangles,
                [[11, 12]])
    io.write_mesh(tmp_path / "m.obj", mesh)
    back = load(tmp_path / "m.obj", check=False)
    assert np.array_equal(back.vertices, mesh.vertices)
    assert np.array_equal(back.triangles, mesh.triangles)
    assert np.array_equal(back.strands, mesh.strands)


@pytest.mark.parametrize("index", ["99999999999999999999", "-9223372036854775809"])
def test_obj_index_beyond_int64_is_one_line_naming_the_line(tmp_path, index):
    path = tmp_path / "huge.obj"
    path.write_text(f"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 {index}\n")
    with pytest.raises(InputError) as info:
        load(path, field="cloth.mesh")
    assert str(info.value) == (f"cloth.mesh: line 5: vertex index {index} out of range "
                               "(beyond 64-bit integers)")
