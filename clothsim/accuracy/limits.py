"""Each method's own limit per measured step, and that basin's objective gap.

On a non-convex step (contact, crumpling) a method may converge fast — to a worse minimum.
The solver error to x* and the objective gap to x_best do not tell "not converged yet" from
"converged elsewhere"; the error to the method's *own limit* does. Per measured step and
per method (:func:`method_limits`):

- the limit x_lim: the method (with its study options, e.g. Chebyshev's ρ) run from the
  same start to :data:`LIMIT_TOLERANCE` or its rounding floor (at most :data:`LIMIT_CAP`
  iterations), then Newton from
  there to its floor, which certifies it (‖∇g‖ at the floor, λ_min > 0) and moves a
  converged point by rounding only. Newton's own limit is the reference x* (Newton from
  y); local/global's is the converged local/global run the reference already made
  (:class:`~clothsim.accuracy.reference.CertifiedReference`), so neither costs anything;
- whether the method reached its floor before the cap (``converged``), and whether x_lim
  is a certified minimum;
- the basin's gap (g(x_lim) − g(x_best)) / (g(y) − g(x_best)), without cancellation
  (:meth:`~clothsim.accuracy.reference.CertifiedReference.objective_gap`): 0 when the method
  ends at the best minimum found, > 0 when it ends in a worse basin.

Every certified limit joins the step's set of minima (y, x_n, each method's limit): a limit
lower than x_best becomes x_best, and a "unique" step whose limits differ becomes
"several-minima". A configuration's *limit error* on a step is
‖x − x_lim‖ / ‖x_lim − x_n‖ (:func:`limit_error`).

The limit run is the longest of the method's runs on the step (:mod:`.runs`): the study
reads the method's configurations off the same iterates (:func:`~.study.measure`).
"""

from __future__ import annotations

import logging
import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..model import Model
from ..solvers import NewtonSolver
from ..solvers.descent import objective_difference
from .blowups import BLOW_UPS
from .parallel import map_jobs
from .phases import advance
from .reference import REFERENCE_ITERATIONS, SAME_POINT
from .runs import Solve, Stop, method_runs

log = logging.getLogger(__name__)

LIMIT_TOLERANCE = 1e-10
"""Relative residual at which a limit run stops (or at its rounding floor, if that comes
first): 100 times below the study's smallest tolerance; Newton then polishes to the floor
(accelerated methods can stall just above the floor, so a floor-only rule wastes the cap)."""
LIMIT_CAP = 5000
"""Iteration cap of a limit run (the tolerance configurations' default cap)."""


@dataclass
class MethodLimit:
    """Where one method converges to on one step.

    Attributes
    ----------
    method : str
        Solver name.
    x : ndarray, shape (n, 3), or None
        The limit [m] (None when the method blew up).
    converged : bool
        The method reached :data:`LIMIT_TOLERANCE` or its rounding floor (local/global,
        reused from the reference: 1e-6) before the cap.
    certified : bool
        x is a certified minimum (Newton's floor and λ_min > 0 there).
    gap : float
        (g(x) − g(x_best)) / (g(y) − g(x_best)), dimensionless (inf: blew up).
    iterations : int
        Iterations of the method's own run (0 when reused from the reference).
    same_as_best : bool
        ‖x − x_best‖ / ‖x* − x_n‖ ≤ :data:`~clothsim.accuracy.reference.SAME_POINT`.
    """

    method: str
    x: np.ndarray | None
    converged: bool
    certified: bool
    gap: float = math.nan
    iterations: int = 0
    same_as_best: bool = False


def _newton(model, backend):
    return NewtonSolver(model, iterations=REFERENCE_ITERATIONS, tolerance=1e-15,
                        backend=backend)


def limit_stop(cap: int):
    """The stop of a method's own limit run (:class:`~.runs.Stop`): ``cap`` iterations,
    :data:`LIMIT_TOLERANCE`.

    Parameters
    ----------
    cap : int
        Iteration cap.

    Returns
    -------
    Stop
    """
    return Stop(int(cap), LIMIT_TOLERANCE)


def limit_stops(steps: Sequence, methods: Sequence[str], *, options: dict | None = None,
                cap: int = LIMIT_CAP) -> dict:
    """The runs :func:`method_limits` needs: (method, options) → [:func:`limit_stop`] for
    each method whose limit the references do not give on some measured step.

    Parameters
    ----------
    steps : sequence of StudyStep
        With their references.
    methods : sequence of str
        Solver names.
    options : dict, optional
        Solver options per method.
    cap : int
        Iteration cap of a limit run.

    Returns
    -------
    dict
        As :func:`~.runs.method_runs` takes it.
    """
    return {(m, tuple(sorted((options or {}).get(m, {}).items()))): [limit_stop(cap)]
            for m in methods if any(s.measured and not _known(s, m) for s in steps)}


def _polish(model: Model, problem, method: str, run: Solve, backend: str) -> MethodLimit:
    """Newton from the end of the method's limit run: the limit, certified."""
    try:
        if run.x is None or not np.all(np.isfinite(run.x)):
            raise FloatingPointError("non-finite limit")
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            polish = _newton(model, backend).solve(problem, x0=run.x)
    except BLOW_UPS as exc:
        log.warning("%s's own limit on step: diverged (%s)", method, exc)
        return MethodLimit(method, None, False, False, math.inf)
    return MethodLimit(method, polish.x, bool(run.converged), bool(polish.certified),
                       iterations=int(run.iterations))


def _merge_minimum(model: Model, problem, ref, x: np.ndarray) -> bool:
    """Add a certified point to the reference's minima (updating x_best); True if new."""
    scale = float(np.linalg.norm(ref.x - problem.x)) or 1.0
    if any(float(np.linalg.norm(x - m)) / scale <= SAME_POINT for m in ref.minimum_points):
        return False
    ref.minimum_points.append(x)
    dgs = [objective_difference(model, problem, ref.x, m - ref.x) for m in ref.minimum_points]
    best = int(np.argmin(dgs))
    ref.x_best = ref.minimum_points[best]
    ref.objective_difference = float(dgs[best])
    ref.objective_scale = float(objective_difference(
        model, problem, ref.x_best, problem.initial_guess() - ref.x_best))
    ref.minima = len(ref.minimum_points)
    if ref.minima > 1:
        ref.two_minima, ref.uncertainty = True, math.nan
    return True


def _known(step, method: str) -> bool:
    """The reference's own runs give Newton's and (when run) local/global's limit."""
    return method == "newton" or (method == "local-global"
                                  and step.reference.local_global is not None)


def method_limits(model: Model, steps: Sequence, methods: Sequence[str], *,
                  options: dict | None = None, cap: int = LIMIT_CAP,
                  backend: str = "auto", jobs: int = 1, runs: dict | None = None) -> None:
    """Each method's own limit on every measured step (module text), in place.

    Fills ``step.limits`` (method → :class:`MethodLimit`), adds every certified limit to
    the step's minima (which may change x_best and turn a "unique" step into
    "several-minima"), then computes each limit's basin gap against the final x_best.

    Parameters
    ----------
    model : Model
        The cloth.
    steps : sequence of StudyStep
        From :func:`~clothsim.accuracy.study.prepare_steps`; only measured steps are run.
    methods : sequence of str
        Solver names (the study's methods).
    options : dict, optional
        Solver options per method, as the study's configurations use them.
    cap : int
        Iteration cap of a method's run.
    backend : {"auto", "cholmod", "splu"}
        Factorization backend.
    jobs : int, default 1
        Parallel workers for the methods' own runs (:func:`~.parallel.map_jobs`; the
        limits are merged in order afterwards, so the result does not depend on it).
    runs : dict, optional
        :func:`~.runs.method_runs` holding each method's :func:`limit_stop` (the study
        shares its runs with the error measurement); default: run them here.
    """
    stop = limit_stop(cap)
    todo = [(s, m) for s in steps if s.measured for m in methods if not _known(s, m)]
    opts = {m: tuple(sorted((options or {}).get(m, {}).items())) for m in methods}
    if runs is None:
        runs = method_runs(model, steps, limit_stops(steps, methods, options=options, cap=cap),
                           backend=backend, jobs=jobs)
    own = iter(map_jobs(_polish, [(model, s.step.problem, m,
                                   runs[(s.step.index, m, opts[m], stop)], backend)
                                  for s, m in todo], jobs=jobs, each=lambda _: advance()))
    for s in steps:
        if not s.measured:
            continue
        ref, problem = s.reference, s.step.problem
        limits = {}
        for m in methods:
            if m == "newton":
                lim = MethodLimit(m, ref.x, bool(ref.at_floor), bool(ref.certified))
                advance()
            elif _known(s, m):
                lg = ref.local_global
                lim = MethodLimit(m, lg.x, bool(ref.local_global_converged),
                                  bool(lg.certified))
                advance()
            else:
                lim = next(own)
            limits[m] = lim
            if lim.certified and lim.x is not None:
                _merge_minimum(model, problem, ref, lim.x)
        if s.kind == "unique" and ref.minima > 1:
            s.kind = "several-minima"
        scale = float(np.linalg.norm(ref.x - problem.x)) or 1.0
        for lim in limits.values():
            if lim.x is None:
                continue
            lim.gap = ref.objective_gap(model, problem, lim.x)
            lim.same_as_best = float(np.linalg.norm(lim.x - ref.x_best)) / scale <= SAME_POINT
            log.info("step %d: %s's own limit: gap %.2e, converged %s, certified %s",
                     s.step.index, lim.method, lim.gap, lim.converged, lim.certified)
        s.limits = limits


def limit_error(study_step, method: str, x: np.ndarray) -> float:
    """‖x − x_lim‖ / ‖x_lim − x_n‖ of a solve of ``method`` on a step.

    Parameters
    ----------
    study_step : StudyStep
        A measured step with its limits (:func:`method_limits`).
    method : str
        The solver that produced ``x``.
    x : ndarray, shape (n, 3)
        Its answer [m].

    Returns
    -------
    float
        Dimensionless; NaN when the method's limit is unknown (not computed, or it blew up),
        inf when ``x`` is not finite.
    """
    lim = (getattr(study_step, "limits", None) or {}).get(method)
    if lim is None or lim.x is None:
        return math.nan
    if not np.all(np.isfinite(x)):
        return math.inf
    scale = float(np.linalg.norm(lim.x - study_step.step.problem.x)) or 1.0
    return float(np.linalg.norm(x - lim.x)) / scale


def worse_minimum_notes(steps: Sequence, target: float) -> list[str]:
    """One note per method whose own limit's basin gap exceeds ``target`` on some step.

    Parameters
    ----------
    steps : sequence of StudyStep
        With their limits.
    target : float
        The answer's target (dimensionless).

    Returns
    -------
    list of str
        E.g. "chebyshev converges to a worse minimum on step 12 (its limit's objective gap
        3.1e-03 > target 1e-03)"; empty when none does.
    """
    worse: dict[str, list] = {}
    for s in steps:
        for lim in (getattr(s, "limits", None) or {}).values():
            if math.isfinite(lim.gap) and lim.gap > target:
                worse.setdefault(lim.method, []).append((s.step.index, lim.gap))
    return [f"{m} converges to a worse minimum on step(s) "
            f"{', '.join(str(i) for i, _ in hits)} (its own limit's objective gap up to "
            f"{max(g for _, g in hits):.1e} > target {target:.0e}): fast there is fast to "
            f"a worse minimum" for m, hits in worse.items()]
