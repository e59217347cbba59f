"""Meshes: cell blocks → Mesh (clothsim.mesh)."""

import numpy as np
import pytest

from clothsim.errors import InputError, MeshWarning
from clothsim.mesh import Mesh, fan_triangles, from_cells

SQUARE = [(0, 0), (1, 0), (1, 1), (0, 1)]
L_SHAPE = [(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)]  # area 3, notch (1,2)×(1,2)

def shoelace(P):
    P = np.asarray(P, float)
    return 0.5 * np.sum(P[:, 0] * np.roll(P[:, 1], -1) - np.roll(P[:, 0], -1) * P[:, 1])


# --------------------------------------------------------------------------- cells → Mesh


def test_fan_triangles_covers_a_convex_polygon():
    angle = np.linspace(0, 2 * np.pi, 6)[:-1]
    x = np.column_stack([np.cos(angle), np.sin(angle), np.zeros(5)])
    tris = fan_triangles(np.array([[0, 1, 2, 3, 4]]))
    assert tris.tolist() == [[0, 1, 2], [0, 2, 3], [0, 3, 4]]
    mesh = Mesh(x, tris)
    assert abs(mesh.triangle_areas().sum() - shoelace(x[:, :2])) < 1e-15


def test_from_cells_types():
    x = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [2, 0], [3, 0]], float)  # 2-D → z = 0
    cells = [("vertex", np.array([[0]])), ("quad", np.array([[0, 1, 2, 3]])),
             ("line", np.array([[1, 4], [4, 5], [0, 1], [5, 4]])),  # (0,1) is a triangle edge
             ("polygon", np.array([[4, 5]]))]  # 2-vertex polygon: a strand (repeats 4-5)
    mesh = from_cells(x, cells)
    assert mesh.vertices.shape == (6, 3) and np.all(mesh.vertices[:, 2] == 0)
    assert mesh.triangles.tolist() == [[0, 1, 2], [0, 2, 3]]
    assert mesh.strands.tolist() == [[1, 4], [4, 5]]


def test_from_cells_volume_cells_warn_or_fail():
    x = np.eye(4, 3)
    with pytest.warns(MeshWarning, match="ignored cells .*: 1 tetra"):
        mesh = from_cells(x, [("triangle", [[0, 1, 2]]), ("tetra", [[0, 1, 2, 3]])])
    assert mesh.triangle_count == 1
    with pytest.raises(InputError, match=r"^mesh: no triangles and no lines .*tetra"):
        from_cells(x, [("tetra", [[0, 1, 2, 3]]), ("vertex", [[0]])])
