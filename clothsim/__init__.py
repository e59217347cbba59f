"""clothsim: cloth simulation with mass-spring systems by the local/global method.

Reference implementation of T. Liu, A. W. Bargteil, J. F. O'Brien, L. Kavan, "Fast
Simulation of Mass-Spring Systems", ACM TOG 32(6), 2013.

The pipeline, one module per stage::

    mesh → springs → model → matrices → factorization → solvers → effects → simulation
                                                                      → io / plotting → cli

``import clothsim`` loads only numpy and scipy; meshio, matplotlib and scikit-sparse are
imported where they are used.
"""

from .effects import (
    Box,
    Damping,
    Effect,
    Force,
    Gravity,
    Impulse,
    Pin,
    Plane,
    Sphere,
    StrainLimit,
    Wind,
)
from .errors import (
    ClothsimError,
    ClothsimWarning,
    ConditioningWarning,
    ConvergenceWarning,
    InputError,
    MeshWarning,
    NonFiniteStateError,
)
from .io.meshes import load_mesh as load
from .mesh import Mesh, grid
from .model import Model
from .polygon import polygon
from .scene import load_scene
from .simulation import Simulation, State
from .solvers import (
                      ChebyshevSolver,
                      LocalGlobalSolver,
                      NewtonSolver,
                      StepProblem,
                      SymplecticEulerSolver,
                      make_solver,
)
from .springs import Springs, grid_springs, mesh_springs

__version__ = "0.1.0"

__all__ = [
    "Mesh", "grid", "polygon", "load", "Springs", "grid_springs", "mesh_springs", "Model",
    "Simulation", "State", "load_scene", "LocalGlobalSolver", "ChebyshevSolver",
    "NewtonSolver", "SymplecticEulerSolver", "StepProblem", "make_solver", "Effect", "Gravity",
    "Force", "Pin", "Plane", "Sphere", "Box", "Impulse", "Wind", "Damping", "StrainLimit",
    "ClothsimError", "ClothsimWarning", "ConvergenceWarning", "ConditioningWarning",
    "InputError", "MeshWarning", "NonFiniteStateError", "__version__",
]
