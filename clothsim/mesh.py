"""Cloth meshes: vertices, triangles and strands (line cells).

The first stage of the pipeline (mesh → springs → model → matrices → factor → solver).
A :class:`Mesh` is geometry and connectivity only; springs and masses are built from it.

Builders
--------
grid
    Rectangular nx × ny grid, each cell split into two triangles.
from_cells
    Cell blocks as mesh files hold them (triangles, quads, polygons, lines) → Mesh.

A closed outline is triangulated by :func:`clothsim.polygon.polygon`; mesh files are read
by :func:`clothsim.io.meshes.load_mesh` (``clothsim.load``).
"""

from __future__ import annotations

import logging
import warnings
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from .errors import InputError, MeshWarning, check_finite

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
        t = _indices("triangles", self.triangles, 3)
        s = _indices("strands", self.strands, 2)
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
        """n, the number of vertices."""
        return len(self.vertices)

    @property
    def triangle_count(self) -> int:
        """m, the number of triangles."""
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
        """For every directed triangle half-edge: its sorted edge key and opposite vertex.

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
        """Area of every triangle [m²], shape (m,), at ``positions`` (default: the mesh's).

        The area of triangle (a, b, c) is ``|(x_b - x_a) × (x_c - x_a)| / 2``.

        Parameters
        ----------
        positions : ndarray, shape (n, 3), optional
            Vertex positions [m]; default the rest positions ``vertices``.

        Returns
        -------
        ndarray, shape (m,)
            Areas [m²] (0 for a degenerate triangle).
        """
        x = self.vertices if positions is None else positions
        t = self.triangles
        cross = np.cross(x[t[:, 1]] - x[t[:, 0]], x[t[:, 2]] - x[t[:, 0]])
        return 0.5 * np.linalg.norm(cross, axis=1)

    def vertex_areas(self) -> np.ndarray:
        """Lumped area of every vertex [m²], shape (n,): a third of each adjacent triangle.

        For a mesh without triangles (strands only), half of each adjacent strand's length
        [m] is used instead, so lumped masses stay proportional to the material.

        Returns
        -------
        ndarray, shape (n,)
            Lumped areas [m²] at the rest positions (lengths [m] for a strands-only mesh);
            0 for a vertex that touches nothing.
        """
        n = self.vertex_count
        if self.triangle_count:
            a = np.repeat(self.triangle_areas() / 3.0, 3)
            return np.bincount(self.triangles.ravel(), weights=a, minlength=n)
        s = self.strands
        length = np.linalg.norm(self.vertices[s[:, 0]] - self.vertices[s[:, 1]], axis=1)
        return np.bincount(s.ravel(), weights=np.repeat(length / 2.0, 2), minlength=n)


def _indices(name: str, cells, width: int) -> np.ndarray:
    """Vertex indices, shape (k, width), int64: integers only (no truncation, no bools)."""
    a = np.asarray(cells)
    if a.size == 0:
        return np.zeros((0, width), np.int64)
    if a.ndim != 2 or a.shape[1] != width:
        raise InputError(f"{name}: expected shape (k, {width}), got {a.shape}")
    if a.dtype.kind == "f" and np.all(np.isfinite(a)) and np.all(a == np.round(a)):
        a = a.astype(np.int64)  # whole numbers stored as floats (e.g. from loadtxt)
    if a.dtype.kind not in "iu":
        r, c = np.argwhere(a != np.round(a))[0] if a.dtype.kind == "f" else (0, 0)
        raise InputError(f"{name}[{r}, {c}]: vertex indices must be integers, got "
                         f"{a.dtype} {a[r, c]!r}"[:200])
    return np.array(a, dtype=np.int64)


def place_in_plane(u: np.ndarray, v: np.ndarray, center, plane: str) -> np.ndarray:
    """Map planar coordinates (u, v) [m], shape (k,) each, to 3-D points, shape (k, 3), in
    ``plane`` (``"xz"``: (u, 0, −v); ``"xy"``: (u, v, 0)) about ``center``.

    Parameters
    ----------
    u, v : ndarray, shape (k,)
        In-plane coordinates [m].
    center : array_like, shape (3,)
        Point [m] the plane's origin is moved to.
    plane : {"xz", "xy"}
        ``"xz"`` is horizontal (normal +y), ``"xy"`` vertical (normal +z).

    Returns
    -------
    ndarray, shape (k, 3)
        The points [m].

    Raises
    ------
    InputError
        On an unknown ``plane`` or a non-finite ``center``.
    """
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
        shown = val.item() if isinstance(val, np.generic) else val
        whole = (isinstance(shown, int) and not isinstance(shown, bool)
                 or isinstance(shown, float) and shown.is_integer())  # not NaN, inf, "3"
        if not whole or shown < 2:
            raise InputError(f"resolution: {name} must be an integer >= 2, got {shown!r}")
    nx, ny = int(nx), int(ny)
    sx, sy = check_finite("size", size).reshape(2)
    if sx <= 0 or sy <= 0:
        raise InputError(f"size: both extents must be positive, got {[float(sx), float(sy)]}")
    jj, ii = np.meshgrid(np.arange(nx), np.arange(ny))
    u = (jj.ravel() / (nx - 1) - 0.5) * sx
    v = (ii.ravel() / (ny - 1) - 0.5) * sy
    vertices = place_in_plane(u, v, center, plane)
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
