"""The paper's Fig. 1 claims, reproduced from the tool alone (``clothsim accuracy --paper``).

Liu et al. (2013), Fig. 1: a sheet held at two corners, h = 1/30 s; local/global beats
Newton's method for the first digit(s) of accuracy, Newton wins asymptotically, and 10
local/global iterations cost a fraction of one Newton iteration. :func:`paper_report` runs
the same setup (n × n instead of 81 × 81 so it finishes in minutes), on a step after
``frames`` converged steps (the sheet has fallen and buckles), and prints the time each
method needs to each error level (median of interleaved repeats), the crossover level and
the cost ratio.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from ..gallery import curtain
from ..solvers import LocalGlobalSolver, NewtonSolver
from .reference import certified_reference
from .timing import _limited_threads
from .trace import ACCURACY_LEVELS, trace_solver


def paper_report(*, n: int = 41, k: float = 1000.0, frames: int = 15, repeats: int = 5,
                 max_seconds: float = 10.0, threads: int = 1) -> str:
    """Crossover of local/global and Newton on the paper's Fig. 1 setup; returns the text.

    Parameters
    ----------
    n : int
        Vertices per side (the paper: 81).
    k : float
        Spring stiffness [N/m].
    frames : int
        Converged steps before the measured one.
    repeats : int
        Interleaved repeats of each trace (medians are reported).
    max_seconds : float
        Wall-time cap of one local/global trace [s].
    threads : int
        BLAS threads during timing.

    Returns
    -------
    str
        The report (plain text, Markdown tables).
    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sim = curtain(n, k=k, plane="xz", method="newton", iterations=100, tolerance=1e-10)
        sim.run(frames)
    problem = sim.problem()
    ref = certified_reference(sim.model, problem)
    lg_times, nt_times = [], []
    lg_err = nt_err = None
    with _limited_threads(threads):
        for _ in range(repeats):
            lg = trace_solver(LocalGlobalSolver(sim.model, check_conditioning=False), problem,
                              ref.x, iterations=10 ** 6, max_seconds=max_seconds,
                              min_error=1e-9)
            nt = trace_solver(NewtonSolver(sim.model), problem, ref.x, iterations=60)
            lg_times.append(lg.seconds)
            nt_times.append(nt.seconds)
            lg_err, nt_err = lg.error, nt.error
    m = min(len(t) for t in lg_times)
    lg_sec = np.median(np.stack([t[:m] for t in lg_times]), axis=0)
    lg_err = lg_err[:m]
    nt_sec = np.median(np.stack(nt_times), axis=0)

    def first(err, sec, level):
        hit = np.flatnonzero(err <= level)
        return (int(hit[0]), float(sec[hit[0]])) if len(hit) else None

    lines = [f"# The paper's Fig. 1 setup: {n} x {n} sheet held at two corners, k = {k:g} N/m, "
             f"h = 1/30 s, step {frames + 1}",
             f"reference: Newton residual {ref.residual:.1e}, lambda_min(H)/m_min = "
             f"{ref.min_eigenvalue:.3g}, uncertainty {ref.uncertainty:.1e}"
             + (" (two minima!)" if ref.two_minima else ""), "",
             "| error | local/global: it, ms | Newton: it, ms | faster |", "|---|---|---|---|"]
    crossover = None
    ahead = []
    for level in ACCURACY_LEVELS:
        a, b = first(lg_err, lg_sec, level), first(nt_err, nt_sec, level)
        faster = ("local/global" if a and (not b or a[1] < b[1]) else
                  "Newton" if b else "neither")
        if faster == "local/global" and crossover is None:
            ahead.append(level)
        if faster == "Newton" and crossover is None:
            crossover = level
        fmt = lambda hit: "not reached" if hit is None else f"{hit[0]}, {1e3 * hit[1]:.3g}"  # noqa: E731
        lines.append(f"| {level:.0e} | {fmt(a)} | {fmt(b)} | {faster} |")
    per_it = float(lg_sec[min(10, m - 1)] / max(min(10, m - 1), 1)) if m > 1 else math.nan
    newton_one = float(nt_sec[1]) if len(nt_sec) > 1 else math.nan
    lines += ["",
              (f"local/global is ahead of Newton down to error {min(ahead):.0e}" if ahead
               else "local/global is never ahead of Newton on this step"),
              (f"crossover: Newton is faster from error {crossover:.0e} on" if crossover
               else "no crossover within the measured levels"),
              f"10 local/global iterations cost {10 * per_it * 1e3:.3g} ms = "
              f"{10 * per_it / newton_one:.2f} of one Newton iteration ({newton_one * 1e3:.3g} ms,"
              f" factorization included)",
              f"medians of {repeats} interleaved repeats, {threads} BLAS thread(s)"]
    return "\n".join(lines)
