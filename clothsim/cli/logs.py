"""Logging for the command line: warnings counted by kind, progress bars only on a terminal."""

from __future__ import annotations

import logging
import os
import re
import sys
import time
import warnings
from contextlib import contextmanager

from .common import PROG, _one_line, log


def _configure_logging(verbose: int):
    """Send clothsim's log records to stderr (warnings only, unless -v); returns an undo."""
    level = logging.WARNING if verbose <= 0 else logging.INFO if verbose == 1 else logging.DEBUG
    root = logging.getLogger("clothsim")
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter(f"{PROG}: %(levelname)s: %(message)s"))
    old_level = root.level
    root.addHandler(handler)
    root.setLevel(level)

    def undo():
        root.removeHandler(handler)
        root.setLevel(old_level)

    return undo


_NUMBER = re.compile(r"[-+]?\d[\d.]*(?:e[-+]?\d+)?")


@contextmanager
def _warnings_to_log():
    """Route Python warnings to the ``clothsim`` logger and count them by kind.

    A kind is the warning category plus its message with numbers blanked out. The first
    warning of each kind is logged at INFO (visible with -v); at exit one WARNING line per
    kind gives its count and the first message. ``ResourceWarning`` stays ignored, as in
    Python's default filters: it speaks of the interpreter's own files (a signal that lands
    inside an import leaves the module's open ``.pyc`` to the collector), never of the run.
    """
    counts: dict[tuple[str, str], list] = {}

    def show(message, category, filename, lineno, file=None, line=None):
        text = _one_line(message)
        key = (category.__name__, _NUMBER.sub("#", text))
        if key not in counts:
            counts[key] = [0, text]
            log.info("%s: %s", category.__name__, text)
        counts[key][0] += 1

    with warnings.catch_warnings():
        warnings.simplefilter("always")
        warnings.simplefilter("ignore", ResourceWarning)
        warnings.showwarning = show
        try:
            yield counts
        finally:
            for (kind, _), (count, first) in counts.items():
                times = "once" if count == 1 else f"{count} times"
                log.warning("%s (%s): %s", kind, times, first)


@contextmanager
def _no_progress_bars_off_terminal():
    """Disable tqdm progress bars (TQDM_DISABLE) when stderr is not a terminal."""
    set_here = not _isatty(sys.stderr) and "TQDM_DISABLE" not in os.environ
    if set_here:
        os.environ["TQDM_DISABLE"] = "1"
    try:
        yield
    finally:
        if set_here:
            os.environ.pop("TQDM_DISABLE", None)


#: loggers whose INFO lines are progress, shown off a terminal (where no bar is drawn)
PROGRESS_LOGGERS = ("clothsim.accuracy.phases",)


@contextmanager
def _progress_lines_off_terminal():
    """Show the progress loggers' INFO lines when stderr is not a terminal (no bar there)."""
    loggers = [logging.getLogger(name) for name in PROGRESS_LOGGERS]
    old = [lg.level for lg in loggers]
    if not _isatty(sys.stderr):
        for lg in loggers:
            if lg.getEffectiveLevel() > logging.INFO:
                lg.setLevel(logging.INFO)
    try:
        yield
    finally:
        for lg, level in zip(loggers, old):
            lg.setLevel(level)


def _isatty(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False


#: Seconds between two progress lines of ``run`` when stderr is not a terminal.
PROGRESS_SECONDS = 5.0


def _duration(seconds: float) -> str:
    seconds = max(0, round(seconds))
    if seconds < 60:
        return f"{seconds} s"
    if seconds < 3600:
        return f"{seconds // 60} min {seconds % 60} s"
    return f"{seconds // 3600} h {seconds // 60 % 60} min"


class ProgressLines:
    """``run``'s progress off a terminal (make, a pipe, nohup, a log file): one line on
    stderr every :data:`PROGRESS_SECONDS`, e.g. ``clothsim: hanging: frame 12 of 90 (13 %),
    2.1 s a frame, about 2 min 44 s left``. A run shorter than that prints none.

    Parameters
    ----------
    name : str
        The scene's name.
    stream : file, optional
        Default: ``sys.stderr`` when called.
    clock : callable
        Seconds (monotonic).
    """

    def __init__(self, name: str, stream=None, clock=time.monotonic):
        self.name, self.stream, self.clock = name, stream, clock
        self.start = self.last = clock()
        self.first: int | None = None

    def __call__(self, k: int, total: int) -> None:
        now = self.clock()
        if self.first is None:
            self.first = k - 1  # frames done before this process (a resumed run)
        if now - self.last < PROGRESS_SECONDS or k >= total:
            return
        self.last = now
        rate = (now - self.start) / max(k - self.first, 1)
        print(f"{PROG}: {self.name}: frame {k} of {total} ({100 * k // max(total, 1)} %), "
              f"{rate:.2g} s a frame, about {_duration(rate * (total - k))} left",
              file=self.stream or sys.stderr, flush=True)
