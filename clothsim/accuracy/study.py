"""The solver-error study: every configuration on the same recorded step problems.

For each recorded step (:mod:`clothsim.accuracy.problems`) that teaches something, a
certified reference (:mod:`clothsim.accuracy.reference`) is computed once; every
configuration (a method with a fixed iteration budget, or with a residual tolerance) then
solves the same problems. Steps are classified by their certificates (:data:`KINDS`):

``"unique"``
    every start reached the same certified minimum x*: the relative solver error
    ‖x − x*‖ / ‖x* − x_n‖ is measured;
``"several-minima"``
    the starts reached several certified minima: measured by the relative objective gap
    (g(x) − g(x_best)) / (g(y) − g(x_best)) (a distance to one minimum is no error);
``"saddle"``
    Newton from y ended at a stationary point whose Hessian is indefinite (never reported
    as a minimum; not measured);
``"reference-failed"``
    Newton from y did not reach its rounding floor (not measured);
``"trivial"``, ``"at-rest"``
    see :func:`~clothsim.accuracy.problems.classify`.

Per configuration: the distribution (median, 90th percentile, worst) of the solver error
over the unique steps, of the objective gap over every measured step, and of the
iterations it used.
The error measurement parallelises over (configuration, step) pairs with joblib
(:func:`measure`, ``jobs``); it is deterministic, so any ``jobs`` gives the same errors.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from ..model import Model
from ..solvers import estimate_spectral_radius, make_solver
from .blowups import BLOW_UPS  # noqa: F401  (re-exported: timing, timestep)
from .limits import limit_error
from .parallel import map_jobs
from .phases import advance
from .problems import RecordedStep, classify
from .reference import CertifiedReference, certified_reference
from .runs import Solve, Stop, method_runs, stops

log = logging.getLogger(__name__)

BUDGETS = (1, 2, 5, 10, 20, 50, 100, 200)
"""Iterations per step of the fixed-budget configurations (Newton: up to 10)."""
TOLERANCES = (1e-2, 1e-4, 1e-6, 1e-8)
"""Relative-residual tolerances of the tolerance configurations."""
TOLERANCE_CAP = {"newton": 100}
DEFAULT_CAP = 5000


@dataclass(frozen=True)
class Configuration:
    """One setting a user could run: a method with an iteration budget or a tolerance.

    Attributes
    ----------
    method : str
        Solver name (:data:`clothsim.solvers.SOLVERS`).
    iterations : int
        Iterations per step (the cap when ``tolerance`` is set).
    tolerance : float or None
        Relative-residual tolerance ‖∇g(x_k)‖ / ‖∇g(x_0)‖, or None (fixed budget).
    options : tuple of (str, object)
        Extra solver constructor options, as sorted (name, value) pairs.
    label : str
        A short name for tables, e.g. ``"chebyshev 10 it"``.
    """

    method: str
    iterations: int
    tolerance: float | None = None
    options: tuple = ()

    def solver(self, model: Model):
        """A fresh solver of this configuration.

        Parameters
        ----------
        model : Model
            The cloth.

        Returns
        -------
        Solver
        """
        return make_solver(self.method, model, iterations=self.iterations,
                           tolerance=self.tolerance, **dict(self.options))

    @property
    def stop(self) -> Stop:
        """Where its ``solve`` stops (:class:`~.runs.Stop`)."""
        return Stop(self.iterations, self.tolerance)

    @property
    def label(self) -> str:
        if self.tolerance is not None:
            return f"{self.method} tol {self.tolerance:g}"
        return f"{self.method} {self.iterations} it"


KINDS = ("unique", "several-minima", "saddle", "reference-failed", "trivial", "at-rest")
"""Step classes, by certificate (module text)."""
MEASURED = ("unique", "several-minima")
"""The classes whose steps every configuration solves."""


@dataclass
class StudyStep:
    """A recorded step with its classification and (when measured) its reference.

    Attributes
    ----------
    step : RecordedStep
        The step problem as recorded.
    kind : str
        One of :data:`KINDS`.
    rest_ratio : float
        ‖∇g(y)‖ / rounding floor.
    one_iteration_error : float
        Relative error of one local/global iteration.
    reference : CertifiedReference or None
        The certified x* (None for steps at rest).
    limits : dict
        Method → :class:`~clothsim.accuracy.limits.MethodLimit`, its own limit (measured
        steps, after :func:`~clothsim.accuracy.limits.method_limits`).
    """

    step: RecordedStep
    kind: str                      # one of KINDS
    rest_ratio: float              # ‖∇g(y)‖ / rounding floor
    one_iteration_error: float
    reference: CertifiedReference | None = None
    rho: float = math.nan          # local/global decay rate (measured steps)
    limits: dict = field(default_factory=dict)

    @property
    def measured(self) -> bool:
        """Whether every configuration solves this step (a class of :data:`MEASURED`)."""
        return self.kind in MEASURED


@dataclass
class ConfigResult:
    """Errors and iterations of one configuration over the measured steps.

    Attributes
    ----------
    config : Configuration
    errors : ndarray, shape (m,)
        Relative solver error ‖x − x*‖ / ‖x* − x_n‖ per measured step (inf if not finite).
    iterations : ndarray of int, shape (m,)
        Iterations used per step.
    seconds : list of float
        Per-step wall time [s], one entry per timing repeat.
    factorizations : float
        Mean factorizations per step (Newton), hardware independent.
    diverged : int
        Measured steps on which the configuration blew up (a non-finite state, force or
        error, or a failed factorization); their error is inf.
    trajectory_diverged : bool
        Its whole-run trajectory blew up.
    gaps : ndarray, shape (m,)
        Relative objective gap (g(x) − g(x_best)) / (g(y) − g(x_best)) per measured step.
    unique : ndarray of bool, shape (m,)
        Which measured steps are "unique" (their solver error is defined).
    limit_errors : ndarray, shape (m,)
        ‖x − x_lim‖ / ‖x_lim − x_n‖ to the method's own limit per measured step (NaN: no
        limit computed).
    residuals : ndarray, shape (m,)
        Relative residual ‖∇g(x)‖ / ‖∇g(x_0)‖ (x_0 = y) per measured step.
    """

    config: Configuration
    errors: np.ndarray                       # (m,) relative solver error per measured step
    iterations: np.ndarray                   # (m,) iterations used per step
    seconds: list[float] = field(default_factory=list)   # per-step seconds, one per repeat
    factorizations: float = 0.0              # per step (Newton), hardware independent
    diverged: int = 0
    trajectory_diverged: bool = False
    gaps: np.ndarray = field(default_factory=lambda: np.zeros(0))
    unique: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))
    limit_errors: np.ndarray = field(default_factory=lambda: np.zeros(0))
    residuals: np.ndarray = field(default_factory=lambda: np.zeros(0))


def prepare_steps(model: Model, recorded: Sequence[RecordedStep], *,
                  backend: str = "auto", jobs: int = 1, cap: int = DEFAULT_CAP,
                  local_global_stops: Sequence[Stop] = ()) -> list[StudyStep]:
    """Classify each recorded step and certify the reference of those worth measuring.

    Parameters
    ----------
    model : Model
        The cloth.
    recorded : sequence of RecordedStep
        Steps recorded from a run (:mod:`clothsim.accuracy.problems`).
    backend : {"auto", "cholmod", "splu"}
        Factorization backend.
    jobs : int, default 1
        Parallel workers, one step each (:func:`~.parallel.map_jobs`; same result).
    cap : int
        Iteration cap of the references' local/global runs (local/global's own limit).
    local_global_stops : sequence of Stop
        The study's local/global settings, kept from those runs
        (:attr:`~.reference.CertifiedReference.local_global_runs`).

    Returns
    -------
    list of StudyStep
        One per recorded step, in order.
    """
    out = map_jobs(_prepare_one, [(model, rec, backend, cap, tuple(local_global_stops))
                                  for rec in recorded], jobs=jobs, each=lambda _: advance())
    for s in out:
        ref = s.reference
        log.info("step %d: %s (|grad g(y)|/floor %.2e, one-iteration error %.2e%s, rho %.4f)",
                 s.step.index, s.kind, s.rest_ratio, s.one_iteration_error,
                 "" if ref is None else f", residual {ref.residual:.1e}, min eig "
                 f"{ref.min_eigenvalue:.3g}, uncertainty {ref.uncertainty:.1e}", s.rho)
    return out


def _prepare_one(model: Model, rec: RecordedStep, backend: str, cap: int,
                 local_global_stops: tuple) -> StudyStep:
    """One recorded step, classified, with its certified reference and ρ."""
    ref = certified_reference(model, rec.problem, backend=backend, local_global_cap=cap,
                              local_global_stops=local_global_stops)
    kind, ratio, err1 = classify(model, rec.problem, ref.x)
    if kind == "measured":
        if not ref.certified:
            kind = ("saddle" if ref.at_floor and not ref.positive_definite
                    else "reference-failed")
        else:
            kind = "several-minima" if ref.two_minima else "unique"
    rho = (estimate_spectral_radius(model, rec.problem, backend=backend)
           if kind in MEASURED else math.nan)
    return StudyStep(rec, kind, ratio, err1, ref if kind != "at-rest" else None, rho)


def default_configurations(methods: Sequence[str], *, budgets: Sequence[int] = BUDGETS,
                           tolerances: Sequence[float] = TOLERANCES,
                           options: dict | None = None,
                           cap: int = DEFAULT_CAP) -> list[Configuration]:
    """Budget and tolerance configurations for each method (Newton budgets ≤ 10).

    Parameters
    ----------
    methods : sequence of str
        Solver names.
    budgets : sequence of int
        Iterations per step of the fixed-budget configurations.
    tolerances : sequence of float
        Relative-residual tolerances (iterations capped at 5000, Newton 100).
    options : dict, optional
        Extra solver options per method, e.g. ``{"chebyshev": {"rho": 0.99}}``.
    cap : int
        Iteration cap of the tolerance configurations (Newton: 100).

    Returns
    -------
    list of Configuration
    """
    out = []
    for m in methods:
        opts = tuple(sorted((options or {}).get(m, {}).items()))
        its = [b for b in budgets if m != "newton" or b <= 10]
        out += [Configuration(m, int(b), None, opts) for b in its]
        its_cap = TOLERANCE_CAP.get(m, cap)
        out += [Configuration(m, its_cap, float(t), opts) for t in tolerances]
    return out


def chebyshev_rho(model: Model, steps: Sequence[StudyStep], *, backend: str = "auto") -> float:
    """ρ for the chebyshev configurations: the largest estimate over the measured steps
    (an underestimate diverges; see :mod:`clothsim.solvers.chebyshev`). A step's own
    estimate (``StudyStep.rho``) is reused when it has one.

    Parameters
    ----------
    model : Model
        The cloth.
    steps : sequence of StudyStep
        Only measured steps (:data:`MEASURED`) are used.
    backend : {"auto", "cholmod", "splu"}
        Factorization backend.

    Returns
    -------
    float
        ρ in [0, 1) (0 when no step is measured).
    """
    rhos = [s.rho if math.isfinite(s.rho)
            else estimate_spectral_radius(model, s.step.problem, backend=backend)
            for s in steps if s.measured]
    return max(rhos, default=0.0)


def _result(model: Model, study_step: StudyStep, config: Configuration, run: Solve) -> tuple:
    """(relative error, iterations, factorizations, diverged, objective gap, limit error,
    relative residual) of one configuration's solve."""
    if run.x is None:
        return math.inf, 0, 0, True, math.inf, math.inf, math.inf
    problem = study_step.step.problem
    x_star = study_step.reference.x
    scale = float(np.linalg.norm(x_star - problem.x)) or 1.0
    err = float(np.linalg.norm(run.x - x_star)) / scale
    if not math.isfinite(err):
        return math.inf, run.iterations, 0, True, math.inf, math.inf, math.inf
    gap = study_step.reference.objective_gap(model, problem, run.x)
    return err, run.iterations, run.factorizations if config.method == "newton" else 0, \
        False, gap, limit_error(study_step, config.method, run.x), run.residual


def measure(model: Model, steps: Sequence[StudyStep], configs: Sequence[Configuration], *,
            jobs: int = 1, scheduler: str | None = None,
            runs: dict | None = None) -> list[ConfigResult]:
    """Solver error and iterations of every configuration on every measured step.

    The configurations of one method are read off one run per step (:mod:`.runs`): the
    iterate where each one's ``solve`` would stop, the same bit for bit.

    Parameters
    ----------
    model : Model
        The cloth.
    steps : sequence of StudyStep
        From :func:`prepare_steps`; only measured steps (:data:`MEASURED`) are solved.
    configs : sequence of Configuration
        What to run.
    jobs : int
        Parallel workers (joblib, loky backend), one run each; 1 runs serially.
    scheduler : str, optional
        Address of a Dask scheduler: run through joblib's dask backend instead.
    runs : dict, optional
        :func:`~.runs.method_runs` already made (the study's limit runs, which hold their
        method's configurations too); the methods it lacks are run here.

    Returns
    -------
    list of ConfigResult
        Same order as ``configs``; identical for any ``jobs`` and ``scheduler``.
    """
    measured = [s for s in steps if s.measured]
    unique = np.array([s.kind == "unique" for s in measured], dtype=bool)
    runs = dict(runs or {})
    todo = {key: wanted for key, wanted in stops(configs).items()
            if any((s.step.index, *key, w) not in runs for s in measured for w in wanted)}
    runs |= method_runs(model, steps, todo, jobs=jobs, scheduler=scheduler)
    out = []
    for c in configs:
        chunk = [_result(model, s, c, runs[(s.step.index, c.method, c.options, c.stop)])
                 for s in measured]
        out.append(ConfigResult(c, np.array([r[0] for r in chunk]),
                                np.array([r[1] for r in chunk]),
                                factorizations=float(np.mean([r[2] for r in chunk]))
                                if chunk else 0.0,
                                diverged=sum(bool(r[3]) for r in chunk),
                                gaps=np.array([r[4] for r in chunk], dtype=np.float64),
                                unique=unique.copy(),
                                limit_errors=np.array([r[5] for r in chunk], dtype=np.float64),
                                residuals=np.array([r[6] for r in chunk], dtype=np.float64)))
    return out


def quantiles(values: np.ndarray) -> tuple[float, float, float]:
    """(median, 90th percentile, max) of ``values`` (NaN when empty; inf propagates).

    Parameters
    ----------
    values : array_like, shape (m,)
        Any samples (e.g. relative errors).

    Returns
    -------
    tuple of float
        (median, 90th percentile, maximum), in the unit of ``values``.
    """
    v = np.asarray(values, dtype=np.float64)
    if len(v) == 0:
        return math.nan, math.nan, math.nan
    if not np.all(np.isfinite(v)):
        v = np.where(np.isfinite(v), v, np.inf)
        return (float(np.quantile(v, 0.5, method="nearest")),
                float(np.quantile(v, 0.9, method="nearest")), float(v.max()))
    return float(np.median(v)), float(np.quantile(v, 0.9)), float(v.max())
