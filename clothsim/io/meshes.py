"""Mesh files: :func:`load_mesh` (read and check), :func:`read_mesh`, :func:`write_mesh`.

Any format meshio 5.3.5 reads (PLY, STL, OFF, MSH, VTU, VTK, XDMF, …); ``.obj`` goes
through clothsim's own reader (:mod:`clothsim.io.obj`). Every meshio call of clothsim is in
:mod:`clothsim.io`.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import InputError
from ..mesh import Mesh, from_cells
from ..mesh_checks import check_mesh
from .cells import cell_blocks
from .common import MeshioFailure, atomic_path, load_meshio, quietly
from .obj import read_obj, write_obj


def supported_formats() -> list[str]:
    """File extensions :func:`read_mesh` accepts (``.obj`` plus meshio's list).

    Returns
    -------
    list of str
        Sorted extensions with their dot, e.g. ``[".obj", ".ply", ".stl", ...]``.
    """
    meshio = load_meshio()
    return sorted(set(meshio.extension_to_filetypes) | {".obj"})


def read_mesh(path, *, field: str = "mesh") -> Mesh:
    """Read a mesh file into a :class:`~clothsim.mesh.Mesh` (no checks; see
    :func:`load_mesh`).

    Parameters
    ----------
    path : str or os.PathLike
        The mesh file; coordinates are taken in [m].
    field : str
        Name used in error messages.

    Returns
    -------
    Mesh
        Vertices (n, 3) [m] in the file's order, triangles (m, 3) (polygons
        fan-triangulated), strands (e, 2) from line cells.

    Raises
    ------
    InputError
        Missing file, a directory, unknown or unreadable format, or no triangles and no
        lines.
    """
    path = Path(path)
    if path.is_dir():
        raise InputError(f"{field}: is a directory, not a mesh file: {path}")
    if not path.is_file():
        raise InputError(f"{field}: file not found: {path}")
    if path.suffix.lower() == ".obj":
        return read_obj(path, field=field)
    meshio = load_meshio()
    try:
        m = quietly(meshio.read, path)
    except MeshioFailure as exc:
        formats = " ".join(supported_formats())
        if path.suffix.lower() not in meshio.extension_to_filetypes:
            raise InputError(f"{field}: unknown mesh format {path.suffix or '(no extension)'!r} "
                             f"of {path}; supported formats: {formats}") from None
        if _empty(path):
            raise InputError(f"{field}: {path} has no triangles (the file is empty)") from None
        raise InputError(f"{field}: cannot read {path} ({exc}); supported formats: "
                         f"{formats}") from None
    if len(m.points) == 0 or _empty(path):
        raise InputError(f"{field}: {path} has no triangles (the file is empty)")
    return from_cells(m.points, [(c.type, c.data) for c in m.cells], field=field)


def _empty(path: Path) -> bool:
    """An empty file, a binary STL whose header says 0 triangles, or an ASCII STL without a
    facet."""
    if path.stat().st_size == 0:
        return True
    if path.suffix.lower() != ".stl":
        return False
    data = path.read_bytes()
    if data[:5].lower() == b"solid":
        return b"facet" not in data.lower()
    return len(data) >= 84 and int.from_bytes(data[80:84], "little") == 0


def load_mesh(path, *, field: str = "mesh", check: bool = True) -> Mesh:
    """Read a cloth mesh from a file (``clothsim.load``).

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
        Run :func:`clothsim.mesh_checks.check_mesh` (errors for non-manifold edges and
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
    mesh = read_mesh(path, field=field)
    if check:
        check_mesh(mesh, field=field)
    return mesh


def write_mesh(path, mesh: Mesh, positions=None, point_data=None) -> None:
    """Write ``mesh`` (at ``positions``, default its vertices) to ``path``.

    The format follows the extension (any meshio writes). ``.obj`` is written by clothsim
    with ``%.17g`` coordinates and strands as ``l`` lines, so :func:`read_mesh` gets the
    same mesh back exactly.

    Parameters
    ----------
    path : str or os.PathLike
        The file to write; its extension picks the format.
    mesh : Mesh
        Connectivity: triangles (m, 3) and strands (e, 2).
    positions : ndarray, shape (n, 3), optional
        Vertex positions [m].
    point_data : dict of str to ndarray (n, …), optional
        Per-vertex arrays (ignored for ``.obj``).

    Returns
    -------
    None

    Raises
    ------
    InputError
        When ``positions`` is not of shape (n, 3) or meshio cannot write the file.
    """
    path = Path(path)
    x = mesh.vertices if positions is None else np.asarray(positions, dtype=np.float64)
    if x.shape != mesh.vertices.shape:
        raise InputError(f"positions: expected shape {mesh.vertices.shape}, got {x.shape}")
    if path.suffix.lower() == ".obj":
        write_obj(path, mesh, x)
        return
    meshio = load_meshio()
    try:
        with atomic_path(path) as tmp:
            quietly(meshio.write, tmp,
                    meshio.Mesh(x, cell_blocks(mesh), point_data=dict(point_data or {})))
    except MeshioFailure as exc:
        raise InputError(f"{path}: cannot write mesh ({exc})") from None
