"""The files of a run besides its frames: ``run.json`` and ``trajectory.npz``.

:class:`TrajectoryStore` appends positions and velocities frame by frame to two raw float64
files (a run never holds its trajectory in memory) and assembles ``trajectory.npz`` from
them in chunks. The folder that holds them, its lock and its status are
:class:`clothsim.io.runfolder.RunFolder`'s.
:func:`write_json` writes ``run.json`` atomically (strict JSON: non-finite floats become
strings); :func:`read_json` reads it.
"""

from __future__ import annotations

import json
import math
import os
import platform
import zipfile
from pathlib import Path

import numpy as np

from ..errors import InputError
from .common import atomic_path
from .folders import LOCK_NAME, FolderLock  # noqa: F401 - re-exported (their old home)

_CHUNK = 1 << 18  # bytes copied at a time when assembling trajectory.npz (256 kB)
#: A run's trajectory, assembled from its store at the end (:class:`TrajectoryStore`).
NPZ_NAME = "trajectory.npz"


def _json_default(obj):
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    return str(obj)  # a Path, a version, ...: as text


def _clean(value):
    """Non-finite floats become strings so run.json stays strict JSON."""
    if isinstance(value, float) and not math.isfinite(value):
        return repr(value)
    if isinstance(value, dict):
        return {k: _clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    return value


def write_json(path, data: dict) -> None:
    """Atomically write ``data`` as indented, strict JSON (numpy values become Python's).

    Parameters
    ----------
    path : str or path-like
        The file, e.g. ``run.json``.
    data : dict
        JSON-able values, numpy arrays and scalars, paths (non-finite floats: strings).
    """
    plain = json.loads(json.dumps(data, default=_json_default))
    text = json.dumps(_clean(plain), indent=1, allow_nan=False)
    with atomic_path(Path(path)) as tmp:
        tmp.write_bytes(text.encode("utf-8") + b"\n")


def read_json(path) -> dict | None:
    """The JSON object in ``path``, or None when it is missing, unreadable or not an object.

    Parameters
    ----------
    path : str or path-like
        The file, e.g. ``run.json``.

    Returns
    -------
    dict or None"""
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) else None


class TrajectoryStore:
    """Positions and velocities of a run, streamed to disk frame by frame.

    Two raw files, ``.positions.f64`` and ``.velocities.f64``, in ``folder`` receive one
    (n, 3) float64 block per frame; memory use does not depend on the number of frames.

    Parameters
    ----------
    folder : Path
        The run folder (exists).
    vertex_count : int
        n.
    """

    NAMES = ("positions", "velocities")

    def __init__(self, folder, vertex_count: int):
        self.folder = Path(folder)
        self.n = int(vertex_count)
        self.paths = {name: self.folder / f".{name}.f64" for name in self.NAMES}
        self._files = {name: _create(p) for name, p in self.paths.items()}
        self.count = 0

    @property
    def frame_bytes(self) -> int:
        """Bytes of one frame of one array: 24 n."""
        return self.n * 3 * 8

    def append(self, positions, velocities) -> None:
        """Append one frame: positions [m] and velocities [m/s], shape (n, 3) each.

        Parameters
        ----------
        positions, velocities : ndarray, shape (n, 3)
            Positions [m] and velocities [m/s].
        """
        for name, a in zip(self.NAMES, (positions, velocities)):
            a = np.ascontiguousarray(a, dtype="<f8")
            if a.shape != (self.n, 3):
                raise InputError(f"{name}: expected shape ({self.n}, 3), got {a.shape}")
            try:
                self._files[name].write(a.tobytes())
                self._files[name].flush()
            except OSError as exc:  # a full disk's error names no file
                exc.filename = exc.filename or str(self.paths[name])
                raise
        self.count += 1

    def view(self, name: str, count: int | None = None) -> np.ndarray:
        """A read-only memory map of the first ``count`` frames of ``name``, (count, n, 3).

        Parameters
        ----------
        name : {"positions", "velocities"}
        count : int, optional
            Frames to map; default all frames appended.

        Returns
        -------
        ndarray, shape (count, n, 3)
            Positions [m] or velocities [m/s] (read-only memmap; empty when count is 0).
        """
        count = self.count if count is None else int(count)
        if count == 0:
            return np.zeros((0, self.n, 3))
        return np.memmap(self.paths[name], dtype="<f8", mode="r", shape=(count, self.n, 3))

    def write_npz(self, path, count: int, extra: dict[str, np.ndarray]) -> None:
        """Atomically write ``trajectory.npz``: ``positions`` and ``velocities`` of frames
        0..count−1 (copied from the raw files in chunks), then the small ``extra`` arrays.

        The archive is what :func:`numpy.savez` writes (stored, not compressed).

        Parameters
        ----------
        path : str or path-like
            The ``.npz`` file.
        count : int
            Frames to write, ``0 <= count <=`` frames appended.
        extra : dict of str to ndarray
            More arrays, e.g. ``time`` (count,) [s], ``vertex_mass`` (n,) [kg]."""
        with atomic_path(Path(path)) as tmp:
            self._write_zip(tmp, count, extra)

    def write_npz_beside(self, path, count: int, extra: dict[str, np.ndarray]) -> Path:
        """:meth:`write_npz` into a temporary file beside ``path`` (the name
        :func:`~clothsim.io.common.atomic_path` gives it), which the caller moves onto
        ``path`` or deletes (:meth:`clothsim.io.runfolder.RunFolder.wait_last`).

        Parameters
        ----------
        path, count, extra
            As for :meth:`write_npz`.

        Returns
        -------
        Path
            The temporary file, complete (deleted again on an error)."""
        path = Path(path)
        tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp{path.suffix}")
        try:
            tmp.unlink(missing_ok=True)    # a link planted there is removed, never followed
            self._write_zip(tmp, count, extra)
        except BaseException:
            tmp.unlink(missing_ok=True)
            raise
        return tmp

    def _write_zip(self, path, count: int, extra: dict[str, np.ndarray]) -> None:
        count = int(count)
        if not 0 <= count <= self.count:
            raise InputError(f"count: must be in 0..{self.count}, got {count}")
        with zipfile.ZipFile(path, "w", zipfile.ZIP_STORED, allowZip64=True) as zf:
            for name in self.NAMES:
                self._files[name].flush()
                header = {"descr": np.lib.format.dtype_to_descr(np.dtype("<f8")),
                          "fortran_order": False, "shape": (count, self.n, 3)}
                with zf.open(f"{name}.npy", "w", force_zip64=True) as f, \
                        open(self.paths[name], "rb") as raw:
                    np.lib.format.write_array_header_1_0(f, header)
                    left = count * self.frame_bytes
                    while left > 0:
                        block = raw.read(min(_CHUNK, left))
                        if not block:
                            raise OSError(f"{self.paths[name]}: ends before frame {count}")
                        f.write(block)
                        left -= len(block)
            for name, a in extra.items():
                with zf.open(f"{name}.npy", "w", force_zip64=True) as f:
                    np.lib.format.write_array(f, np.asarray(a), allow_pickle=False)

    def close(self, *, remove: bool = True) -> None:
        """Close the raw files and (by default) delete them.

        Parameters
        ----------
        remove : bool
            Delete ``.positions.f64`` and ``.velocities.f64`` after closing."""
        for f in self._files.values():
            f.close()
        if remove:
            for p in self.paths.values():
                p.unlink(missing_ok=True)


def _create(path: Path):
    """A new file opened for writing: an earlier one (or a link) at ``path`` is removed
    first, and the file is created exclusively, never through a link."""
    path.unlink(missing_ok=True)
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o644)
    return os.fdopen(fd, "wb")


def package_versions() -> dict[str, str | None]:
    """Versions of python and of the packages a run depends on (None if not installed).

    Returns
    -------
    dict of str to str or None
        Distribution name (and ``"python"``) to version string.
    """
    from importlib import metadata

    out: dict[str, str | None] = {"python": platform.python_version()}
    for dist in ("clothsim", "numpy", "scipy", "meshio", "matplotlib", "scikit-sparse", "tqdm"):
        try:
            out[dist] = metadata.version(dist)
        except metadata.PackageNotFoundError:
            out[dist] = None
    return out


def write_trajectory(path: Path, model, positions, velocities, time) -> None:
    """Atomically write trajectory.npz from in-memory arrays (listed in clothsim.runner).

    Parameters
    ----------
    path : Path
        The ``.npz`` file.
    model : Model
        Its :func:`model_arrays` are stored too.
    positions, velocities : array_like, shape (f, n, 3)
        [m] and [m/s] of f frames.
    time : array_like, shape (f,)
        Time of each frame [s].
    """
    arrays = dict(positions=np.asarray(positions, np.float64),
                  velocities=np.asarray(velocities, np.float64),
                  time=np.asarray(time, np.float64), **model_arrays(model))
    with atomic_path(Path(path)) as tmp, open(tmp, "wb") as f:
        np.savez(f, **arrays)


def model_arrays(model) -> dict[str, np.ndarray]:
    """The arrays trajectory.npz holds besides the trajectory: ``triangles``, ``springs``,
    ``strands`` (int64) and ``vertex_mass`` (float64).

    Parameters
    ----------
    model : Model
        The simulated model.

    Returns
    -------
    dict of str to ndarray
        ``triangles`` (m, 3), ``springs`` (s, 2), ``strands`` (e, 2), ``vertex_mass`` (n,) [kg].
    """
    return dict(triangles=np.asarray(model.mesh.triangles, np.int64),
                springs=np.asarray(model.springs.spring_vertices, np.int64),
                strands=np.asarray(model.mesh.strands, np.int64),
                vertex_mass=np.asarray(model.vertex_mass, np.float64))


__all__ = ["NPZ_NAME", "TrajectoryStore", "FolderLock", "write_json", "read_json",
           "write_trajectory", "model_arrays", "package_versions", "LOCK_NAME"]
