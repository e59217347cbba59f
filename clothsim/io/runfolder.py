"""A run's folder: :class:`RunFolder` owns everything :func:`clothsim.runner.run_scene` puts
on disk.

It is the :class:`~clothsim.io.outfolder.OutputFolder` of kind ``run`` (claimed, locked,
its status in ``run.json``) and holds the run's frame writer
(:class:`~clothsim.io.frames.FrameWriter`: ``frame_%06d.vtu`` and ``trajectory.pvd``), its
trajectory store (:class:`~clothsim.io.runfiles.TrajectoryStore`, assembled into
``trajectory.npz``), its per-frame records, where ``--resume`` continues
(:meth:`RunFolder.resume_point`), and the removal of an earlier run before a fresh one. The
runner computes frames and hands them over; it never touches a file itself.
"""

from __future__ import annotations

import logging
import re
import time as _time
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from ..errors import InputError
from .folders import RUN_RECORD
from .frames import OBSTACLES_NAME, PVD_NAME, FrameWriter, read_frame
from .outfolder import OutputFolder
from .runfiles import TrajectoryStore, model_arrays, read_json

log = logging.getLogger(__name__)

FRAME_PATTERN = re.compile(r"frame_(\d{6})\.vtu")
RESULT_FILES = (PVD_NAME, "trajectory.npz", "preview.gif", "final.png", RUN_RECORD)
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


class RunFolder(OutputFolder):
    """The folder of one run (see the module docstring); use it as a context manager.

    Parameters
    ----------
    path : str or Path
        The run folder (created when missing).
    force : bool
        Write into a folder clothsim does not own (files named like a run's are replaced).
    guard : callable, optional
        As for :class:`~clothsim.io.outfolder.OutputFolder`.

    Attributes
    ----------
    previous : dict or None
        The folder's ``run.json`` before this run (None when missing or unreadable).
    info : dict
        What run.json says besides the status, the last frame and the records.
    records : list of dict
        One per frame 1..done.
    done : int
        The last complete frame (−1 before frame 0).
    """

    def __init__(self, path, *, force: bool = False, guard=None):
        super().__init__(path, "run", force=force, guard=guard)
        self.previous: dict | None = None
        self.info: dict = {}
        self.records: list[dict] = []
        self.done = -1
        self.npz_frames: int | None = None
        self.store: TrajectoryStore | None = None
        self.writer: FrameWriter | None = None
        self._wall = _time.perf_counter()
        self._npz_at = -np.inf   # perf_counter when trajectory.npz was last written
        self._npz_cost = 0.0     # seconds that took
        self._model = None
        self._fps = 1.0

    def __enter__(self) -> RunFolder:
        super().__enter__()
        self.previous = read_json(self.path / RUN_RECORD)
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        try:
            super().__exit__(exc_type, exc, tb)
        finally:
            if self.store is not None:
                self.store.close()

    def resume_point(self, shash: str, frames: int, inputs: dict | None = None) -> int | None:
        """The frame ``--resume`` continues from: the last k ≤ ``frames`` such that frames
        0..k are on disk, read back, and have a record in run.json.

        Parameters
        ----------
        shash : str
            :func:`clothsim.runner.scene_hash` of the scene to resume.
        frames : int
            Frames requested: the point is never beyond it.
        inputs : dict, optional
            :func:`clothsim.scene.inputs.input_hashes` of the scene now, compared with those
            run.json recorded at the start.

        Returns
        -------
        int or None
            None when no frame is on disk.

        Raises
        ------
        InputError
            The folder holds another scene's run, an input file changed since the run
            started (named), or frames no run record describes.
        """
        out, previous = self.path, self.previous
        last = completed_frames(out)
        if last is None:
            return None
        if previous is None or "clothsim_run" not in previous:
            raise InputError(f"{out}: frame files but no readable run.json; cannot check they "
                             "are this scene's, so cannot resume (run without --resume into "
                             "another folder)")
        recorded = previous.get("inputs")
        if inputs is not None and isinstance(recorded, dict):
            changed = changed_input(recorded, inputs)
            if changed:
                raise InputError(f"{out}: cannot resume: input file {changed}; the frames on "
                                 "disk are of the old input (run without --resume to start "
                                 "afresh)")
        if "scene_hash" not in previous:
            raise InputError(f"{out}: its run.json has no scene hash (an older clothsim wrote "
                             "it), so it cannot be checked to be this scene; cannot resume")
        if previous["scene_hash"] != shash:
            raise InputError(f"{out}: holds a run of a different scene (scene hash "
                             f"{previous['scene_hash']} here, {shash} now); cannot resume")
        k = 0
        while k < min(last, frames):  # the frames must read back; stop before a bad one
            try:
                read_frame(out / f"frame_{k + 1:06d}.vtu")
            except InputError as exc:
                log.warning("resuming before %s", exc)
                break
            k += 1
        log.info("%s: resuming a run whose run.json says %r", out, self.earlier.word)
        return self._recorded_through(k)

    def _recorded_through(self, start: int) -> int:
        """The last frame k <= start with records for frames 1..k in run.json: after
        SIGKILL, a full disk or ``--frames`` down then up, frames on disk may lack one."""
        recorded = {r.get("frame") for r in self.previous.get("frames", [])
                    if isinstance(r, dict)}
        k = 0
        while k < start and k + 1 in recorded:
            k += 1
        if k < start:
            log.info("frames %d..%d have no record in run.json; recomputing them", k + 1,
                     start)
        return k

    def clear_earlier_run(self) -> None:
        """A fresh run replaces an earlier one: remove its frames and result files.

        Raises
        ------
        InputError
            Frame files without a clothsim run.json beside them (and not ``force``).
        """
        out = self.path
        ours = self.force or (self.previous is not None and "clothsim_run" in self.previous)
        frames = [p for p in out.glob("frame_*.vtu") if FRAME_PATTERN.fullmatch(p.name)]
        if frames and not ours:
            raise InputError(f"{out}: holds {len(frames)} frame files and no clothsim "
                             "run.json; refusing to delete files clothsim did not write "
                             "(choose another --out or remove them)")
        stale = frames + [out / name for name in STALE_FILES if (out / name).exists()]
        for p in stale:
            p.unlink()
        if stale:
            log.info("removed %d files of an earlier run in %s", len(stale), out)

    def begin(self, info: dict, model, fps: float, *, pinned=None, compression: str = "auto",
              start: int | None = None) -> tuple[np.ndarray, np.ndarray] | None:
        """Open the frame writer and the trajectory store; resume from frame ``start``
        (frames 0..start read back) or, without one, start afresh (an earlier run removed,
        run.json marked ``writing`` before any frame).

        Parameters
        ----------
        info : dict
            What run.json records besides the status, last frame and frame records.
        model : Model
            The simulated model (its mesh and springs go into every frame).
        fps : float
            Frames per second; frame k is at time k / fps [s].
        pinned : callable, optional
            ``pinned(t)``: the pinned vertices at time t, written into each frame.
        compression : {"auto", "zlib", "none"}
            The frames' compression (:func:`clothsim.io.frames.choose_frame_compression`).
        start : int, optional
            The resume point (:meth:`resume_point`).

        Returns
        -------
        (positions, velocities) or None
            Frame ``start`` as read back when resuming, else None.
        """
        self.info, self._model, self._fps = info, model, fps
        if start is None:
            self.clear_earlier_run()
        self.store = TrajectoryStore(self.path, model.vertex_count)
        self.writer = FrameWriter(self.path, model.mesh, springs=model.springs,
                                  pinned=pinned, compression=compression)
        self.info["frame_compression"] = self.writer.compression_reason
        if start is None:
            self.mark("writing")  # the folder is a run folder before any frame exists
            return None
        for j in range(start + 1):
            x, v = read_frame(self.path / self.writer.filename(j))
            self.store.append(x, v)
        self.writer.adopt({j: j / fps for j in range(start + 1)})
        self.records = [r for r in self.previous.get("frames", [])
                        if isinstance(r, dict) and 1 <= r.get("frame", 0) <= start]
        self.done = start
        return x, v

    def add_static(self, name: str) -> None:
        """List the file ``name`` (written into the folder) beside every frame of
        ``trajectory.pvd``.

        Parameters
        ----------
        name : str
            E.g. ``obstacles.vtu``.
        """
        self.writer.add_static(name)

    def write_frame(self, k: int, positions, velocities, record: dict | None = None) -> None:
        """Frame k: its ``.vtu`` file, the store, its record (none for frame 0) and run.json
        with ``last_frame`` = k (trajectory.npz every few seconds, :meth:`save_npz`).

        Parameters
        ----------
        k : int
            The frame's index; frame k is at time k / fps.
        positions, velocities : ndarray, shape (n, 3)
            [m] and [m/s].
        record : dict, optional
            The frame's record (iterations, residual, ...).
        """
        self.writer.write(k, k / self._fps, positions, velocities)
        self.store.append(positions, velocities)
        if record is not None:
            self.records.append(record)
        self.done = k
        if k > 0:
            self.save_npz()
            self.mark("writing")

    def save_npz(self, force: bool = False) -> None:
        """Rebuild trajectory.npz from the store when forced, or when the time since the
        last rebuild exceeds both 2 s and 20 × its cost (at most ~5 % of the run's time).

        Parameters
        ----------
        force : bool

        Returns
        -------
        None
        """
        now = _time.perf_counter()
        if not force and now - self._npz_at < max(2.0, 20 * self._npz_cost):
            return
        count = self.done + 1
        self.store.write_npz(self.path / "trajectory.npz", count,
                             dict(time=np.arange(count) / self._fps,
                                  **model_arrays(self._model)))
        self.npz_frames = count
        self._npz_at = _time.perf_counter()
        self._npz_cost = self._npz_at - now

    def mark(self, status: str, record=None, *, error: str | None = None) -> None:
        """Write run.json: info, status, error, wall time [s], frame records.

        Parameters
        ----------
        status : {"writing", "complete", "interrupted", "failed"}
            Stored as run.json's words: ``running``, ``completed``, ``interrupted``,
            ``failed``.
        record : None
            Ignored: run.json is assembled from :attr:`info` and the records.
        error : str, optional
            One line, for interrupted and failed.
        """
        data = dict(self.info)
        data.update(status=None, last_frame=self.done if self.done >= 0 else None,
                    trajectory_frames=self.npz_frames, error=error,
                    wall_seconds=_time.perf_counter() - self._wall,
                    finished=(datetime.now(UTC).isoformat(timespec="seconds")
                              if status != "writing" else None),
                    frames=self.records)
        super().mark(status, data, error=error)

    def end(self, status: str, error: str | None) -> None:
        """trajectory.npz one last time (when any frame is done), then run.json.

        Parameters
        ----------
        status : {"complete", "interrupted", "failed"}
        error : str or None
            One line, for interrupted and failed.
        """
        if self.done >= 0:
            self.save_npz(force=True)
        self.mark(status, error=error)

    def trajectory(self, name: str = "positions", count: int | None = None) -> np.ndarray:
        """A read-only memory map of the frames in the store.

        Parameters
        ----------
        name : {"positions", "velocities"}
        count : int, optional
            Frames 0..count−1 (default: all written).

        Returns
        -------
        ndarray, shape (count, n, 3)
        """
        return self.store.view(name, count)

    def frame_files(self) -> list[Path]:
        """The frame files 0..done.

        Returns
        -------
        list of Path
        """
        return [self.path / self.writer.filename(j) for j in range(self.done + 1)]


__all__ = ["RunFolder", "completed_frames", "changed_input", "FRAME_PATTERN", "RESULT_FILES",
           "STALE_FILES"]
