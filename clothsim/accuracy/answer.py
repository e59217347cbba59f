"""The study's answers: for each accuracy target, the cheapest setting that reaches it.

:func:`short_answer` opens the report with one line per requested target (the cheapest
setting, its time per step and its speed-up over local/global); :func:`answer_table` lists
every target, in each error the recorded steps support. Each row's choice comes from
:func:`~.decide.choose`: decided by enough interleaved timing repeats, or named as a tie
within noise, with a "how sure" cell (:mod:`.decide`); :func:`questions` lists the rows
both print, which the timing repeats until each is decided. Where no measured setting
reaches a target, local/global's iterations to it are extrapolated from its measured tail
contraction (:mod:`.extrapolate`) when the study computed them.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

from .decide import choose, fastest
from .report import Row
from .trace import ACCURACY_LEVELS

BASELINE = "local-global"
SOLVER, GAP, TRAJECTORY = "solver_error_p90", "objective_gap_p90", "trajectory_error"


def cheapest(table: Sequence[Row], level: float, *, error: str = SOLVER) -> Row | None:
    """The setting an answer names for ``level``: the cheapest that reaches it, decided by
    its timing repeats, or the simplest of those tied within noise (:func:`~.decide.choose`).

    Parameters
    ----------
    table : sequence of Row
        The rows.
    level : float
        Accuracy target (relative error).
    error : str, default "solver_error_p90"
        The Row column compared with ``level``.

    Returns
    -------
    Row or None
        None when no timed row reaches ``level``.
    """
    return choose(table, level, error=error).row


def _columns(table, levels, trajectory_levels, gap_levels):
    """(column, name, levels) of the answer table's three blocks."""
    unique = max((r.steps_unique for r in table), default=1)
    several = max((r.steps_several_minima for r in table), default=0)
    if gap_levels is None:
        gap_levels = levels if (several or not unique) and table else ()
    if not unique and table:
        levels = ()
    return ((SOLVER, "solver error (p90 over unique steps)", levels),
            (GAP, "objective gap (p90 over measured steps)", gap_levels),
            (TRAJECTORY, "trajectory error", trajectory_levels))


def short_column(table: Sequence[Row]) -> tuple[str, str]:
    """(column, name) of the short answer: the solver error when some step is unique, else
    the objective gap.

    Parameters
    ----------
    table : sequence of Row

    Returns
    -------
    tuple of str
    """
    unique = max((r.steps_unique for r in table), default=0)
    return (SOLVER, "solver error") if unique else (GAP, "objective gap")


def questions(table: Sequence[Row], *, levels: Sequence[float] = ACCURACY_LEVELS,
              short_levels: Sequence[float] = (1e-3,), trajectory_levels=(),
              uncertainty: float = 0.0, gap_levels=None) -> list[tuple]:
    """Every choice the report prints: (error column, level, method or None).

    Parameters
    ----------
    table : sequence of Row
    levels, trajectory_levels, uncertainty, gap_levels
        As :func:`answer_table`.
    short_levels : sequence of float
        As :func:`short_answer` (each asks the cheapest setting, and local/global's).

    Returns
    -------
    list of tuple
        No duplicates, in print order.
    """
    out = []
    for col, _, levs in _columns(table, levels, trajectory_levels, gap_levels):
        out += [(col, lev, None) for lev in levs if not (col == SOLVER and lev < uncertainty)]
    col, _ = short_column(table)
    for lev in short_levels:
        out += [(col, lev, None), (col, lev, BASELINE)]
    return list(dict.fromkeys(out))


def _cell(extrapolated: Mapping | None, col: str, level: float) -> str:
    e = (extrapolated or {}).get((col, level))
    return "" if e is None else f"; {e.short()}"


def answer_table(table: Sequence[Row], *, levels: Sequence[float] = ACCURACY_LEVELS,
                 trajectory_levels: Sequence[float] = (), uncertainty: float = 0.0,
                 gap_levels: Sequence[float] | None = None,
                 extrapolated: Mapping | None = None) -> str:
    """The answer: for each target, the cheapest setting with its time, spread and how
    sure the choice is.

    Solver-error levels below ``uncertainty`` (the largest reference uncertainty over the
    measured steps) are not answered: the reference cannot tell them apart.

    Parameters
    ----------
    table : sequence of Row
        The rows.
    levels : sequence of float
        Solver-error targets (p90 over the steps).
    trajectory_levels : sequence of float
        Trajectory-error targets.
    uncertainty : float, default 0
        The references' relative uncertainty.
    gap_levels : sequence of float, optional
        Relative-objective-gap targets (p90 over every measured step); default ``levels``
        when some step has several minima or no step is unique, else none. Solver-error
        lines are left out when no step is unique.
    extrapolated : mapping, optional
        (column, level) → :class:`~.extrapolate.Extrapolation`: local/global's iterations
        to a level no setting reached, shown in that row.

    Returns
    -------
    str
        A Markdown table, one line per target.
    """
    lines = ["| target | error measured | cheapest setting | ms/step: median (fastest) "
             "| IQR [ms] | how sure |", "|---|---|---|---|---|---|"]
    for col, name, levs in _columns(table, levels, trajectory_levels, gap_levels):
        for level in levs:
            if col == SOLVER and level < uncertainty:
                lines.append(f"| {level:.0e} | {name} | below the reference's uncertainty "
                             f"{uncertainty:.1e}: not measurable | | | |")
                continue
            c = choose(table, level, error=col)
            r = c.row
            if r is None:
                lines.append(f"| {level:.0e} | {name} | no setting reaches this"
                             f"{_cell(extrapolated, col, level)} | | | |")
            else:
                iqr = r.seconds_per_step_iqr
                spread = f"{1e3 * iqr:.2g}" if math.isfinite(iqr) else "(1 repeat)"
                lines.append(f"| {level:.0e} | {name} | {r.setting} | "
                             f"{1e3 * r.seconds_per_step_median:.3g} "
                             f"({1e3 * fastest(r):.3g}) | {spread} | {c.sureness()} |")
    return "\n".join(lines)


def short_answer(table: Sequence[Row], levels: Sequence[float] = (1e-3,), *,
                 extrapolated: Mapping | None = None) -> list[str]:
    """One line per target: the cheapest setting, its time per step, how sure the choice
    is, and its speed-up over the cheapest local/global setting that reaches the target
    (the student's question).

    Parameters
    ----------
    table : sequence of Row
        The rows.
    levels : sequence of float, default (1e-3,)
        Targets, in the solver error (p90 over unique steps) when some step is unique, else
        in the relative objective gap.
    extrapolated : mapping, optional
        (column, level) → :class:`~.extrapolate.Extrapolation` of local/global: its
        iterations to a level none of its measured settings reaches.

    Returns
    -------
    list of str
    """
    col, what = short_column(table)
    out = []
    for level in levels:
        c = choose(table, level, error=col)
        best = c.row
        more = (extrapolated or {}).get((col, level))
        if best is None:
            out.append(f"answer for {level:.0e} ({what}): no setting measured reaches it"
                       + (f"; {more.sentence()}" if more is not None else ""))
            continue
        lg = choose(table, level, error=col, method=BASELINE).row
        ms = 1e3 * best.seconds_per_step_median
        if lg is None:
            versus = ("local/global: no setting measured reaches it"
                      + (f"; {more.sentence()}" if more is not None else ""))
        elif lg is best:
            versus = "local/global itself is the cheapest"
        else:
            versus = (f"{fastest(lg) / fastest(best):.2g}x faster than local/global "
                      f"({lg.setting}, {1e3 * lg.seconds_per_step_median:.3g} ms/step; "
                      f"ratio of the fastest repeats)")
        sure = c.sureness()
        out.append(f"answer for {level:.0e} ({what}): {best.setting}, {ms:.3g} ms/step"
                   + (f" ({sure})" if sure else "") + f"; {versus}")
    return out
