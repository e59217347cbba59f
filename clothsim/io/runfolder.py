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

import copy
import logging
import os
import time as _time
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from . import frameproc
from .background import BackgroundJob
from .diskspace import check_run_plan, run_plan
from .earlier import RESULT_FILES, STALE_FILES, earlier_bytes, remove_earlier_run
from .effectstate import planned_state_bytes, write_state
from .folders import RUN_RECORD
from .frames import FrameWriter, read_frame
from .outfolder import OutputFolder
from .resume import FRAME_PATTERN, changed_input, completed_frames, recorded_through, resume_point
from .runfiles import NPZ_NAME, TrajectoryStore, model_arrays, read_json

log = logging.getLogger(__name__)


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
    state_bytes : int
        One frame's state file at most, stored (set before :meth:`begin`; 0: none).
    """

    def __init__(self, path, *, force: bool = False, guard=None):
        super().__init__(path, "run", force=force, guard=guard)
        self.previous: dict | None = None
        self.info: dict = {}
        self.records: list[dict] = []
        self.done = -1
        self.state_bytes = 0
        self.npz_frames: int | None = None
        self.store: TrajectoryStore | None = None
        self.writer: FrameWriter | None = None
        self._wall = _time.perf_counter()
        self._prebuilt: tuple[Path, int] | None = None   # (temporary npz, its frames)
        self._model = None
        self._fps = 1.0
        self._job = BackgroundJob()    # the frame being written in the background, if any

    def __enter__(self) -> RunFolder:
        super().__enter__()
        self.previous = read_json(self.path / RUN_RECORD)
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        try:
            super().__exit__(exc_type, exc, tb)
        finally:
            self._job.join()           # never leave a frame half-handled behind the lock
            if (process := getattr(self.writer, "process", None)) is not None:
                process.close()              # the frame process (io.frameproc), if any
            if self.store is not None:
                self.store.close()
            if self._prebuilt is not None:   # end was not reached
                self._prebuilt[0].unlink(missing_ok=True)

    def resume_point(self, shash: str, frames: int, inputs: dict | None = None, *,
                     scene: dict | None = None) -> int | None:
        """The frame ``--resume`` continues from: :func:`clothsim.io.resume.resume_point`
        of this folder and its run.json, cut to the frames run.json holds records of.

        Parameters
        ----------
        shash, frames, inputs, scene
            As for :func:`clothsim.io.resume.resume_point`.

        Returns
        -------
        int or None
            None when no frame is on disk.
        """
        k = resume_point(self.path, self.previous, shash, frames, inputs, scene=scene)
        if k is None:
            return None
        log.info("%s: resuming a run whose run.json says %r", self.path, self.earlier.word)
        return recorded_through(self.previous, k)

    def clear_earlier_run(self) -> None:
        """A fresh run replaces an earlier one: remove its frames and result files
        (:func:`clothsim.io.earlier.remove_earlier_run`).

        Raises
        ------
        InputError
            Frame files without a clothsim run.json beside them (and not ``force``).
        """
        remove_earlier_run(self.path, self.force or (
            self.previous is not None and "clothsim_run" in self.previous))

    def begin(self, info: dict, model, fps: float, *, frames: int | None = None, pinned=None,
              compression: str = "auto",
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
        frames : int, optional
            The last frame the run will write: the disk it needs is estimated
            (:meth:`plan`), warned about when large and refused when the disk does not hold
            it (:func:`clothsim.io.diskspace.check_run_plan`).
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
        self.writer = FrameWriter(self.path, model.mesh, springs=model.springs,
                                  pinned=pinned, compression=compression)
        self.info["frame_compression"] = self.writer.compression_reason
        if frameproc.wanted(model.vertex_count) and (frames is None or frames > (start or 0)):
            self.writer.process = frameproc.FrameProcess(self.writer)   # io.frameproc
        if frames is not None:
            self._plan(frames, start)  # before an earlier run goes: it may be refused
        if start is None:
            self.clear_earlier_run()
        for stale in self.path.glob(f".{NPZ_NAME}.*.tmp.npz"):   # a killed run's (locked:
            stale.unlink()                                      # no live writer's)
        self.store = TrajectoryStore(self.path, model.vertex_count)
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

    def plan(self, frames: int, start: int | None = None) -> dict:
        """The disk the run will use [bytes], estimated before anything is written
        (:func:`clothsim.io.diskspace.run_plan`).

        Parameters
        ----------
        frames : int
            The last frame the run writes.
        start : int, optional
            The resume point (frames 0..start are on disk already).

        Returns
        -------
        dict
            ``frame``, ``frames``, ``trajectory``, ``end`` and ``peak`` [bytes].
        """
        model_bytes = sum(a.nbytes for a in model_arrays(self._model).values())
        frame = self.writer.estimated_bytes() + (self.state_bytes and planned_state_bytes(
            self.state_bytes, self.writer.compression))
        return run_plan(frame, self._model.vertex_count, frames, start, model_bytes)

    def _plan(self, frames: int, start: int | None) -> None:
        """Warn about a large run, refuse one the disk cannot hold; run.json records the
        estimate as ``disk_estimate``."""
        plan = self.plan(frames, start)
        self.info["disk_estimate"] = plan
        reclaim = earlier_bytes(self.path) if start is None else 0  # a fresh run removes them
        check_run_plan(self.path, plan, frames, reclaim, self.writer.compression)

    def add_static(self, name: str) -> None:
        """List the file ``name`` (written into the folder) beside every frame of
        ``trajectory.pvd``.

        Parameters
        ----------
        name : str
            E.g. ``obstacles.vtu``.
        """
        self.writer.add_static(name)

    def write_frame(self, k: int, positions, velocities, record: dict | None = None, *,
                    wait: bool = True, state: dict | None = None) -> None:
        """Frame k: the store (at once), then its ``.vtu`` file, its record (none for frame
        0) and run.json with ``last_frame`` = k (trajectory.npz is written by :meth:`end`).

        Parameters
        ----------
        k : int
            The frame's index; frame k is at time k / fps.
        positions, velocities : ndarray, shape (n, 3)
            [m] and [m/s] (copied: the caller may reuse them).
        record : dict, optional
            The frame's record (iterations, residual, ...).
        wait : bool, default True
            False: return at once and write the frame on a background thread (see the
            module docstring); the previous frame handed over is waited for first, and its
            error, if any, raised here.
        state : dict of str to ndarray, optional
            What the effects carry into the next step (not to be changed by the caller):
            ``state/frame_%06d.npz``, written first (:mod:`clothsim.io.effectstate`).
        """
        self.wait()
        x = np.array(positions, dtype=np.float64)
        v = np.array(velocities, dtype=np.float64)
        info = copy.deepcopy(self.info)      # run.json as of now, whatever changes next
        self.store.append(x, v)   # raw and private: what end's trajectory.npz copies
        if wait:
            self._write_frame(k, x, v, record, info, state)
        else:
            self._job.start(self._write_frame, k, x, v, record, info, state,
                            name=f"clothsim frame {k}")

    def _write_frame(self, k: int, x, v, record: dict | None, info: dict,
                     state: dict | None = None) -> None:
        # first: a frame on disk has its state (compressed as the frames are)
        write_state(self.path, k, state or {}, compress=self.writer.compression == "zlib")
        self.writer.write(k, k / self._fps, x, v)
        if record is not None:
            self.records.append(record)
        self.done = k
        self._mark("writing", info=info)

    def wait(self) -> None:
        """Wait for the frame being written in the background, if any.

        Raises
        ------
        Exception
            The background write's error (e.g. OSError: the disk is full).
        """
        self._job.wait()

    def save_npz(self) -> None:
        """Rebuild trajectory.npz from the store now: frames 0..done (a resumed run's
        start, before its first new frame).

        Returns
        -------
        None
        """
        self.wait()
        self._save_npz()

    def _save_npz(self) -> None:
        count = self.done + 1
        self.store.write_npz(self.path / NPZ_NAME, count, self._npz_extra(count))
        self.npz_frames = count

    def _npz_extra(self, count: int) -> dict:
        return dict(time=np.arange(count) / self._fps, **model_arrays(self._model))

    def wait_last(self) -> None:
        """:meth:`wait` for the last frame handed over, building meanwhile trajectory.npz of
        every frame handed over (the store holds them) in a temporary file, which
        :meth:`end` moves into place once they are all on disk: the copy overlaps the last
        ``.vtu`` file (written by the frame process, :mod:`clothsim.io.frameproc`).
        """
        count = self.store.count
        if count and count != self.npz_frames and self._prebuilt is None:
            self._prebuilt = (self.store.write_npz_beside(self.path / NPZ_NAME, count,
                                                          self._npz_extra(count)), count)
        self.wait()

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
        self.wait()
        self._mark(status, error=error)

    def _mark(self, status: str, *, error: str | None = None, info: dict | None = None) -> None:
        data = dict(self.info if info is None else info)
        data.update(status=None, last_frame=self.done if self.done >= 0 else None,
                    trajectory_frames=self.npz_frames, error=error,
                    wall_seconds=_time.perf_counter() - self._wall,
                    finished=(datetime.now(UTC).isoformat(timespec="seconds")
                              if status != "writing" else None),
                    frames=self.records)
        super().mark(status, data, error=error)

    def end(self, status: str, error: str | None) -> None:
        """trajectory.npz one last time (when any frame is done and the last rebuild did
        not hold them all), then run.json.

        Parameters
        ----------
        status : {"complete", "interrupted", "failed"}
        error : str or None
            One line, for interrupted and failed.

        Raises
        ------
        Exception
            When ``status`` is "complete", the error of a frame written in the background
            (then nothing is marked: the caller's failure handling marks the run). For
            another status it is logged: the run already stops for a reason of its own.
        """
        error_in_flight = self._job.join()
        if error_in_flight is not None:
            if status == "complete":
                raise error_in_flight
            log.info("the frame being written when %s stopped failed too: %s", self.path,
                     error_in_flight)
        tmp, built = self._prebuilt or (None, None)   # by wait_last
        self._prebuilt = None
        if tmp is not None:
            try:   # used when it holds frames 0..done, which are all on disk now
                if built == self.done + 1 != self.npz_frames:
                    os.replace(tmp, self.path / NPZ_NAME)
                    self.npz_frames = built
            finally:
                tmp.unlink(missing_ok=True)
        if self.done >= 0 and self.npz_frames != self.done + 1:   # unless it holds them all
            self._save_npz()
        self._mark(status, error=error)

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
