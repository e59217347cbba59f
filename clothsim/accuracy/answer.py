"""The study's answers: for each accuracy target, the cheapest setting that reaches it.

:func:`short_answer` opens the report with one line per requested target (the cheapest
setting, its time per step and its speed-up over local/global); :func:`answer_table` lists
every target, in each error the recorded steps support.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from .report import Row
from .trace import ACCURACY_LEVELS


def cheapest(table: Sequence[Row], level: float, *, error: str = "solver_error_p90"
             ) -> Row | None:
    """The row with the least median seconds per step whose ``error`` is ≤ ``level``.

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
    ok = [r for r in table if math.isfinite(getattr(r, error)) and getattr(r, error) <= level
          and math.isfinite(r.seconds_per_step_median) and r.status != "diverged"]
    return min(ok, key=lambda r: r.seconds_per_step_median) if ok else None


def answer_table(table: Sequence[Row], *, levels: Sequence[float] = ACCURACY_LEVELS,
                 trajectory_levels: Sequence[float] = (), uncertainty: float = 0.0,
                 gap_levels: Sequence[float] | None = None) -> str:
    """The answer: for each target, the cheapest setting with its time and spread.

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

    Returns
    -------
    str
        A Markdown table, one line per target.
    """
    unique = max((r.steps_unique for r in table), default=1)
    several = max((r.steps_several_minima for r in table), default=0)
    if gap_levels is None:
        gap_levels = levels if (several or not unique) and table else ()
    if not unique and table:
        levels = ()
    lines = ["| target | error measured | cheapest setting | ms/step (median) | IQR [ms] |",
             "|---|---|---|---|---|"]
    for col, name, levs in (("solver_error_p90", "solver error (p90 over unique steps)",
                             levels),
                            ("objective_gap_p90", "objective gap (p90 over measured steps)",
                             gap_levels),
                            ("trajectory_error", "trajectory error", trajectory_levels)):
        for level in levs:
            if col == "solver_error_p90" and level < uncertainty:
                lines.append(f"| {level:.0e} | {name} | below the reference's uncertainty "
                             f"{uncertainty:.1e}: not measurable | | |")
                continue
            r = cheapest(table, level, error=col)
            if r is None:
                lines.append(f"| {level:.0e} | {name} | no setting reaches this | | |")
            else:
                iqr = r.seconds_per_step_iqr
                spread = f"{1e3 * iqr:.2g}" if math.isfinite(iqr) else "(1 repeat)"
                lines.append(f"| {level:.0e} | {name} | {r.setting} | "
                             f"{1e3 * r.seconds_per_step_median:.3g} | {spread} |")
    return "\n".join(lines)


def short_answer(table: Sequence[Row], levels: Sequence[float] = (1e-3,)) -> list[str]:
    """One line per target: the cheapest setting, its time per step, and its speed-up over
    the cheapest local/global setting that reaches the target (the student's question).

    Parameters
    ----------
    table : sequence of Row
        The rows.
    levels : sequence of float, default (1e-3,)
        Targets, in the solver error (p90 over unique steps) when some step is unique, else
        in the relative objective gap.

    Returns
    -------
    list of str
    """
    unique = max((r.steps_unique for r in table), default=0)
    col, what = (("solver_error_p90", "solver error") if unique
                 else ("objective_gap_p90", "objective gap"))
    out = []
    for level in levels:
        best = cheapest(table, level, error=col)
        if best is None:
            out.append(f"answer for {level:.0e} ({what}): no setting measured reaches it")
            continue
        lg = cheapest([r for r in table if r.method == "local-global"], level, error=col)
        ms = 1e3 * best.seconds_per_step_median
        if lg is None:
            versus = "local/global: no setting measured reaches it"
        elif lg is best:
            versus = "local/global itself is the cheapest"
        else:
            versus = (f"{lg.seconds_per_step_median / best.seconds_per_step_median:.2g}x "
                      f"faster than local/global ({lg.setting}, "
                      f"{1e3 * lg.seconds_per_step_median:.3g} ms/step)")
        out.append(f"answer for {level:.0e} ({what}): {best.setting}, {ms:.3g} ms/step; "
                   f"{versus}")
    return out
