"""Where ``--resume`` continues a run: the frames on disk, the scene and input files they
are of, and the records run.json keeps (used by :class:`clothsim.io.runfolder.RunFolder`)."""

from __future__ import annotations

import logging
import re
from pathlib import Path

from ..errors import InputError
from .frames import read_frame

log = logging.getLogger(__name__)

FRAME_PATTERN = re.compile(r"frame_(\d{6})\.vtu")


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
    indices = {int(m.group(1)) for p in Path(out_dir).glob("frame_*.vtu")
               if (m := FRAME_PATTERN.fullmatch(p.name))}
    k = -1
    while k + 1 in indices:
        k += 1
    return None if k < 0 else k


def changed_input(recorded: dict, now: dict) -> str | None:
    """The first input file whose content differs from what a run recorded.

    Parameters
    ----------
    recorded : dict of str to str
        ``run.json``'s ``inputs`` (path to sha256).
    now : dict of str to str
        :func:`clothsim.scene.inputs.input_hashes` of the scene about to resume.

    Returns
    -------
    str or None
        ``"<path>: ..."`` naming the file and what changed, or None when every file is as
        recorded.
    """
    for path in sorted(set(recorded) | set(now)):
        before, after = recorded.get(path), now.get(path)
        if before == after:
            continue
        if after is None:
            what = ("is missing now" if not Path(path).exists()
                    else "is no longer read by the scene")
        elif before is None:
            what = "is read by the scene now but was not when the run started"
        else:
            what = "changed since the run started (its content hash differs)"
        return f"{path}: {what}"
    return None


def scene_difference(before, now, key: str = "") -> str | None:
    """The first key at which two resolved scenes (``Scene.to_dict()``) differ, as
    ``"cloth.mass: 1.0 there, 2.0 now"``, leaving out ``scene.frames`` and ``[output]``
    (which change no state); None when they agree.

    Parameters
    ----------
    before, now : dict
        The scene a run folder's run.json recorded, and the scene to resume.
    key : str
        The key path of ``before`` and ``now`` (for the recursion).

    Returns
    -------
    str or None
    """
    if isinstance(before, dict) and isinstance(now, dict):
        names = sorted(set(before) | set(now), key=str)
        if not key and "scene" in names:  # another scene by name says so first
            names.remove("scene")
            names.insert(0, "scene")
        for name in names:
            sub = f"{key}.{name}" if key else str(name)
            if sub in ("scene.frames", "output", "scene.description"):
                continue
            found = scene_difference(before.get(name), now.get(name), sub)
            if found:
                return found
        return None
    if isinstance(before, list) and isinstance(now, list) and len(before) == len(now):
        for i, (a, b) in enumerate(zip(before, now)):
            found = scene_difference(a, b, f"{key}[{i}]")
            if found:
                return found
        return None
    if before == now:
        return None

    def shown(value):
        return "missing" if value is None else repr(value)[:60]
    return f"{key}: {shown(before)} there, {shown(now)} now"


def resume_point(out: Path, previous: dict | None, shash: str, frames: int,
                 inputs: dict | None = None, *, scene: dict | None = None) -> int | None:
    """The last frame k <= ``frames`` such that frames 0..k are on disk and read back, once
    the folder is checked to hold this scene's run.

    Parameters
    ----------
    out : Path
        The run folder.
    previous : dict or None
        Its run.json (None when missing or unreadable).
    shash : str
        :func:`clothsim.runner.scene_hash` of the scene to resume.
    frames : int
        Frames requested: the point is never beyond it.
    inputs : dict, optional
        :func:`clothsim.scene.inputs.input_hashes` of the scene now, compared with those
        run.json recorded at the start.
    scene : dict, optional
        The resolved scene now (``Scene.to_dict()``): a refusal names the first key at which
        it differs from the one run.json recorded.

    Returns
    -------
    int or None
        None when no frame is on disk.

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
        differs = (scene_difference(previous.get("scene"), scene) if scene is not None
                   else None) or f"scene hash {previous['scene_hash']} there, {shash} now"
        raise InputError(f"{out}: cannot resume: it holds a run of a different scene "
                         f"({differs}); run without --resume to start afresh, or choose "
                         "another --out")
    k = 0
    while k < min(last, frames):  # the frames must read back; stop before the first bad one
        try:
            read_frame(out / f"frame_{k + 1:06d}.vtu")
        except InputError as exc:
            log.warning("resuming before %s", exc)
            break
        k += 1
    return k


def recorded_through(previous: dict, start: int) -> int:
    """The last frame k <= start with records for frames 1..k in ``previous`` (run.json):
    after SIGKILL, a full disk or ``--frames`` down then up, frames on disk may lack one.

    Parameters
    ----------
    previous : dict
        The run's run.json.
    start : int
        The last frame on disk that reads back.

    Returns
    -------
    int
    """
    recorded = {r.get("frame") for r in previous.get("frames", []) if isinstance(r, dict)}
    k = 0
    while k < start and k + 1 in recorded:
        k += 1
    if k < start:
        log.info("frames %d..%d have no record in run.json; recomputing them", k + 1, start)
    return k


__all__ = ["FRAME_PATTERN", "changed_input", "completed_frames", "recorded_through",
           "resume_point"]
