"""Ctrl-C, SIGTERM and SIGHUP during a run: one path for all three.

:func:`handle_signals` makes the three signals raise :class:`SignalInterrupt` (a
:class:`KeyboardInterrupt`); :func:`signals_deferred` holds them while a frame's files and
its record are written, so a signal never separates the two. A signal the process inherited
as ignored (``SIG_IGN``: ``nohup`` ignores SIGHUP, a background job of a non-interactive
shell ignores SIGINT) stays ignored.
"""

from __future__ import annotations

import os
import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager

SIGNALS = tuple(getattr(signal, s) for s in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, s))
_handling = False  # a handle_signals block is open (an inner one then does nothing)


class SignalInterrupt(KeyboardInterrupt):
    """SIGINT, SIGTERM or SIGHUP arrived during a run (see :func:`handle_signals`).

    Attributes
    ----------
    signum : int
        The signal's number (e.g. ``signal.SIGTERM``).
    """

    def __init__(self, signum: int):
        self.signum = int(signum)
        super().__init__(signal.Signals(signum).name)


@contextmanager
def handle_signals() -> Iterator[None]:
    """Within the block, SIGINT, SIGTERM and SIGHUP raise :class:`SignalInterrupt` (once:
    a second signal while the run cleans up is ignored), so all three take Ctrl-C's path.
    A signal whose handler is ``SIG_IGN`` (inherited, e.g. SIGHUP under ``nohup``) stays
    ignored. Does nothing outside the main thread, or inside another such block (whose
    handlers stay: a second signal never escapes while the outer block cleans up).

    Yields
    ------
    None
        Control to the block; the previous handlers are restored when it ends.

    Raises
    ------
    SignalInterrupt
        Inside the block, on the first SIGINT, SIGTERM or SIGHUP.
    """
    global _handling
    if threading.current_thread() is not threading.main_thread() or _handling:
        yield  # nested (the CLI installs them around every command): the outer ones act
        return
    fired: list[int] = []

    def handler(signum, frame):
        if not fired:
            fired.append(signum)
            raise SignalInterrupt(signum)

    old = {s: signal.signal(s, handler) for s in _not_ignored()}
    _handling = True
    try:
        yield
    finally:
        _handling = False
        for s, h in old.items():
            signal.signal(s, h)


def _not_ignored() -> list[int]:
    """The signals of :data:`SIGNALS` whose current handler is not ``SIG_IGN``."""
    return [s for s in SIGNALS if signal.getsignal(s) != signal.SIG_IGN]


@contextmanager
def signals_deferred() -> Iterator[None]:
    """Hold SIGINT/SIGTERM/SIGHUP until the block ends, so a frame's files and its record
    are written together; a signal that arrived meanwhile is then handled as it would have
    been (a signal thus interrupts the next frame's computation, never a write). Does
    nothing outside the main thread.

    Yields
    ------
    None
        Control to the block, with the signals blocked (a held signal is delivered when
        the block ends).
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    pending: list[int] = []

    def hold(signum, frame):
        pending.append(signum)

    old = {s: signal.signal(s, hold) for s in _not_ignored()}
    try:
        yield
    finally:
        for s, h in old.items():
            signal.signal(s, h)
        if pending:
            signum = pending[0]
            handler = old[signum]
            if callable(handler):
                handler(signum, None)
            elif handler == signal.SIG_DFL:
                os.kill(os.getpid(), signum)


__all__ = ["SignalInterrupt", "handle_signals", "signals_deferred", "SIGNALS"]
