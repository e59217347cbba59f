"""Timings a referee accepts: interleaved repeats, fixed BLAS threads, one-off costs apart.

:func:`time_configurations` solves every measured step with every configuration, ``repeats``
times, interleaved (repeat 1 of every configuration, then repeat 2, …), so a slow phase of
a shared machine hits all configurations alike. Given the errors the answers use, it
repeats only the configurations an answer could choose: after the first repeat, one for
which another setting reaches every answered target it reaches, in every error, in at most
half its time, is not timed again (:mod:`.dominance`). BLAS/OpenMP threads are fixed with
threadpoolctl during measurement. The cached factorization of M + h² L is built before
timing (a one-off cost, reported apart by :func:`one_off_costs`, as is ρ estimation for
Chebyshev). :func:`machine_info` is written next to the CSV.
"""

from __future__ import annotations

import contextlib
import math
import os
import platform
import time
import warnings
from collections.abc import Sequence

import numpy as np

from ..model import Model
from ..solvers import LocalGlobalSolver, estimate_spectral_radius
from .decide import MAX_REPEATS
from .dominance import dominated
from .phases import add, advance, shrink
from .study import BLOW_UPS, ConfigResult, StudyStep


def _limited_threads(threads: int):
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:  # pragma: no cover - threadpoolctl is a dependency
        return contextlib.nullcontext()
    return threadpool_limits(limits=threads)


def timing_clock(threads: int = 1):
    """The clock timings are read on: this process's CPU seconds with one BLAS thread (the
    work itself: on a shared machine, wall time adds the time spent waiting for a core,
    which moved single samples by 6x and medians by 3x under a load of 10 on 2 cores), wall
    seconds with more threads (their CPU seconds add up).

    Parameters
    ----------
    threads : int, default 1
        BLAS threads during timing.

    Returns
    -------
    tuple of (callable, str)
        The clock and its name ("process CPU" or "wall").
    """
    return (time.process_time, "process CPU") if threads == 1 else (time.perf_counter,
                                                                       "wall")


MIN_SAMPLE_SECONDS = 0.05
"""A timing sample repeats its pass over the steps until it lasts at least this long [s]: a
pass of a 1-iteration setting takes about a millisecond, where clock resolution, caches and
interrupts made identical work (Chebyshev 1 it and local/global 1 it) differ by 20 %."""


def _time_once(solver, problems, clock=time.perf_counter) -> float:
    """Mean seconds per step of passes of ``solver`` over ``problems`` on ``clock``, as many
    passes as make :data:`MIN_SAMPLE_SECONDS` (the timing seam: tests replace it by a
    deterministic clock)."""
    passes, t0 = 0, clock()
    while True:
        for p in problems:
            solver.solve(p)
        passes += 1
        spent = clock() - t0
        if spent >= MIN_SAMPLE_SECONDS:
            return spent / (passes * len(problems))


def time_configurations(model: Model, steps: Sequence[StudyStep],
                        results: Sequence[ConfigResult], *, repeats: int = 5,
                        threads: int = 1,
                        errors: Sequence[Sequence[float]] | None = None,
                        levels=None, undecided=None, cap: int = MAX_REPEATS) -> set[int]:
    """Fill each result's ``seconds`` with per-step times [s] (:func:`timing_clock`), one
    per repeat.

    Each repeat solves all measured steps with one configuration (as many passes as last
    :data:`MIN_SAMPLE_SECONDS`) and records the mean seconds per step; configurations are
    interleaved within each repeat. With ``errors``, repeats after the second skip the
    configurations no answer can choose (:func:`~.dominance.dominated`, on the fastest of
    two samples of each, so that one slow sample never drops a setting); they keep their two
    times. With ``undecided``, further interleaved rounds time the configurations it names
    until it names none or each has ``cap`` samples (:mod:`.decide`).

    Parameters
    ----------
    model : Model
        The cloth.
    steps : sequence of StudyStep
        Only measured steps are solved.
    results : sequence of ConfigResult
        Filled in place (``seconds``).
    repeats : int, default 5
        Interleaved repeats of every configuration an answer could choose.
    threads : int, default 1
        BLAS threads during timing.
    errors : sequence of sequence of float, optional
        Per result, the errors the answers read (same order for all; NaN: not measured);
        None times every configuration ``repeats`` times.
    levels : sequence, optional
        Per error, the targets the answers ask about (:func:`~.dominance.dominated`).
    undecided : callable, optional
        ``undecided() -> set of int``: results to time again (read from their ``seconds``
        so far), empty when every answer is decided (:func:`~.decide.undecided`).
    cap : int, default :data:`~.decide.MAX_REPEATS`
        Most samples of one configuration in the ``undecided`` rounds.

    Returns
    -------
    set of int
        Indices of the results left out of later repeats because they are dominated (empty
        without ``errors``); ``results`` are changed in place.
    """
    measured = [s.step.problem for s in steps if s.measured]
    if not measured:
        return set()
    skipped: set[int] = set()
    clock = timing_clock(threads)[0]
    solvers = [r.config.solver(model) for r in results]
    broken = set()

    def one_round(which) -> None:
        for i in which:
            if i in broken or results[i].diverged:  # blown up: not timed
                continue
            try:
                results[i].seconds.append(_time_once(solvers[i], measured, clock))
            except BLOW_UPS:
                broken.add(i)
                continue
            advance()

    with warnings.catch_warnings(), _limited_threads(threads), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        for i, solver in enumerate(solvers):  # warm-up: factor M + h² L, estimate ρ (one-off)
            its, tol = solver.iterations, solver.tolerance
            solver.iterations, solver.tolerance = 1, None  # one iteration does all of it
            try:
                solver.solve(measured[0])
            except BLOW_UPS:
                broken.add(i)
            finally:
                solver.iterations, solver.tolerance = its, tol
        for repeat in range(repeats):
            if repeat == 2 and errors is not None:  # only what an answer could choose
                fastest = [min(r.seconds) if r.seconds and i not in broken else math.nan
                           for i, r in enumerate(results)]
                typical = [float(np.median(r.seconds)) if r.seconds and i not in broken
                           else math.nan for i, r in enumerate(results)]
                skipped = dominated([r.config.method for r in results], fastest, errors,
                                    levels=levels, against=typical)
                shrink(len(skipped) * (repeats - 2))
            one_round(i for i in range(len(results)) if i not in skipped)
        # until decided: a setting that became a close candidate late (the leader changed)
        # gets its samples too; each round adds one to every setting it times, so this ends
        for _ in range(cap * len(results)):
            again = (set() if undecided is None
                     else {i for i in undecided() if len(results[i].seconds) < cap} - broken)
            if not again:
                break
            add(len(again))
            one_round(sorted(again))
    for i in broken:
        results[i].diverged = max(results[i].diverged, 1)
        results[i].seconds.clear()
    return skipped - broken


def median_iqr(seconds: Sequence[float]) -> tuple[float, float]:
    """(median, inter-quartile range) [s]; NaN when empty (the IQR too for one sample).

    Parameters
    ----------
    seconds : sequence of float
        Wall times [s].

    Returns
    -------
    tuple of float
        (median, q3 − q1) [s]; the IQR is NaN for a single repeat.
    """
    if not len(seconds):
        return math.nan, math.nan
    if len(seconds) == 1:   # no spread is measured by one repeat
        return float(seconds[0]), math.nan
    q1, q2, q3 = np.quantile(np.asarray(seconds), [0.25, 0.5, 0.75])
    return float(q2), float(q3 - q1)


def one_off_costs(model: Model, steps: Sequence[StudyStep], *, repeats: int = 3,
                  threads: int = 1) -> dict[str, float]:
    """Median seconds of the one-off costs: factoring M + h² L and estimating ρ.

    Parameters
    ----------
    model : Model
        The cloth.
    steps : sequence of StudyStep
        The first measured step is used.
    repeats : int, default 3
        Repeats (medians are returned).
    threads : int, default 1
        BLAS threads.

    Returns
    -------
    dict of str to float
        ``factorization_seconds`` and ``rho_estimation_seconds`` [s]; empty when no
        step is measured.
    """
    measured = [s for s in steps if s.measured]
    if not measured:
        return {}
    problem = measured[0].step.problem
    fac, rho = [], []
    with _limited_threads(threads):
        for _ in range(repeats):
            lg = LocalGlobalSolver(model, check_conditioning=False)
            t0 = time.perf_counter()
            lg.system(problem)
            fac.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            estimate_spectral_radius(model, problem, solver=lg)
            rho.append(time.perf_counter() - t0)
    return {"factorization_seconds": float(np.median(fac)),
            "rho_estimation_seconds": float(np.median(rho))}


def source_commit() -> str:
    """The git commit of the clothsim source that runs ("+dirty" with local changes).

    Returns
    -------
    str
        A short hash, or "unknown" outside a git checkout.
    """
    import subprocess
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    try:
        head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=root, text=True,
                              capture_output=True, check=True, timeout=10).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no",
                                "clothsim"], cwd=root, text=True, capture_output=True,
                               check=True, timeout=10).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    return head + ("+dirty" if dirty else "")


def installed_version() -> str:
    """clothsim's installed version ("unknown" when run from a source tree not installed).

    Returns
    -------
    str
        The package metadata's version.
    """
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("clothsim")
    except PackageNotFoundError:  # pragma: no cover - running from a source tree
        return "unknown"


def machine_info(threads: int = 1) -> dict:
    """Machine, Python and library versions, and the thread settings of the measurement.

    Parameters
    ----------
    threads : int, default 1
        BLAS threads used by the measurement (recorded as given).

    Returns
    -------
    dict
        JSON-able description (platform, versions, threadpools, CHOLMOD availability).
    """
    import scipy

    clothsim_version = installed_version()
    info = {"machine": platform.machine(), "processor": platform.processor(),
            "platform": platform.platform(), "cpu_count": os.cpu_count(),
            "python": platform.python_version(), "numpy": np.__version__,
            "scipy": scipy.__version__, "clothsim": clothsim_version,
            "commit": source_commit(),
            "blas_threads": threads}
    try:
        from threadpoolctl import threadpool_info

        info["threadpools"] = [{k: p.get(k) for k in ("internal_api", "version",
                                                       "num_threads")}
                               for p in threadpool_info()]
    except ImportError:  # pragma: no cover
        pass
    try:
        from ..factorization import cholmod_available

        info["cholmod"] = cholmod_available()
    except ImportError:  # pragma: no cover
        pass
    return info
