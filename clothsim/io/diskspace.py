"""The disk a writer needs, known before it writes: estimates, a warning, a refusal.

:func:`run_plan` estimates what a run writes (its frames, ``trajectory.npz``, and while it
runs the trajectory store and the rebuilt ``trajectory.npz`` beside the old one) from the
frame writer's :meth:`~clothsim.io.frames.FrameWriter.estimated_bytes`;
:func:`check_run_plan` warns above :data:`DISK_WARNING` and refuses, before anything is
written, a run the disk cannot hold, naming how to need less.
"""

from __future__ import annotations

import logging
import shutil
from pathlib import Path

from ..errors import InputError

log = logging.getLogger(__name__)

#: A run that will write more than this [bytes] is announced with a warning (its size and
#: how to need less).
DISK_WARNING = 1e9


def gigabytes(count: float) -> str:
    """A byte count for a message: ``"4.4 GB"``, ``"49 MB"``, ``"12 kB"``.

    Parameters
    ----------
    count : float
        Bytes.

    Returns
    -------
    str
    """
    for unit, size in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if count >= size:
            value = count / size
            return f"{value:.2g} {unit}" if value < 10 else f"{value:.0f} {unit}"
    return f"{count:.0f} B"


def free_bytes(path) -> int | None:
    """Bytes free for an unprivileged writer on the disk holding ``path`` (None when it
    cannot be known).

    Parameters
    ----------
    path : str or Path
        A folder that exists.

    Returns
    -------
    int or None
    """
    try:
        return shutil.disk_usage(path).free
    except OSError:
        return None


def file_bytes(paths) -> int:
    """The summed size of the regular files among ``paths`` (links and missing ones: 0).

    Parameters
    ----------
    paths : iterable of Path

    Returns
    -------
    int
    """
    total = 0
    for p in paths:
        try:
            total += p.stat().st_size if p.is_file() and not p.is_symlink() else 0
        except OSError:
            pass
    return total


def run_plan(frame: int, vertex_count: int, frames: int, start: int | None = None,
             model_bytes: int = 0) -> dict:
    """The disk a run will use [bytes].

    Parameters
    ----------
    frame : int
        Bytes of one frame file (:meth:`clothsim.io.frames.FrameWriter.estimated_bytes`).
    vertex_count : int
        n: a frame of trajectory.npz holds 48 n bytes (positions and velocities, float64).
    frames : int
        The last frame the run writes.
    start : int, optional
        The resume point (frames 0..start are on disk already).
    model_bytes : int
        What trajectory.npz holds besides the frames (triangles, springs, masses).

    Returns
    -------
    dict
        ``frame`` (one frame file), ``frames`` (the frame files to write), ``trajectory``
        (trajectory.npz, and as much again in the store's raw files while the run lasts),
        ``model`` (what trajectory.npz holds besides the frames),
        ``end`` (frames + trajectory.npz) and ``peak`` (the end plus the store and a
        trajectory.npz rebuilt beside the old one).
    """
    new = frames - (-1 if start is None else start)
    trajectory = 48 * int(vertex_count) * (frames + 1) + int(model_bytes)
    end = new * frame + trajectory
    return {"frame": int(frame), "frames": new * frame, "trajectory": trajectory,
            "model": int(model_bytes), "end": end, "peak": end + 2 * trajectory}


def check_run_plan(folder: Path, plan: dict, frames: int, reclaim: int = 0,
                   compression: str = "zlib") -> None:
    """Refuse a run the disk cannot hold; warn about one above :data:`DISK_WARNING`.

    Parameters
    ----------
    folder : Path
        The run folder (exists).
    plan : dict
        :func:`run_plan`.
    frames : int
        The last frame the run writes.
    reclaim : int
        Bytes of an earlier run's files the run removes before it writes.
    compression : {"zlib", "none"}
        How the frames are written ("none": zlib is suggested).

    Raises
    ------
    InputError
        The peak exceeds the free disk (plus ``reclaim``): names the folder, the bytes
        needed and free, and ``--frames`` (how many fit), zlib frames or another ``--out``.
    """
    frame = plan["frame"]
    what = (f"{plan['frames'] // max(frame, 1)} frames of {gigabytes(frame)}, trajectory.npz "
            f"{gigabytes(plan['trajectory'])}, and while it runs its store and a rebuilt "
            f"trajectory.npz beside the old one")
    less = ("zlib frames need about half: --set output.frame_compression='zlib'"
            if compression == "none" else None)
    free = free_bytes(folder)
    if free is not None and plan["peak"] - reclaim > free:
        fixed = 3 * plan["model"]  # the store, the npz and its rebuilt copy hold ...
        per_frame = frame + 3 * (plan["trajectory"] - plan["model"]) / (frames + 1)  # ... and
        fits = int((free + reclaim - fixed) // per_frame) - 1  # a frame, frames 0..N each
        options = [o for o in (f"fewer frames (--frames {fits} fits)" if 0 < fits < frames
                               else None, less) if o]
        options = "; ".join(options + [f"{'or' if options else 'choose'} another --out on a "
                                       "larger disk"])
        raise InputError(f"{folder}: the run needs about {gigabytes(plan['peak'] - reclaim)} "
                         f"({what}) but {gigabytes(free)} are free on its disk; {options}")
    if plan["end"] > DISK_WARNING:
        log.warning("%s: this run will write about %s (%s; up to %s while it runs)%s",
                    folder, gigabytes(plan["end"]), what.split(", and")[0],
                    gigabytes(plan["peak"]), f"; {less}" if less else "")


__all__ = ["DISK_WARNING", "check_run_plan", "file_bytes", "free_bytes", "gigabytes",
           "run_plan"]
