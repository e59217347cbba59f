"""Time-step solvers: each minimizes the same implicit Euler objective g(x).

====================  ===================================================================
method                class
====================  ===================================================================
``local-global``      :class:`LocalGlobalSolver` (Liu et al. 2013, the paper)
``chebyshev``         :class:`ChebyshevSolver` (local/global + Chebyshev, Wang 2015)
``anderson``          :class:`AndersonSolver` (local/global + Anderson, Peng et al. 2018)
``lbfgs``             :class:`LBFGSSolver` (L-BFGS, H₀ = (M + h²L)⁻¹, Liu et al. 2017)
``newton``            :class:`NewtonSolver` (exact reference, line search)
``symplectic-euler``  :class:`SymplecticEulerSolver` (explicit baseline: a different
                      integrator, no optimization; stable only for h < 2/ω_max)
====================  ===================================================================
"""

from ..objective import augmented_objective, gradient_noise_floor, objective, objective_gradient
from ..problem import PinSet, StepProblem
from .anderson import AndersonSolver
from .base import Iterate, Solver, StepResult
from .chebyshev import ChebyshevSolver, estimate_spectral_radius
from .lbfgs import LBFGSSolver
from .local_global import LocalGlobalSolver
from .newton import NewtonSolver
from .symplectic import StabilityWarning, SymplecticEulerSolver, stable_time_step

SOLVERS: dict[str, type[Solver]] = {
    "local-global": LocalGlobalSolver,
    "chebyshev": ChebyshevSolver,
    "anderson": AndersonSolver,
    "lbfgs": LBFGSSolver,
    "newton": NewtonSolver,
    "symplectic-euler": SymplecticEulerSolver,
}


def make_solver(method: str, model, **options) -> Solver:
    """Build the solver named ``method`` for ``model``.

    Parameters
    ----------
    method : {"local-global", "chebyshev", "newton", "symplectic-euler"}
        A key of :data:`SOLVERS`; anything else is an :class:`InputError` naming
        ``solver.method``.
    model : Model
        The cloth model.
    **options
        Passed to the solver's constructor (``iterations``, ``tolerance``, ``backend``, ...).

    Returns
    -------
    Solver
        A new solver instance.
    """
    from ..errors import InputError

    try:
        cls = SOLVERS[method]
    except KeyError:
        raise InputError(f"solver.method: must be one of {', '.join(map(repr, SOLVERS))}, "
                         f"got {method!r}") from None
    return cls(model, **options)


__all__ = ["StepProblem", "StepResult", "Iterate", "Solver", "LocalGlobalSolver", "ChebyshevSolver",
           "NewtonSolver", "SymplecticEulerSolver", "StabilityWarning", "SOLVERS",
           "make_solver", "PinSet", "gradient_noise_floor", "objective", "augmented_objective",
           "objective_gradient", "estimate_spectral_radius", "stable_time_step",
           "AndersonSolver", "LBFGSSolver"]
