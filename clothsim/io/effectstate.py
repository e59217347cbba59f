"""What the effects carry from frame k into the next step, one file per frame:
``state/frame_%06d.npz`` in a run folder (used by :class:`clothsim.io.runfolder.RunFolder`).

Positions and velocities (the frame's ``.vtu``) and the solver's state (``run.json``) are
not all a step starts from: an obstacle in the default contact mode ``"hold"`` hands the
next step the contacts it holds (:class:`clothsim.effects.holding.Holding`: which
vertices, their planes, sticking or sliding, normal forces). ``--resume`` from frame k
restores them from this file, so that the resumed run repeats the uninterrupted one bit for
bit. The arrays are :func:`clothsim.effects.base.effect_states`' (keys
``"<effect index>.<kind>.<name>"``) in a NumPy archive, compressed when the run's frames
are (``[output] frame_compression``): with every vertex held it is about as large as a
frame file stored, a third of that compressed, and compressing it costs a fraction of what
compressing the frame does (both on the background thread that writes the frames).

Each file is written atomically, and before the frame's ``.vtu`` file and its record in
``run.json``: a frame on disk always has its state beside it. A run whose effects carry
nothing (no obstacle in ``"hold"`` mode) writes no state files; a run folder written by a
clothsim before this file existed has none: :func:`restore_state` then warns that the
contacts start empty (the resumed run is a valid simulation, not the uninterrupted one bit
for bit) rather than refusing, which would throw away a long run's frames; run.json
records ``effect_state_restored``.
"""

from __future__ import annotations

import logging
import zipfile
from pathlib import Path

import numpy as np

from ..effects.base import effect_states, restore_effect_states
from ..errors import InputError
from .common import atomic_path
from .frames import ZLIB_RATIO

log = logging.getLogger(__name__)

#: The folder of the state files inside a run folder.
STATE_DIR = "state"


def state_path(out, k: int) -> Path:
    """The state file of frame k in the run folder ``out``.

    Parameters
    ----------
    out : str or Path
    k : int

    Returns
    -------
    Path
        ``out/state/frame_%06d.npz``.
    """
    return Path(out) / STATE_DIR / f"frame_{k:06d}.npz"


def planned_state_bytes(bound: int, compression: str) -> int:
    """The disk one frame's state file is planned for (:mod:`clothsim.io.diskspace`).

    Parameters
    ----------
    bound : int
        Its arrays' bytes at most (:meth:`clothsim.effects.base.Effect.state_bytes` summed).
    compression : {"zlib", "none"}
        The frames' compression, which the state file follows.

    Returns
    -------
    int
        ``bound``, or :data:`~clothsim.io.frames.ZLIB_RATIO` of it compressed (an upper
        bound: the normals, offsets and vertex numbers compress well, the forces less).
    """
    return int(bound * (ZLIB_RATIO if compression == "zlib" else 1.0))


def write_state(out, k: int, arrays: dict[str, np.ndarray], *,
                compress: bool = True) -> Path | None:
    """Write frame k's state atomically (nothing when ``arrays`` is empty).

    Parameters
    ----------
    out : str or Path
        The run folder.
    k : int
        The frame.
    arrays : dict of str to ndarray
        :func:`clothsim.effects.base.effect_states` after frame k's last step.
    compress : bool, default True
        :func:`numpy.savez_compressed` rather than :func:`numpy.savez`.

    Returns
    -------
    Path or None
        The file written.
    """
    if not arrays:
        return None
    path = state_path(out, k)
    path.parent.mkdir(exist_ok=True)
    with atomic_path(path) as tmp, open(tmp, "wb") as f:
        (np.savez_compressed if compress else np.savez)(f, **arrays)
    return path


def read_state(out, k: int) -> dict[str, np.ndarray] | None:
    """Frame k's state as :func:`write_state` wrote it.

    Parameters
    ----------
    out : str or Path
        The run folder.
    k : int
        The frame.

    Returns
    -------
    dict of str to ndarray or None
        None when the file is missing (the effects carried nothing, or an older clothsim
        wrote the run).

    Raises
    ------
    InputError
        The file is there but unreadable (naming it).
    """
    path = state_path(out, k)
    if not path.exists():
        return None
    try:
        with np.load(path, allow_pickle=False) as data:
            return {key: data[key] for key in data.files}
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as exc:
        raise InputError(f"{path}: cannot read the effects' state of frame {k} ({exc}); "
                         f"cannot resume from it (run without --resume to start afresh)",
                         field=str(path)) from None


def restore_state(folder, k: int, effects) -> bool | None:
    """Give ``effects`` the state saved with frame k in a run folder.

    Parameters
    ----------
    folder : RunFolder
        The run folder (:class:`clothsim.io.runfolder.RunFolder`), resuming.
    k : int
        The frame the run resumes from.
    effects : sequence of Effect
        The simulation's effects, bound.

    Returns
    -------
    bool or None
        None: no effect carries state; True: restored (or k = 0, the state every effect is
        bound with); False: frame k has no state file (an older clothsim wrote the run):
        the effects keep the state they were bound with, with a warning.

    Raises
    ------
    InputError
        The file is unreadable or does not fit the effects (naming it).
    """
    if not effect_states(effects):
        return None
    out = folder.path
    saved = read_state(out, k)
    if saved is None:
        if k > 0:
            log.warning("%s: frame %d has no saved effect state (%s/frame_%06d.npz; an older "
                        "clothsim wrote the run): the obstacles' held contacts start empty, so "
                        "the resumed run is not bit for bit the uninterrupted one",
                        out, k, STATE_DIR, k)
        return k == 0
    restore_effect_states(effects, saved, str(state_path(out, k)))
    return True


def state_files(out) -> list[Path]:
    """Every state file in the run folder ``out`` (a fresh run removes them).

    Parameters
    ----------
    out : str or Path

    Returns
    -------
    list of Path
    """
    return sorted((Path(out) / STATE_DIR).glob("frame_*.npz"))


__all__ = ["STATE_DIR", "planned_state_bytes", "read_state", "restore_state", "state_files",
           "state_path", "write_state"]
