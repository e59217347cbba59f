"""benchmarks/cloth_depth.py: how far an obstacle lies in front of the cloth's triangles,
on constructed cases with known answers (a chord over a box edge, a triangle over a box
corner, a triangle inscribed in a sphere's circle)."""

import numpy as np
import pytest

from benchmarks.cloth_depth import box_depth, depth_through_cloth, sphere_depth
from clothsim.effects import Box, Plane, Sphere

ONE = np.array([[0, 1, 2]])


@pytest.mark.parametrize("a, b", [(0.3, 0.1), (0.05, 0.05), (0.01, 0.2)])
@pytest.mark.parametrize("winding", [[0, 1, 2], [0, 2, 1]])
def test_chord_over_a_box_edge(a, b, winding):
    """A triangle with two corners on the top face a from the edge and one on the side face
    b below it cuts the edge off: the edge stands ab / √(a² + b²) in front of it."""
    x = np.array([(-a, 0, -0.5), (-a, 0, 0.5), (0, -b, 0)])
    d = box_depth((-1, -1, -1), (0, 0, 1), x, np.array([winding]))
    assert d == pytest.approx(a * b / np.hypot(a, b), rel=1e-12)


@pytest.mark.parametrize("winding", [[0, 1, 2], [0, 2, 1]])
def test_flat_triangle_over_a_box_corner(winding):
    """The triangle through (−d,0,0), (0,−d,0), (0,0,−d) has the box's corner at the origin
    d/√3 in front of it (the corner projects onto its centroid)."""
    d = 0.2
    x = np.array([(-d, 0, 0), (0, -d, 0), (0, 0, -d)])
    assert box_depth((-1, -1, -1), (0, 0, 0), x, np.array([winding])) == pytest.approx(
        d / np.sqrt(3), rel=1e-12)
    # moved out along the diagonal by more than d/√3 it clears the corner
    assert box_depth((-1, -1, -1), (0, 0, 0), x + 0.3, np.array([winding])) == 0.0


def test_cloth_lying_on_a_box_or_beside_it_is_not_pierced():
    """A sheet on the top face (also reaching past its edges, flat) and a sheet hanging a
    little off a side face: depth 0; the same sheet dropped 1 mm into the top: 1 mm."""
    u, v = np.meshgrid(np.linspace(-0.8, 0.8, 9), np.linspace(-0.8, 0.8, 9))
    top = np.column_stack([u.ravel(), np.full(81, 0.5), v.ravel()])
    tri = np.array([[i * 9 + j, i * 9 + j + 1, (i + 1) * 9 + j] for i in range(8)
                    for j in range(8)] + [[i * 9 + j + 1, (i + 1) * 9 + j + 1, (i + 1) * 9 + j]
                                          for i in range(8) for j in range(8)])
    lo, hi = (-0.5, 0, -0.5), (0.5, 0.5, 0.5)
    assert box_depth(lo, hi, top, tri) == 0.0
    side = np.column_stack([np.full(81, 0.51), u.ravel() * 0.3 + 0.25, v.ravel()])
    assert box_depth(lo, hi, side, tri) == 0.0
    sunk = top - (0, 1e-3, 0)
    assert box_depth(lo, hi, sunk, tri) == pytest.approx(1e-3, rel=1e-9)


@pytest.mark.parametrize("R, r", [(1.0, 0.2), (0.3, 0.02), (0.3, 0.29)])
def test_triangle_inscribed_in_a_sphere_circle(R, r):
    """Corners on the sphere on a circle of radius r: the sphere passes R − √(R² − r²)
    through the triangle (the sagitta); the corners moved out to R + that: it clears it."""
    angle = np.array([0.0, 2.1, 4.0])
    h = np.sqrt(R * R - r * r)
    c = np.array([1.0, 2.0, 3.0])
    x = np.column_stack([r * np.cos(angle), np.full(3, h), r * np.sin(angle)]) + c
    assert sphere_depth(c, R, x, ONE) == pytest.approx(R - h, rel=1e-9)
    assert sphere_depth(c, R, x, ONE[:, [0, 2, 1]]) == pytest.approx(R - h, rel=1e-9)
    assert sphere_depth(c, R, c + (x - c) * (R / h), ONE) == pytest.approx(0.0, abs=1e-12)


def test_sphere_beside_a_triangle_reaches_through_its_edge():
    """The centre projects outside the triangle: the depth is R minus the distance to the
    nearest edge."""
    x = np.array([(0.1, 0.0, -1.0), (0.1, 0.0, 1.0), (2.0, 0.0, 0.0)])
    assert sphere_depth((0, 0, 0), 0.3, x, ONE) == pytest.approx(0.2, rel=1e-12)


def test_depth_of_the_effects_uses_the_declared_solid():
    """depth_through_cloth measures against min/max, centre/radius, point/normal, not the
    surface a contact thickness moves the cloth to."""
    x = np.array([(-0.3, 0.5, -0.5), (-0.3, 0.5, 0.5), (0.0, 0.2, 0.0)]) + (0.25, 0, 0)
    box = Box((-0.25, 0, -0.25), (0.25, 0.5, 0.25), thickness=0.1)
    assert depth_through_cloth(box, x, ONE) == pytest.approx(0.3 * 0.3 / np.hypot(0.3, 0.3))
    plane = Plane((0, 0.3, 0), (0, 1, 0), thickness=0.05)
    assert depth_through_cloth(plane, x, ONE) == pytest.approx(0.1)
    sphere = Sphere((0, 0, 0), 0.5, thickness=1.0)
    assert depth_through_cloth(sphere, np.array([(0, 0.4, 0), (1, 0.4, 0), (0, 0.4, 1)]),
                               ONE) == pytest.approx(0.1)


def test_a_wrinkle_standing_on_the_box_is_not_pierced():
    """A near-vertical triangle 1 cm above the top face has the box in its prism (along its
    tilted normal) but does not meet it: depth 0; pushed 1 cm into the top it does."""
    x = np.array([(-0.04, 0.01, -0.26), (-0.02, 0.011, -0.258), (-0.02, 0.03, -0.267)])
    lo, hi = (-1.0, -1.0, -1.0), (0.0, 0.0, 1.0)
    assert box_depth(lo, hi, x, ONE) == 0.0
    assert box_depth(lo, hi, x - (0, 0.02, 0), ONE) > 0.0
