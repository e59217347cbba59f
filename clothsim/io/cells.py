"""What mesh and frame files hold besides the points: cell blocks from a
:class:`~clothsim.mesh.Mesh` (the reverse, files to a mesh, is
:func:`clothsim.mesh.from_cells`), and the per-vertex and per-cell fields of a frame
(``pinned``, ``stretch``, ``area_ratio``) that ParaView colours by."""

from __future__ import annotations

import numpy as np

from ..mesh import Mesh


def cell_blocks(mesh: Mesh, springs=None) -> list[tuple[str, np.ndarray]]:
    """``[("triangle", (m, 3)), ("line", (e, 2))]`` of ``mesh``, empty blocks left out.

    Parameters
    ----------
    mesh : Mesh
        The mesh, ``m`` triangles and ``e`` strands.
    springs : ndarray, shape (s, 2), int, optional
        Vertex pairs of the cloth's springs, written as line cells when the mesh has
        neither triangles nor strands (a spring network read from files).

    Returns
    -------
    list of (str, ndarray)
        ``("triangle", triangles)`` with an (m, 3) int array of vertex indices when the
        mesh has triangles, then ``("line", strands)`` with an (e, 2) int array when it
        has strands. A mesh with neither gets ``("line", springs)`` when there are springs,
        else one ``("vertex", (n, 1))`` cell per vertex, so that every file holds cells (a
        VTU file without cells cannot be read back).
    """
    blocks = []
    if mesh.triangle_count:
        blocks.append(("triangle", np.asarray(mesh.triangles)))
    if len(mesh.strands):
        blocks.append(("line", np.asarray(mesh.strands)))
    if not blocks:
        pairs = np.zeros((0, 2), np.int64) if springs is None else np.asarray(springs)
        if len(pairs):
            blocks.append(("line", pairs.astype(np.int64).reshape(-1, 2)))
        else:
            blocks.append(("vertex", np.arange(mesh.vertex_count, dtype=np.int64)[:, None]))
    return blocks


def vertex_stretch(x: np.ndarray, spring_vertices: np.ndarray,
                   spring_rest_length: np.ndarray) -> np.ndarray:
    """Mean relative stretch of each vertex's springs: mean over them of |ℓ/r − 1|.

    Parameters
    ----------
    x : ndarray, shape (n, 3)
        Positions [m].
    spring_vertices : ndarray, shape (s, 2), int
        The two vertices of each spring.
    spring_rest_length : ndarray, shape (s,)
        Rest length r of each spring [m] (springs of rest length 0 are left out).

    Returns
    -------
    ndarray, shape (n,), float64
        Dimensionless; 0 for a vertex without springs and everywhere at rest.
    """
    x = np.asarray(x, dtype=np.float64)
    ij = np.asarray(spring_vertices, dtype=np.int64).reshape(-1, 2)
    r = np.asarray(spring_rest_length, dtype=np.float64)
    ok = r > 0
    ij, r = ij[ok], r[ok]
    strain = np.abs(np.linalg.norm(x[ij[:, 0]] - x[ij[:, 1]], axis=1) / r - 1.0)
    n = len(x)
    total = np.bincount(ij.ravel(), np.repeat(strain, 2), minlength=n)
    count = np.bincount(ij.ravel(), minlength=n)
    return total / np.maximum(count, 1)


def _areas(x: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    t = x[triangles]
    return 0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1)


def cell_area_ratio(blocks, rest: np.ndarray, x: np.ndarray) -> list[np.ndarray]:
    """Cell data ``area_ratio``: each triangle's area over its area at rest, per block.

    Parameters
    ----------
    blocks : list of (str, ndarray)
        Cell blocks as :func:`cell_blocks` returns them.
    rest, x : ndarray, shape (n, 3)
        Rest and current positions [m].

    Returns
    -------
    list of ndarray
        One array per block: the ratio for ``triangle`` blocks (NaN for a triangle of zero
        rest area), NaN for line and vertex cells (they have no area).
    """
    out = []
    for kind, cells in blocks:
        if kind == "triangle":
            a0 = _areas(rest, cells)
            with np.errstate(divide="ignore", invalid="ignore"):
                out.append(np.where(a0 > 0, _areas(x, cells) / a0, np.nan))
        else:
            out.append(np.full(len(cells), np.nan))
    return out


__all__ = ["cell_blocks", "vertex_stretch", "cell_area_ratio"]
