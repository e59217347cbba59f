"""Mixed Voronoi areas (Meyer et al. 2003), libigl's lumped mass: fast path vs reference."""

import numpy as np
import pytest

from clothsim.mesh import grid
from clothsim.voronoi import voronoi_areas, voronoi_areas_reference


def areas(x, t):
    return 0.5 * np.linalg.norm(np.cross(x[t[:, 1]] - x[t[:, 0]], x[t[:, 2]] - x[t[:, 0]]),
                                axis=1)


@pytest.mark.parametrize("seed", range(5))
def test_fast_path_matches_the_reference_and_sums_to_the_area(seed):
    rng = np.random.default_rng(seed)
    x = rng.normal(size=(30, 3))
    t = np.array([rng.choice(30, 3, replace=False) for _ in range(60)])
    a = voronoi_areas(x, t)
    np.testing.assert_allclose(a, voronoi_areas_reference(x, t), rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(a.sum(), areas(x, t).sum(), rtol=1e-12)
    assert np.all(a >= 0)


def test_equilateral_right_and_obtuse_triangles():
    s = np.sqrt(3.0) / 2
    eq = voronoi_areas(np.array([[0, 0, 0], [1, 0, 0], [0.5, s, 0]], float), [[0, 1, 2]])
    np.testing.assert_allclose(eq, np.full(3, s / 2 / 3), rtol=1e-14)
    # right angle at 0 (not obtuse): the circumcentre is the hypotenuse's midpoint
    # (1, 0.5); corner 0 gets the rectangle [0, 1] × [0, 0.5], corners 1 and 2 a triangle
    # of 0.25 each
    x = np.array([[0, 0, 0], [2, 0, 0], [0, 1, 0]], float)
    np.testing.assert_allclose(voronoi_areas(x, [[0, 1, 2]]), [0.5, 0.25, 0.25], rtol=1e-14)
    np.testing.assert_allclose(voronoi_areas_reference(x, [[0, 1, 2]]), [0.5, 0.25, 0.25],
                               rtol=1e-14)
    # acute but not equilateral: Meyer's cotangent formula by hand
    x = np.array([[0, 0, 0], [2, 0, 0], [0.8, 1.5, 0]], float)
    cot = [0.8 / 1.5, 1.2 / 1.5, None]
    cot[2] = (np.dot(x[0] - x[2], x[1] - x[2])
              / np.linalg.norm(np.cross(x[0] - x[2], x[1] - x[2])))
    l2 = [np.sum((x[2] - x[1]) ** 2), np.sum((x[2] - x[0]) ** 2), 4.0]
    want = [(l2[2] * cot[2] + l2[1] * cot[1]) / 8, (l2[0] * cot[0] + l2[2] * cot[2]) / 8,
            (l2[1] * cot[1] + l2[0] * cot[0]) / 8]
    np.testing.assert_allclose(voronoi_areas(x, [[0, 1, 2]]), want, rtol=1e-14)
    # obtuse at 2: half the area to it, a quarter to each other corner (libigl, Meyer)
    ob = voronoi_areas(np.array([[0, 0, 0], [4, 0, 0], [1, 0.5, 0]], float), [[0, 1, 2]])
    np.testing.assert_allclose(ob, [0.25, 0.25, 0.5], rtol=1e-14)


def test_a_uniform_grid_gets_its_cell_areas_and_lone_vertices_none():
    mesh = grid(5, 4, size=(2.0, 1.5))
    a = voronoi_areas(mesh.vertices, mesh.triangles)
    cell = 0.5 * 0.5
    corner = np.array([0, 4, 15, 19])
    np.testing.assert_allclose(a.reshape(4, 5)[1:-1, 1:-1], cell, rtol=1e-12)
    np.testing.assert_allclose(a[corner], cell / 4, rtol=1e-12)
    np.testing.assert_allclose(a.sum(), 3.0, rtol=1e-14)
    x = np.vstack([mesh.vertices, [[9.0, 9.0, 9.0]]])
    assert voronoi_areas(x, mesh.triangles)[-1] == 0.0
    assert voronoi_areas(x, np.zeros((0, 3), int)).tolist() == [0.0] * 21
    # a degenerate (zero-area) triangle adds nothing
    deg = voronoi_areas(np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0]], float), [[0, 1, 2]])
    assert deg.tolist() == [0.0, 0.0, 0.0]
    assert voronoi_areas_reference(np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0]], float),
                                   [[0, 1, 2]]).tolist() == [0.0, 0.0, 0.0]
