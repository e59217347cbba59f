"""A large run's frame files written by a second process, on the machine's second core.

A run writes each frame on a background thread while the next frame is computed
(:meth:`clothsim.io.runfolder.RunFolder.write_frame`). Its colour fields and meshio's
encoding hold the GIL, and so do CHOLMOD's solves (scikit-sparse 0.4): at 513² the thread
took about half a second of the GIL per frame from the solves, one after the other on one
core. :class:`FrameProcess` does that work in a process of its own: the background thread
hands it the frame (a pipe) and waits for its answer without the GIL.

What is on disk stays true at every instant, as with the thread: the process writes the
frame's ``.vtu`` file under its temporary name (:func:`clothsim.io.common.atomic_path`),
the run moves it onto its name once the process says it is complete, and only then lists
it in ``trajectory.pvd`` and claims its record in ``run.json``. A process that finds its
run gone removes the file it was writing. The bytes are those the run would have written
itself (:meth:`clothsim.io.frames.FrameWriter.write_file`, on the same arrays). If the
process cannot start or dies, the run writes its frames itself from then on; an error
writing a frame (a full disk) is raised in the run as if it had written it.

Used for cloths of more than :data:`PROCESS_FROM` vertices on a machine with two cores or
more (smaller frames take a few milliseconds: a pipe's round trip would cost as much).
"""

from __future__ import annotations

import logging
import os
import pickle
import sys
from pathlib import Path
from types import SimpleNamespace

from .child import answer_stream, cores, end_child, start_child

log = logging.getLogger(__name__)

#: Cloths with more vertices have their frame files written by a second process.
PROCESS_FROM = 50_000


class FrameProcess:
    """The process writing one :class:`~clothsim.io.frames.FrameWriter`'s frame files (see
    the module docstring); :meth:`close` ends it.

    Parameters
    ----------
    writer : FrameWriter
        The writer whose files it writes (its mesh, springs and compression are sent once).
    """

    def __init__(self, writer):
        self._proc = None
        springs = None if writer.springs is None else SimpleNamespace(
            spring_vertices=writer.springs.spring_vertices,
            spring_rest_length=writer.springs.spring_rest_length)
        try:
            self._proc = start_child("clothsim.io.frameproc")
            pickle.dump(dict(out_dir=str(writer.out_dir), mesh=writer.mesh, springs=springs,
                             compression=writer.compression, parent=os.getpid()),
                        self._proc.stdin, protocol=pickle.HIGHEST_PROTOCOL)
            self._proc.stdin.flush()
        except (OSError, pickle.PicklingError) as exc:
            log.info("frames written in this process (no second one: %s)", exc)
            self.close()

    @property
    def running(self) -> bool:
        """Whether the process runs and takes frames."""
        return self._proc is not None

    def write(self, path, x, v, mask) -> bool:
        """Have the process write one frame file at ``path``; wait for it (without the GIL).

        Parameters
        ----------
        path : path-like
            The file to write (a temporary name: the caller moves it).
        x, v : ndarray, shape (n, 3), float64
            Positions [m] and velocities [m/s].
        mask : ndarray of bool, shape (n,), or None
            The pinned vertices (None: no ``pinned`` field).

        Returns
        -------
        bool
            True when the process wrote the file; False when there is no process or it
            failed (then it is ended, and the caller writes the file).

        Raises
        ------
        Exception
            What writing the file raised in the process (e.g. OSError: the disk is full).
        """
        if self._proc is None:
            return False
        try:
            pickle.dump((str(path), x, v, mask), self._proc.stdin,
                        protocol=pickle.HIGHEST_PROTOCOL)
            self._proc.stdin.flush()
            answer = pickle.load(self._proc.stdout)
        except (OSError, EOFError, pickle.PickleError, AttributeError, ValueError) as exc:
            log.info("frames written in this process from now on (the second one failed: "
                     "%s)", exc or type(exc).__name__)
            self.close()
            return False
        if answer is not None:
            raise answer
        return True

    def close(self) -> None:
        """End the process (its input closes, it ends) and wait for it."""
        proc, self._proc = self._proc, None
        end_child(proc)


def serve() -> None:
    """The process's side: read the writer's description, then write each frame asked for
    and answer None or the error raised. Ends when its input closes, or when its run is
    gone (then the file it was writing is removed).

    Returns
    -------
    None
    """
    from .frames import FrameWriter

    out = answer_stream()
    try:
        init = pickle.load(sys.stdin.buffer)
    except EOFError:
        return
    writer = FrameWriter(init["out_dir"], init["mesh"], springs=init["springs"],
                         compression=init["compression"])
    while True:
        try:
            path, x, v, mask = pickle.load(sys.stdin.buffer)
        except EOFError:
            return
        try:
            writer.write_file(path, x, v, mask)
            answer = None
        except Exception as exc:  # noqa: BLE001 - handed to the run, raised there
            answer = exc
        if os.getppid() != init["parent"]:   # the run is gone: nobody moves the file
            Path(path).unlink(missing_ok=True)
            return
        try:
            data = pickle.dumps(answer, protocol=pickle.HIGHEST_PROTOCOL)
        except Exception:  # noqa: BLE001 - an error that does not pickle: its text
            data = pickle.dumps(RuntimeError(f"{type(answer).__name__}: {answer}"))
        out.write(data)
        out.flush()


def wanted(vertex_count: int) -> bool:
    """Whether a cloth of ``vertex_count`` vertices has its frames written by a process.

    Parameters
    ----------
    vertex_count : int

    Returns
    -------
    bool
    """
    return vertex_count > PROCESS_FROM and cores() >= 2 and bool(sys.executable)


__all__ = ["FrameProcess", "PROCESS_FROM", "serve", "wanted"]
