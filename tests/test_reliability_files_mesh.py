"""The files shape runs the mesh checks of a mesh file: zero-area, repeated-vertex,
duplicate and non-manifold triangles are named by index; a duplicate face is refused in a
mesh file too (it would double its wind force)."""

import numpy as np
import pytest

from clothsim.errors import InputError
from clothsim.mesh import Mesh
from clothsim.mesh_checks import check_mesh
from clothsim.scene import SceneError, load_scene

X = "0 0 0\n1 0 0\n1 0 1\n0 0 1\n0 1 0\n"


def _scene(tmp_path, triangles, x=X):
    (tmp_path / "x.txt").write_text(x)
    (tmp_path / "t.txt").write_text(triangles)
    p = tmp_path / "s.toml"
    p.write_text('[scene]\nframes = 1\n[cloth]\nshape = "files"\nvertices = "x.txt"\n'
                 'triangles = "t.txt"\n[springs]\nstructural = 10.0\n')
    return p


@pytest.mark.parametrize("tris, words", [
    ("0 1 2\n0 0 3\n", "zero-area triangles, indices 1"),           # repeated vertex
    ("0 1 2\n0 1 1\n", "zero-area triangles, indices 1"),
    ("0 1 2\n2 1 0\n", "duplicate triangles .* indices 1"),        # same face, other order
    ("0 1 2\n0 1 3\n0 1 4\n", "non-manifold edges"),
])
def test_files_triangles_are_checked(tmp_path, tris, words):
    with pytest.raises(SceneError, match=f"cloth.triangles: .*{words}"):
        load_scene(_scene(tmp_path, tris)).build_model()


def test_collinear_triangle_is_zero_area(tmp_path):
    x = "0 0 0\n1 0 0\n2 0 0\n0 0 1\n"
    with pytest.raises(SceneError, match="zero-area"):
        load_scene(_scene(tmp_path, "0 1 3\n0 1 2\n", x=x)).build_model()


def test_good_files_mesh_still_builds(tmp_path):
    assert load_scene(_scene(tmp_path, "0 1 2\n0 2 3\n")).build_model().vertex_count == 5


def test_duplicate_face_refused_in_check_mesh():
    x = np.array([[0, 0, 0], [1, 0, 0], [1, 0, 1.0]])
    with pytest.raises(InputError, match="mesh: 1 duplicate triangles"):
        check_mesh(Mesh(x, np.array([[0, 1, 2], [1, 2, 0]])), warn=False)
