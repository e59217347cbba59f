"""Mixed Voronoi areas of a triangle mesh's vertices (Meyer et al. 2003), as libigl lumps mass.

The assignment's ``main.cpp`` gives each vertex the mass of libigl's lumped mass matrix
(``igl::massmatrix``, ``MASSMATRIX_TYPE_VORONOI``, the default for triangles) when its JSON
has no ``m``: the vertex's mixed Voronoi area at unit density (1 kg/m²). Each triangle
with corners 0, 1, 2, area A, side lengths l_i (l_i opposite corner i) and angles θ_i
gives corner i

- when no angle is obtuse, the part of the triangle nearer to corner i than to the others
  (the Voronoi region, bounded at the circumcentre):
  A_0 = (l_2² cot θ_2 + l_1² cot θ_1) / 8 (Meyer et al. 2003, Eq. 7), and so on;
- when an angle is obtuse (the circumcentre is outside), A/2 to the obtuse corner and A/4
  to each other corner (Meyer et al. 2003, Fig. 4, "mixed area").

A right angle counts as not obtuse (libigl tests cos θ < 0). The areas of every triangle sum
to A, so the masses sum to the mesh's area. Triangles of zero area give nothing.

- :func:`voronoi_areas`: the areas, vectorized over triangles;
- :func:`voronoi_areas_reference`: the same one triangle at a time through the
  circumcentre's barycentric coordinates (libigl's route), for teaching and tests.

References
----------
M. Meyer, M. Desbrun, P. Schröder, A. H. Barr, "Discrete Differential-Geometry Operators
for Triangulated 2-Manifolds", Visualization and Mathematics III, 2003.
"""

from __future__ import annotations

import numpy as np


def voronoi_areas(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Mixed Voronoi area of every vertex (libigl's Voronoi mass at 1 kg/m²).

    Parameters
    ----------
    vertices : ndarray, shape (n, 3)
        Positions [m].
    triangles : ndarray, shape (t, 3), int
        Corner indices.

    Returns
    -------
    ndarray, shape (n,)
        Area [m²] of each vertex (0 for a vertex on no triangle).
    """
    x = np.asarray(vertices, dtype=np.float64)
    tri = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    n = len(x)
    if len(tri) == 0:
        return np.zeros(n)
    p = x[tri]                                   # (t, 3 corners, 3)
    # the side opposite corner i runs from corner i+1 to corner i+2
    side = np.roll(p, -2, axis=1) - np.roll(p, -1, axis=1)
    l2 = np.einsum("tij,tij->ti", side, side)    # squared lengths, (t, 3)
    # corner i's angle: its two sides are −side[i+2] and side[i+1]
    dots = -np.einsum("tij,tij->ti", np.roll(side, -2, axis=1), np.roll(side, -1, axis=1))
    area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    ok = area > 0
    cot = np.zeros_like(dots)
    cot[ok] = dots[ok] / (2.0 * area[ok, None])
    # non-obtuse: A_i = (l_{i+2}² cot θ_{i+2} + l_{i+1}² cot θ_{i+1}) / 8
    weighted = l2 * cot
    part = (np.roll(weighted, -2, axis=1) + np.roll(weighted, -1, axis=1)) / 8.0
    obtuse = dots < 0
    any_obtuse = obtuse.any(axis=1)
    part[any_obtuse] = np.where(obtuse[any_obtuse], 0.5, 0.25) * area[any_obtuse, None]
    part[~ok] = 0.0
    return np.bincount(tri.reshape(-1), part.reshape(-1), minlength=n)


def voronoi_areas_reference(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """:func:`voronoi_areas`, one triangle at a time, the way libigl computes it.

    For each triangle: the cosines of its angles, the circumcentre's barycentric
    coordinates (proportional to l_i cos θ_i), the sub-triangle areas ``partial_i`` from
    the circumcentre to each side, and corner i's quadrilateral as half of the two
    sub-triangles beside it; an obtuse triangle instead gives A/2 and A/4.

    Parameters
    ----------
    vertices : ndarray, shape (n, 3)
        Positions [m].
    triangles : ndarray, shape (t, 3), int
        Corner indices.

    Returns
    -------
    ndarray, shape (n,)
        Area [m²] of each vertex.
    """
    x = np.asarray(vertices, dtype=np.float64)
    out = np.zeros(len(x))
    for tri in np.asarray(triangles, dtype=np.int64).reshape(-1, 3):
        p = [x[i] for i in tri]
        length = [float(np.linalg.norm(p[(i + 2) % 3] - p[(i + 1) % 3])) for i in range(3)]
        area = 0.5 * float(np.linalg.norm(np.cross(p[1] - p[0], p[2] - p[0])))
        if area == 0.0:
            continue
        cos = []
        for i in range(3):
            a, b, c = length[i], length[(i + 1) % 3], length[(i + 2) % 3]
            cos.append((b * b + c * c - a * a) / (2.0 * b * c))
        if min(cos) < 0:
            share = [0.5 * area if c < 0 else 0.25 * area for c in cos]
        else:
            bary = [length[i] * cos[i] for i in range(3)]
            partial = [area * b / sum(bary) for b in bary]   # circumcentre to side i
            share = [0.5 * (partial[(i + 1) % 3] + partial[(i + 2) % 3]) for i in range(3)]
        for i in range(3):
            out[tri[i]] += share[i]
    return out


__all__ = ["voronoi_areas", "voronoi_areas_reference"]
