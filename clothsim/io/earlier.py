"""An earlier run's files in a run folder: what a fresh run removes
(:func:`remove_earlier_run`) and how much disk that frees (:func:`earlier_bytes`, counted
by the disk estimate before anything is written). Used by
:class:`clothsim.io.runfolder.RunFolder`.
"""

from __future__ import annotations

import logging
from pathlib import Path

from ..errors import InputError
from .diskspace import file_bytes
from .effectstate import state_files
from .folders import RUN_RECORD
from .frames import OBSTACLES_NAME, PVD_NAME
from .resume import FRAME_PATTERN

log = logging.getLogger(__name__)

#: A run's result files beside its frames.
RESULT_FILES = (PVD_NAME, "trajectory.npz", "preview.gif", "final.png", RUN_RECORD)
#: Files of an earlier run that a fresh run removes (besides its frame files).
STALE_FILES = RESULT_FILES + (OBSTACLES_NAME,)


def _frame_files(out: Path) -> list[Path]:
    return [p for p in out.glob("frame_*.vtu") if FRAME_PATTERN.fullmatch(p.name)]


def earlier_bytes(out) -> int:
    """Bytes of an earlier run's frames and result files in ``out`` (0 where none).

    Parameters
    ----------
    out : path-like
        A run folder.

    Returns
    -------
    int
    """
    out = Path(out)
    return file_bytes(_frame_files(out) + [out / name for name in STALE_FILES])


def remove_earlier_run(out, ours: bool) -> None:
    """Remove an earlier run's frames, result files and per-frame effect states from
    ``out``.

    Parameters
    ----------
    out : path-like
        A run folder.
    ours : bool
        The folder's run.json says clothsim wrote them (or the user forced it).

    Raises
    ------
    InputError
        Frame files there and not ``ours``: nothing is removed.
    """
    out = Path(out)
    frames = _frame_files(out)
    if frames and not ours:
        raise InputError(f"{out}: holds {len(frames)} frame files and no clothsim "
                         "run.json; refusing to delete files clothsim did not write "
                         "(choose another --out or remove them)")
    stale = frames + [out / name for name in STALE_FILES if (out / name).exists()]
    stale += state_files(out)   # the effects' state per frame (io.effectstate)
    for p in stale:
        p.unlink()
    if stale:
        log.info("removed %d files of an earlier run in %s", len(stale), out)


__all__ = ["RESULT_FILES", "STALE_FILES", "earlier_bytes", "remove_earlier_run"]
