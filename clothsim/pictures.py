"""A large run's pictures drawn in a second process, on the machine's second core.

:func:`clothsim.plotting.draw_run_pictures` holds the GIL for most of its second or so;
drawn on a thread beside the run it waits for the frame writer (and the writer for it), so
after the last step a large run paid the pictures and the last frame's write one after the
other. :class:`PictureProcess` starts a Python process once the run's first frame is
computed, with the mesh (it imports clothsim, matplotlib and Pillow beside the next frames'
solves, which hold the GIL on one core) and hands it the frames once the last one is
computed (the store's name: a few hundred bytes): it draws while the main process writes the
last frame, ``trajectory.npz`` and ``run.json``. The pictures are the very bytes the runner
would have drawn itself (the same function on the same positions: every frame memory-mapped
from the run's trajectory store, which holds the last one since it was handed over), and
they are written by the runner, once the run is complete, as before.

It is used for cloths of more than :data:`PROCESS_FROM` vertices on a machine with two
cores or more, when more than one frame is computed (smaller and shorter runs end before
the process would have imported matplotlib). The
process runs in a session of its own, so Ctrl-C at the terminal reaches the run alone (which
then ends it); it also ends by itself when its input closes, which the end of the run, or
of the run's process, does. If it cannot start or dies, the runner draws the pictures itself.
"""

from __future__ import annotations

import logging
import pickle
import sys

import numpy as np

from .io.child import answer_stream, end_child, send_answer, start_child
from .io.child import cores as _cores
from .io.frameproc import pack, unpack
from .plotting import draw_run_pictures

log = logging.getLogger(__name__)

#: Cloths with more vertices have their pictures drawn in a second process (the steps of
#: the first frames then outlast its start, ~1 s of the other core's time).
PROCESS_FROM = 50_000


#: What a picture reads of each kind of effect (:func:`clothsim.display.obstacle_surfaces`,
#: :func:`clothsim.display.pinned_points`).
SHOWN = {"plane": ("normal", "point", "thickness"), "sphere": ("center", "radius"),
         "box": ("min", "max"), "pin": ("vertices",)}


class ShownEffect:
    """What the pictures read of one effect, without the model and simulation a bound
    effect refers to (which do not pickle, and would be large): an obstacle's shape, a
    pin's vertices and whether it holds at each time drawn.

    Parameters
    ----------
    effect : Effect
        A plane, sphere, box or bound pin (:data:`SHOWN`).
    times : ndarray
        The times [s] the pictures are drawn at.
    """

    def __init__(self, effect, times):
        self.kind = effect.kind
        for name in SHOWN[self.kind]:
            if hasattr(effect, name) or name != "thickness":
                setattr(self, name, getattr(effect, name))
        if self.kind == "pin":
            self.model = True   # bound (pinned_points draws bound pins only)
            self._holds = {float(t): bool(effect.active(float(t))) if hasattr(effect, "active")
                           else True for t in times}

    def active(self, t: float) -> bool:
        """Whether the pin holds at time t.

        Parameters
        ----------
        t : float
            One of the times drawn [s].

        Returns
        -------
        bool
        """
        return self._holds[float(t)]


def shown_effects(effects, times) -> list[ShownEffect]:
    """:class:`ShownEffect` of each effect a picture draws (obstacles, bound pins).

    Parameters
    ----------
    effects : iterable of Effect
    times : ndarray
        The times [s] drawn.

    Returns
    -------
    list of ShownEffect
    """
    return [ShownEffect(e, times) for e in effects if getattr(e, "kind", "") in SHOWN
            and not (e.kind == "pin" and getattr(e, "model", None) is None)]


class PictureProcess:
    """A process that draws one run's ``preview.gif`` and ``final.png`` (see the module
    docstring); use it as a context manager, or call :meth:`close`.

    Parameters
    ----------
    vertex_count : int
        The cloth's vertices: :meth:`start` starts the process only above
        :data:`PROCESS_FROM`, on two cores or more (otherwise :meth:`request` returns False
        and the caller draws).

    Attributes
    ----------
    running : bool
        Whether a process was started and may take :meth:`request`'s frames.
    """

    def __init__(self, vertex_count: int):
        self._proc = None
        self._mesh = None    # the mesh the process was given at its start, if any
        self.wanted = vertex_count > PROCESS_FROM and _cores() >= 2 and bool(sys.executable)

    def start(self, mesh=None) -> None:
        """Start the process, if the cloth is large enough and there is a second core.

        The runner starts it once the first frame is computed: its imports (about a second
        of the other core) then run beside CHOLMOD's single-threaded solves, not beside the
        factorization's second thread.

        Parameters
        ----------
        mesh : Mesh, optional
            The cloth's mesh, sent now (its arrays through a file without a name,
            :func:`clothsim.io.frameproc.pack`), so that :meth:`request` hands over only
            a few hundred bytes after the last step (at 513² the mesh is 19 MB: through the
            pipe, 0.05-0.25 s of the run's thread after its last step).

        Returns
        -------
        None
        """
        if not self.wanted or self._proc is not None:
            return
        init, file = {"mesh": None}, None
        if mesh is not None:
            try:
                init["mesh"], file = pack(mesh)
            except (OSError, pickle.PickleError) as exc:   # then it goes with the request
                log.info("the mesh goes to the picture process with the frames (%s)", exc)
        try:
            self._proc = start_child("clothsim.pictures", () if file is None else (
                file.fileno(),))
            # a few hundred bytes: the pipe takes them while the process imports
            pickle.dump(init, self._proc.stdin, protocol=pickle.HIGHEST_PROTOCOL)
            self._proc.stdin.flush()
            self._mesh = mesh if file is not None else None
        except OSError as exc:
            log.info("pictures drawn in this process (no second one: %s)", exc)
            self.close()
        finally:
            if file is not None:   # the process has its own descriptor of it
                file.close()

    @property
    def running(self) -> bool:
        """Whether a process was started and may take :meth:`request`'s frames."""
        return self._proc is not None

    def request(self, store_path, stored: int, last, mesh, *, times, effects,
                title: str) -> bool:
        """Hand the process the frames to draw (it draws while the caller goes on).

        Parameters
        ----------
        store_path : path-like
            The run's raw positions store (``(count, n, 3)`` float64, little-endian), of
            which frames 0..stored−1 are complete.
        stored : int
            Frames drawn from the store.
        last : ndarray, shape (n, 3), or None
            The last frame's positions [m], when it is not in the store.
        mesh, times, effects, title
            As for :func:`clothsim.plotting.draw_run_pictures` (the mesh given to
            :meth:`start` is not sent again).

        Returns
        -------
        bool
            True when the process took the request (:meth:`answer` then has the pictures);
            False when there is no process or it failed: the caller draws them.
        """
        if self._proc is None:
            return False
        request = dict(store=str(store_path), stored=int(stored), n=mesh.vertex_count,
                       last=None if last is None else np.asarray(last, np.float64),
                       mesh=None if mesh is self._mesh else mesh, times=np.asarray(times),
                       title=title)
        try:
            request["effects"] = shown_effects(effects, request["times"])
            pickle.dump(request, self._proc.stdin, protocol=pickle.HIGHEST_PROTOCOL)
            self._proc.stdin.close()
        except (OSError, pickle.PicklingError, AttributeError, TypeError, KeyError) as exc:
            log.info("pictures drawn in this process (the second one failed: %s)", exc)
            self.close()
            return False
        return True

    def answer(self):
        """The pictures :meth:`request` asked for (waits for them).

        Returns
        -------
        dict of str to bytes, or Exception, or None
            What :func:`~clothsim.plotting.draw_run_pictures` returned, or the error it
            raised; None when the process failed (the caller draws them).
        """
        if self._proc is None:
            return None
        try:
            answer = pickle.loads(self._proc.stdout.read())
        except (OSError, pickle.UnpicklingError, EOFError, AttributeError) as exc:
            log.info("pictures drawn in this process (the second one failed: %s)", exc)
            answer = None
        self.close()
        return answer

    def close(self) -> None:
        """End the process (if it runs: its input closes, it ends) and wait for it.

        Returns
        -------
        None
        """
        proc, self._proc, self._mesh = self._proc, None, None
        end_child(proc)

    def __enter__(self) -> PictureProcess:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def serve() -> None:
    """The process's side: import matplotlib, read the mesh sent at the start (if any) and
    one request from stdin, draw it, write the pictures (or the error) to stdout as a pickle.
    Ends quietly when stdin closes first.

    Returns
    -------
    None
    """
    out = answer_stream()      # anything printed goes to stderr, never into the answer
    from PIL import Image  # noqa: F401 - imported while the run computes

    from .plotting import _matplotlib
    _matplotlib()
    try:
        init = pickle.load(sys.stdin.buffer)
        mesh = None if init["mesh"] is None else unpack(init["mesh"])
        request = pickle.load(sys.stdin.buffer)
    except EOFError:           # the run ended without pictures
        return
    if request["mesh"] is None:
        request["mesh"] = mesh
    stored, n = request["stored"], request["n"]
    positions = list(np.memmap(request["store"], dtype="<f8", mode="r", shape=(stored, n, 3))
                     if stored else [])
    positions += [] if request["last"] is None else [request["last"]]
    try:
        answer = draw_run_pictures(positions, request["mesh"], times=request["times"],
                                   effects=request["effects"], title=request["title"])
    except Exception as exc:  # noqa: BLE001 - handed to the runner, raised there
        answer = exc
    send_answer(out, answer)


__all__ = ["PictureProcess", "ShownEffect", "shown_effects", "PROCESS_FROM", "SHOWN", "serve"]
