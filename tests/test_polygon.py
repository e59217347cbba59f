"""Triangulating a closed outline: clothsim.polygon."""

import numpy as np
import pytest

from clothsim.errors import InputError
from clothsim.mesh_checks import check_mesh
from clothsim.polygon import polygon

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
