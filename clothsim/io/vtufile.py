"""A run's frame files written without re-encoding what every frame shares.

A frame's ``.vtu`` file holds its points and point and cell data, which change from frame to
frame, and the cells (connectivity, offsets, types), which do not: at 513² the cells are 21
of the 37 MB of a raw frame's arrays, base64-encoded (and zlib-compressed in a ``zlib``
frame) anew by ``meshio.write`` for every frame. :class:`VtuTemplate` encodes the cells once
per run and writes each frame's file as the very bytes ``meshio.write`` (binary, UInt32
headers, ``zlib`` or no compression) writes for it: meshio's layout, its comment naming the
installed meshio, its 32 KiB zlib blocks (tests/io/test_vtufile.py compares the two byte
for byte). meshio and ParaView read the files as before.
"""

from __future__ import annotations

import base64
import zlib

import numpy as np

#: meshio's VTK cell type numbers of the cell blocks frames hold.
VTK_TYPES = {"vertex": 1, "line": 3, "triangle": 5}
#: meshio's zlib block size [bytes].
BLOCK = 32768
_VTU_TYPES = {np.dtype(t): t.__name__.capitalize().replace("Uint", "UInt") for t in (
    np.float32, np.float64, np.int8, np.int16, np.int32, np.int64, np.uint8, np.uint16,
    np.uint32, np.uint64)}


def meshio_version() -> str:
    """The installed meshio's version (what its files' comment names), without importing it.

    Returns
    -------
    str
    """
    from importlib import metadata

    return metadata.version("meshio")


class VtuTemplate:
    """The frame files of one mesh: the cells encoded once, each frame's arrays per file.

    Parameters
    ----------
    blocks : list of (str, ndarray)
        Cell blocks (:func:`clothsim.io.cells.cell_blocks`: ``triangle``, ``line``,
        ``vertex``).
    n : int
        Points of every frame.
    compression : {"zlib", "none"}
    version : str, optional
        The meshio version the comment names (default: the installed one).
    """

    def __init__(self, blocks, n: int, compression: str, version: str | None = None):
        self.zlib = compression == "zlib"
        self.n = int(n)
        version = meshio_version() if version is None else version
        compressor = ' compressor="vtkZLibDataCompressor"' if self.zlib else ""
        cells = sum(len(c) for _, c in blocks)
        self._head = (f'<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="0.1" '
                      f'byte_order="LittleEndian"{compressor}>\n<!--This file was created by '
                      f'meshio v{version}-->\n<UnstructuredGrid>\n<Piece NumberOfPoints='
                      f'"{self.n}" NumberOfCells="{cells}">\n').encode()
        connectivity = np.concatenate([np.asarray(c).reshape(len(c), -1).flatten()
                                       for _, c in blocks])
        offsets = [c.shape[1] * np.arange(1, len(c) + 1, dtype=connectivity.dtype)
                   for _, c in blocks]
        for k in range(1, len(offsets)):
            offsets[k] += offsets[k - 1][-1]
        types = np.concatenate([np.full(len(c), VTK_TYPES[kind]) for kind, c in blocks])
        self._cells = b"<Cells>\n" + b"".join(
            self.array(name, a) for name, a in (("connectivity", connectivity),
                                                ("offsets", np.concatenate(offsets)),
                                                ("types", types))) + b"</Cells>\n"

    def array(self, name: str, data: np.ndarray) -> bytes:
        """One ``<DataArray>`` element as meshio writes it (binary, base64).

        Parameters
        ----------
        name : str
        data : ndarray, 1-D or 2-D
            Little-endian numbers of a type VTK names.

        Returns
        -------
        bytes
        """
        data = np.ascontiguousarray(data)
        components = f' NumberOfComponents="{data.shape[1]}"' if data.ndim == 2 else ""
        raw = data.tobytes()
        if self.zlib:
            count = -int(-len(raw) // BLOCK)
            chunks = [zlib.compress(raw[k:k + BLOCK]) for k in range(0, len(raw), BLOCK)]
            header = np.array([count, BLOCK, len(raw) - (count - 1) * BLOCK]
                              + [len(c) for c in chunks], dtype=np.uint32)
            text = base64.b64encode(header.tobytes()) + base64.b64encode(b"".join(chunks))
        else:
            text = base64.b64encode(np.uint32(len(raw)).tobytes() + raw)
        return (f'<DataArray type="{_VTU_TYPES[data.dtype]}" Name="{name}"{components} '
                f'format="binary">\n').encode() + text + b"\n</DataArray>\n"

    def write(self, path, points: np.ndarray, point_data: dict, cell_data: dict) -> None:
        """Write one frame's file.

        Parameters
        ----------
        path : path-like
        points : ndarray, shape (n, 3), float64
        point_data : dict of str to ndarray
            In the order they are written (as ``meshio.Mesh``'s ``point_data``).
        cell_data : dict of str to list of ndarray
            One array per cell block (as ``meshio.Mesh``'s ``cell_data``).
        """
        with open(path, "wb") as f:
            f.write(self._head)
            f.write(b"<Points>\n" + self.array("Points", points) + b"</Points>\n")
            f.write(self._cells)
            for tag, arrays in (("PointData", point_data), ("CellData", {
                    name: np.concatenate(parts) for name, parts in cell_data.items()})):
                if arrays:
                    f.write(f"<{tag}>\n".encode())
                    for name, a in arrays.items():
                        f.write(self.array(name, a))
                    f.write(f"</{tag}>\n".encode())
            f.write(b"</Piece>\n</UnstructuredGrid>\n</VTKFile>\n")


__all__ = ["VtuTemplate", "meshio_version", "VTK_TYPES", "BLOCK"]
