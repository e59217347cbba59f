"""Mesh builders (polygon, cells → Mesh) and mesh checks."""

import numpy as np
import pytest

from clothsim.errors import InputError, MeshWarning
from clothsim.mesh import Mesh, fan_triangles, from_cells, grid, polygon
from clothsim.validate_mesh import check_mesh

SQUARE = [(0, 0), (1, 0), (1, 1), (0, 1)]
L_SHAPE = [(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)]  # area 3, notch (1,2)×(1,2)


def shoelace(P):
    P = np.asarray(P, float)
    return 0.5 * np.sum(P[:, 0] * np.roll(P[:, 1], -1) - np.roll(P[:, 0], -1) * P[:, 1])


def planar(mesh):
    """(u, v) of an "xz" mesh centred at the origin: u = x, v = −z."""
    return np.column_stack([mesh.vertices[:, 0], -mesh.vertices[:, 2]])


def edge_lengths(mesh):
    e = mesh.edges
    return np.linalg.norm(mesh.vertices[e[:, 0]] - mesh.vertices[e[:, 1]], axis=1)


def normals(mesh):
    x, t = mesh.vertices, mesh.triangles
    return np.cross(x[t[:, 1]] - x[t[:, 0]], x[t[:, 2]] - x[t[:, 0]])


# --------------------------------------------------------------------------- polygon


def test_polygon_square_area_edges_and_orientation():
    spacing = 0.1
    mesh = polygon(SQUARE, spacing=spacing)
    assert abs(mesh.triangle_areas().sum() - 1.0) < 1e-12
    lengths = edge_lengths(mesh)
    # measured: 0.50 … 1.51 × spacing
    assert lengths.max() < 2 * spacing and lengths.min() > 0.3 * spacing
    assert np.all(normals(mesh)[:, 1] > 0)  # "xz": counter-clockwise in (u, v) → normal +y
    assert np.all(mesh.vertices[:, 1] == 0)
    report = check_mesh(mesh)  # no warnings (they are errors in the test suite)
    assert report.clean and report.component_count == 1
    # the outline's corners are vertices
    uv = planar(mesh)
    for corner in SQUARE:
        assert np.min(np.linalg.norm(uv - corner, axis=1)) == 0


def test_polygon_non_convex_has_no_triangle_outside():
    spacing = 0.13
    mesh = polygon(L_SHAPE, spacing=spacing)
    assert abs(mesh.triangle_areas().sum() - 3.0) < 1e-12
    uv = planar(mesh)
    centroid = uv[mesh.triangles].mean(axis=1)
    in_notch = (centroid[:, 0] > 1) & (centroid[:, 1] > 1)
    assert not in_notch.any()
    assert np.all((uv >= -1e-15) & (uv <= 2 + 1e-15))
    # no vertex inside the notch, and no triangle edge cuts across it
    assert not np.any((uv[:, 0] > 1 + 1e-12) & (uv[:, 1] > 1 + 1e-12))
    assert edge_lengths(mesh).max() < 2 * spacing
    check_mesh(mesh)


def test_polygon_sharp_star_clockwise_and_placement():
    angle = np.linspace(0, 2 * np.pi, 11)[:-1]
    radius = np.where(np.arange(10) % 2 == 0, 1.0, 0.3)
    star = np.column_stack([radius * np.cos(angle), radius * np.sin(angle)])[::-1]  # clockwise
    assert shoelace(star) < 0
    mesh = polygon(star, spacing=0.05, center=(1.0, 2.0, 3.0), plane="xy")
    assert abs(mesh.triangle_areas().sum() - abs(shoelace(star))) < 1e-12
    assert np.all(normals(mesh)[:, 2] > 0)  # "xy": normal +z whatever the outline's order
    assert np.all(mesh.vertices[:, 2] == 3.0)
    assert np.allclose(mesh.vertices[:, :2].max(axis=0), [2.0, 2 + np.sin(angle[2])])
    check_mesh(mesh)


def test_polygon_closed_outline_repeating_first_corner_is_accepted():
    a = polygon(SQUARE + [SQUARE[0]], spacing=0.25)
    b = polygon(SQUARE, spacing=0.25)
    assert np.array_equal(a.vertices, b.vertices) and np.array_equal(a.triangles, b.triangles)


@pytest.mark.parametrize("outline, spacing, message", [
    ([(0, 0), (1, 0)], 0.1, "outline: needs at least 3"),
    ([(0, 0), (1, np.nan), (0, 1)], 0.1, "outline[1, 1]: must be a finite number"),
    ([(0, 0), (1, 0), (2, 0)], 0.1, "outline: encloses zero area"),
    ([(0, 0), (1, 1), (1, 0), (0, 1)], 0.1, "outline: edges 0 and 2 intersect"),
    ([(0, 0), (1, 0), (1, 0), (0, 1)], 0.1, "outline[1]: corner repeated"),
    (SQUARE, 0.0, "spacing: must be positive"),
    (SQUARE, 1e-6, "spacing: 1e-06 m would give more than"),
    ([(0, 0, 0), (1, 0, 0), (0, 1, 0)], 0.1, "outline: expected shape (k, 2)"),
])
def test_polygon_rejects_bad_input(outline, spacing, message):
    with pytest.raises(InputError) as info:
        polygon(outline, spacing=spacing)
    assert str(info.value).startswith(message)
    assert "\n" not in str(info.value)


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
