"""One run per method and step: every configuration of the method is read off it.

A solver's iterates do not depend on its stop settings (iterations, tolerance), except
Newton's (its stop rule decides when it leaves a saddle along negative curvature). So the
configurations of one method on one step — its fixed budgets, its tolerances and its own
limit run (:mod:`.limits`) — are prefixes of one iteration: :func:`method_runs` runs it
once, from the same fresh solver a configuration's ``solve`` would use, and keeps, for each
configuration, the iterate where :meth:`~clothsim.solvers.Solver.solve`'s stop rule stops
it (``iterations`` reached, a non-finite residual, or with a tolerance the relative
residual at most the tolerance or ‖∇g‖ at its rounding floor; the last iterate when the
method returns early). The answers are those of a ``solve`` per configuration, bit for bit
(tests/accuracy/test_runs.py), for the work of the longest one: on the 21 × 21 seed demo
with held contacts the limits and the error measurement each ran the same 1000-iteration
prefixes. Newton runs once per configuration.
"""

from __future__ import annotations

import contextlib
import logging
import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import NonFiniteStateError
from ..factorization import single_threaded
from ..model import Model
from ..objective import relative
from ..solvers import LocalGlobalSolver, make_solver
from ..solvers.base import gradient_noise_floor
from .blowups import BLOW_UPS
from .parallel import map_jobs
from .phases import advance

log = logging.getLogger(__name__)

OWN_STOP = ("newton",)
"""Methods whose iterates depend on the stop settings: one run per configuration."""


@dataclass(frozen=True)
class Stop:
    """Where a configuration's ``solve`` stops.

    Attributes
    ----------
    iterations : int
        Its iteration cap.
    tolerance : float or None
        Its relative-residual tolerance (None: a fixed budget, no floor stop).
    """

    iterations: int
    tolerance: float | None = None


@dataclass
class Solve:
    """What one configuration's ``solve`` returns on one step (None x: it blew up).

    Attributes
    ----------
    x : ndarray, shape (n, 3), or None
        The iterate where the stop rule stopped [m]; None when the method blew up first.
    iterations : int
        Its iteration count.
    residual : float
        Relative residual ‖∇g(x)‖ / ‖∇g(x_0)‖ there.
    converged : bool
        With a tolerance: the residual at most the tolerance, or ‖∇g‖ at its floor.
    factorizations : int
        The solver's sparse factorizations up to there (Newton).
    """

    x: np.ndarray | None
    iterations: int = 0
    residual: float = math.inf
    converged: bool = False
    factorizations: int = 0


def run_stops(model: Model, problem, method: str, options: dict, stops: Sequence[Stop],
              backend: str = "auto") -> list[Solve]:
    """One run of ``method`` on one step, until every stop in ``stops`` has fired.

    Parameters
    ----------
    model : Model
        The cloth.
    problem : StepProblem
        The step (from its own initial guess).
    method : str
        Solver name.
    options : dict
        Solver options (e.g. Chebyshev's ρ).
    stops : sequence of Stop
        Where to keep the iterate (module text); one for Newton (:data:`OWN_STOP`).
    backend : {"auto", "cholmod", "splu"}
        Factorization backend.

    Returns
    -------
    list of Solve
        One per stop, in order (x None where the method blew up first).
    """
    solver = make_solver(method, model, iterations=max(s.iterations for s in stops),
                         tolerance=min((s.tolerance for s in stops if s.tolerance),
                                       default=None), backend=backend, **options)
    out: list[Solve | None] = [None] * len(stops)
    last = None
    try:
        # one thread, as LocalGlobalSolver.solve runs its family (Newton: as its solve)
        threads = (single_threaded() if isinstance(solver, LocalGlobalSolver)
                   else contextlib.nullcontext())
        with warnings.catch_warnings(), np.errstate(all="ignore"), threads:
            warnings.simplefilter("ignore")
            floor = r0 = None
            for last in solver.iterates(problem):
                rn = last.gradient_norm
                if floor is None:
                    if not math.isfinite(rn):
                        raise NonFiniteStateError("non-finite gradient at the start")
                    floor, r0 = gradient_noise_floor(model, problem, last.x), rn
                rel, finite = relative(rn, r0), math.isfinite(rn)
                for i, s in enumerate(stops):
                    if out[i] is None and (
                            last.k >= s.iterations or not finite
                            or (s.tolerance is not None
                                and (rel <= s.tolerance or rn <= floor))):
                        out[i] = _solve(solver, last, rel, rn <= floor, s)
                if all(o is not None for o in out):
                    break
    except BLOW_UPS as exc:
        log.warning("%s diverged on a step: %s", method, exc)
        return [o if o is not None else Solve(None) for o in out]
    # the method returned early (a fixed point, no descent): its last iterate for the rest
    rel = relative(last.gradient_norm, r0)
    at_floor = last.gradient_norm <= floor
    return [o if o is not None else _solve(solver, last, rel, at_floor, s)
            for o, s in zip(out, stops)]


def _solve(solver, it, rel: float, at_floor: bool, stop: Stop) -> Solve:
    converged = stop.tolerance is not None and (rel <= stop.tolerance or at_floor)
    return Solve(np.array(it.x, order="C"), int(it.k), float(rel), bool(converged),
                 int(getattr(solver, "factor_count", 0)))


def method_runs(model: Model, steps: Sequence, stops: dict, *, backend: str = "auto",
                jobs: int = 1, scheduler: str | None = None) -> dict:
    """Every method's stops on every measured step, one run per (step, method).

    Parameters
    ----------
    model : Model
        The cloth.
    steps : sequence of StudyStep
        Only measured steps are run.
    stops : dict
        (method, options) → sequence of :class:`Stop` (its configurations, its own limit
        run); options as sorted (name, value) pairs (e.g. Chebyshev's ρ).
    backend : {"auto", "cholmod", "splu"}
        Factorization backend.
    jobs : int, default 1
        Parallel workers, one run each (:func:`~.parallel.map_jobs`; same results).
    scheduler : str, optional
        Address of a Dask scheduler (joblib's dask backend).

    Returns
    -------
    dict
        (step index, method, options, stop) → :class:`Solve`.
    """
    tasks, keys = [], []
    for s in steps:
        if not s.measured:
            continue
        for (m, opts), wanted in stops.items():
            wanted = list(dict.fromkeys(wanted))
            for g in ([w] for w in wanted) if m in OWN_STOP else [wanted]:
                tasks.append((model, s.step.problem, m, dict(opts), g, backend))
                keys.append([(s.step.index, m, opts, w) for w in g])
    results = map_jobs(run_stops, tasks, jobs=jobs, scheduler=scheduler, each=lambda _: advance())
    return {k: r for ks, rs in zip(keys, results) for k, r in zip(ks, rs)}


def stops(configs: Sequence) -> dict:
    """(method, options) → the stops of its configurations, in order.

    Parameters
    ----------
    configs : sequence of Configuration
        :class:`~clothsim.accuracy.study.Configuration` objects.

    Returns
    -------
    dict
        As :func:`method_runs` takes it.
    """
    out: dict = {}
    for c in configs:
        out.setdefault((c.method, c.options), []).append(c.stop)
    return out


def run_count(stops: dict) -> int:
    """Runs per measured step that :func:`method_runs` makes for ``stops``.

    Parameters
    ----------
    stops : dict
        As :func:`method_runs` takes it.

    Returns
    -------
    int
    """
    return sum(len(set(w)) if m in OWN_STOP else 1 for (m, _), w in stops.items())
