"""Cell blocks as mesh files store them, from a :class:`~clothsim.mesh.Mesh` (the reverse,
files to a mesh, is :func:`clothsim.mesh.from_cells`)."""

from __future__ import annotations

import numpy as np

from ..mesh import Mesh


def cell_blocks(mesh: Mesh) -> list[tuple[str, np.ndarray]]:
    """``[("triangle", (m, 3)), ("line", (e, 2))]`` of ``mesh``, empty blocks left out."""
    blocks = []
    if mesh.triangle_count:
        blocks.append(("triangle", np.asarray(mesh.triangles)))
    if len(mesh.strands):
        blocks.append(("line", np.asarray(mesh.strands)))
    return blocks
