"""Cloth meshes: vertices, triangles and strands (line cells).

The first stage of the pipeline (mesh → springs → model → matrices → factor → solver).
A :class:`Mesh` is geometry and connectivity only; springs and masses are built from it.

Builders
--------
grid
    Rectangular nx × ny grid, each cell split into two triangles.
polygon
    A closed outline triangulated (scipy Delaunay) at a target spacing.
load
    Any mesh meshio reads (OBJ, PLY, STL, MSH, VTU …); see :mod:`clothsim.io`. Checked by
    :func:`clothsim.validate_mesh.check_mesh`.
from_cells
    Cell blocks as mesh files hold them (triangles, quads, polygons, lines) → Mesh.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from .errors import InputError, check_finite

PLANES = ("xz", "xy")

logger = logging.getLogger(__name__)


@dataclass(frozen=True, eq=False)
class Mesh:
    """A triangle mesh, optionally with strands (line cells, e.g. a chain or a net).

    Attributes
    ----------
    vertices : ndarray, shape (n, 3), float64
        Vertex positions [m].
    triangles : ndarray, shape (m, 3), int64
        Vertex indices of each triangle, counter-clockwise about the normal.
    strands : ndarray, shape (e, 2), int64
        Vertex indices of line cells (edges that are not triangle edges).
    grid_shape : tuple of int or None
        ``(ny, nx)`` when the mesh is a :func:`grid` (vertex ``(i, j)`` has index
        ``i * nx + j``), else None.
    """

    vertices: np.ndarray
    triangles: np.ndarray = field(default_factory=lambda: np.zeros((0, 3), np.int64))
    strands: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), np.int64))
    grid_shape: tuple[int, int] | None = None

    def __post_init__(self):
        v = check_finite("vertices", self.vertices)
        if v.ndim != 2 or v.shape[1] != 3:
            raise InputError(f"vertices: expected shape (n, 3), got {v.shape}")
        t = np.asarray(self.triangles, dtype=np.int64).reshape(-1, 3)
        s = np.asarray(self.strands, dtype=np.int64).reshape(-1, 2)
        n = len(v)
        for name, cells in (("triangles", t), ("strands", s)):
            if cells.size and (cells.min() < 0 or cells.max() >= n):
                bad = int(np.flatnonzero((cells < 0) | (cells >= n))[0])
                r, c = divmod(bad, cells.shape[1])
                raise InputError(
                    f"{name}[{r}, {c}]: vertex index {int(cells[r, c])} out of range 0..{n - 1}"
                )
        v = v.copy()
        v.flags.writeable = False
        t.flags.writeable = False
        s.flags.writeable = False
        object.__setattr__(self, "vertices", v)
        object.__setattr__(self, "triangles", t)
        object.__setattr__(self, "strands", s)

    @property
    def vertex_count(self) -> int:
        return len(self.vertices)

    @property
    def triangle_count(self) -> int:
        return len(self.triangles)

    @cached_property
    def edges(self) -> np.ndarray:
        """Unique undirected edges of triangles and strands, shape (e, 2), each row sorted."""
        t = self.triangles
        e = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]], self.strands])
        e.sort(axis=1)
        e = np.unique(e, axis=0) if len(e) else e.reshape(0, 2)
        e.flags.writeable = False
        return e

    @cached_property
    def edge_triangles(self) -> tuple[np.ndarray, np.ndarray]:
        """For every directed triangle half-edge: its sorted edge key and owning triangle.

        Returns
        -------
        keys : ndarray, shape (3m, 2)
            Sorted vertex pair of each half-edge.
        opposite : ndarray, shape (3m,)
            The triangle vertex opposite that half-edge.
        """
        t = self.triangles
        keys = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
        opposite = np.concatenate([t[:, 2], t[:, 0], t[:, 1]])
        keys = np.sort(keys, axis=1)
        return keys, opposite

    @cached_property
    def interior_edge_opposites(self) -> np.ndarray:
        """Vertex pairs opposite each interior (two-triangle) edge, shape (k, 2).

        These are the endpoints of the bending springs of a general mesh. Edges shared by
        more than two triangles (non-manifold) contribute no pair.
        """
        keys, opposite = self.edge_triangles
        if len(keys) == 0:
            return np.zeros((0, 2), np.int64)
        order = np.lexsort((keys[:, 1], keys[:, 0]))
        k, o = keys[order], opposite[order]
        same = np.all(k[1:] == k[:-1], axis=1)
        # an edge with exactly two half-edges: same[i] true and neither neighbour also same
        prev_same = np.concatenate([[False], same[:-1]])
        next_same = np.concatenate([same[1:], [False]])
        pair = same & ~prev_same & ~next_same
        idx = np.flatnonzero(pair)
        out = np.stack([o[idx], o[idx + 1]], axis=1)
        out = out[out[:, 0] != out[:, 1]]
        return np.sort(out, axis=1)

    def triangle_areas(self, positions: np.ndarray | None = None) -> np.ndarray:
        """Area of every triangle [m²], shape (m,), at ``positions`` (default: the mesh's)."""
        x = self.vertices if positions is None else positions
        t = self.triangles
        cross = np.cross(x[t[:, 1]] - x[t[:, 0]], x[t[:, 2]] - x[t[:, 0]])
        return 0.5 * np.linalg.norm(cross, axis=1)

    def vertex_areas(self) -> np.ndarray:
        """Lumped area of every vertex [m²], shape (n,): a third of each adjacent triangle.

        For a mesh without triangles (strands only), half of each adjacent strand's length
        [m] is used instead, so lumped masses stay proportional to the material.
        """
        n = self.vertex_count
        if self.triangle_count:
            a = np.repeat(self.triangle_areas() / 3.0, 3)
            return np.bincount(self.triangles.ravel(), weights=a, minlength=n)
        s = self.strands
        length = np.linalg.norm(self.vertices[s[:, 0]] - self.vertices[s[:, 1]], axis=1)
        return np.bincount(s.ravel(), weights=np.repeat(length / 2.0, 2), minlength=n)


def _place(u: np.ndarray, v: np.ndarray, center, plane: str) -> np.ndarray:
    """Map planar coordinates (u, v) to 3-D points in ``plane`` about ``center``."""
    if plane not in PLANES:
        raise InputError(f"plane: must be one of {', '.join(map(repr, PLANES))}, got {plane!r}")
    c = check_finite("center", center).reshape(3)
    zero = np.zeros_like(u)
    if plane == "xz":  # horizontal, normal +y: u along x, v along -z
        p = np.stack([u, zero, -v], axis=1)
    else:  # "xy": vertical, normal +z
        p = np.stack([u, v, zero], axis=1)
    return p + c


def grid(
    nx: int,
    ny: int,
    *,
    size: tuple[float, float] = (1.0, 1.0),
    center=(0.0, 0.0, 0.0),
    plane: str = "xz",
) -> Mesh:
    """Rectangular grid of ``nx × ny`` vertices, each cell split into two triangles.

    Parameters
    ----------
    nx, ny : int
        Vertices along the first and second axis (each >= 2).
    size : (float, float)
        Extent [m] along the two axes.
    center : (3,) array_like
        Centre of the rectangle [m].
    plane : {"xz", "xy"}
        ``"xz"`` lies flat (normal +y, second axis along −z); ``"xy"`` hangs vertically
        (second axis along +y, so row ``ny - 1`` is the top).

    Returns
    -------
    Mesh
        ``nx * ny`` vertices; vertex ``(i, j)`` (row i < ny, column j < nx) has index
        ``i * nx + j``; ``2 (nx - 1)(ny - 1)`` triangles.
    """
    for name, val in (("nx", nx), ("ny", ny)):
        if int(val) != val or val < 2:
            raise InputError(f"resolution: {name} must be an integer >= 2, got {val!r}")
    nx, ny = int(nx), int(ny)
    sx, sy = check_finite("size", size).reshape(2)
    if sx <= 0 or sy <= 0:
        raise InputError(f"size: both extents must be positive, got {[sx, sy]}")
    jj, ii = np.meshgrid(np.arange(nx), np.arange(ny))
    u = (jj.ravel() / (nx - 1) - 0.5) * sx
    v = (ii.ravel() / (ny - 1) - 0.5) * sy
    vertices = _place(u, v, center, plane)
    a = (np.arange(ny - 1)[:, None] * nx + np.arange(nx - 1)[None, :]).ravel()
    b, c, d = a + 1, a + nx, a + nx + 1
    tris = np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)])
    return Mesh(vertices, tris, grid_shape=(ny, nx))


# --------------------------------------------------------------------------- cells → Mesh

#: Cell types whose first corners form a triangle, a quad or a segment (higher-order nodes
#: beyond the corners are dropped).
_TRIANGLE_TYPES = {"triangle": 3, "triangle6": 3, "triangle7": 3}
_QUAD_TYPES = {"quad": 4, "quad8": 4, "quad9": 4}
_LINE_TYPES = {"line": 2, "line3": 2}


def fan_triangles(faces: np.ndarray) -> np.ndarray:
    """Split polygons of k >= 3 vertices into k − 2 triangles fanned from their first vertex.

    Exact for convex (and star-shaped about the first vertex) polygons, which is what mesh
    files hold in practice; a non-convex face may give overlapping triangles.

    Parameters
    ----------
    faces : ndarray, shape (c, k), int
        Vertex indices of c polygons with k vertices each.

    Returns
    -------
    ndarray, shape (c (k − 2), 3), int64
        Triangles in face order: the k − 2 triangles of face 0, then of face 1, …
    """
    faces = np.asarray(faces, dtype=np.int64)
    c, k = faces.shape
    i = np.arange(1, k - 1)
    tris = np.stack([np.broadcast_to(faces[:, :1], (c, k - 2)), faces[:, i], faces[:, i + 1]],
                    axis=2)
    return tris.reshape(-1, 3)


def from_cells(vertices, cells, *, field: str = "mesh") -> Mesh:
    """Build a :class:`Mesh` from cell blocks as mesh files store them.

    Parameters
    ----------
    vertices : array_like, shape (n, 2) or (n, 3)
        Vertex positions [m]; 2-D points get z = 0.
    cells : sequence of (str, ndarray (c, k))
        Cell blocks by meshio type name. ``triangle*`` are kept (corners only); ``quad*`` and
        ``polygon`` with k >= 3 are fan-triangulated (:func:`fan_triangles`); ``line*`` and
        2-vertex ``polygon`` become strands; ``vertex`` cells are ignored. Any other type
        (volume cells) is ignored with a :class:`~clothsim.errors.MeshWarning`.
    field : str
        Name used in error messages (e.g. the scene key holding the file name).

    Returns
    -------
    Mesh
        Strands that repeat a triangle edge or another strand are dropped.

    Raises
    ------
    InputError
        No triangles and no lines, or a bad vertex array.
    """
    import warnings

    from .errors import MeshWarning

    v = np.asarray(vertices, dtype=np.float64)
    if v.ndim != 2 or v.shape[1] not in (2, 3):
        raise InputError(f"{field}: expected points of shape (n, 2) or (n, 3), got {v.shape}")
    if v.shape[1] == 2:
        v = np.column_stack([v, np.zeros(len(v))])
    tris, strands, ignored, found = [], [], {}, []
    for kind, data in cells:
        data = np.asarray(data, dtype=np.int64)
        if data.size == 0:
            continue
        found.append(kind)
        k = data.shape[1]
        if kind in _TRIANGLE_TYPES:
            tris.append(data[:, :3])
        elif kind in _QUAD_TYPES:
            tris.append(fan_triangles(data[:, :4]))
        elif kind == "polygon" and k >= 3:
            tris.append(fan_triangles(data))
        elif kind in _LINE_TYPES or (kind == "polygon" and k == 2):
            strands.append(data[:, :2])
        elif kind != "vertex":
            ignored[kind] = ignored.get(kind, 0) + len(data)
    if not tris and not strands:
        kinds = ", ".join(sorted(set(found))) or "none"
        raise InputError(f"{field}: no triangles and no lines in the file (cell types found: "
                         f"{kinds})")
    if ignored:
        what = ", ".join(f"{c} {kind}" for kind, c in sorted(ignored.items()))
        warnings.warn(f"{field}: ignored cells that are neither surfaces nor lines: {what}",
                      MeshWarning, stacklevel=2)
    t = np.concatenate(tris) if tris else np.zeros((0, 3), np.int64)
    s = np.concatenate(strands) if strands else np.zeros((0, 2), np.int64)
    s = _unique_strands(t, s)
    return Mesh(v, t, s)


def _unique_strands(triangles: np.ndarray, strands: np.ndarray) -> np.ndarray:
    """Drop strands that repeat an earlier strand or a triangle edge (order kept)."""
    if len(strands) == 0:
        return strands
    key = np.sort(strands, axis=1)
    _, first = np.unique(key, axis=0, return_index=True)
    keep = np.zeros(len(strands), bool)
    keep[first] = True
    if len(triangles):
        t = triangles
        edges = np.sort(np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]]), axis=1)
        n = int(max(edges.max(), key.max())) + 1
        on_triangle = np.isin(key[:, 0] * n + key[:, 1], edges[:, 0] * n + edges[:, 1])
        keep &= ~on_triangle
    dropped = len(strands) - int(keep.sum())
    if dropped:
        logger.info("dropped %d strands repeating a triangle edge or another strand", dropped)
    return strands[keep]


def load(path, *, field: str = "mesh", check: bool = True) -> Mesh:
    """Read a cloth mesh from a file.

    Any format meshio 5.3.5 reads (PLY, STL, OFF, MSH, VTU, VTK, XDMF, …); ``.obj`` is read
    by clothsim's own reader, which also understands 2-vertex faces and ``l`` lines as
    strands, ``v/vt/vn`` index forms and negative (relative) indices. Triangles are kept,
    quads and polygons are fan-triangulated from their first vertex (exact for convex
    faces), line cells become strands, vertex cells are ignored.

    Parameters
    ----------
    path : str or os.PathLike
        The mesh file.
    field : str
        Name used in error messages, e.g. ``"cloth.mesh"`` for a scene key.
    check : bool
        Run :func:`clothsim.validate_mesh.check_mesh` (errors for non-manifold edges and
        zero-area triangles, warnings for suspicious meshes).

    Returns
    -------
    Mesh
        Vertices in the file's order and units (taken as metres).

    Raises
    ------
    InputError
        Missing file, unknown or unreadable format, no triangles and no lines, or a failed
        check.
    """
    from .io import read_mesh

    mesh = read_mesh(path, field=field)
    if check:
        from .validate_mesh import check_mesh

        check_mesh(mesh, field=field)
    return mesh


# --------------------------------------------------------------------------- polygon


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
        Same convention as :func:`grid`: ``"xz"`` maps (u, v) to (u, 0, −v) (normal +y),
        ``"xy"`` to (u, v, 0) (normal +z).

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
    from scipy.spatial import Delaunay

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
    vertices = _place(uv[:, 0], uv[:, 1], center, plane)
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
