"""Frames of a run: one VTK ``.vtu`` file per frame and the ParaView collection
``trajectory.pvd`` listing them (and, beside each frame, the scene's static parts such as
``obstacles.vtu``, so that opening the one file shows the scene).

Frames are binary VTU, zlib-compressed or not (:func:`choose_frame_compression`, the
scene's ``[output] frame_compression``); meshio, ParaView and :func:`read_frame` read both.

:class:`FrameWriter` writes them (each file to a temporary name, then :func:`os.replace`,
so an interrupted run leaves only complete files); :mod:`clothsim.io.frame_reading` reads
them back (:func:`read_frame` bit for bit, :func:`read_pvd` lists a collection).
"""

from __future__ import annotations

import logging
import re
import xml.etree.ElementTree as ET
from importlib.metadata import PackageNotFoundError
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..mesh import Mesh
from .cells import FrameFields, cell_blocks
from .common import atomic_path, load_meshio
from .frame_reading import read_frame, read_pvd  # noqa: F401  (their home before)
from .vtufile import VtuTemplate

logger = logging.getLogger(__name__)

PVD_NAME = "trajectory.pvd"
#: File name of the obstacle surfaces in a run folder (beside ``trajectory.pvd``).
OBSTACLES_NAME = "obstacles.vtu"
FRAME_COMPRESSIONS = ("auto", "zlib", "none")
#: Vertices up to which "auto" compresses frames. meshio's zlib (level 6, one core) costs
#: microseconds of CPU per vertex and frame and shrinks the file to about a third, while
#: the raw write costs several times less (docs/data/scale-ladder.md, the "frame write"
#: table of benchmarks/scale_ladder.py): compression never saves time, only disk. Up to
#: 100 000 vertices (257² and smaller) it costs well under half a second a frame and small
#: frames are worth keeping small; above, it costs a second or more a frame, as much as a
#: step, for files that are large either way.
ZLIB_UP_TO = 100_000
#: Size of a zlib frame over a raw one, at most: 0.48 measured at 129² and 257² with
#: random velocities (nothing to compress there); a smooth cloth's frames shrink more
#: (0.12 for hanging at 21²), so a zlib run's estimate is an upper bound.
ZLIB_RATIO = 0.5


def choose_frame_compression(vertex_count: int, requested: str = "auto") -> tuple[str, str]:
    """How frames of a cloth of ``vertex_count`` vertices are written, and why.

    Parameters
    ----------
    vertex_count : int
        Vertices of the cloth.
    requested : {"auto", "zlib", "none"}
        ``[output] frame_compression``: "auto" decides by size (:data:`ZLIB_UP_TO`).

    Returns
    -------
    (str, str)
        "zlib" or "none", and the reason in one line.

    Raises
    ------
    InputError
        For an unknown ``requested``.
    """
    if requested not in FRAME_COMPRESSIONS:
        raise InputError(f"output.frame_compression: must be one of "
                         f"{', '.join(map(repr, FRAME_COMPRESSIONS))}, got {requested!r}")
    if requested != "auto":
        return requested, f"{requested}: requested by output.frame_compression"
    if vertex_count <= ZLIB_UP_TO:
        return "zlib", (f"zlib: {vertex_count} vertices <= {ZLIB_UP_TO}, where compressing "
                        f"a frame costs well under a second for a file a third the size")
    return "none", (f"none: {vertex_count} vertices > {ZLIB_UP_TO}, where zlib would cost "
                    f"about a second or more a frame (about 4 us per vertex)")


class FrameWriter:
    """Write a simulation frame by frame: ``<basename>_%06d.vtu`` + ``trajectory.pvd``.

    Each frame file holds the positions as points, the triangles and the strands (line
    cells) of ``mesh``, and float64 point data ``"velocity"`` [m/s]. A mesh with neither
    triangles nor strands gets its springs as line cells, or one vertex cell per vertex,
    so every frame reads back. Given ``springs``, frames also carry float32 point data
    ``"stretch"`` (mean |ℓ/r − 1| of the vertex's springs) and, for triangles, float32 cell
    data ``"area_ratio"`` (area over rest area, the rest shape being ``mesh.vertices``; NaN
    for line and vertex cells); given ``pinned``, uint8 point data ``"pinned"`` (1 pinned,
    0 free).
    ``trajectory.pvd`` (a ParaView collection) lists every frame written so far with its
    time [s] (``part="0"``), and with each frame every static part added by
    :meth:`add_static` (``part="1"``, …: ParaView shows them together as one multiblock);
    it is rewritten after each frame. Both are written to a temporary file and then
    :func:`os.replace` d, so after an interruption every listed file is complete.

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
    springs : clothsim.springs.Springs, optional
        The cloth's springs (``spring_vertices``, ``spring_rest_length``), for ``stretch``
        and as line cells of a cloth without triangles and strands.
    pinned : ndarray (n,) of bool, or callable, optional
        The pinned vertices, or a function of the frame's time [s] returning them (pins
        released in time).
    compression : {"auto", "zlib", "none"}
        The frames' data arrays zlib-compressed or raw (base64, as VTK's XML writers do
        without a compressor); "auto" by size (:func:`choose_frame_compression`).

    Attributes
    ----------
    compression : str
        "zlib" or "none", what is written.
    compression_reason : str
        Why, in one line (recorded in run.json).

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

    def __init__(self, out_dir, mesh: Mesh, *, basename: str = "frame", springs=None,
                 pinned=None, compression: str = "auto"):
        self.compression, self.compression_reason = choose_frame_compression(
            mesh.vertex_count, compression)
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
        self.springs = springs
        self.pinned = pinned
        self._static: list[str] = []
        self._cells = cell_blocks(mesh, None if springs is None else springs.spring_vertices)
        self._fields_of = None   # FrameFields, prepared by the first write (its thread)
        self._template = None    # its VtuTemplate (io.vtufile), likewise
        self.process = None      # a FrameProcess writing the files (io.frameproc), if any

    def filename(self, index: int) -> str:
        """File name of frame ``index``, e.g. ``frame_000012.vtu``.

        Parameters
        ----------
        index : int
            Frame number, >= 0.

        Returns
        -------
        str
            ``<basename>_<index:06d>.vtu`` (a name, not a path).
        """
        return f"{self.basename}_{index:06d}.vtu"

    def estimated_bytes(self) -> int:
        """Bytes of one frame file, estimated before any is written: within a few % for
        raw frames, an upper bound for zlib ones.

        Raw frames hold per vertex 24 bytes of positions, 24 of velocities, 4 of
        ``stretch`` and 1 of ``pinned``, per cell its vertex indices, an offset and a type
        (8 bytes each) and 4 of ``area_ratio``, base64-encoded (4/3); zlib frames are
        counted at :data:`ZLIB_RATIO` of that (``benchmarks/scale_ladder.py`` measures
        both).

        Returns
        -------
        int
        """
        per_vertex = 48 + (4 if self.springs is not None else 0) + (
            1 if self.pinned is not None else 0)
        per_cells = sum(len(c) * (8 * c.shape[1] + 20) for _, c in self._cells)
        data = (per_vertex * self.mesh.vertex_count + per_cells) * 4 / 3
        return int(data * (ZLIB_RATIO if self.compression == "zlib" else 1.0)) + 1024

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

        Returns
        -------
        pathlib.Path
            The frame file written.

        Raises
        ------
        InputError
            On a negative or non-integer ``index`` or arrays not of shape (n, 3).
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
        path = self.out_dir / self.filename(index)
        mask = None if self.pinned is None else np.asarray(
            self.pinned(time) if callable(self.pinned) else self.pinned, dtype=bool)
        with atomic_path(path) as tmp:   # by the frame process when there is one
            if self.process is None or not self.process.write(tmp, x, v, mask):
                self.write_file(tmp, x, v, mask)
        self._entries[index] = float(time)
        self._write_pvd()
        logger.debug("wrote %s (t = %g s)", path, time)
        return path

    def write_file(self, path, x: np.ndarray, v: np.ndarray, mask: np.ndarray | None) -> None:
        """Write one frame's ``.vtu`` file at ``path`` (no temporary name, no collection);
        :meth:`write` calls it, or the frame process does (:mod:`clothsim.io.frameproc`).

        Parameters
        ----------
        path : path-like
        x, v : ndarray, shape (n, 3), float64
            Positions [m] and velocities [m/s].
        mask : ndarray of bool, shape (n,), or None
            The pinned vertices (None: no ``pinned`` field)."""
        point_data, cell_data = {"velocity": v}, {}
        if mask is not None:
            point_data["pinned"] = mask.astype(np.uint8)
        if self.springs is not None:  # for colouring: float32 keeps the files small
            if self._fields_of is None:
                self._fields_of = FrameFields(self.mesh.vertices, self._cells,
                                              self.springs.spring_vertices,
                                              self.springs.spring_rest_length)
            with np.errstate(over="ignore"):  # beyond float32 (a cloth blown to 1e30 m): inf
                point_data["stretch"] = self._fields_of.stretch(x).astype(np.float32)
                if self.mesh.triangle_count:
                    cell_data["area_ratio"] = [a.astype(np.float32)
                                               for a in self._fields_of.area_ratio(x)]
        if self._template is None:
            try:   # the cells encoded once (io.vtufile): the bytes meshio.write writes
                self._template = VtuTemplate(self._cells, self.mesh.vertex_count,
                                             self.compression)
            except PackageNotFoundError:   # meshio without its metadata: meshio.write
                self._template = False
        if self._template:
            self._template.write(path, x, point_data, cell_data)
        else:
            meshio = load_meshio()
            meshio.write(path, meshio.Mesh(x, self._cells, point_data=point_data,
                                           cell_data=cell_data), file_format="vtu",
                         compression=None if self.compression == "none" else "zlib")

    def add_static(self, name: str) -> None:
        """List the file ``name`` (in the output folder, e.g. ``obstacles.vtu``) beside every
        frame of ``trajectory.pvd`` as a further part, and rewrite the collection.

        Parameters
        ----------
        name : str
            File name of a static part (written by the caller; it does not move).
        """
        if name not in self._static:
            self._static.append(name)
        if self._started:
            self._write_pvd()

    def adopt(self, entries: dict[int, float]) -> None:
        """Make the collection exactly ``entries`` (index → time [s], frame files already on
        disk) and rewrite ``trajectory.pvd``; later :meth:`write` calls add to it. Used to
        resume: the index then lists what is kept, even if the old one was unreadable.

        Parameters
        ----------
        entries : dict of int to float
            Frame index -> time [s] of each frame to list.
        """
        self._started = True
        self._entries = {int(i): float(t) for i, t in entries.items()}
        self._write_pvd()

    def frames(self) -> list[tuple[int, float, Path]]:
        """(index, time [s], path) of every frame in the collection, by index.

        Returns
        -------
        list of (int, float, pathlib.Path)
            Frame index, time [s] and frame file, sorted by index.
        """
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
                          file=self.filename(i), name="cloth")
            for part, name in enumerate(self._static, start=1):
                ET.SubElement(collection, "DataSet", timestep=repr(t), group="",
                              part=str(part), file=name, name=Path(name).stem)
        ET.indent(root)
        with atomic_path(self.pvd_path) as tmp:
            ET.ElementTree(root).write(tmp, encoding="utf-8", xml_declaration=True)
