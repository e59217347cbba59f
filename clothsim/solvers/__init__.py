"""Time-step solvers: each minimizes the same implicit Euler objective g(x).

=================  ======================================================================
method             class
=================  ======================================================================
``local-global``   :class:`LocalGlobalSolver` (Liu et al. 2013, the paper)
``newton``         :class:`NewtonSolver` (exact reference, line search)
=================  ======================================================================
"""

from .base import (StepProblem, StepResult, Solver, augmented_objective, objective,
                   objective_gradient)
from .local_global import LocalGlobalSolver
from .newton import NewtonSolver

SOLVERS: dict[str, type[Solver]] = {
    "local-global": LocalGlobalSolver,
    "newton": NewtonSolver,
}


def make_solver(method: str, model, **options) -> Solver:
    """Build the solver named ``method`` for ``model`` (options go to its constructor)."""
    from ..errors import InputError

    try:
        cls = SOLVERS[method]
    except KeyError:
        raise InputError(f"solver.method: must be one of {', '.join(map(repr, SOLVERS))}, "
                         f"got {method!r}") from None
    return cls(model, **options)


__all__ = ["StepProblem", "StepResult", "Solver", "LocalGlobalSolver", "NewtonSolver",
           "SOLVERS", "make_solver", "objective", "augmented_objective", "objective_gradient"]
