"""Triangulating a closed 2-D outline at a target spacing (:func:`polygon`)."""

from __future__ import annotations

import numpy as np

from .errors import InputError, check_finite
from .mesh import Mesh, place_in_plane


def polygon(outline, *, spacing: float, center=(0.0, 0.0, 0.0), plane: str = "xz") -> Mesh:
    """Triangulate the inside of a closed 2-D outline at a target edge length.

    The boundary is resampled so no boundary edge is longer than ``spacing`` (the outline's
    corners are kept exactly); the inside is filled with a triangular lattice of pitch
    ``spacing``, dropping lattice points closer than ``spacing / 2`` to the boundary. The
    points are triangulated with :class:`scipy.spatial.Delaunay` and triangles whose
    centroid lies outside the outline are discarded, so non-convex outlines work. Boundary
    edges that some point encroaches upon (lies inside their diametral circle, which would
    let Delaunay cut across the boundary) are split, or the encroaching lattice point is
    removed, until every boundary edge is an edge of the triangulation.

    Parameters
    ----------
    outline : array_like, shape (k, 2)
        Corners of a simple (non-self-intersecting) polygon in planar coordinates (u, v)
        [m], either orientation; a repeated first corner at the end is ignored.
    spacing : float
        Target edge length [m], > 0. Edges come out between about 0.5 and 1.6 × spacing
        (shorter where the outline has features or corners smaller than that).
    center : (3,) array_like
        Where the planar origin (u, v) = (0, 0) goes [m].
    plane : {"xz", "xy"}
        Same convention as :func:`clothsim.mesh.grid`: ``"xz"`` maps (u, v) to (u, 0, −v)
        (normal +y), ``"xy"`` to (u, v, 0) (normal +z).

    Returns
    -------
    Mesh
        Triangles counter-clockwise in (u, v), so their normal is the plane's normal; the
        sum of triangle areas equals the outline's area (to rounding).

    Raises
    ------
    InputError
        Fewer than 3 distinct finite corners, zero area, crossing edges, or a bad spacing.

    Examples
    --------
    >>> import numpy as np
    >>> square = [(0, 0), (1, 0), (1, 1), (0, 1)]
    >>> mesh = polygon(square, spacing=0.25)
    >>> bool(np.isclose(mesh.triangle_areas().sum(), 1.0, rtol=0, atol=1e-12))
    True
    """
    from scipy.spatial import Delaunay  # scipy.spatial loads only when a polygon is built

    P = _check_outline(outline)
    h = float(check_finite("spacing", spacing))
    if h <= 0:
        raise InputError(f"spacing: must be positive, got {h!r}")
    size = np.ptp(P, axis=0)
    if (size / h).prod() > 4e6:
        raise InputError(f"spacing: {h!r} m would give more than ~4 million points for an "
                         f"outline of size {size[0]:g} × {size[1]:g} m")
    boundary = _resample_boundary(P, h)
    interior = _lattice(P, h)
    inside = _inside_polygon(interior, P) & (_distance_to_outline(interior, P) >= 0.5 * h)
    interior = interior[inside]
    boundary, interior = _protect_boundary(boundary, interior)
    points = np.concatenate([boundary, interior])
    tri = Delaunay(points).simplices.astype(np.int64)
    a, b, c = points[tri[:, 0]], points[tri[:, 1]], points[tri[:, 2]]
    ab, ac = b - a, c - a
    twice_area = ab[:, 0] * ac[:, 1] - ab[:, 1] * ac[:, 0]  # > 0: counter-clockwise
    keep = _inside_polygon((a + b + c) / 3.0, P) & (np.abs(twice_area) > 1e-12 * h * h)
    tri, twice_area = tri[keep], twice_area[keep]
    tri[twice_area < 0] = tri[twice_area < 0][:, [0, 2, 1]]
    _check_boundary_edges(tri, len(boundary))
    # drop points no kept triangle uses (Qhull may skip coplanar points) and renumber
    used = np.zeros(len(points), bool)
    used[tri.ravel()] = True
    new_index = np.cumsum(used) - 1
    uv = points[used]
    vertices = place_in_plane(uv[:, 0], uv[:, 1], center, plane)
    return Mesh(vertices, new_index[tri])


def _check_outline(outline) -> np.ndarray:
    P = check_finite("outline", outline)
    if P.ndim != 2 or P.shape[1] != 2:
        raise InputError(f"outline: expected shape (k, 2), got {P.shape}")
    if len(P) > 1 and np.array_equal(P[0], P[-1]):
        P = P[:-1]
    seg = np.roll(P, -1, axis=0) - P
    repeated = np.flatnonzero(np.all(seg == 0, axis=1))
    if len(repeated):
        raise InputError(f"outline[{int(repeated[0])}]: corner repeated by the next corner")
    if len(P) < 3:
        raise InputError(f"outline: needs at least 3 distinct corners, got {len(P)}")
    _check_simple(P)
    area = 0.5 * np.sum(P[:, 0] * np.roll(P[:, 1], -1) - np.roll(P[:, 0], -1) * P[:, 1])
    scale = np.ptp(P, axis=0).max()
    if abs(area) <= 1e-12 * scale * scale:
        raise InputError("outline: encloses zero area")
    return P if area > 0 else P[::-1].copy()


def _check_simple(P: np.ndarray) -> None:
    """Raise if two non-adjacent edges of the closed outline intersect (O(k²), vectorized)."""
    k = len(P)
    if k < 4 or k > 4000:
        return
    A, B = P, np.roll(P, -1, axis=0)
    i, j = np.triu_indices(k, 2)
    nonadjacent = ~((i == 0) & (j == k - 1))
    i, j = i[nonadjacent], j[nonadjacent]

    def orient(p, q, r):
        return np.sign((q[:, 0] - p[:, 0]) * (r[:, 1] - p[:, 1])
                       - (q[:, 1] - p[:, 1]) * (r[:, 0] - p[:, 0]))

    o1, o2 = orient(A[i], B[i], A[j]), orient(A[i], B[i], B[j])
    o3, o4 = orient(A[j], B[j], A[i]), orient(A[j], B[j], B[i])
    cross = (o1 * o2 <= 0) & (o3 * o4 <= 0)
    # collinear, disjoint segments satisfy the sign test too: require overlapping boxes
    lo_i, hi_i = np.minimum(A[i], B[i]), np.maximum(A[i], B[i])
    lo_j, hi_j = np.minimum(A[j], B[j]), np.maximum(A[j], B[j])
    cross &= np.all((lo_i <= hi_j) & (lo_j <= hi_i), axis=1)
    if cross.any():
        first = int(np.flatnonzero(cross)[0])
        raise InputError(f"outline: edges {int(i[first])} and {int(j[first])} intersect "
                         "(the outline must be a simple polygon)")


def _resample_boundary(P: np.ndarray, h: float) -> np.ndarray:
    """Points along the closed outline, corners included, no gap longer than h."""
    seg = np.roll(P, -1, axis=0) - P
    count = np.maximum(1, np.ceil(np.linalg.norm(seg, axis=1) / h * (1 - 1e-12))).astype(int)
    edge = np.repeat(np.arange(len(P)), count)
    t = (np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count)) / count[edge]
    return P[edge] + t[:, None] * seg[edge]


def _lattice(P: np.ndarray, h: float) -> np.ndarray:
    """Triangular lattice of pitch h covering the outline's bounding box."""
    lo, hi = P.min(axis=0), P.max(axis=0)
    dy = h * np.sqrt(3.0) / 2.0
    ny = int(np.floor((hi[1] - lo[1]) / dy)) + 1
    nx = int(np.floor((hi[0] - lo[0]) / h)) + 2
    y = lo[1] + dy * np.arange(ny)
    # centre the rows in the box so the outline gets a symmetric margin
    y += 0.5 * ((hi[1] - lo[1]) - (y[-1] - lo[1]))
    x = lo[0] + h * np.arange(nx) - 0.5 * h
    xx = x[None, :] + 0.5 * h * (np.arange(ny) % 2)[:, None]
    yy = np.broadcast_to(y[:, None], xx.shape)
    return np.column_stack([xx.ravel(), yy.ravel()])


def _inside_polygon(points: np.ndarray, P: np.ndarray) -> np.ndarray:
    """Even-odd point-in-polygon test, shape (p,) bool; a loop over the k outline edges."""
    x, y = points[:, 0], points[:, 1]
    inside = np.zeros(len(points), bool)
    for (x0, y0), (x1, y1) in zip(P, np.roll(P, -1, axis=0)):
        straddles = (y0 > y) != (y1 > y)
        with np.errstate(divide="ignore", invalid="ignore"):
            x_cross = x0 + (y - y0) * (x1 - x0) / (y1 - y0)
        inside ^= straddles & (x < x_cross)
    return inside


def _distance_to_outline(points: np.ndarray, P: np.ndarray) -> np.ndarray:
    """Distance [m] from each point to the closed outline, shape (p,)."""
    best = np.full(len(points), np.inf)
    for a, b in zip(P, np.roll(P, -1, axis=0)):
        ab = b - a
        t = np.clip((points - a) @ ab / (ab @ ab), 0.0, 1.0)
        best = np.minimum(best, np.linalg.norm(points - a - t[:, None] * ab, axis=1))
    return best


def _protect_boundary(boundary: np.ndarray, interior: np.ndarray, *, rounds: int = 30):
    """Make every boundary edge Delaunay: no point inside its diametral circle.

    Lattice points encroaching an edge are removed; an edge encroached by other boundary
    points (sharp corners) is split at its midpoint. Returns the new (boundary, interior).
    """
    from scipy.spatial import cKDTree

    for _ in range(rounds):
        k = len(boundary)
        nxt = np.roll(boundary, -1, axis=0)
        mid = 0.5 * (boundary + nxt)
        radius = 0.5 * np.linalg.norm(nxt - boundary, axis=1) * (1 + 1e-9)
        points = np.concatenate([boundary, interior])
        hits = cKDTree(points).query_ball_point(mid, radius, return_sorted=False)
        count = np.fromiter((len(x) for x in hits), np.int64, k)
        edge = np.repeat(np.arange(k), count)
        other = np.fromiter((p for x in hits for p in x), np.int64, int(count.sum()))
        own = (other == edge) | (other == (edge + 1) % k)
        edge, other = edge[~own], other[~own]
        if len(edge) == 0:
            return boundary, interior
        drop = np.unique(other[other >= k]) - k
        interior = np.delete(interior, drop, axis=0)
        split = np.unique(edge[other < k])
        if len(split):
            new = 0.5 * (boundary[split] + nxt[split])
            boundary = np.insert(boundary, split + 1, new, axis=0)
    return boundary, interior


def _check_boundary_edges(tri: np.ndarray, k: int) -> None:
    """Raise unless each boundary edge (i, i+1 mod k) is an edge of exactly one triangle."""
    e = np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1)
    n = int(tri.max()) + 1 if len(tri) else k
    key, count = np.unique(e[:, 0] * n + e[:, 1], return_counts=True)
    b = np.sort(np.column_stack([np.arange(k), (np.arange(k) + 1) % k]), axis=1)
    pos = np.searchsorted(key, b[:, 0] * n + b[:, 1])
    pos = np.minimum(pos, len(key) - 1)
    ok = (key[pos] == b[:, 0] * n + b[:, 1]) & (count[pos] == 1)
    if not ok.all():
        raise InputError(f"outline: could not triangulate conformingly ({int((~ok).sum())} "
                         "boundary edges missing); try a smaller spacing")
