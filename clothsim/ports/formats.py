"""Trajectories in every format a port may write, read into one shape: (frames, n, 3).

Formats (chosen by the file name, or by ``fmt``):

``.npz``
    Any array key (``key``, default ``positions``); shape (frames, n, 3) or (frames, 3n).
``.npy``
    One array, same shapes.
``.txt``, ``.csv``, ``.dat``
    One frame a line of 3n numbers (x0 y0 z0 x1 …), separated by spaces or commas; ``#``
    starts a comment.
a folder of per-frame text files
    ``*.txt`` / ``*.csv`` sorted by the number in their names, each n lines of 3 numbers.
    A folder holding ``positions.txt`` (and ``velocities.txt``) is read as the one-line-per-frame
    layout of the shared port data instead; a run folder (``trajectory.npz`` or
    ``trajectory.pvd``) is read as that file.
``.bin``, ``.raw``, ``.f64``, ``.f32``
    Raw little-endian floats, frame after frame, vertex after vertex, x y z: element
    [f, i, c] at offset ((f · n + i) · 3 + c) · itemsize. Give ``dtype`` (``.f32`` and
    ``.f64`` imply it) and ``vertex_count`` (the frame count follows from the file size).
``.pvd``
    A ParaView collection of VTU frames (``clothsim run`` writes one).
"""

from __future__ import annotations

import re
import zipfile
from pathlib import Path

import numpy as np

from .. import io
from ..errors import InputError
from ..io.common import is_number, refuse_special
from ..io.folders import require_complete

TEXT_SUFFIXES = (".txt", ".csv", ".dat")
RAW_SUFFIXES = (".bin", ".raw", ".f64", ".f32")
FORMATS = ("npz", "npy", "text", "frames", "raw", "pvd")


def _as_frames(a: np.ndarray, source: str, vertex_count: int | None = None) -> np.ndarray:
    a = np.asarray(a)
    if a.dtype.kind not in "iuf":
        raise InputError(f"{source}: holds {a.dtype} values, not real numbers")
    a = a.astype(np.float64, copy=False)
    if a.size == 0:
        raise InputError(f"{source}: holds no numbers (shape {a.shape})")
    if a.ndim == 3 and a.shape[2] == 3:
        out = a
    elif a.ndim == 2 and a.shape[1] % 3 == 0 and not (a.shape[1] == 3 and vertex_count is None
                                                          and a.shape[0] > 1):
        out = a.reshape(len(a), -1, 3)
    elif a.ndim == 2 and a.shape[1] == 3:
        out = a[None]
    elif a.ndim == 1 and a.size % 3 == 0:
        out = a.reshape(1, -1, 3)
    else:
        raise InputError(f"{source}: expected (frames, n, 3) or (frames, 3n) numbers, "
                         f"got shape {a.shape}")
    if vertex_count is not None and out.shape[1] != vertex_count:
        raise InputError(f"{source}: {out.shape[1]} vertices per frame, expected {vertex_count}")
    return out


def _read_text(path: Path) -> np.ndarray:
    refuse_special(path)
    try:
        text = path.read_bytes().decode("utf-8")
    except UnicodeDecodeError as exc:
        raise InputError(f"{path}: not a text file: byte {exc.start} is not UTF-8") from None
    rows, numbers = [], []
    for n, line in enumerate(text.splitlines(), start=1):
        line = line.split("#", 1)[0].strip()
        if line:
            rows.append((n, line.replace(",", " ").split()))
    if not rows:
        raise InputError(f"{path}: no numbers")
    width = len(rows[0][1])
    for n, tokens in rows:
        if len(tokens) != width:
            raise InputError(f"{path}: line {n}: {len(tokens)} numbers where line "
                             f"{rows[0][0]} has {width} (lines hold different counts)")
        try:
            numbers.append([float(t) for t in tokens])
        except ValueError:
            bad = next(t for t in tokens if not is_number(t))
            raise InputError(f"{path}: line {n}: not a number: {bad[:40]!r}") from None
    return np.array(numbers, dtype=np.float64)


def _why(exc: BaseException) -> str:
    """What went wrong reading a file, in words (never the file's content)."""
    text = str(exc)
    if isinstance(exc, EOFError):
        return "the file ends early"
    if isinstance(exc, MemoryError):
        return "too large to read into memory"
    if isinstance(exc, UnicodeDecodeError):
        return f"byte {exc.start} is not text"
    if isinstance(exc, OSError):
        return exc.strerror or "cannot be read"
    if isinstance(exc, zipfile.BadZipFile):
        return "not a valid .npz (zip) archive"
    if "pickle" in text:
        return "holds pickled Python objects, not an array of numbers"
    return f"not a valid file of this format ({type(exc).__name__})"


def _frame_number(p: Path) -> tuple[int, str]:
    nums = re.findall(r"\d+", p.stem)
    return (int(nums[-1]) if nums else -1, p.name)


def read_trajectory(path, *, key: str = "positions", fmt: str | None = None,
                    dtype: str | None = None, vertex_count: int | None = None) -> np.ndarray:
    """Read a trajectory in any format of the module docstring.

    Parameters
    ----------
    path : path
        File or folder.
    key : str, default "positions"
        Array name in an ``.npz``; ``"velocities"`` also selects ``velocities.txt`` in a port
        folder and the velocity field of VTU frames.
    fmt : {"npz", "npy", "text", "frames", "raw", "pvd"}, optional
        Override the format implied by the name.
    dtype : {"float32", "float64"}, optional
        Raw files only.
    vertex_count : int, optional
        n; required for raw files, checked for the others.

    Returns
    -------
    ndarray, shape (frames, n, 3), float64

    Raises
    ------
    InputError
        One line naming the file (and the line of a text file) for anything it cannot
        read: a missing or special file, a malformed, truncated or pickled one, a wrong
        shape.
    """
    try:
        return _read_trajectory(path, key, fmt, dtype, vertex_count)
    except InputError:
        raise
    except (ValueError, TypeError, IndexError, KeyError, EOFError, OSError, MemoryError,
            zipfile.BadZipFile, RecursionError) as exc:
        raise InputError(f"{path}: cannot read: {_why(exc)}") from None


def _read_trajectory(path, key, fmt, dtype, vertex_count) -> np.ndarray:
    p = Path(path)
    require_complete(p)  # never half of one export and half of an earlier one
    if not p.exists():
        raise InputError(f"{path}: file not found")
    refuse_special(p, inside=True)  # a FIFO would block the read forever
    if p.is_dir() and fmt in (None, "frames"):
        name = "velocities" if key == "velocities" else "positions"
        for cand in (p / f"{name}.txt", p / "trajectory.npz", p / "trajectory.pvd"):
            if cand.is_file() and fmt is None:
                return read_trajectory(cand, key=key, dtype=dtype, vertex_count=vertex_count)
        files = sorted((f for f in p.iterdir() if f.suffix in TEXT_SUFFIXES), key=_frame_number)
        if not files:
            raise InputError(f"{path}: no positions.txt, trajectory.npz, trajectory.pvd or "
                             f"per-frame text files in this folder")
        frames = [_read_text(f) for f in files]
        if len({f.shape for f in frames}) != 1:
            raise InputError(f"{path}: the per-frame files hold different numbers of "
                             f"vertices ({files[0].name}: {len(frames[0])} lines)")
        return _as_frames(np.stack(frames), str(p), vertex_count)
    suffix = p.suffix.lower()
    if fmt is None:
        fmt = {".npz": "npz", ".npy": "npy", ".pvd": "pvd"}.get(suffix)
        fmt = fmt or ("text" if suffix in TEXT_SUFFIXES else "raw" if suffix in RAW_SUFFIXES
                      else None)
    if fmt not in FORMATS:
        raise InputError(f"{path}: unknown trajectory format (use --format one of "
                         f"{', '.join(FORMATS)})")
    if fmt == "npz":
        with np.load(p, allow_pickle=False) as data:
            if key not in data:
                raise InputError(f"{p}: has no array {key!r} (has {', '.join(data.files)}); "
                                 f"choose one with --key")
            return _as_frames(data[key], str(p), vertex_count)
    if fmt == "npy":
        a = np.load(p, allow_pickle=False)
        if not isinstance(a, np.ndarray):
            raise InputError(f"{p}: an .npz archive, not an .npy array (use --format npz)")
        return _as_frames(a, str(p), vertex_count)
    if fmt == "text":
        a = _read_text(p)
        return _as_frames(a if a.shape[1] != 3 else a[None], str(p), vertex_count)
    if fmt == "pvd":
        which = 1 if key == "velocities" else 0
        frames = [io.read_frame(f)[which] for _, f in io.read_pvd(p)]
        if not frames or len({f.shape for f in frames}) != 1:
            raise InputError(f"{p}: no frames, or frames with different vertex counts")
        return _as_frames(np.stack(frames), str(p), vertex_count)
    dtype = dtype or {".f32": "float32", ".f64": "float64"}.get(suffix)
    if dtype not in ("float32", "float64"):
        raise InputError(f"{path}: a raw file needs --dtype float32 or float64")
    if not vertex_count:
        raise InputError(f"{path}: a raw file needs --vertices N (the frame count follows)")
    frame_bytes = 3 * vertex_count * np.dtype(dtype).itemsize
    size = p.stat().st_size
    if size == 0 or size % frame_bytes:
        raise InputError(f"{path}: {size} bytes is not a whole number of frames of "
                         f"{vertex_count} vertices of {dtype} (at least one)")
    raw = np.fromfile(p, dtype=np.dtype(dtype).newbyteorder("<"))
    return raw.astype(np.float64).reshape(-1, vertex_count, 3)


def write_trajectory(path, frames, *, key: str = "positions", fmt: str | None = None,
                     dtype: str = "float64") -> Path:
    """Write (frames, n, 3) numbers in one format of the module docstring.

    Text uses ``%.17g`` (float64 round-trip exact; ``%.9g`` for ``dtype="float32"``); a
    ``frames`` folder gets ``frame_00000.txt`` …; raw is little-endian ``dtype``.

    Parameters
    ----------
    path : path
        File or folder to write; its suffix chooses the format unless ``fmt`` is given.
    frames : array_like, shape (frames, n, 3) or (frames, 3n)
        Positions [m] (or velocities [m/s]).
    key : str, default "positions"
        Array name in an ``.npz``.
    fmt : {"npz", "npy", "text", "frames", "raw"}, optional
        Override the format implied by the name.
    dtype : {"float64", "float32"}
        Precision of text digits and raw files.

    Returns
    -------
    Path
        What was written.
    """
    p = Path(path)
    a = np.asarray(frames, dtype=np.float64).reshape(len(frames), -1, 3)
    if fmt is None:
        suffix = p.suffix.lower()
        fmt = ({".npz": "npz", ".npy": "npy"}.get(suffix)
               or ("text" if suffix in TEXT_SUFFIXES else "raw" if suffix in RAW_SUFFIXES
                   else "frames" if not suffix else None))
    spec = "%.9g" if dtype == "float32" else "%.17g"
    if fmt == "npz":
        np.savez(p, **{key: a})
    elif fmt == "npy":
        np.save(p, a)
    elif fmt == "text":
        np.savetxt(p, a.reshape(len(a), -1), fmt=spec, delimiter="," if p.suffix == ".csv"
                   else " ")
    elif fmt == "frames":
        p.mkdir(parents=True, exist_ok=True)
        for f, x in enumerate(a):
            np.savetxt(p / f"frame_{f:05d}.txt", x, fmt=spec)
    elif fmt == "raw":
        a.astype(np.dtype(dtype).newbyteorder("<")).tofile(p)
    else:
        raise InputError(f"{path}: cannot write format {fmt!r} (one of npz, npy, text, "
                         f"frames, raw)")
    return p


def read_velocities(path, **options) -> np.ndarray | None:
    """The velocities stored with a trajectory, or None when the format holds none.

    Folders (``velocities.txt``, ``trajectory.npz``, ``trajectory.pvd``), ``.npz`` files with a
    ``velocities`` array and ``.pvd`` collections hold them; other files hold one field only.

    Parameters
    ----------
    path : path
        File or folder.
    **options
        Passed to :func:`read_trajectory` (``fmt``, ``dtype``, ``vertex_count``).

    Returns
    -------
    ndarray, shape (frames, n, 3), or None
        Velocities [m/s].
    """
    p = Path(path)
    if p.is_dir():
        if not any((p / f).is_file() for f in ("velocities.txt", "trajectory.npz",
                                                "trajectory.pvd")):
            return None
    elif p.suffix.lower() == ".npz":
        try:
            with np.load(p, allow_pickle=False) as data:
                if "velocities" not in data:
                    return None
        except (ValueError, OSError, EOFError, zipfile.BadZipFile, MemoryError) as exc:
            raise InputError(f"{p}: cannot read: {_why(exc)}") from None
    elif p.suffix.lower() != ".pvd":
        return None
    return read_trajectory(p, key="velocities", **options)
