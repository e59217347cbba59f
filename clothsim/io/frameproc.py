"""A large run's frame files written by a second process, on the machine's second core.

A run writes each frame on a background thread while the next frame is computed
(:meth:`clothsim.io.runfolder.RunFolder.write_frame`). Its colour fields and meshio's
encoding hold the GIL, and so do CHOLMOD's solves (scikit-sparse 0.4): at 513² the thread
took about half a second of the GIL per frame from the solves, one after the other on one
core. :class:`FrameProcess` does that work in a process of its own: the background thread
hands it the frame (through shared memory, :class:`SharedFrame`) and waits for its answer
(a pipe) without the GIL.

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
import mmap
import os
import pickle
import sys
import tempfile
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from .child import answer_stream, cores, end_child, send_answer, start_child

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
        self._proc = self._shared = None
        springs = None if writer.springs is None else SimpleNamespace(
            spring_vertices=writer.springs.spring_vertices,
            spring_rest_length=writer.springs.spring_rest_length)
        try:
            self._shared = SharedFrame(writer.mesh.vertex_count)
        except (OSError, ValueError) as exc:
            log.info("frames written in this process (no second one: %s)", exc)
        # the process starts, and is sent the mesh (tens of MB at 513²), with the first frame,
        # by the thread writing it: the run's own thread does not wait for either, and the
        # process's imports do not run beside the first factorization (runner: frame 0 is
        # handed over after it)
        self._init_file = None
        self._init = dict(out_dir=str(writer.out_dir), mesh=writer.mesh, springs=springs,
                          compression=writer.compression, parent=os.getpid(),
                          fd=None if self._shared is None else self._shared.fd)

    def _start(self) -> None:
        """Start the process; the writer's description goes with the first frame, its arrays
        (the mesh and springs) in a file the process inherits (:func:`pack`)."""
        try:
            self._init, self._init_file = pack(self._init)
            self._proc = start_child("clothsim.io.frameproc",
                                     (self._shared.fd, self._init_file.fileno()), light=True)
        except (OSError, ValueError, pickle.PickleError) as exc:
            log.info("frames written in this process (no second one: %s)", exc)
            self.close()

    @property
    def running(self) -> bool:
        """Whether the process runs and takes frames (or will start with the first one)."""
        return self._proc is not None or (self._init is not None and self._shared is not None)

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
        if self._init is not None and self._proc is None and self._shared is not None:
            self._start()   # the first frame
        if self._proc is None:
            return False
        self._shared.put(x, v, mask)   # the arrays through shared memory, the rest a pipe
        try:
            if self._init is not None:
                pickle.dump(self._init, self._proc.stdin, protocol=pickle.HIGHEST_PROTOCOL)
                self._init = None
            pickle.dump((str(path), mask is not None), self._proc.stdin,
                        protocol=pickle.HIGHEST_PROTOCOL)
            self._proc.stdin.flush()
            answer = pickle.load(self._proc.stdout)
            self._close_init()   # read by the process before it answered
        except (OSError, EOFError, pickle.PickleError, AttributeError, ValueError) as exc:
            log.info("frames written in this process from now on (the second one failed: "
                     "%s)", exc or type(exc).__name__)
            self.close()
            return False
        if answer is not None:
            raise answer
        return True

    def _close_init(self) -> None:
        init_file, self._init_file = self._init_file, None
        if init_file is not None:
            init_file.close()

    def close(self) -> None:
        """End the process (its input closes, it ends) and wait for it."""
        proc, self._proc = self._proc, None
        end_child(proc)
        self._close_init()
        shared, self._shared = self._shared, None
        if shared is not None:
            shared.close()


class SharedFrame:
    """One frame's positions, velocities and pinned mask in a memory-mapped file without a
    name (in ``/dev/shm`` where there is one), which the frame process inherits: a frame
    crosses in one copy, not through a pipe's 64 KiB at a time (at 513², 200 round trips
    between the processes, each waiting for a core on a loaded machine).

    Parameters
    ----------
    n : int
        Vertices.
    fd : int, optional
        The file, inherited (the frame process's side, read-only); default: a new one.

    Attributes
    ----------
    x, v : ndarray, shape (n, 3), float64
    mask : ndarray, shape (n,), bool
    fd : int
    """

    def __init__(self, n: int, fd: int | None = None):
        size = max(49 * n, 1)
        if fd is None:
            self._file = tempfile.TemporaryFile(dir=_shm_dir())
            fd = self._file.fileno()
            # its pages reserved now: a full /dev/shm (or disk) raises OSError here (no
            # process then), never SIGBUS when a frame is copied in
            os.posix_fallocate(fd, 0, size)
            self._map = mmap.mmap(fd, size)
        else:
            self._file = None
            self._map = mmap.mmap(fd, size, access=mmap.ACCESS_READ)
        self.fd = fd
        self.x = np.frombuffer(self._map, np.float64, 3 * n).reshape(n, 3)
        self.v = np.frombuffer(self._map, np.float64, 3 * n, 24 * n).reshape(n, 3)
        self.mask = np.frombuffer(self._map, np.bool_, n, 48 * n)

    def put(self, x, v, mask) -> None:
        """Copy one frame in (``mask`` None: left as it is).

        Parameters
        ----------
        x, v : ndarray, shape (n, 3)
        mask : ndarray of bool, shape (n,), or None
        """
        self.x[...] = x
        self.v[...] = v
        if mask is not None:
            self.mask[...] = mask

    def close(self) -> None:
        """Unmap and close the file (it has no name: it is gone).

        Returns
        -------
        None
        """
        self.x = self.v = self.mask = None
        try:
            self._map.close()
        except BufferError:  # pragma: no cover - a view still held somewhere
            pass
        if self._file is not None:
            self._file.close()


def _shm_dir() -> str | None:
    return "/dev/shm" if os.path.isdir("/dev/shm") else None


def pack(obj) -> tuple[dict, object]:
    """``obj`` as a small message and a file: pickled with its large buffers (contiguous
    arrays) out of band, written one after the other into a file without a name (in
    ``/dev/shm`` where there is one). Through a pipe, the mesh and springs of a 513² cloth
    (about 60 MB) took a thousand writes of 64 KiB, each taking Python's lock back from the
    first step's iterations; into the file, one write per array.

    Parameters
    ----------
    obj : object
        What to send (the writer's description).

    Returns
    -------
    (dict, file)
        The message for :func:`unpack` (the pickle, the buffers' sizes, the file's
        descriptor, which the process must inherit), and the file (close it once read).
    """
    buffers = []
    data = pickle.dumps(obj, protocol=5, buffer_callback=buffers.append)
    file = tempfile.TemporaryFile(dir=_shm_dir())
    sizes = []
    for buffer in buffers:
        raw = buffer.raw()
        file.write(raw)
        sizes.append(raw.nbytes)
    file.flush()
    return {"pickle": data, "sizes": sizes, "fd": file.fileno()}, file


def unpack(message: dict):
    """The object :func:`pack` sent (in the process that inherited its file; its arrays are
    copies, writable).

    Parameters
    ----------
    message : dict
        :func:`pack`'s message.

    Returns
    -------
    object
    """
    buffers = []
    with os.fdopen(message["fd"], "rb", buffering=0) as file:
        file.seek(0)
        for size in message["sizes"]:
            buffer = bytearray(size)
            view, done = memoryview(buffer), 0
            while done < size:
                got = file.readinto(view[done:])
                if not got:
                    raise EOFError("the writer's description is cut short")
                done += got
            buffers.append(buffer)
    return pickle.loads(message["pickle"], buffers=buffers)


def serve() -> None:
    """The process's side: read the writer's description, then write each frame asked for
    and answer None or the error raised. Ends when its input closes, or when its run is
    gone; the last file it wrote is removed if its run did not move it (killed).

    Returns
    -------
    None
    """
    from .frames import FrameWriter

    out = answer_stream()
    try:
        init = unpack(pickle.load(sys.stdin.buffer))
    except (EOFError, pickle.UnpicklingError):   # its run ended (mid-message)
        return
    writer = FrameWriter(init["out_dir"], init["mesh"], springs=init["springs"],
                         compression=init["compression"])
    shared = SharedFrame(init["mesh"].vertex_count, init["fd"])
    path = None
    while True:
        try:
            path, masked = pickle.load(sys.stdin.buffer)
        except (EOFError, pickle.UnpicklingError):   # its run ended (mid-message)
            if path is not None:   # killed before moving the last file: it goes
                Path(path).unlink(missing_ok=True)
            return
        try:
            writer.write_file(path, shared.x, shared.v, shared.mask if masked else None)
            answer = None
        except Exception as exc:  # noqa: BLE001 - handed to the run, raised there
            answer = exc
        if os.getppid() != init["parent"]:   # the run is gone: nobody moves the file
            Path(path).unlink(missing_ok=True)
            return
        send_answer(out, answer)


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


__all__ = ["FrameProcess", "SharedFrame", "PROCESS_FROM", "pack", "serve", "unpack", "wanted"]
