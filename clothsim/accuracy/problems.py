"""The same step problems for every configuration: recorded along one converged run.

:func:`record_problems` runs a simulation (solved to convergence, at the scene's own h,
frames and substeps) and keeps the step problems of several steps spread over the whole
run — contact and buckling included, whatever the run goes through. Every configuration of
the study then solves exactly these problems (never its own drifting state), so rows are
comparable. :func:`classify` names the steps that teach nothing:

``"at-rest"``
    ‖∇g(y)‖ within 1e3 of its rounding floor
    (:func:`clothsim.solvers.base.gradient_noise_floor`): the cloth does not move; any
    "error" is rounding noise.
``"trivial"``
    one local/global iteration already reaches relative error 1e-12 (free fall: the
    springs are at rest length and the global step is exact).
``"measured"``
    everything else.
"""

from __future__ import annotations

import copy
import logging
import warnings
from dataclasses import dataclass

import numpy as np

from ..model import Model
from ..simulation import Simulation
from ..solvers import LocalGlobalSolver, StepProblem, objective_gradient
from ..solvers.base import gradient_noise_floor

log = logging.getLogger(__name__)

AT_REST_FACTOR = 1e3
TRIVIAL_ERROR = 1e-12


@dataclass(eq=False)
class RecordedStep:
    """One recorded step problem.

    Attributes
    ----------
    index : int
        Step number in the run (0 is the first step).
    time : float
        Simulated time at the start of the step [s].
    problem : StepProblem
        A copy of the step's problem (h, y, f_ext, pins).
    """

    index: int
    time: float
    problem: StepProblem


def record_problems(sim: Simulation, *, steps: int, count: int = 8) -> list[RecordedStep]:
    """Run ``sim`` for ``steps`` steps and record ``count`` step problems spread over it.

    Parameters
    ----------
    sim : Simulation
        The run (give it a converged solver, e.g. Newton to 1e-10, so the recorded states
        are implicit Euler's); advanced by ``steps`` steps.
    steps : int
        Steps of the run (frames × substeps of the scene).
    count : int
        Problems to keep, at evenly spread steps (first and last included).

    Returns
    -------
    list of RecordedStep
    """
    picks = set(np.unique(np.linspace(0, max(steps - 1, 0), max(1, count)).round().astype(int)))
    out = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for i in range(steps):
            if i in picks:
                out.append(RecordedStep(i, i * sim.h, copy.deepcopy(sim.problem())))
            sim.step()
    return out


def at_rest_ratio(model: Model, problem: StepProblem) -> float:
    """‖∇g(y)‖ / its rounding floor (∞ when the floor is 0): "how far from rest".

    Parameters
    ----------
    model : Model
        The cloth.
    problem : StepProblem
        The step.

    Returns
    -------
    float
        The ratio (dimensionless).
    """
    x0 = problem.initial_guess()
    norm = float(np.linalg.norm(objective_gradient(model, problem, x0)))
    floor = gradient_noise_floor(model, problem, x0)
    return norm / floor if floor > 0 else (np.inf if norm > 0 else 0.0)


def one_iteration_error(model: Model, problem: StepProblem, x_star: np.ndarray) -> float:
    """Relative error ‖x_1 − x*‖ / ‖x* − x_n‖ after one local/global iteration.

    Parameters
    ----------
    model : Model
        The cloth.
    problem : StepProblem
        The step.
    x_star : ndarray, shape (n, 3)
        The converged step [m].

    Returns
    -------
    float
        The relative error (dimensionless).
    """
    gen = LocalGlobalSolver(model, check_conditioning=False).iterates(problem)
    next(gen)
    x1 = next(gen).x
    gen.close()
    scale = float(np.linalg.norm(x_star - problem.x)) or 1.0
    return float(np.linalg.norm(x1 - x_star)) / scale


def classify(model: Model, problem: StepProblem, x_star: np.ndarray) -> tuple[str, float, float]:
    """Classify a step as in the module docstring.

    Parameters
    ----------
    model : Model
        The cloth.
    problem : StepProblem
        The step.
    x_star : ndarray, shape (n, 3)
        The converged step [m].

    Returns
    -------
    kind : str
        "measured", "at-rest" or "trivial".
    ratio : float
        ‖∇g(y)‖ / rounding floor (:func:`at_rest_ratio`).
    error : float
        One-iteration relative error (0 when at rest: not computed).
    """
    ratio = at_rest_ratio(model, problem)
    if ratio <= AT_REST_FACTOR:
        return "at-rest", ratio, 0.0
    err1 = one_iteration_error(model, problem, x_star)
    return ("trivial" if err1 <= TRIVIAL_ERROR else "measured"), ratio, err1
