"""Solver accuracy within one step: iterates of a solver against the converged step x*.

After k iterations (or t seconds) of a method, the relative error ‖x_k − x*‖ / ‖x* − x_n‖
against the converged step x* (Newton to ‖∇g‖ ≤ 1e-12 relative, :func:`converged_solution`)
and the objective gap g(x_k) − g(x*) [J·s²]. The iterates come from the solver's own
:meth:`~clothsim.solvers.Solver.iterates` (the same work per iteration as its ``solve``);
nothing here iterates on its own or changes a solver's settings.
"""

from __future__ import annotations

import copy
import logging
import math
import time
import warnings
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

import numpy as np

from ..model import Model
from ..simulation import Simulation
from ..solvers import (
    LocalGlobalSolver,
    NewtonSolver,
    Solver,
    StepProblem,
    estimate_spectral_radius,
    make_solver,
    objective,
    objective_gradient,
)

log = logging.getLogger(__name__)

ITERATIVE_METHODS = ("local-global", "chebyshev", "anderson", "lbfgs", "newton")
EXPLICIT_METHODS = ("symplectic-euler",)
ACCURACY_LEVELS = tuple(10.0 ** -p for p in range(1, 9))
"""Solver accuracy targets 1e-1 … 1e-8 (relative error within a step)."""


def converged_solution(model: Model, problem: StepProblem, *, tolerance: float = 1e-12,
                       iterations: int = 200, backend: str = "auto") -> np.ndarray:
    """x* = argmin g for one step, by Newton's method to ‖∇g‖/‖∇g(x_0)‖ ≤ ``tolerance``.

    g(x) = ½ (x − y)ᵀ M (x − y) + h² E(x) (Liu et al. 2013, Eq. 3).

    Parameters
    ----------
    model : Model
        The cloth.
    problem : StepProblem
        The step's h [s], y [m], f_ext [N] and pins.
    tolerance : float, default 1e-12
        Relative residual ‖∇g(x_k)‖ / ‖∇g(x_0)‖ to reach.
    iterations : int, default 200
        Maximum Newton iterations.
    backend : {"auto", "cholmod", "splu"}
        Factorization backend.

    Returns
    -------
    ndarray, shape (n, 3)
        The converged implicit Euler step [m]. If Newton stops at its rounding floor above
        ``tolerance`` the result is still returned (no warning): it is optimal to rounding.
    """
    newton = NewtonSolver(model, iterations=iterations, tolerance=tolerance, backend=backend)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return newton.solve(problem).x


@dataclass
class IterateTrace:
    """Errors and cumulative wall time of one method's iterates on one step.

    Attributes
    ----------
    method : str
        The solver's name.
    iterations : ndarray, shape (k,), int
        Iteration count of each iterate (0 is the initial guess y).
    seconds : ndarray, shape (k,)
        Cumulative wall time to reach each iterate [s] (factorization of the cached local/
        global matrix excluded, as it is reused every step; Newton's factorizations
        included).
    error : ndarray, shape (k,)
        ‖x_k − x*‖ / ‖x* − x_n‖.
    objective_gap : ndarray, shape (k,)
        g(x_k) − g(x*) [J·s²].
    """

    method: str
    iterations: np.ndarray
    seconds: np.ndarray
    error: np.ndarray
    objective_gap: np.ndarray

    def first_below(self, level: float) -> tuple[int, float] | None:
        """The first iterate whose relative error is at most ``level``.

        Parameters
        ----------
        level : float
            Relative error ‖x_k − x*‖ / ‖x* − x_n‖ to reach.

        Returns
        -------
        tuple of (int, float) or None
            (iterations, cumulative seconds [s]) of that iterate; None when none reaches it.
        """
        hit = np.flatnonzero(self.error <= level)
        if len(hit) == 0:
            return None
        i = int(hit[0])
        return int(self.iterations[i]), float(self.seconds[i])



def iterates(solver: Solver, problem: StepProblem) -> Iterator[np.ndarray]:
    """x_0, x_1, … of ``solver`` on ``problem`` (x_0 = y with pins applied).

    Ends when the method can make no further progress (see :meth:`Solver.iterates`).

    Parameters
    ----------
    solver : Solver
        Any iterative solver.
    problem : StepProblem
        The step to solve.

    Returns
    -------
    iterator of ndarray, shape (n, 3)
        The iterates [m]; each is valid until the next is drawn (copy it to keep it).
    """
    return (it.x for it in solver.iterates(problem))


def representative_problem(sim: Simulation, *, steps: int) -> StepProblem:
    """The step, among the next ``steps`` of ``sim``, whose initial guess is farthest from
    optimal (largest ‖∇g(y)‖): a step with real motion, not one at rest.

    A step of a cloth at rest has ‖∇g(y)‖ near its rounding floor
    (:func:`clothsim.solvers.base.gradient_noise_floor`), where no method can show
    more than a few digits of accuracy. ``sim`` is advanced by ``steps`` steps.

    Parameters
    ----------
    sim : Simulation
        The scene's simulation (advanced in place).
    steps : int
        Steps to look at (at least one).

    Returns
    -------
    StepProblem
        A copy of the chosen step's problem.
    """
    best, best_norm = None, -1.0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for _ in range(max(1, steps)):
            problem = sim.problem()
            norm = float(np.linalg.norm(objective_gradient(sim.model, problem,
                                                           problem.initial_guess())))
            if norm > best_norm:
                best, best_norm = copy.deepcopy(problem), norm
            sim.step()
    return best


def trace_solver(solver: Solver, problem: StepProblem, x_star: np.ndarray, *,
                 iterations: int, max_seconds: float | None = None,
                 min_error: float = 1e-13) -> IterateTrace:
    """Measure a solver's error and cumulative wall time at each iterate on one step.

    Parameters
    ----------
    solver : Solver
        Any iterative solver; traced through its :meth:`~clothsim.solvers.Solver.iterates`.
    problem : StepProblem
        The step to solve.
    x_star : ndarray, shape (n, 3)
        The converged step (:func:`converged_solution`) [m].
    iterations : int
        Maximum iterations to trace.
    max_seconds : float, optional
        Stop once the cumulative solver time passes this [s].
    min_error : float, default 1e-13
        Stop once the relative error is below this (rounding level).

    Returns
    -------
    IterateTrace
        One entry per traced iterate (k = 0 the initial guess).
    """
    if isinstance(solver, LocalGlobalSolver):
        solver.system(problem)  # the cached factor: paid once per scene and h, not timed
    model = solver.model
    g_star = objective(model, problem, x_star)
    scale = float(np.linalg.norm(x_star - problem.x)) or 1.0
    its, secs, errs, gaps = [], [], [], []
    elapsed = 0.0
    gen = iterates(solver, problem)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        for k in range(iterations + 1):
            t0 = time.perf_counter()
            x = next(gen, None)
            elapsed += time.perf_counter() - t0
            if x is None:  # the method can make no further progress
                break
            err = float(np.linalg.norm(x - x_star)) / scale
            its.append(k)
            secs.append(elapsed)
            errs.append(err)
            gaps.append(objective(model, problem, x) - g_star)
            if not math.isfinite(err) or err <= min_error:
                break
            if max_seconds is not None and elapsed >= max_seconds:
                break
    gen.close()
    return IterateTrace(solver.name, np.asarray(its), np.asarray(secs), np.asarray(errs),
                        np.asarray(gaps))


def solver_accuracy(model: Model, problem: StepProblem, *,
                    methods: Sequence[str] = ITERATIVE_METHODS, iterations: int = 200,
                    newton_iterations: int = 30, max_seconds: float | None = None,
                    backend: str = "auto", x_star: np.ndarray | None = None,
                    solver_options: dict[str, dict] | None = None) -> dict[str, IterateTrace]:
    """Trace every method in ``methods`` on one step against the converged step x*.

    Parameters
    ----------
    model : Model
        The cloth.
    problem : StepProblem
        The step to solve (a representative one: mid-motion, not from rest).
    methods : sequence of str
        Iterative methods (names in :data:`clothsim.solvers.SOLVERS`).
    iterations : int
        Iterations traced for local/global and Chebyshev.
    newton_iterations : int
        Iterations traced for Newton.
    max_seconds : float, optional
        Per-method wall-time budget [s].
    backend : {"auto", "cholmod", "splu"}
        Factorization backend.
    x_star : ndarray, shape (n, 3), optional
        The converged step [m]; default :func:`converged_solution`.
    solver_options : dict, optional
        Extra constructor options per method, e.g. ``{"chebyshev": {"rho": 0.99}}``.

    Returns
    -------
    dict
        Method name → :class:`IterateTrace`.
    """
    if x_star is None:
        x_star = converged_solution(model, problem, backend=backend)
    options = solver_options or {}
    traces = {}
    for method in methods:
        if method in EXPLICIT_METHODS:
            continue
        opts = dict(options.get(method, {}))
        if method == "chebyshev" and opts.get("rho") is None:  # a one-off cost: not traced
            opts["rho"] = estimate_spectral_radius(model, problem, backend=backend)
        solver = make_solver(method, model, backend=backend, **opts)
        n_it = newton_iterations if method == "newton" else iterations
        traces[method] = trace_solver(solver, problem, x_star, iterations=n_it,
                                      max_seconds=max_seconds)
        log.info("%s: error %.2e after %d iterations, %.3f s", method,
                 traces[method].error[-1], traces[method].iterations[-1],
                 traces[method].seconds[-1])
    return traces

