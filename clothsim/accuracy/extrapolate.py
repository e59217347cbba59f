"""A number for a target no measured setting reaches: local/global's iterations, extrapolated.

When no local/global setting of the study reaches a target, :func:`tail_runs` runs plain
local/global on every step the answer measures for as many iterations as the study's
longest setting (its tolerance cap), and reads the error at the points of the run's last
quarter (:data:`TAIL`; the study has the references' local/global runs keep these iterates,
:func:`tail_stops`, so nothing runs again). The **tail contraction**
ρ_tail = (e_K / e_a)^(1/(K − a)) over iterations a = 3K/4 … K predicts, per step, the
iterations to ε: K + ln(ε / e_K) / ln ρ_tail; :func:`extrapolate` reports their 90th
percentile over the steps, like the answers' p90 errors.

Why the tail and not the early rate: local/global's error contracts fast at first and
ever more slowly (the slowest modes remain), so ρ measured early (e.g. over iterations
100–150, ``rho_local_global`` in steps.md) predicts far too few iterations (on ``hanging``,
ρ = 0.994 gives ≈ 770 iterations for 1e-2; after 1000 the error is still 0.067). Where the
contraction is still slowing at the end of the run (the second half of the tail slower
than the first), the count is a lower bound and is reported as "at least". A step whose
error has stopped falling (local/global converges to another minimum: its solver error to
x* never goes below the distance between the two) gets no count.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..model import Model
from ..solvers import LocalGlobalSolver
from .blowups import BLOW_UPS
from .phases import advance
from .runs import Stop

TAIL = 0.25
"""The fraction of the run (its end) whose contraction is extrapolated."""
SAMPLES = 9
"""Errors read in the tail (evenly spaced, the run's last iterate included)."""
SLOWING = 0.97
"""(1 − ρ) of the tail's second half below this fraction of the first half's: still slowing."""


@dataclass
class StepTail:
    """One step's local/global run: its end error and tail contraction.

    Attributes
    ----------
    index : int
        The recorded step.
    iterations : int
        Iterations run (K).
    error : float
        Error after K iterations (dimensionless).
    rate : float
        ρ_tail, the error's mean contraction per iteration over the tail.
    slowing : bool
        The contraction is still slowing at the end (the count is a lower bound).
    """

    index: int
    iterations: int
    error: float
    rate: float
    slowing: bool

    def count(self, level: float) -> float:
        """Iterations to ``level``: K when reached within the run, else extrapolated.

        Parameters
        ----------
        level : float
            The target (dimensionless).

        Returns
        -------
        float
            Iterations; inf when the error does not fall.
        """
        if self.error <= level:
            return float(self.iterations)
        if not (math.isfinite(self.error) and 0 < self.rate < 1 - 1e-12):
            return math.inf
        return self.iterations + math.ceil(math.log(level / self.error) / math.log(self.rate))


def tail_stops(iterations: int) -> list[Stop]:
    """The iterates :func:`tail_runs` reads in a run of ``iterations`` (its last quarter).

    The study asks the references' local/global runs to keep them
    (:attr:`~.reference.CertifiedReference.local_global_runs`), so that the extrapolation
    reads them there instead of running local/global again.

    Parameters
    ----------
    iterations : int
        K, the run's length.

    Returns
    -------
    list of Stop
        Fixed budgets a = 3K/4 … K, :data:`SAMPLES` of them.
    """
    a = int(round(iterations * (1 - TAIL)))
    return [Stop(k) for k in sorted(set(np.linspace(a, iterations, SAMPLES).round()
                                         .astype(int).tolist()))]


def _tail(model, problem, index, error_of, iterations, kept) -> StepTail:
    at = {s.iterations for s in tail_stops(iterations)}
    if all(Stop(k) in kept for k in at):   # the reference's run kept them
        ends = [kept[Stop(k)] for k in sorted(at)]
        if any(e.x is None for e in ends):
            return StepTail(index, iterations, math.inf, math.nan, False)
        return fit_tail([e.iterations for e in ends], [error_of(e.x) for e in ends], index)
    ks, es = [], []
    solver = LocalGlobalSolver(model, iterations=iterations, check_conditioning=False)
    try:
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            for it in solver.iterates(problem):
                if it.k in at:
                    ks.append(it.k)
                    es.append(error_of(it.x))
                if it.k >= iterations:
                    break
    except BLOW_UPS:
        return StepTail(index, iterations, math.inf, math.nan, False)
    return fit_tail(ks, es, index)


def fit_tail(iterations, errors, index: int = 0) -> StepTail:
    """A :class:`StepTail` from errors read at iterations of the end of a run.

    Parameters
    ----------
    iterations : sequence of int
        Iteration counts, increasing (the last is the run's end).
    errors : sequence of float
        The error there (dimensionless).
    index : int
        The step, for the text.

    Returns
    -------
    StepTail
        ρ_tail is the least-squares contraction of log error over these points.
    """
    k, e = np.asarray(iterations, dtype=float), np.asarray(errors, dtype=float)
    if len(k) < 3 or not np.all(np.isfinite(e)) or np.any(e <= 0):
        end = float(e[-1]) if len(e) else math.nan
        return StepTail(index, int(k[-1]) if len(k) else 0, end, math.nan, False)
    rate = float(np.exp(np.polyfit(k, np.log(e), 1)[0]))
    mid = len(k) // 2
    first = np.log(e[mid] / e[0]) / (k[mid] - k[0])
    second = np.log(e[-1] / e[mid]) / (k[-1] - k[mid])
    slowing = bool(first < 0 and second > SLOWING * first)
    return StepTail(index, int(k[-1]), float(e[-1]), rate, slowing)


def tail_runs(model: Model, steps: Sequence, *, iterations: int,
              measure: str = "solver error") -> list[StepTail]:
    """Plain local/global on each step the answer measures, K = ``iterations`` each.

    Parameters
    ----------
    model : Model
        The cloth.
    steps : sequence of StudyStep
        The study's steps: the unique ones for the solver error, every measured one for the
        objective gap.
    iterations : int
        K, the iterations of each run.
    measure : {"solver error", "objective gap"}
        ‖x − x*‖ / ‖x* − x_n‖, or (g(x) − g(x_best)) / (g(y) − g(x_best)).

    Returns
    -------
    list of StepTail
    """
    out = []
    for s in steps:
        if not (s.kind == "unique" if measure == "solver error" else s.measured):
            continue
        problem, ref = s.step.problem, s.reference
        if measure == "solver error":
            scale = float(np.linalg.norm(ref.x - problem.x)) or 1.0

            def error_of(x, ref=ref, scale=scale):
                return float(np.linalg.norm(x - ref.x)) / scale
        else:
            def error_of(x, ref=ref, problem=problem):
                return ref.objective_gap(model, problem, x)
        out.append(_tail(model, problem, s.step.index, error_of, iterations,
                         ref.local_global_runs))
        advance()
    return out


@dataclass
class Extrapolation:
    """Local/global's iterations per step to a level (p90 over the steps).

    Attributes
    ----------
    level : float
        The target.
    measure : str
        "solver error" or "objective gap".
    count : float
        Iterations per step (p90 over the steps; inf when some step's error stops falling).
    tails : list of StepTail
        The runs it is extrapolated from.
    """

    level: float
    measure: str
    count: float
    tails: list

    @property
    def lower_bound(self) -> bool:
        """Some step's contraction was still slowing: the count is at least this."""
        return any(t.slowing and t.error > self.level for t in self.tails)

    def _number(self) -> str:
        return ("at least ≈ " if self.lower_bound else "≈ ") + f"{float(f'{self.count:.2g}'):.0f}"

    def short(self) -> str:
        """The answer-table cell.

        Returns
        -------
        str
            E.g. "local/global ≈ 3500 it/step (extrapolated)".
        """
        if not math.isfinite(self.count):
            return "local/global does not get there (its error stops falling)"
        return f"local/global {self._number()} it/step (extrapolated)"

    def sentence(self) -> str:
        """The short answer's clause.

        Returns
        -------
        str
            The count and its basis (the tail's contraction, the error left).
        """
        k = max(t.iterations for t in self.tails)
        left = float(np.quantile([t.error for t in self.tails], 0.9))
        stuck = [t.index for t in self.tails if not math.isfinite(t.count(self.level))]
        if not math.isfinite(self.count):
            return (f"local/global does not get there: its {self.measure} stops falling on "
                    f"step(s) {', '.join(map(str, stuck))} (it converges to another "
                    f"minimum there), after {k} iterations it is {left:.2g} (p90)")
        rates = ([t.rate for t in self.tails if t.error > self.level
                  and math.isfinite(t.count(self.level))] or [t.rate for t in self.tails])
        return (f"local/global would need {self._number()} iterations per step "
                f"(extrapolated, not run: p90 over {len(self.tails)} step(s); after {k} "
                f"iterations its {self.measure} is {left:.2g} (p90) and falls by a factor "
                f"{min(rates):.5f}–{max(rates):.5f} per iteration over iterations "
                f"{int(round(k * (1 - TAIL)))}–{k}, the tail of the run"
                + ("; still slowing there, so at least this" if self.lower_bound else "")
                + ")")


def extrapolate(tails: Sequence[StepTail], level: float, measure: str) -> Extrapolation | None:
    """The p90 over the steps of the iterations each needs to ``level`` (module text).

    Parameters
    ----------
    tails : sequence of StepTail
        From :func:`tail_runs`.
    level : float
        The target (dimensionless).
    measure : str
        What the tails measured (for the text).

    Returns
    -------
    Extrapolation or None
        None without runs.
    """
    if not tails:
        return None
    counts = np.array([t.count(level) for t in tails])
    if np.all(np.isfinite(counts)):
        p90 = float(np.ceil(np.quantile(counts, 0.9)))
    else:
        p90 = float(np.quantile(np.where(np.isfinite(counts), counts, np.inf), 0.9,
                                method="nearest"))
    return Extrapolation(level, measure, p90, list(tails))
