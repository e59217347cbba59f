"""Files: meshes in, frames and matrices out. The only module that imports meshio.

Meshes
    :func:`read_mesh` reads any format meshio 5.3.5 reads; ``.obj`` goes through a small
    reader of clothsim's own (meshio's ignores ``l`` lines and negative indices).
    :func:`write_mesh` writes one.
Frames
    :class:`FrameWriter` writes one VTK ``.vtu`` file per frame (triangles, strands as line
    cells, point data ``velocity``) plus a ParaView collection ``trajectory.pvd`` listing
    each frame's time. Every file is written to a temporary name and moved into place with
    :func:`os.replace`, so an interrupted run leaves only complete files.
    :func:`read_frame` reads a frame back bit for bit.
Matrices
    :func:`write_matrix` / :func:`read_matrix` (Matrix Market, exact float64) and
    :func:`write_vector` / :func:`read_vector` (text, ``%.17g``) export M, L, J, … for
    other implementations. 3n-sized objects use the interleaved layout x0 y0 z0 x1 … .

meshio is imported inside the functions that use it, so ``import clothsim`` stays light.
"""

from __future__ import annotations

import logging
import os
import re
import xml.etree.ElementTree as ET
from contextlib import contextmanager, redirect_stderr, redirect_stdout
from io import StringIO
from pathlib import Path

import numpy as np

from .errors import InputError
from .mesh import Mesh, from_cells

logger = logging.getLogger(__name__)

PVD_NAME = "trajectory.pvd"


def _meshio():
    try:
        import meshio
    except ImportError as exc:  # pragma: no cover - meshio is a declared dependency
        raise ImportError("clothsim needs meshio for mesh files: pip install meshio") from exc
    return meshio


def _one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split()) or type(exc).__name__
    return text if len(text) < 200 else text[:197] + "..."


class _MeshioFailure(Exception):
    """meshio failed; the message is one line."""


def _quietly(call, *args, **kwargs):
    """Run a meshio function without letting it print or exit.

    On a file it cannot parse, meshio 5.3.5 prints the reason and calls ``sys.exit(1)``;
    here the output is captured and any failure becomes :class:`_MeshioFailure`.
    """
    buffer = StringIO()
    try:
        with redirect_stdout(buffer), redirect_stderr(buffer):
            return call(*args, **kwargs)
    except (Exception, SystemExit) as exc:
        said = " ".join(buffer.getvalue().split())
        text = _one_line(exc) if not isinstance(exc, SystemExit) else ""
        text = "; ".join(t for t in (said, text) if t) or type(exc).__name__
        raise _MeshioFailure(text if len(text) < 300 else text[:297] + "...") from exc


@contextmanager
def atomic_path(path):
    """Yield a temporary name beside ``path``; on success move it onto ``path``
    (:func:`os.replace`, atomic), otherwise delete it. Readers never see a partial file."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        yield tmp
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


def supported_formats() -> list[str]:
    """File extensions :func:`read_mesh` accepts (``.obj`` plus meshio's list)."""
    meshio = _meshio()
    return sorted(set(meshio.extension_to_filetypes) | {".obj"})


# --------------------------------------------------------------------------- meshes


def read_mesh(path, *, field: str = "mesh") -> Mesh:
    """Read a mesh file into a :class:`~clothsim.mesh.Mesh` (no checks; see ``mesh.load``).

    Parameters
    ----------
    path : str or os.PathLike
    field : str
        Name used in error messages.

    Raises
    ------
    InputError
        Missing file, unknown or unreadable format, or no triangles and no lines.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{field}: file not found: {path}")
    if path.suffix.lower() == ".obj":
        return _read_obj(path, field)
    meshio = _meshio()
    try:
        m = _quietly(meshio.read, path)
    except _MeshioFailure as exc:
        formats = " ".join(supported_formats())
        if path.suffix.lower() not in meshio.extension_to_filetypes:
            raise InputError(f"{field}: unknown mesh format {path.suffix or '(no extension)'!r} "
                             f"of {path}; supported formats: {formats}") from None
        raise InputError(f"{field}: cannot read {path} ({exc}); supported formats: "
                         f"{formats}") from None
    return from_cells(m.points, [(c.type, c.data) for c in m.cells], field=field)


def _read_obj(path: Path, field: str) -> Mesh:
    """Wavefront OBJ as a :class:`Mesh` (polygons fan-split; see :func:`read_obj_cells`)."""
    return from_cells(*read_obj_cells(path, field=field), field=field)


def read_obj_cells(path, *, field: str = "mesh") -> tuple[np.ndarray, list]:
    """Vertices and cell blocks of a Wavefront OBJ file, faces kept as written.

    Reads ``v`` (first 3 numbers), ``f`` with k >= 3 vertices (a ``"triangle"`` or
    ``"polygon"`` block per run of one size, in file order), ``f`` with 2 vertices and ``l``
    polylines (``"line"`` segments); ``i``, ``i/t``, ``i//n``, ``i/t/n`` and negative
    (relative) indices. Everything else (vt, vn, groups, materials) is ignored.

    Returns
    -------
    vertices : ndarray, shape (n, 3), float64
    cells : list of (str, ndarray (c, k) int64)
        0-based vertex indices, as :func:`clothsim.mesh.from_cells` takes them.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError as exc:
        raise InputError(f"{field}: cannot read {path}: {_one_line(exc)}") from None
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
        raise InputError(f"{field}: bad vertex coordinate: {_one_line(exc)}") from None

    def indices(tokens, size, base, lines):
        size = np.asarray(size, np.int64)
        try:
            idx = np.array([tok.split("/", 1)[0] for tok in tokens], dtype=np.int64)
        except ValueError as exc:
            raise InputError(f"{field}: bad vertex index: {_one_line(exc)}") from None
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


def _cell_blocks(mesh: Mesh) -> list[tuple[str, np.ndarray]]:
    blocks = []
    if mesh.triangle_count:
        blocks.append(("triangle", np.asarray(mesh.triangles)))
    if len(mesh.strands):
        blocks.append(("line", np.asarray(mesh.strands)))
    return blocks


def write_mesh(path, mesh: Mesh, positions=None, point_data=None) -> None:
    """Write ``mesh`` (at ``positions``, default its vertices) to ``path``.

    The format follows the extension (any meshio writes). ``.obj`` is written by clothsim
    with ``%.17g`` coordinates and strands as ``l`` lines, so :func:`read_mesh` gets the
    same mesh back exactly.

    Parameters
    ----------
    path : str or os.PathLike
    mesh : Mesh
    positions : ndarray, shape (n, 3), optional
        Vertex positions [m].
    point_data : dict of str to ndarray (n, …), optional
        Per-vertex arrays (ignored for ``.obj``).
    """
    path = Path(path)
    x = mesh.vertices if positions is None else np.asarray(positions, dtype=np.float64)
    if x.shape != mesh.vertices.shape:
        raise InputError(f"positions: expected shape {mesh.vertices.shape}, got {x.shape}")
    if path.suffix.lower() == ".obj":
        with open(path, "w", encoding="utf-8") as f:
            f.write("# written by clothsim\n")
            np.savetxt(f, x, fmt="v %.17g %.17g %.17g")
            np.savetxt(f, mesh.triangles + 1, fmt="f %d %d %d")
            np.savetxt(f, mesh.strands + 1, fmt="l %d %d")
        return
    meshio = _meshio()
    try:
        _quietly(meshio.write, path,
                 meshio.Mesh(x, _cell_blocks(mesh), point_data=dict(point_data or {})))
    except _MeshioFailure as exc:
        raise InputError(f"{path}: cannot write mesh ({exc})") from None


# --------------------------------------------------------------------------- frames


class FrameWriter:
    """Write a simulation frame by frame: ``<basename>_%06d.vtu`` + ``trajectory.pvd``.

    Each frame file holds the positions as points, the triangles and the strands (line
    cells) of ``mesh``, and the velocities [m/s] as float64 point data ``"velocity"``.
    ``trajectory.pvd`` (a ParaView collection) lists every frame written so far with its
    time [s] and is rewritten after each frame. Both are written to a temporary file and
    then :func:`os.replace` d, so after an interruption every listed file is complete.

    Resuming: the first :meth:`write` at index k > 0 keeps the entries of an existing
    ``trajectory.pvd`` with index < k (files already on disk) and drops those >= k; a
    first write at index 0 starts a new collection. Old frame files are never deleted.

    Parameters
    ----------
    out_dir : str or os.PathLike
        Created if missing.
    mesh : Mesh
        Connectivity written into every frame.
    basename : str
        Frame file prefix.

    Examples
    --------
    >>> import tempfile, numpy as np, clothsim as cs
    >>> mesh = cs.grid(3, 3)
    >>> with tempfile.TemporaryDirectory() as out:
    ...     writer = FrameWriter(out, mesh)
    ...     _ = writer.write(0, 0.0, mesh.vertices, np.zeros((9, 3)))
    ...     [p.name for _, _, p in writer.frames()]
    ['frame_000000.vtu']
    """

    def __init__(self, out_dir, mesh: Mesh, *, basename: str = "frame"):
        if not re.fullmatch(r"[A-Za-z0-9_.-]+", basename):
            raise InputError(f"basename: only letters, digits, '_', '.', '-' allowed, got "
                             f"{basename!r}")
        self.out_dir = Path(out_dir)
        self.out_dir.mkdir(parents=True, exist_ok=True)
        self.mesh = mesh
        self.basename = basename
        self.pvd_path = self.out_dir / PVD_NAME
        self._pattern = re.compile(re.escape(basename) + r"_(\d+)\.vtu")
        self._entries: dict[int, float] = {}
        self._started = False
        self._cells = _cell_blocks(mesh)

    def filename(self, index: int) -> str:
        """File name of frame ``index``, e.g. ``frame_000012.vtu``."""
        return f"{self.basename}_{index:06d}.vtu"

    def write(self, index: int, time: float, positions, velocities) -> Path:
        """Write frame ``index`` at ``time`` [s]; return its path.

        Parameters
        ----------
        index : int
            Frame number, >= 0.
        time : float
            Simulated time [s].
        positions, velocities : ndarray, shape (n, 3)
            [m] and [m/s]; stored as float64 bit for bit.
        """
        if int(index) != index or index < 0:
            raise InputError(f"index: must be a non-negative integer, got {index!r}")
        index = int(index)
        n = self.mesh.vertex_count
        x = np.ascontiguousarray(positions, dtype=np.float64)
        v = np.ascontiguousarray(velocities, dtype=np.float64)
        for name, a in (("positions", x), ("velocities", v)):
            if a.shape != (n, 3):
                raise InputError(f"{name}: expected shape ({n}, 3), got {a.shape}")
        if not self._started:
            self._started = True
            if index > 0:
                self._entries = {i: t for i, t in self._read_pvd().items() if i < index}
        meshio = _meshio()
        path = self.out_dir / self.filename(index)
        with atomic_path(path) as tmp:
            meshio.write(tmp, meshio.Mesh(x, self._cells, point_data={"velocity": v}),
                         file_format="vtu")
        self._entries[index] = float(time)
        self._write_pvd()
        logger.debug("wrote %s (t = %g s)", path, time)
        return path

    def frames(self) -> list[tuple[int, float, Path]]:
        """(index, time [s], path) of every frame in the collection, by index."""
        return [(i, t, self.out_dir / self.filename(i)) for i, t in sorted(self._entries.items())]

    def _read_pvd(self) -> dict[int, float]:
        """Entries of an existing trajectory.pvd whose frame file exists ({} if none)."""
        if not self.pvd_path.exists():
            return {}
        try:
            root = ET.parse(self.pvd_path).getroot()
        except ET.ParseError as exc:
            logger.warning("ignoring unreadable %s: %s", self.pvd_path, exc)
            return {}
        entries = {}
        for ds in root.iter("DataSet"):
            match = self._pattern.fullmatch(ds.get("file", ""))
            if match and (self.out_dir / match.group(0)).exists():
                entries[int(match.group(1))] = float(ds.get("timestep", "nan"))
        return entries

    def _write_pvd(self) -> None:
        root = ET.Element("VTKFile", type="Collection", version="0.1",
                          byte_order="LittleEndian")
        collection = ET.SubElement(root, "Collection")
        for i, t in sorted(self._entries.items()):
            ET.SubElement(collection, "DataSet", timestep=repr(t), group="", part="0",
                          file=self.filename(i))
        ET.indent(root)
        with atomic_path(self.pvd_path) as tmp:
            ET.ElementTree(root).write(tmp, encoding="utf-8", xml_declaration=True)


def read_pvd(path) -> list[tuple[float, Path]]:
    """(time [s], frame path) of each DataSet in a ParaView collection, in file order."""
    path = Path(path)
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError) as exc:
        raise InputError(f"{path}: cannot read collection ({_one_line(exc)})") from None
    return [(float(ds.get("timestep")), path.parent / ds.get("file"))
            for ds in root.iter("DataSet")]


def read_frame(path) -> tuple[np.ndarray, np.ndarray]:
    """Read a frame written by :class:`FrameWriter`.

    Returns
    -------
    positions, velocities : ndarray, shape (n, 3), float64
        [m] and [m/s], exactly as written.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"frame: file not found: {path}")
    meshio = _meshio()
    try:
        m = _quietly(meshio.read, path, file_format="vtu")
    except _MeshioFailure as exc:
        raise InputError(f"{path}: cannot read frame ({exc})") from None
    if "velocity" not in m.point_data:
        raise InputError(f"{path}: point data 'velocity' missing")
    x = np.asarray(m.points, dtype=np.float64)
    v = np.asarray(m.point_data["velocity"], dtype=np.float64)
    return x, v


# --------------------------------------------------------------------------- matrices


def write_matrix(path, A) -> None:
    """Write a sparse or dense matrix in Matrix Market format, float64 round-trip exact.

    Use a ``.mtx`` name. The 3n × 3n matrices (M, L, M + h²L) and the 3n × 3s matrix J use
    the interleaved layout of PAPER.md: row 3 i + c is coordinate c of vertex i.
    """
    import scipy.io

    with open(path, "wb") as f:
        scipy.io.mmwrite(f, A, precision=17)


def read_matrix(path):
    """Read a Matrix Market file: a ``scipy.sparse`` CSR matrix if stored sparse, else an
    ndarray."""
    import scipy.io
    import scipy.sparse

    path = Path(path)
    if not path.is_file():
        raise InputError(f"matrix: file not found: {path}")
    A = scipy.io.mmread(path)
    return scipy.sparse.csr_matrix(A) if scipy.sparse.issparse(A) else np.asarray(A)


def write_vector(path, v) -> None:
    """Write a vector as text, one number per line with ``%.17g`` (exact float64)."""
    np.savetxt(path, np.asarray(v, dtype=np.float64).ravel(), fmt="%.17g")


def read_vector(path) -> np.ndarray:
    """Read a vector written by :func:`write_vector`, shape (k,)."""
    return np.atleast_1d(np.loadtxt(path, dtype=np.float64))
