"""Newton: the reference solver, its iterates and its indefinite-Hessian handling."""

import warnings

import numpy as np
import pytest

from clothsim.errors import InputError
from clothsim.solvers import NewtonSolver, objective_gradient

from .cases import buckling_step, convex_step


def test_newton_iterates_start_at_y_and_reach_the_floor():
    model, problem = convex_step()
    its = list(NewtonSolver(model).iterates(problem))
    assert its[0].k == 0 and np.array_equal(its[0].x, problem.initial_guess())
    assert its[-1].gradient_norm < 1e-10 * its[0].gradient_norm  # at its rounding floor
    assert len(its) < 12  # quadratic convergence


@pytest.mark.parametrize("indefinite", ["shift", "project"])
def test_newton_on_buckling_steps_converges_in_few_iterations(indefinite):
    """The sheet held at two corners buckles (H indefinite at y); Newton reaches its
    rounding floor in a few dozen iterations, not hundreds."""
    model, problem = buckling_step()
    solver = NewtonSolver(model, iterations=60, tolerance=1e-13, indefinite=indefinite)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no ConvergenceWarning
        res = solver.solve(problem)
    assert res.converged and res.iterations < 40, res.iterations
    g = np.linalg.norm(objective_gradient(model, problem, res.x))
    g0 = np.linalg.norm(objective_gradient(model, problem, problem.initial_guess()))
    assert g < 1e-10 * g0


def test_newton_stalled_at_rest_counts_as_converged():
    """Started at its own solution, Newton cannot improve: converged, no warning."""
    model, problem = convex_step()
    x_star = NewtonSolver(model).solve(problem).x
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        res = NewtonSolver(model, tolerance=1e-15).solve(problem, x0=x_star)
    assert res.converged and res.iterations <= 2


def test_newton_rejects_unknown_indefinite_option():
    model, _ = convex_step(4)
    with pytest.raises(InputError, match="solver.indefinite"):
        NewtonSolver(model, indefinite="flip")
