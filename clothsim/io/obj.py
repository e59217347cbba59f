"""Wavefront OBJ, read and written by clothsim itself (meshio's reader ignores ``l`` lines
and negative indices)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import InputError
from ..mesh import Mesh, from_cells
from .common import atomic_path, one_line


def read_obj(path, *, field: str = "mesh") -> Mesh:
    """Wavefront OBJ as a :class:`~clothsim.mesh.Mesh` (polygons fan-split; see
    :func:`read_obj_cells`).

    Parameters
    ----------
    path : str or path-like
        The ``.obj`` file; coordinates are taken in [m].
    field : str
        Name used in error messages (e.g. the scene key that named the file).

    Returns
    -------
    Mesh
        Rest positions (n, 3) [m], triangles (m, 3) and strands (e, 2).

    Raises
    ------
    InputError
        On an unreadable file, a bad coordinate or an index out of range.
    """
    return from_cells(*read_obj_cells(path, field=field), field=field)


def read_obj_cells(path, *, field: str = "mesh") -> tuple[np.ndarray, list]:
    """Vertices and cell blocks of a Wavefront OBJ file, faces kept as written.

    Reads ``v`` (first 3 numbers), ``f`` with k >= 3 vertices (a ``"triangle"`` or
    ``"polygon"`` block per run of one size, in file order), ``f`` with 2 vertices and ``l``
    polylines (``"line"`` segments); ``i``, ``i/t``, ``i//n``, ``i/t/n`` and negative
    (relative) indices. Everything else (vt, vn, groups, materials) is ignored.

    Parameters
    ----------
    path : str or path-like
        The ``.obj`` file.
    field : str
        Name used in error messages.

    Returns
    -------
    vertices : ndarray, shape (n, 3), float64
    cells : list of (str, ndarray (c, k) int64)
        0-based vertex indices, as :func:`clothsim.mesh.from_cells` takes them.

    Raises
    ------
    InputError
        On an unreadable file, a bad number, or a vertex index out of range (the message
        names the line).
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError as exc:
        raise InputError(f"{field}: cannot read {path}: {one_line(exc)}") from None
    coords, face_tokens, face_size, face_base, face_line = [], [], [], [], []
    strand_tokens, strand_size, strand_base, strand_line = [], [], [], []
    nv = 0
    for number, line in enumerate(text.splitlines(), 1):
        parts = line.split()
        if not parts:
            continue
        key = parts[0]
        if key == "v":
            if len(parts) < 4:
                raise InputError(f"{field}: line {number}: a vertex needs 3 coordinates")
            coords.append(parts[1:4])
            nv += 1
        elif key == "f" or key == "l":
            items = parts[1:]
            if len(items) < 2:
                raise InputError(f"{field}: line {number}: '{key}' needs at least 2 vertices")
            if key == "f" and len(items) > 2:
                target = (face_tokens, face_size, face_base, face_line)
            else:
                target = (strand_tokens, strand_size, strand_base, strand_line)
            target[0].extend(items)
            target[1].append(len(items))
            target[2].append(nv)
            target[3].append(number)
    try:
        vertices = np.array(coords, dtype=np.float64).reshape(-1, 3)
    except ValueError as exc:
        raise InputError(f"{field}: bad vertex coordinate: {one_line(exc)}") from None

    def indices(tokens, size, base, lines):
        size = np.asarray(size, np.int64)
        heads = [tok.split("/", 1)[0] for tok in tokens]
        try:
            idx = np.array(heads, dtype=np.int64)
        except ValueError as exc:
            raise InputError(f"{field}: bad vertex index: {one_line(exc)}") from None
        except OverflowError:  # an integer beyond int64: name its line
            i = next(i for i, h in enumerate(heads) if not -2**63 <= int(h) < 2**63)
            line = np.repeat(np.asarray(lines), size)[i]
            shown = heads[i] if len(heads[i]) <= 40 else heads[i][:37] + "..."
            raise InputError(f"{field}: line {line}: vertex index {shown} out of range "
                             "(beyond 64-bit integers)") from None
        seen = np.repeat(np.asarray(base, np.int64), size)  # vertices defined so far
        idx = np.where(idx < 0, idx + seen + 1, idx)  # -1 is the last vertex defined
        bad = np.flatnonzero((idx < 1) | (idx > seen))
        if len(bad):
            line = np.repeat(np.asarray(lines), size)[bad[0]]
            raise InputError(f"{field}: line {line}: vertex index {tokens[bad[0]]} out of range "
                             f"(1..{seen[bad[0]]} defined so far)")
        return idx - 1, size

    cells = []
    if face_size:
        flat, size = indices(face_tokens, face_size, face_base, face_line)
        start = np.cumsum(size) - size
        # consecutive faces of one size form a block; fan_triangles keeps the file's order
        cut = np.flatnonzero(np.diff(size)) + 1
        for lo, hi in zip(np.r_[0, cut], np.r_[cut, len(size)]):
            k = int(size[lo])
            block = flat[start[lo]:start[lo] + (hi - lo) * k].reshape(-1, k)
            cells.append(("triangle" if k == 3 else "polygon", block))
    if strand_size:
        flat, size = indices(strand_tokens, strand_size, strand_base, strand_line)
        # a polyline of k vertices gives k - 1 segments: all consecutive pairs, minus the
        # pairs that straddle two polylines
        pair = np.column_stack([flat[:-1], flat[1:]])
        last = np.cumsum(size) - 1
        cells.append(("line", np.delete(pair, last[:-1], axis=0)))
    return vertices, cells


def write_obj(path, mesh: Mesh, positions: np.ndarray) -> None:
    """Write ``mesh`` at ``positions`` [m] as OBJ: ``%.17g`` coordinates, strands as ``l``
    lines, so :func:`read_obj` gets the same mesh back exactly.

    Parameters
    ----------
    path : str or path-like
        The ``.obj`` file to write (overwritten).
    mesh : Mesh
        Connectivity: triangles (m, 3) and strands (e, 2).
    positions : ndarray, shape (n, 3)
        Vertex positions [m].
    """
    with atomic_path(path) as tmp, open(tmp, "w", encoding="utf-8") as f:
        f.write("# written by clothsim\n")
        np.savetxt(f, positions, fmt="v %.17g %.17g %.17g")
        np.savetxt(f, mesh.triangles + 1, fmt="f %d %d %d")
        np.savetxt(f, mesh.strands + 1, fmt="l %d %d")
