"""The study's phases: a tqdm progress bar each (on stderr) and their wall and CPU seconds.

:func:`run_accuracy <clothsim.accuracy.command.run_accuracy>` opens one phase at a time
(:data:`PHASES`: recording, references, limits, errors, time-step study, trajectories,
timing, extrapolation) with :meth:`Phases.phase`; the loops inside call :func:`advance`
once per unit of work (a step, a solve, a frame), which moves the open phase's bar and
does nothing when no phase is open (a library call of one function). The bars go to stderr and are
off when stderr is not a terminal or ``TQDM_DISABLE`` is set (the CLI sets it then,
:mod:`clothsim.cli.logs`); with the bar off, the phase logs its progress instead (INFO on
this module's logger, at most every :data:`LOG_EVERY` seconds, and once at its end: the
command line shows these lines off a terminal, so a long study or ``--paper`` run under
make, a pipe or nohup is never silent). The seconds per phase land in ``accuracy.json``
(``phase_seconds``), where ``benchmarks/accuracy_full.py`` reads them.
"""

from __future__ import annotations

import logging
import os
import sys
import time
from contextlib import contextmanager

log = logging.getLogger(__name__)

PHASES = ("recording", "references", "limits", "errors", "time-step study", "trajectories",
          "timing", "extrapolation")
"""The phases of a full study, in the order they run."""

LOG_EVERY = 5.0
"""Seconds between two progress lines of a phase whose bar is off."""

_current = None


class _Progress:
    """A phase's bar (maybe disabled) and its count, logged every :data:`LOG_EVERY` s when
    the bar is off."""

    def __init__(self, bar, name: str, unit: str, logged: bool):
        self.bar, self.name, self.unit, self.logged = bar, name, unit, logged
        self.n, self.total = 0, bar.total
        self.t0 = self.last = time.perf_counter()

    def update(self, n: int = 1) -> None:
        self.n += n
        self.bar.update(n)
        if self.logged and time.perf_counter() - self.last >= LOG_EVERY:
            self.log()

    def refresh(self) -> None:
        self.bar.total = self.total
        self.bar.refresh()

    def log(self) -> None:
        self.last = time.perf_counter()
        of = f"/{self.total}" if self.total is not None else ""
        log.info("%s: %d%s %s(s) done, %.0f s", self.name, self.n, of, self.unit,
                 self.last - self.t0)


def advance(n: int = 1) -> None:
    """Move the open phase's progress bar by ``n`` units (nothing when none is open).

    Parameters
    ----------
    n : int
        Units of work done (steps, solves or frames, as the phase counts them).
    """
    if _current is not None:
        _current.update(n)


def shrink(n: int) -> None:
    """Lower the open phase's expected total by ``n`` units (work found unnecessary).

    Parameters
    ----------
    n : int
        Units of work the phase will not do after all.
    """
    if _current is not None and _current.total is not None and n:
        _current.total = max(_current.n, _current.total - n)
        _current.refresh()


def add(n: int) -> None:
    """Raise the open phase's expected total by ``n`` units (work found necessary).

    Parameters
    ----------
    n : int
        Units of work the phase will do besides those it expected.
    """
    if _current is not None and _current.total is not None and n:
        _current.total += n
        _current.refresh()


def _isatty(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False


class Phases:
    """Wall and CPU seconds of each phase run, with a progress bar per phase.

    Attributes
    ----------
    seconds : dict
        Phase name → {"wall": s, "cpu": s} (CPU: this process only, not joblib workers).
    """

    def __init__(self, enabled: bool = True):
        self.seconds: dict[str, dict[str, float]] = {}
        self.enabled = enabled

    @contextmanager
    def phase(self, name: str, total: int | None = None, unit: str = "it"):
        """Run one phase: a bar of ``total`` units on stderr, its seconds recorded.

        Parameters
        ----------
        name : str
            The phase (:data:`PHASES`).
        total : int, optional
            Units of work the phase will :func:`advance` by (None: unknown).
        unit : str
            What a unit is ("step", "solve", "frame").

        Yields
        ------
        object
            The progress (``update(n)``; ``total`` may be changed, then ``refresh()``).
        """
        global _current
        from tqdm import tqdm

        off = (not self.enabled or bool(os.environ.get("TQDM_DISABLE"))
               or not _isatty(sys.stderr))
        bar = _Progress(tqdm(total=total, desc=name, unit=unit, file=sys.stderr, leave=True,
                             disable=off), name, unit, logged=off and self.enabled)
        previous, _current = _current, bar
        t0, c0 = time.perf_counter(), time.process_time()
        try:
            yield bar
        finally:
            _current = previous
            bar.bar.close()
            spent = self.seconds.setdefault(name, {"wall": 0.0, "cpu": 0.0})
            spent["wall"] += time.perf_counter() - t0
            spent["cpu"] += time.process_time() - c0
        # only a phase that ended: an interrupted or failed one's seconds are kept, but its
        # command's one-line error stays the only line (tests/test_reliability_stops.py)
        log.info("phase %s: %.1f s wall, %.1f s CPU", name, spent["wall"], spent["cpu"])
