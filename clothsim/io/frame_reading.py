"""Reading a run's frames back: :func:`read_frame` (one ``.vtu`` frame, bit for bit as
:class:`clothsim.io.frames.FrameWriter` wrote it) and :func:`read_pvd` (the frames a
ParaView collection lists). Split from :mod:`clothsim.io.frames`, which writes them and
still exports both names.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from ..errors import InputError
from .common import MeshioFailure, load_meshio, one_line, quietly


def read_pvd(path) -> list[tuple[float, Path]]:
    """(time [s], frame path) of each DataSet of the first part in a ParaView collection.

    Parameters
    ----------
    path : str or path-like
        A ``.pvd`` file, e.g. ``trajectory.pvd`` written by :class:`FrameWriter`.

    Returns
    -------
    list of (float, pathlib.Path)
        Time [s] and frame file (relative names resolved against the collection's
        folder) of each ``DataSet`` whose ``part`` is that of the first one, in file order
        (the cloth's frames; a run's ``obstacles.vtu``, listed as a further part, is left
        out).

    Raises
    ------
    InputError
        When the file cannot be read or parsed.
    """
    path = Path(path)
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError) as exc:
        raise InputError(f"{path}: cannot read collection ({one_line(exc)})") from None
    datasets = list(root.iter("DataSet"))
    first = datasets[0].get("part", "0") if datasets else "0"
    return [(float(ds.get("timestep")), path.parent / ds.get("file"))
            for ds in datasets if ds.get("part", "0") == first]


def read_frame(path) -> tuple[np.ndarray, np.ndarray]:
    """Read a frame written by :class:`FrameWriter`.

    Parameters
    ----------
    path : str or path-like
        A ``.vtu`` frame file with point data ``"velocity"``.

    Returns
    -------
    positions, velocities : ndarray, shape (n, 3), float64
        [m] and [m/s], exactly as written.

    Raises
    ------
    InputError
        When the file is missing, unreadable or has no ``"velocity"`` point data.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"frame: file not found: {path}")
    meshio = load_meshio()
    try:
        m = quietly(meshio.read, path, file_format="vtu")
    except MeshioFailure as exc:
        raise InputError(f"{path}: cannot read frame ({exc})") from None
    if "velocity" not in m.point_data:
        raise InputError(f"{path}: point data 'velocity' missing")
    x = np.asarray(m.points, dtype=np.float64)
    v = np.asarray(m.point_data["velocity"], dtype=np.float64)
    return x, v
