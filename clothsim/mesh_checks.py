"""Checks that a cloth mesh is fit to simulate.

:func:`check_mesh` raises :class:`~clothsim.errors.InputError` for defects that break the
method and warns with :class:`~clothsim.errors.MeshWarning` for suspicious but usable
meshes. Every check is vectorized (sorting, a k-d tree, a sparse graph).

Errors
------
non-manifold edges
    An edge shared by more than two triangles: "the two triangles across an edge" (the
    bending springs) is undefined there.
zero-area triangles
    Area <= 1e-12 × (bounding-box diagonal)², including triangles that repeat a vertex.
duplicate triangles
    The same three vertices as an earlier triangle (in any order).
self-loop strands
    A strand from a vertex to itself (a spring with no direction).

Warnings
--------
unreferenced vertices
    In no triangle and no strand: they only fall under gravity.
near-duplicate vertices
    Closer than 1e-9 × the bounding-box diagonal: usually an unwelded seam, which leaves
    the cloth in pieces that can pass through each other.
several connected components
    Over triangles and strands, counting only referenced vertices.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from .errors import InputError, MeshWarning
from .mesh import Mesh

#: Relative thresholds (of the bounding-box diagonal) used by :func:`check_mesh`.
DUPLICATE_DISTANCE = 1e-9
ZERO_AREA = 1e-12
_LISTED = 5  # how many offending items a message lists


@dataclass(frozen=True, eq=False)
class MeshReport:
    """What :func:`check_mesh` found.

    Attributes
    ----------
    vertex_count, triangle_count, strand_count : int
        n, m and e of the mesh.
    boundary_edge_count : int
        Triangle edges with exactly one triangle.
    component_count : int
        Connected components over triangles and strands (referenced vertices only).
    unreferenced_vertices : ndarray, shape (u,), int64
        Vertices in no triangle and no strand.
    duplicate_vertex_pairs : ndarray, shape (d, 2), int64
        Vertex pairs (i < j) closer than ``DUPLICATE_DISTANCE`` × bounding-box diagonal.
    bounding_box_diagonal : float
        [m].
    """

    vertex_count: int
    triangle_count: int
    strand_count: int
    boundary_edge_count: int
    component_count: int
    unreferenced_vertices: np.ndarray
    duplicate_vertex_pairs: np.ndarray
    bounding_box_diagonal: float

    @property
    def clean(self) -> bool:
        """True when no warning applies."""
        return (len(self.unreferenced_vertices) == 0 and len(self.duplicate_vertex_pairs) == 0
                and self.component_count <= 1)


def _listing(items, total: int) -> str:
    shown = ", ".join(items[:_LISTED])
    return shown + (f", … ({total} in all)" if total > _LISTED else "")


def check_mesh(mesh: Mesh, *, field: str = "mesh", warn: bool = True) -> MeshReport:
    """Check a mesh; raise for defects, warn for suspicious features, return a report.

    Parameters
    ----------
    mesh : Mesh
        Vertices (n, 3) [m], triangles (m, 3), strands (e, 2).
    field : str
        Name used at the start of every message, e.g. ``"cloth.mesh"``.
    warn : bool
        Issue :class:`~clothsim.errors.MeshWarning` s (one per kind, with a count). With
        False the report still holds everything.

    Returns
    -------
    MeshReport
        Counts, unreferenced vertices and near-duplicate vertex pairs.

    Raises
    ------
    InputError
        Non-manifold edges (lists the first vertex pairs), zero-area triangles (lists the
        first triangle indices) or self-loop strands.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    x, t, s = mesh.vertices, mesh.triangles, mesh.strands
    n = len(x)
    diagonal = float(np.linalg.norm(np.ptp(x, axis=0))) if n else 0.0

    # --- errors
    # zero-area first: a triangle repeating a vertex also doubles one of its edges
    area = mesh.triangle_areas()
    zero = np.flatnonzero(area <= ZERO_AREA * diagonal**2)
    if len(zero):
        raise InputError(f"{field}: {len(zero)} zero-area triangles, indices "
                         f"{_listing([str(i) for i in zero.tolist()], len(zero))}")
    if len(t):  # the same face twice doubles its mass, its springs and its wind force
        faces = np.sort(t, axis=1)
        _, first, inverse = np.unique(faces, axis=0, return_index=True, return_inverse=True)
        dup = np.flatnonzero(first[inverse.ravel()] != np.arange(len(t)))
        if len(dup):
            raise InputError(f"{field}: {len(dup)} duplicate triangles (the same three "
                             f"vertices as an earlier one), indices "
                             f"{_listing([str(i) for i in dup.tolist()], len(dup))}")
    keys, _ = mesh.edge_triangles
    boundary_edges = 0
    if len(keys):
        code, count = np.unique(keys[:, 0] * n + keys[:, 1], return_counts=True)
        bad = np.column_stack(np.divmod(code[count > 2], n))
        if len(bad):
            pairs = [f"({a}, {b})" for a, b in bad.tolist()]
            raise InputError(f"{field}: {len(bad)} non-manifold edges (shared by more than two "
                             f"triangles): {_listing(pairs, len(bad))}")
        boundary_edges = int(np.count_nonzero(count == 1))
    loops = np.flatnonzero(s[:, 0] == s[:, 1])
    if len(loops):
        raise InputError(f"{field}: {len(loops)} strands join a vertex to itself, indices "
                         f"{_listing([str(i) for i in loops.tolist()], len(loops))}")

    # --- warnings
    referenced = np.zeros(n, bool)
    referenced[t.ravel()] = True
    referenced[s.ravel()] = True
    unreferenced = np.flatnonzero(~referenced)
    if n > 1:
        duplicates = cKDTree(x).query_pairs(DUPLICATE_DISTANCE * diagonal, output_type="ndarray")
        duplicates = duplicates[np.lexsort((duplicates[:, 1], duplicates[:, 0]))]
    else:
        duplicates = np.zeros((0, 2), np.int64)
    e = np.concatenate([keys, s])  # duplicates are harmless for connectivity
    graph = coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n))
    _, label = connected_components(graph, directed=False)
    components = len(np.unique(label[referenced]))

    report = MeshReport(n, len(t), len(s), boundary_edges, components, unreferenced,
                        duplicates.astype(np.int64), diagonal)
    if warn:
        if len(unreferenced):
            idx = [str(i) for i in unreferenced.tolist()]
            warnings.warn(f"{field}: {len(unreferenced)} unreferenced vertices (in no triangle "
                          f"or strand): {_listing(idx, len(unreferenced))}", MeshWarning,
                          stacklevel=2)
        if len(duplicates):
            pairs = [f"({a}, {b})" for a, b in duplicates.tolist()]
            warnings.warn(f"{field}: {len(duplicates)} near-duplicate vertex pairs (closer than "
                          f"{DUPLICATE_DISTANCE:g} × bounding-box diagonal): "
                          f"{_listing(pairs, len(duplicates))}", MeshWarning, stacklevel=2)
        if components > 1:
            warnings.warn(f"{field}: {components} connected components (expected one piece "
                          "of cloth)", MeshWarning, stacklevel=2)
    return report
