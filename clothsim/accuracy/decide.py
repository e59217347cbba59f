"""Answers that do not hang on one timing sample: each answer row's choice, and how sure it is.

An answer row asks "the cheapest setting whose ``error`` is at most ``level``" (among all
methods, or among one method's settings: the local/global baseline of the short answer).
On a shared machine a timing sample can be several times too slow (another process took
the core: on this 2-core machine under load, medians of 15 repeats were 1.5–2.5 times the
fastest repeat), never much too fast; so a setting's cost is read from its **fastest**
repeat, and a ranking by single samples, or by medians, changes from study to study.
:func:`choose` decides a row only when its timings allow it:

- the candidate with the fastest repeat (the *leader*) has at least :data:`MIN_REPEATS`
  samples;
- every other candidate is either **far** slower — at least two samples, all at least
  :data:`~.dominance.MARGIN` times the leader's fastest (one slow sample is never enough) —
  or **clearly** slower: at least :data:`MIN_REPEATS` samples, the fastest at least
  :data:`TIE_RATIO` times the leader's, and more than either one's own scatter (median over
  fastest repeat, :func:`scatter`: on a loaded machine the fastest of a few samples moves
  by more than :data:`TIE_RATIO` from study to study);
- a candidate that is neither after :data:`MAX_REPEATS` samples of both is a **tie within
  noise**: such settings cost the same to the resolution of this machine's timings, and the
  row names the simplest of them (:func:`preference`: local/global first, then the fewest
  iterations; never a timing), so two studies name the same setting, and says which others
  it is tied with.

Undecided rows name the candidates still to time (:attr:`Choice.pending`);
:func:`~.timing.time_configurations` times those again, interleaved, until every row is
decided or tied (``undecided`` there). :meth:`Choice.sureness` is the report's "how sure"
cell.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

from .dominance import MARGIN
from .trace import ITERATIVE_METHODS

MIN_REPEATS = 3
"""Timing samples a setting needs before its fastest ranks it."""
TIE_RATIO = 1.1
"""Fastest repeats closer than this ratio are never called different (differences of a few
per cent change between processes: frequency, caches, the other jobs)."""
MAX_REPEATS = 10
"""Samples after which two settings not yet told apart are a tie within noise."""


def _n(r) -> int:
    return int(getattr(r, "repeats", 1) or 0)


def _median(r) -> float:
    return float(r.seconds_per_step_median)


def fastest(r) -> float:
    """A row's fastest timing repeat [s] (its median when the row has no minimum).

    Parameters
    ----------
    r : Row

    Returns
    -------
    float
        Seconds per step.
    """
    v = getattr(r, "seconds_per_step_min", math.nan)
    return float(v) if math.isfinite(v) else _median(r)


def separated(leader, other, *, margin: float = MARGIN) -> bool:
    """Whether ``other`` is slower than ``leader`` beyond this machine's noise (module text).

    Parameters
    ----------
    leader, other : Row
        Rows with ``seconds_per_step_min`` (the fastest repeat) [s] and ``repeats``;
        ``leader`` has the faster one.
    margin : float, default :data:`~.dominance.MARGIN`
        A setting this many times slower in every one of at least two samples is far.

    Returns
    -------
    bool
    """
    ratio = fastest(other) / fastest(leader) if fastest(leader) > 0 else math.inf
    if _n(other) >= 2 and ratio >= margin:
        return True
    return (min(_n(leader), _n(other)) >= MIN_REPEATS
            and ratio >= max(TIE_RATIO, scatter(leader), scatter(other)))


def scatter(r) -> float:
    """A row's own timing scatter: its median repeat over its fastest (1 with one sample).

    Two settings whose fastest repeats differ by less than either one's scatter are not told
    apart (:func:`separated`): on a shared 2-core machine under a heavy load, the fastest of
    3 samples of one setting moved by tens of percent from one study to the next, while its
    median stood well above its fastest.

    Parameters
    ----------
    r : Row

    Returns
    -------
    float
        ≥ 1 (dimensionless).
    """
    low, mid = fastest(r), _median(r)
    return mid / low if low > 0 and math.isfinite(mid) and mid > low else 1.0


def preference(r) -> tuple:
    """Sort key naming one of tied settings: local/global first (the paper's method, the
    report's baseline), then the methods' usual order, then the fewest iterations used, a
    fixed budget before a tolerance; hardware independent, so the same in every study.

    Parameters
    ----------
    r : Row

    Returns
    -------
    tuple
    """
    order = (ITERATIVE_METHODS.index(r.method) if r.method in ITERATIVE_METHODS
             else len(ITERATIVE_METHODS))
    used = getattr(r, "iterations_median", r.iterations)
    used = used if isinstance(used, (int, float)) and math.isfinite(used) else r.iterations
    return (order, r.method, float(used), r.tolerance is not None, r.iterations,
            -(r.tolerance or 0.0))


@dataclass
class Choice:
    """One answer row's choice.

    Attributes
    ----------
    row : Row or None
        The setting named (None: no setting reaches the level).
    tied : list of Row
        Other settings within noise of it (a tie after :data:`MAX_REPEATS` samples).
    runner_up : Row or None
        The cheapest setting clearly slower than the named one(s).
    pending : list of Row
        Settings to time again before the row is decided (empty when it is).
    """

    row: object | None
    tied: list = field(default_factory=list)
    runner_up: object | None = None
    pending: list = field(default_factory=list)

    @property
    def decided(self) -> bool:
        """No more timing can change the setting named."""
        return not self.pending

    def sureness(self) -> str:
        """The "how sure" cell: the margin to the next setting, a tie, or provisional.

        Returns
        -------
        str
        """
        if self.row is None:
            return ""
        n = f"{_n(self.row)} timing repeat{'s' if _n(self.row) != 1 else ''}"
        if self.pending:
            return f"provisional: not yet told apart from the others, {n}"
        if self.tied:
            return ("tie within noise with " + " and ".join(t.setting for t in self.tied)
                    + f", {n}")
        if self.runner_up is None:
            return f"the only setting that reaches it, {n}"
        ratio = fastest(self.runner_up) / fastest(self.row)
        return f"next cheapest is {ratio:.2g}x slower ({self.runner_up.setting}), {n}"


def reaches(r, level: float, error: str) -> bool:
    """Whether row ``r`` answers ``level`` in ``error``: reached, timed, not diverged.

    Parameters
    ----------
    r : Row
    level : float
        The target (dimensionless).
    error : str
        The Row column compared with ``level``.

    Returns
    -------
    bool
    """
    e = getattr(r, error)
    return (math.isfinite(e) and e <= level and math.isfinite(_median(r))
            and getattr(r, "status", "ok") != "diverged")


def choose(table: Sequence, level: float, *, error: str = "solver_error_p90",
           method: str | None = None, cap: int = MAX_REPEATS) -> Choice:
    """The setting an answer row names for ``level`` (module text).

    Parameters
    ----------
    table : sequence of Row
        The study's rows.
    level : float
        The target (dimensionless).
    error : str, default "solver_error_p90"
        The Row column compared with ``level``.
    method : str, optional
        Only this method's settings (the baseline of the short answer).
    cap : int, default :data:`MAX_REPEATS`
        Samples after which settings not told apart are a tie.

    Returns
    -------
    Choice
    """
    cands = sorted((r for r in table if reaches(r, level, error)
                    and (method is None or r.method == method)), key=fastest)
    if not cands:
        return Choice(None)
    leader = cands[0]
    close = [c for c in cands[1:] if not separated(leader, c)]
    pending = [leader] + close if (_n(leader) < MIN_REPEATS or any(
        min(_n(leader), _n(c)) < cap for c in close)) else []
    tie = [leader, *close]
    named = min(tie, key=preference)
    runner = next((c for c in cands[1:] if c not in close), None)
    return Choice(named, [t for t in tie if t is not named], runner,
                  [r for r in pending if _n(r) < cap])


def undecided(table: Sequence, questions, *, cap: int = MAX_REPEATS) -> set[int]:
    """Indices (into ``table``) of the settings to time again so that every question is
    decided; empty when all are.

    Parameters
    ----------
    table : sequence of Row
        The study's rows, in the order of the timed results.
    questions : iterable of (str, float, str or None)
        (error column, level, method or None) per answer row (:func:`~.answer.questions`).
    cap : int, default :data:`MAX_REPEATS`

    Returns
    -------
    set of int
    """
    index = {id(r): i for i, r in enumerate(table)}
    out: set[int] = set()
    for error, level, method in questions:
        out |= {index[id(r)] for r in choose(table, level, error=error, method=method,
                                              cap=cap).pending}
    return out
