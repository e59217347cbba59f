"""Small ready-made cloths shared by examples, tests and benchmarks.

Each function builds a model (and, where a scene needs them, its effects or a whole
:class:`~clothsim.simulation.Simulation`) from the public API in a few lines, so that no
test or benchmark carries its own copy of "a hanging cloth".

- :func:`grid_cloth`: an n × n square cloth model (structural, shear, bending springs).
- :func:`hanging_cloth`: a cloth held at two corners, with gravity: (model, effects).
- :func:`curtain`: a vertical cloth hanging from its two top corners, as a Simulation.
- :func:`swing`: a horizontal cloth hinged along one edge, released from rest.

Examples
--------
>>> from clothsim import gallery
>>> model = gallery.grid_cloth(4, k=100.0)
>>> model.vertex_count, model.spring_count
(16, 58)
"""

from __future__ import annotations

import numpy as np

from .effects import Gravity, Pin
from .mesh import grid
from .model import Model
from .simulation import Simulation
from .springs import grid_springs

#: Standard gravity along −y [m/s²], the direction every gallery cloth falls in.
GRAVITY = np.array([0.0, -9.81, 0.0])


def grid_cloth(n: int = 5, *, k: float = 800.0, bending: float | None = None,
               plane: str = "xz", total_mass: float = 1.0, vertex_mass=None,
               size: float = 1.0, center=(0.0, 0.0, 0.0),
               bending_pattern: str = "every") -> Model:
    """An n × n square cloth model.

    Parameters
    ----------
    n : int
        Vertices per side.
    k : float
        Stiffness of structural and shear springs [N/m].
    bending : float, optional
        Stiffness of bending springs [N/m]; default ``k / 10``.
    plane : {"xz", "xy"}
        Plane of the flat cloth ("xy" is vertical).
    total_mass : float
        Mass of the cloth [kg], lumped by area (ignored when ``vertex_mass`` is given).
    vertex_mass : float or array_like, optional
        Mass of each vertex [kg].
    size : float
        Side length [m].
    center : sequence of 3 floats
        Centre of the cloth [m].
    bending_pattern : {"every", "every-other"}
        Where bending springs start.

    Returns
    -------
    Model
    """
    mesh = grid(n, n, size=(size, size), center=center, plane=plane)
    springs = grid_springs(mesh, structural=k, shear=k,
                           bending=k / 10 if bending is None else bending,
                           bending_pattern=bending_pattern)
    return Model.build(mesh, springs, total_mass=None if vertex_mass is not None else total_mass,
                       vertex_mass=vertex_mass)


def top_corners(n: int, plane: str = "xy") -> list[int]:
    """The two corners a gallery cloth hangs from.

    Parameters
    ----------
    n : int
        Vertices per side of the :func:`grid_cloth`.
    plane : {"xy", "xz"}
        "xy": the ends of the top row; "xz": the ends of row 0.

    Returns
    -------
    list of int
        Two vertex indices.
    """
    return [n * (n - 1), n * n - 1] if plane == "xy" else [0, n - 1]


def hanging_cloth(n: int = 7, *, k: float = 800.0, bending: float | None = None,
                  plane: str = "xy", total_mass: float = 1.0, size: float = 1.0,
                  center=(0.0, 1.0, 0.0), pin_method: str = "constraint",
                  pin_stiffness: float = 1e5) -> tuple[Model, list]:
    """A cloth held at two corners (:func:`top_corners`) under gravity.

    Parameters
    ----------
    n : int
        Vertices per side.
    k : float
        Stiffness of structural and shear springs [N/m].
    bending : float, optional
        Stiffness of bending springs [N/m]; default ``k / 10``.
    total_mass : float
        Mass of the cloth [kg], lumped by area.
    plane : {"xy", "xz"}
        Plane of the flat cloth at rest ("xy" is vertical).
    size : float
        Side length [m].
    center : sequence of 3 floats
        Centre of the cloth [m].
    pin_method : {"constraint", "penalty"}
        Exact pins, or zero-rest-length penalty springs.
    pin_stiffness : float
        Penalty pin stiffness [N/m] (``pin_method="penalty"`` only).

    Returns
    -------
    model : Model
        :func:`grid_cloth` with the given parameters.
    effects : list of Effect
        ``[Gravity(GRAVITY), Pin(corners, method=pin_method)]``.
    """
    model = grid_cloth(n, k=k, bending=bending, plane=plane, total_mass=total_mass,
                       size=size, center=center)
    pin = Pin(top_corners(n, plane), method=pin_method, stiffness=pin_stiffness)
    return model, [Gravity(GRAVITY), pin]


def curtain(n: int = 7, *, k: float = 800.0, bending: float | None = None,
            total_mass: float = 1.0, plane: str = "xy", h: float = 1 / 30,
            method: str = "local-global", iterations: int | None = 10,
            tolerance: float | None = None, **solver_options) -> Simulation:
    """A 1 m cloth hanging from two corners, as a :class:`Simulation`.

    ``plane="xy"``: a vertical curtain; ``plane="xz"``: a horizontal sheet held at two
    corners that falls, buckles and swings (the paper's Fig. 1 setup).

    Parameters
    ----------
    n : int
        Vertices per side.
    k : float
        Stiffness of structural and shear springs [N/m].
    bending : float, optional
        Stiffness of bending springs [N/m]; default ``k / 10``.
    total_mass : float
        Mass of the cloth [kg], lumped by area.
    plane : {"xy", "xz"}
        Plane of the cloth at rest.
    h : float
        Time step [s].
    method : str
        Solver name (see :func:`clothsim.solvers.make_solver`).
    iterations : int or None
        Iterations per step (the maximum with a tolerance); None means 10.
    tolerance : float or None
        Relative residual at which a step stops (None: fixed iteration count).
    **solver_options
        Passed to the solver's constructor.

    Returns
    -------
    Simulation
        At rest at t = 0, with gravity :data:`GRAVITY` and exact pins on two corners.
    """
    model, effects = hanging_cloth(n, k=k, bending=bending, plane=plane,
                                   total_mass=total_mass)
    return Simulation(model, h=h, effects=effects, solver=method,
                      iterations=iterations or 10, tolerance=tolerance, **solver_options)


def swing(n: int = 7, *, k: float = 800.0, bending: float | None = None,
          total_mass: float = 1.0, h: float = 1 / 30, method: str = "local-global",
          iterations: int | None = 10, tolerance: float | None = None,
          **solver_options) -> Simulation:
    """A horizontal 1 m cloth hinged along one edge (row 0 pinned), released from rest.

    Its free edge falls about 1 m in 0.5 s: a slow, large motion next to the springs'
    fast vibrations (the trajectory-accuracy scene).

    Parameters
    ----------
    n : int
        Vertices per side.
    k : float
        Stiffness of structural and shear springs [N/m].
    bending : float, optional
        Stiffness of bending springs [N/m]; default ``k / 10``.
    total_mass : float
        Mass of the cloth [kg], lumped by area.
    h : float
        Time step [s].
    method : str
        Solver name (see :func:`clothsim.solvers.make_solver`).
    iterations : int or None
        Iterations per step (the maximum with a tolerance); None means 10.
    tolerance : float or None
        Relative residual at which a step stops (None: fixed iteration count).
    **solver_options
        Passed to the solver's constructor.

    Returns
    -------
    Simulation
        At rest at t = 0 (cloth at height 1 m), with gravity and row 0 pinned exactly.
    """
    model = grid_cloth(n, k=k, bending=bending, plane="xz", total_mass=total_mass,
                       center=(0.0, 1.0, 0.0))
    return Simulation(model, h=h, effects=[Gravity(GRAVITY), Pin(list(range(n)))],
                      solver=method, iterations=iterations or 10, tolerance=tolerance,
                      **solver_options)
