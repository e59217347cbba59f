"""Mesh checks: clothsim.mesh_checks.check_mesh."""

import numpy as np
import pytest

from clothsim.errors import InputError, MeshWarning
from clothsim.mesh import Mesh, grid
from clothsim.mesh_checks import check_mesh

SQUARE = [(0, 0), (1, 0), (1, 1), (0, 1)]
L_SHAPE = [(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)]  # area 3, notch (1,2)×(1,2)

# --------------------------------------------------------------------------- checks


def test_check_grid_is_clean_and_counts_boundary():
    report = check_mesh(grid(5, 4))
    assert report.clean
    assert report.boundary_edge_count == 2 * (4 + 3)
    assert (report.vertex_count, report.triangle_count, report.component_count) == (20, 24, 1)


def test_check_non_manifold_edge():
    x = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1]], float)
    mesh = Mesh(x, [[0, 1, 2], [1, 0, 3], [0, 1, 4]])  # edge (0, 1) has three triangles
    with pytest.raises(InputError) as info:
        check_mesh(mesh, field="cloth.mesh")
    assert str(info.value) == ("cloth.mesh: 1 non-manifold edges (shared by more than two "
                               "triangles): (0, 1)")


def test_check_zero_area_triangles():
    x = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [2, 0, 0]], float)
    mesh = Mesh(x, [[0, 1, 2], [0, 1, 3], [2, 2, 1]])  # collinear, repeated vertex
    with pytest.raises(InputError, match=r"^mesh: 2 zero-area triangles, indices 1, 2$"):
        check_mesh(mesh)


def test_check_self_loop_strand():
    mesh = Mesh(np.eye(3), strands=[[0, 1], [2, 2]])
    with pytest.raises(InputError, match=r"^mesh: 1 strands join a vertex to itself, indices 1$"):
        check_mesh(mesh)


def test_check_unreferenced_vertices():
    x = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [5, 5, 5], [6, 5, 5]], float)
    with pytest.warns(MeshWarning, match=r"^mesh: 2 unreferenced vertices .*: 3, 4$"):
        report = check_mesh(Mesh(x, [[0, 1, 2]]))
    assert report.unreferenced_vertices.tolist() == [3, 4]
    assert report.component_count == 1  # unreferenced vertices are not pieces of cloth


def test_check_near_duplicates_and_components():
    x = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0],
                  [1 + 1e-12, 0, 0], [1, 1, 0], [0, 1, 0]], float)  # an unwelded seam
    mesh = Mesh(x, [[0, 1, 2], [3, 4, 5]])
    with pytest.warns(MeshWarning) as record:
        report = check_mesh(mesh)
    messages = sorted(str(w.message) for w in record)
    assert messages[0] == "mesh: 2 connected components (expected one piece of cloth)"
    assert messages[1].startswith("mesh: 2 near-duplicate vertex pairs")
    assert messages[1].endswith(": (1, 3), (2, 5)")
    assert report.duplicate_vertex_pairs.tolist() == [[1, 3], [2, 5]]
    # welding the seam removes both warnings
    welded = Mesh(x[[0, 1, 2, 4]], [[0, 1, 2], [1, 3, 2]])
    assert check_mesh(welded).clean


def test_check_strands_count_as_connectivity():
    x = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [3, 0, 0], [4, 0, 0], [3, 1, 0]], float)
    tris = [[0, 1, 2], [3, 4, 5]]
    assert check_mesh(Mesh(x, tris, [[1, 3]])).component_count == 1
    with pytest.warns(MeshWarning, match="2 connected components"):
        check_mesh(Mesh(x, tris))
    report = check_mesh(Mesh(x, tris), warn=False)
    assert report.component_count == 2 and not report.clean


def test_check_lists_at_most_five_items():
    n = 8
    x = np.vstack([np.eye(3), np.arange(n)[:, None] * [0, 0, 1] + [5, 5, 5]])
    with pytest.warns(MeshWarning, match=r": 3, 4, 5, 6, 7, … \(8 in all\)$"):
        check_mesh(Mesh(x, [[0, 1, 2]]))
