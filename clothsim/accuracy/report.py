"""Rows, CSV and the answer tables of the accuracy study.

CSV columns (:data:`COLUMNS`, units in docs/accuracy.md): one row per configuration.
"""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from ..io.common import atomic_path, write_text
from .steps_report import STEP_CLASSES, steps_table  # noqa: F401  (re-exported)
from .study import KINDS, MEASURED, ConfigResult, StudyStep, quantiles
from .timing import median_iqr

COLUMNS = ("method", "h", "iterations", "tolerance", "solver_error_median",
           "solver_error_p90", "solver_error_max", "objective_gap_median", "objective_gap_p90",
           "objective_gap_max", "limit_error_median", "limit_error_p90", "limit_error_max",
           "limit_gap_median", "limit_gap_max", "residual_median", "residual_p90",
           "residual_max", "iterations_median", "iterations_max",
           "steps_measured", "steps_skipped", "steps_unique", "steps_several_minima",
           "steps_saddle", "steps_reference_failed", "steps_at_rest", "steps_trivial",
           "time_step_error", "trajectory_error",
           "seconds_per_step_median", "seconds_per_step_iqr", "seconds_per_step_min", "repeats",
           "solves_per_step", "factorizations_per_step", "status", "steps_diverged")
FIXED_BUDGETS = (5, 10, 20)


@dataclass
class Row:
    """One CSV row (see :data:`COLUMNS`).

    Attributes
    ----------
    method : str
        Solver name.
    h : float
        Time step [s].
    iterations : int
        Iterations per step (the cap when ``tolerance`` is set).
    tolerance : float or None
        Relative-residual tolerance, or None (fixed budget).
    solver_error_median, solver_error_p90, solver_error_max : float
        Relative solver error ‖x − x*‖ / ‖x* − x_n‖ over the unique steps.
    objective_gap_median, objective_gap_p90, objective_gap_max : float
        Relative objective gap (g(x) − g(x_best)) / (g(y) − g(x_best)) over every measured
        step (unique and several minima).
    iterations_median, iterations_max : float
        Iterations used per step.
    steps_measured, steps_skipped : int
        Steps measured (unique + several minima) and not.
    steps_unique, steps_several_minima, steps_saddle, steps_reference_failed : int
        Steps per certificate class (:data:`~clothsim.accuracy.study.KINDS`).
    steps_at_rest, steps_trivial : int
        Steps at rest and trivially solved.
    time_step_error : float
        Relative error of implicit Euler itself at this h (NaN when not measured).
    trajectory_error : float
        ‖X − X_ref‖ / ‖X_ref − X_0‖ over the run (NaN when not measured).
    seconds_per_step_median, seconds_per_step_iqr : float
        Wall time per step and its interquartile range [s].
    repeats : int
        Timing repeats.
    seconds_per_step_min : float
        The fastest repeat [s] (a slow sample is another process's doing; a fast one is not).
    solves_per_step : float
        Global-step solves per step (median iterations; 0 for Newton).
    factorizations_per_step : float
        Factorizations per step (Newton).
    status : str
        "ok", or "diverged" when the configuration blew up on a measured step, in timing
        or on its trajectory (its errors there are inf; it is never an answer).
    steps_diverged : int
        Measured steps on which it blew up.
    limit_error_median, limit_error_p90, limit_error_max : float
        ‖x − x_lim‖ / ‖x_lim − x_n‖ to its method's own limit over the measured steps
        (:mod:`clothsim.accuracy.limits`).
    limit_gap_median, limit_gap_max : float
        The objective gap of its method's own limit (the basin it converges to) over the
        measured steps: 0 when the method ends at x_best on every step.
    residual_median, residual_p90, residual_max : float
        Relative residual ‖∇g(x)‖ / ‖∇g(y)‖ after its solve over the measured steps.
    setting : str
        A short description, e.g. ``"chebyshev, 10 it/step"``.
    """

    method: str
    h: float
    iterations: int
    tolerance: float | None
    solver_error_median: float
    solver_error_p90: float
    solver_error_max: float
    objective_gap_median: float
    objective_gap_p90: float
    objective_gap_max: float
    iterations_median: float
    iterations_max: float
    steps_measured: int
    steps_skipped: int
    steps_unique: int
    steps_several_minima: int
    steps_saddle: int
    steps_reference_failed: int
    steps_at_rest: int
    steps_trivial: int
    time_step_error: float
    trajectory_error: float
    seconds_per_step_median: float
    seconds_per_step_iqr: float
    repeats: int
    solves_per_step: float
    factorizations_per_step: float
    status: str = "ok"
    steps_diverged: int = 0
    limit_error_median: float = math.nan
    limit_error_p90: float = math.nan
    limit_error_max: float = math.nan
    limit_gap_median: float = math.nan
    limit_gap_max: float = math.nan
    residual_median: float = math.nan
    residual_p90: float = math.nan
    residual_max: float = math.nan
    seconds_per_step_min: float = math.nan

    @property
    def setting(self) -> str:
        if self.tolerance is not None:
            return f"{self.method}, tolerance {self.tolerance:g}"
        return f"{self.method}, {self.iterations} it/step"


def rows(results: Sequence[ConfigResult], steps: Sequence[StudyStep], *, h: float,
         time_step_error: float = math.nan,
         trajectory_errors: dict | None = None) -> list[Row]:
    """One :class:`Row` per configuration.

    Parameters
    ----------
    results : sequence of ConfigResult
        From :func:`~clothsim.accuracy.study.measure` (with timings filled in).
    steps : sequence of StudyStep
        The classified steps (for the step counts).
    h : float
        The time step [s].
    time_step_error : float, optional
        Relative time-discretization error at h.
    trajectory_errors : dict, optional
        Configuration → trajectory error.

    Returns
    -------
    list of Row
        Same order as ``results``.
    """
    kinds = [s.kind for s in steps]
    count = {k: kinds.count(k) for k in KINDS}
    measured = sum(count[k] for k in MEASURED)
    out = []
    for r in results:
        c = r.config
        unique = r.unique if len(r.unique) == len(r.errors) else np.ones(len(r.errors), bool)
        med, p90, mx = quantiles(r.errors[unique])
        gaps = quantiles(r.gaps) if len(r.gaps) else (math.nan,) * 3
        it_med = float(_median(r.iterations))
        sec, iqr = median_iqr(r.seconds)
        solves = it_med if c.method != "newton" else 0.0
        traj = (trajectory_errors or {}).get(c, math.nan)
        diverged = bool(r.diverged or r.trajectory_diverged or traj == math.inf)
        limit = _known(r.limit_errors)  # NaN: no limit computed (left out)
        basin = _known([s.limits[c.method].gap for s in steps
                        if s.measured and c.method in s.limits])
        resid = _known(r.residuals)
        out.append(Row(c.method, h, c.iterations, c.tolerance, med, p90, mx, *gaps, it_med,
                       float(r.iterations.max()) if len(r.iterations) else math.nan,
                       measured, len(steps) - measured, count["unique"],
                       count["several-minima"], count["saddle"], count["reference-failed"],
                       count["at-rest"], count["trivial"], time_step_error,
                       traj, sec, iqr, len(r.seconds), solves, r.factorizations,
                       "diverged" if diverged else "ok", int(r.diverged), *limit,
                       basin[0], basin[2], *resid,
                       seconds_per_step_min=min(r.seconds) if r.seconds else math.nan))
    return out


def _known(values):
    v = np.asarray(values, dtype=np.float64)
    return quantiles(v[~np.isnan(v)])


def _median(v):
    return float("nan") if len(v) == 0 else float(sorted(v)[len(v) // 2])


def write_csv(table: Sequence[Row], path) -> Path:
    """Write rows to ``path`` (columns :data:`COLUMNS`; empty cell for no tolerance).

    Parameters
    ----------
    table : sequence of Row
        The rows.
    path : str or Path
        The CSV file (overwritten).

    Returns
    -------
    Path
        ``path``, written atomically (a temporary file renamed over it): a crash leaves the
        previous complete CSV, never half of one.
    """
    path = Path(path)
    with atomic_path(path) as tmp, tmp.open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=COLUMNS)
        w.writeheader()
        for row in table:
            w.writerow({k: ("" if v is None else v) for k, v in asdict(row).items()})
    return path


def write_sidecar(info: dict, path) -> Path:
    """Machine, versions, threads and one-off costs as JSON next to the CSV.

    Parameters
    ----------
    info : dict
        What to record (values that JSON cannot hold are written as strings).
    path : str or Path
        The JSON file (overwritten atomically).

    Returns
    -------
    Path
        ``path``.
    """
    return write_text(path, json.dumps(info, indent=2, sort_keys=True, default=str) + "\n")



def fixed_budget_table(table: Sequence[Row], budgets: Sequence[int] = FIXED_BUDGETS) -> str:
    """Solver error (median / p90) after 5, 10, 20 iterations per step, per method; the
    relative objective gap instead when no step is unique (see :func:`fixed_budget_measure`).

    Parameters
    ----------
    table : sequence of Row
        The rows (Newton's are left out).
    budgets : sequence of int
        The iteration budgets shown.

    Returns
    -------
    str
        A Markdown table, one line per method.
    """
    measure = fixed_budget_measure(table)
    prefix = "solver_error" if measure == "solver error" else "objective_gap"
    methods = list(dict.fromkeys(r.method for r in table if r.method != "newton"))
    head = "| method | " + " | ".join(f"{b} it: median / p90" for b in budgets) + " |"
    lines = [head, "|---" * (len(budgets) + 1) + "|"]
    for m in methods:
        cells = []
        for b in budgets:
            r = next((r for r in table if r.method == m and r.tolerance is None
                      and r.iterations == b), None)
            cells.append("–" if r is None else
                         f"{getattr(r, prefix + '_median'):.1e} / "
                         f"{getattr(r, prefix + '_p90'):.1e}")
        lines.append(f"| {m} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


WORSE = 1.5
"""An accelerated method's p90 error this many times local/global's, at the same budget, is
called less accurate (:func:`worse_than_local_global`)."""


def worse_than_local_global(table: Sequence[Row], budgets: Sequence[int] = (1, 2, 5, 10),
                            ) -> list[str]:
    """One note per accelerated method that is less accurate than plain local/global at the
    small budgets real-time users run (at least :data:`WORSE` times its p90 error, in the
    fixed-budget table's measure, or else in the objective gap, which a method may raise
    while it brings the solver error down), detected from the rows, e.g. Chebyshev's gap on
    contact steps resolved after the solve (the seed's ``[contact] mode = "post-solve"``).

    Parameters
    ----------
    table : sequence of Row
        The rows.
    budgets : sequence of int
        The budgets compared (those measured).

    Returns
    -------
    list of str
        Empty when no method is worse at any of them.
    """
    first = fixed_budget_measure(table)
    measures = dict.fromkeys((first, "objective gap"))

    def p90(method, b, measure):
        col = "solver_error_p90" if measure == "solver error" else "objective_gap_p90"
        r = next((r for r in table if r.method == method and r.tolerance is None
                  and r.iterations == b and r.status != "diverged"), None)
        return getattr(r, col) if r is not None else math.nan

    notes = []
    for m in dict.fromkeys(r.method for r in table if r.method not in ("local-global",
                                                                        "newton")):
        for measure in measures:   # the table's measure first; one note per method
            worse = [(b, p90(m, b, measure), p90("local-global", b, measure)) for b in budgets
                     if p90(m, b, measure) > WORSE * p90("local-global", b, measure) > 0]
            if worse:
                break
        if not worse:
            continue
        larger = sorted({r.iterations for r in table if r.method == m and r.tolerance is None
                         and r.iterations > max(b for b, _, _ in worse)})
        pays = next((b for b in larger
                     if p90(m, b, measure) < p90("local-global", b, measure)), None)
        notes.append(
            f"{m} is less accurate than plain local/global at "
            f"{', '.join(str(b) for b, _, _ in worse)} iterations per step ({measure} p90 "
            f"{', '.join(f'{e:.1e}' for _, e, _ in worse)} against "
            f"{', '.join(f'{e:.1e}' for _, _, e in worse)}): with a budget this small use "
            f"local/global" + (f"; {m} is ahead from {pays} iterations per step" if pays
                               else ""))
    return notes


def fixed_budget_measure(table: Sequence[Row]) -> str:
    """What :func:`fixed_budget_table` shows: "solver error", or "objective gap" when no
    recorded step is unique (every measured step has several minima).

    Parameters
    ----------
    table : sequence of Row
        The rows.

    Returns
    -------
    str
        "solver error" or "objective gap".
    """
    unique = max((r.steps_unique for r in table), default=1)
    return "solver error" if unique or not table else "objective gap"


def reference_uncertainty(steps: Sequence[StudyStep]) -> float:
    """Largest reference uncertainty over the measured steps (0 when none).

    Parameters
    ----------
    steps : sequence of StudyStep
        The classified steps.

    Returns
    -------
    float
        Relative uncertainty of x* (dimensionless).
    """
    u = [s.reference.uncertainty for s in steps if s.kind == "unique"
         and s.reference is not None and math.isfinite(s.reference.uncertainty)]
    return max(u, default=0.0)
