"""Cell blocks as mesh files store them, from a :class:`~clothsim.mesh.Mesh` (the reverse,
files to a mesh, is :func:`clothsim.mesh.from_cells`)."""

from __future__ import annotations

import numpy as np

from ..mesh import Mesh


def cell_blocks(mesh: Mesh) -> list[tuple[str, np.ndarray]]:
    """``[("triangle", (m, 3)), ("line", (e, 2))]`` of ``mesh``, empty blocks left out.

    Parameters
    ----------
    mesh : Mesh
        The mesh, ``m`` triangles and ``e`` strands.

    Returns
    -------
    list of (str, ndarray)
        ``("triangle", triangles)`` with an (m, 3) int array of vertex indices when the
        mesh has triangles, then ``("line", strands)`` with an (e, 2) int array when it
        has strands.
    """
    blocks = []
    if mesh.triangle_count:
        blocks.append(("triangle", np.asarray(mesh.triangles)))
    if len(mesh.strands):
        blocks.append(("line", np.asarray(mesh.strands)))
    return blocks
