"""Which configurations can never be an answer, so that their timing is not repeated.

The study answers "the cheapest setting that reaches this error" (:mod:`.answer`). A
configuration A can never be that answer when another configuration B reaches every target A
reaches, in *every* error the answers use (solver error, objective gap and trajectory error,
at the levels the answer tables ask about), and takes at most half of A's time per step (the
faster of A's first two timing repeats against B's median): wherever A reaches a target, B
reaches it too, at well under A's cost. The margin of :data:`MARGIN` = 2 is far above the
spread of interleaved repeats (the IQRs of the docs' tables are a few per cent), so more
repeats of A could not change an answer. Local/global is the report's baseline (the "N×
faster than local/global" of :func:`~.answer.short_answer`), so a local/global configuration
counts as dominated only by another local/global one.

:func:`~.timing.time_configurations` times every configuration twice (interleaved), then
repeats only those :func:`dominated` leaves; a dominated configuration keeps its two
timings (CSV column ``repeats`` = 2) and the report says how many there are. Two, not one:
on a shared machine one sample can be several times too slow, and a setting must not be
dropped for it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

MARGIN = 2.0
"""A dominating configuration is at least this many times faster (module text)."""
BASELINE = "local-global"
"""The method whose own cheapest setting every answer is compared with."""


def _as_accurate(b: Sequence[float], a: Sequence[float], levels) -> bool:
    """B reaches every answered level A reaches, in every error (NaN: not measured, so it
    reaches none); without levels for an error, B's must be at most A's."""
    for i, (eb, ea) in enumerate(zip(b, a)):
        levs = None if levels is None else levels[i]
        if levs is None:
            if not (math.isnan(ea) or eb <= ea):
                return False
        elif any(ea <= lev and not eb <= lev for lev in levs):
            return False
    return True


def dominated(methods: Sequence[str], seconds: Sequence[float],
              errors: Sequence[Sequence[float]], *, levels=None,
              margin: float = MARGIN, against: Sequence[float] | None = None) -> set[int]:
    """Indices of the configurations that no answer can choose (module text).

    Parameters
    ----------
    methods : sequence of str
        Each configuration's method.
    seconds : sequence of float
        Each configuration's time per step as a dominated one [s] (the fastest of its first
        repeats; NaN or inf: not timed, e.g. diverged: such a configuration neither
        dominates nor is dominated).
    errors : sequence of sequence of float
        Each configuration's errors as the answers read them, in the same order for all
        (e.g. p90 solver error, p90 objective gap, trajectory error); NaN where not
        measured, inf where diverged.
    levels : sequence of (sequence of float or None), optional
        Per error, the targets the answers ask about: B is as accurate as A when it reaches
        every target A reaches (two errors both below every target are equal for the
        answers, e.g. both under the reference's uncertainty). None (for all or for one
        error) compares the values themselves.
    margin : float, default :data:`MARGIN`
        How many times faster a dominating configuration must be.
    against : sequence of float, optional
        Each configuration's time as a dominating one [s] (default ``seconds``): the timing
        passes the fastest of two samples as ``seconds`` and their median here, so that
        one slow sample makes no setting look dominated.

    Returns
    -------
    set of int
        Indices into the sequences.
    """
    out = set()
    against = seconds if against is None else against
    timed = [i for i, s in enumerate(seconds) if math.isfinite(s) and s > 0
             and math.isfinite(against[i])]
    for a in timed:
        for b in timed:
            if b == a or against[b] * margin > seconds[a]:
                continue
            if methods[a] == BASELINE and methods[b] != BASELINE:
                continue
            if _as_accurate(errors[b], errors[a], levels):
                out.add(a)
                break
    return out
