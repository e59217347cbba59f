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
    Any mesh meshio reads (OBJ, PLY, STL, MSH, VTU …); see :mod:`clothsim.io`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from .errors import InputError, check_finite

PLANES = ("xz", "xy")


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
