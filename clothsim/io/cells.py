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


class FrameFields:
    """The fields of a cloth's frames that depend on its rest state, prepared once:
    ``stretch`` per vertex and ``area_ratio`` per cell (see :func:`vertex_stretch`,
    :func:`cell_area_ratio`).

    Parameters
    ----------
    rest : ndarray, shape (n, 3)
        Rest positions [m] (the areas at rest).
    blocks : list of (str, ndarray)
        Cell blocks as :func:`cell_blocks` returns them.
    spring_vertices : ndarray, shape (s, 2), int
        The two vertices of each spring.
    spring_rest_length : ndarray, shape (s,)
        Rest length r of each spring [m] (springs of rest length 0 are left out).
    """

    def __init__(self, rest, blocks, spring_vertices, spring_rest_length):
        ij = np.asarray(spring_vertices, dtype=np.int64).reshape(-1, 2)
        r = np.asarray(spring_rest_length, dtype=np.float64)
        self.n = len(rest)
        self.ij, self.inv_rest = ij[r > 0], 1.0 / r[r > 0]
        self.flat = self.ij.T.ravel()  # first ends, then second ends
        self.count = np.maximum(np.bincount(self.flat, minlength=self.n), 1)
        self.blocks = blocks
        self.rest_area = [_areas(np.asarray(rest, float), c) if k == "triangle" else None
                          for k, c in blocks]

    def stretch(self, x: np.ndarray) -> np.ndarray:
        """Mean |ℓ/r − 1| of each vertex's springs, shape (n,) (0 without springs).

        Parameters
        ----------
        x : ndarray, shape (n, 3)
            Positions [m].

        Returns
        -------
        ndarray, shape (n,), float64
            Dimensionless.
        """
        d = x[self.ij[:, 0]] - x[self.ij[:, 1]]
        strain = np.abs(np.sqrt(np.einsum("ij,ij->i", d, d)) * self.inv_rest - 1.0)
        return np.bincount(self.flat, np.tile(strain, 2), minlength=self.n) / self.count

    def area_ratio(self, x: np.ndarray) -> list[np.ndarray]:
        """Area over rest area per cell of each block (NaN for lines, vertices and triangles
        of zero rest area).

        Parameters
        ----------
        x : ndarray, shape (n, 3)
            Positions [m].

        Returns
        -------
        list of ndarray
            One array per block.
        """
        out = []
        for (_, cells), a0 in zip(self.blocks, self.rest_area):
            if a0 is None:
                out.append(np.full(len(cells), np.nan))
            else:
                with np.errstate(divide="ignore", invalid="ignore"):
                    out.append(np.where(a0 > 0, _areas(x, cells) / a0, np.nan))
        return out


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
    return FrameFields(x, [], spring_vertices, spring_rest_length).stretch(x)


def _areas(x: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    t = x[triangles]
    c = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    return 0.5 * np.sqrt(np.einsum("ij,ij->i", c, c))


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
    return FrameFields(rest, blocks, np.zeros((0, 2), np.int64), np.zeros(0)).area_ratio(
        np.asarray(x, dtype=np.float64))


__all__ = ["cell_blocks", "FrameFields", "vertex_stretch", "cell_area_ratio"]
