"""One job at a time on a background thread: :class:`BackgroundJob`, which writes a run's
frames while the next one is computed (:meth:`clothsim.io.runfolder.RunFolder.write_frame`).
"""

from __future__ import annotations

import threading


class BackgroundJob:
    """At most one call in flight on a daemon thread; its error handed to the caller.

    Completion is an :class:`threading.Event`, not ``Thread.join``: a join interrupted by a
    signal handler's exception (Ctrl-C, SIGTERM) may take a running thread for stopped
    (CPython 3.11), and an interrupted run must still wait for its frame in flight.
    """

    def __init__(self) -> None:
        self._done: threading.Event | None = None
        self._error: BaseException | None = None

    def start(self, fn, *args, name: str = "clothsim background job") -> None:
        """Run ``fn(*args)`` on a new thread, after the call in flight (its error raised).

        Parameters
        ----------
        fn : callable
        *args
            Its arguments.
        name : str
            The thread's name.
        """
        self.wait()
        done = self._done = threading.Event()

        def body():
            try:
                fn(*args)
            except BaseException as exc:   # raised in the caller's thread by wait()
                self._error = exc
            finally:
                done.set()

        threading.Thread(target=body, name=name, daemon=True).start()

    def join(self) -> BaseException | None:
        """Wait for the call in flight, if any; return (and forget) its error.

        Returns
        -------
        BaseException or None
        """
        if self._done is not None:
            self._done.wait()
            self._done = None
        error, self._error = self._error, None
        return error

    def wait(self) -> None:
        """Wait for the call in flight, if any, and raise its error.

        Raises
        ------
        BaseException
            What the call raised.
        """
        error = self.join()
        if error is not None:
            raise error
