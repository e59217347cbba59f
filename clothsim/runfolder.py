"""What a run folder holds: its frames on disk, where ``--resume`` continues, and clearing
an earlier run before a fresh one (used by :func:`clothsim.runner.run_scene`)."""

from __future__ import annotations

import logging
import re
from pathlib import Path

from .display import OBSTACLES_NAME
from .errors import InputError
from .io.frames import read_frame
from .scene.inputs import changed_input

log = logging.getLogger(__name__)

FRAME_PATTERN = re.compile(r"frame_(\d{6})\.vtu")
RESULT_FILES = ("trajectory.pvd", "trajectory.npz", "preview.gif", "final.png", "run.json")
#: Files of an earlier run that a fresh run removes (besides its frame files).
STALE_FILES = RESULT_FILES + (OBSTACLES_NAME,)


def completed_frames(out_dir) -> int | None:
    """Index of the last frame k such that frames 0..k all exist in ``out_dir`` (None: none).

    The ``frame_%06d.vtu`` files on disk count (each is written atomically, so each one
    present is complete), whether or not ``trajectory.pvd`` is readable.

    Parameters
    ----------
    out_dir : str or Path
        A run folder.

    Returns
    -------
    int or None"""
    out = Path(out_dir)
    indices = {int(m.group(1)) for p in out.glob("frame_*.vtu")
               if (m := FRAME_PATTERN.fullmatch(p.name))}
    k = -1
    while k + 1 in indices:
        k += 1
    return None if k < 0 else k


def resume_point(out: Path, previous: dict | None, shash: str, frames: int,
                 inputs: dict | None = None) -> int | None:
    """The frame ``--resume`` continues from.

    Parameters
    ----------
    out : Path
        The run folder.
    previous : dict or None
        Its ``run.json`` (None when missing or unreadable).
    shash : str
        :func:`clothsim.runner.scene_hash` of the scene to resume.
    frames : int
        Frames requested: the point is never beyond it.
    inputs : dict, optional
        :func:`clothsim.scene.inputs.input_hashes` of the scene now: compared with the
        ``inputs`` its ``run.json`` recorded at the start.

    Returns
    -------
    int or None
        The last frame that reads back, of 0..min(last on disk, frames); None when no frame
        is on disk.

    Raises
    ------
    InputError
        The folder holds another scene's run, an input file changed since the run started
        (named), or frames no run record describes.
    """
    last = completed_frames(out)
    if last is None:
        return None
    if previous is None or "clothsim_run" not in previous:
        raise InputError(f"{out}: frame files but no readable run.json; cannot check they are "
                         "this scene's, so cannot resume (run without --resume into another "
                         "folder)")
    recorded = previous.get("inputs")
    if inputs is not None and isinstance(recorded, dict):
        changed = changed_input(recorded, inputs)
        if changed:
            raise InputError(f"{out}: cannot resume: input file {changed}; the frames on disk "
                             "are of the old input (run without --resume to start afresh)")
    if "scene_hash" not in previous:
        raise InputError(f"{out}: its run.json has no scene hash (an older clothsim wrote it), "
                         "so it cannot be checked to be this scene; cannot resume")
    if previous["scene_hash"] != shash:
        raise InputError(f"{out}: holds a run of a different scene (scene hash "
                         f"{previous['scene_hash']} here, {shash} now); cannot resume")
    k = 0
    while k < min(last, frames):  # the frames must read back; stop before the first bad one
        try:
            read_frame(out / f"frame_{k + 1:06d}.vtu")
        except InputError as exc:
            log.warning("resuming before %s", exc)
            break
        k += 1
    return k


def clear_earlier_run(out: Path, ours: bool) -> None:
    """A fresh run replaces an earlier one: remove its frames and result files.

    Parameters
    ----------
    out : Path
        The run folder.
    ours : bool
        The folder holds a clothsim run record (or ``--force`` was given).

    Returns
    -------
    None

    Raises
    ------
    InputError
        Frame files without a clothsim run.json beside them (and not ``ours``).
    """
    frames = [p for p in out.glob("frame_*.vtu") if FRAME_PATTERN.fullmatch(p.name)]
    if frames and not ours:
        raise InputError(f"{out}: holds {len(frames)} frame files and no clothsim run.json; "
                         "refusing to delete files clothsim did not write (choose another "
                         "--out or remove them)")
    stale = frames + [out / name for name in STALE_FILES if (out / name).exists()]
    for p in stale:
        p.unlink()
    if stale:
        log.info("removed %d files of an earlier run in %s", len(stale), out)


__all__ = ["completed_frames", "resume_point", "clear_earlier_run", "FRAME_PATTERN",
           "RESULT_FILES", "STALE_FILES"]
