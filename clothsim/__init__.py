"""clothsim: cloth simulation with mass-spring systems by the local/global method.

Reference implementation of T. Liu, A. W. Bargteil, J. F. O'Brien, L. Kavan, "Fast
Simulation of Mass-Spring Systems", ACM TOG 32(6), 2013.

The pipeline, one module per stage::

    mesh → springs → model → matrices → factorization → solvers → effects → simulation
                                                                      → io / plotting → cli

``import clothsim`` loads only numpy and scipy; meshio, matplotlib and scikit-sparse are
imported where they are used.
"""

from .effects import Effect, Gravity, Pin
from .errors import (ClothsimError, ClothsimWarning, ConditioningWarning, ConvergenceWarning,
                     InputError)
from .mesh import Mesh, grid
from .model import Model
from .simulation import Simulation, State
from .solvers import LocalGlobalSolver, NewtonSolver, StepProblem, make_solver
from .springs import Springs, grid_springs, mesh_springs

__version__ = "0.1.0"

__all__ = [
    "Mesh", "grid", "Springs", "grid_springs", "mesh_springs", "Model", "Simulation", "State",
    "LocalGlobalSolver", "NewtonSolver", "StepProblem", "make_solver", "Effect", "Gravity",
    "Pin", "ClothsimError", "ClothsimWarning", "ConvergenceWarning", "ConditioningWarning",
    "InputError", "__version__",
]
