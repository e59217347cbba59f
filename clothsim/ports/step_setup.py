"""The set-up of the per-step check (:mod:`clothsim.ports.check`): the simulation a port is
checked against, its step tolerance per precision, the scene's fixed iteration settings, the
system's condition number, and the float32 numbers of docs/ports.md.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from .compare import EPS32, RTOL64, cloth_size, condition_number
from .judge import refine
from .rounding import (
    converged_float32_floor,
    float32_deviation,
    float32_newton_stagnation,
    float32_tolerance,
)

__all__ = ["as_simulation", "fixed_settings", "float32_report", "step_tolerance",
           "system_condition_number"]


def as_simulation(source):
    """A fresh Simulation from a Scene, a Simulation factory, or a Simulation.

    Parameters
    ----------
    source : Scene, Simulation or callable returning a Simulation

    Returns
    -------
    Simulation
        Built from the scene or the factory; a Simulation is returned as is.
    """
    if hasattr(source, "build_simulation"):
        return source.build_simulation(source.build_model())
    if callable(source):
        return source()
    if hasattr(source, "step") and hasattr(source, "problem"):
        return source
    raise InputError("simulation: expected a Scene, a Simulation or a function returning one")

def step_tolerance(sim, x: np.ndarray, precision: str = "float64") -> float:
    """Allowed per-vertex distance of one step [m] (docs/ports.md derives it).

    float64: 1e-9 of the cloth size. float32: the next step's float32 bound
    (:func:`clothsim.ports.rounding.float32_tolerance`), at least the float64 tolerance:
    measured on its local/global iterations, or for a Newton scene the converged floor at
    the step's minimizer.

    Parameters
    ----------
    sim : Simulation
        The simulation at the step's start (supplies M, L, h and the pins).
    x : ndarray, shape (n, 3)
        Positions [m] setting the cloth size.
    precision : {"float64", "float32"}
        The port's precision.

    Returns
    -------
    float
        Tolerance [m].
    """
    if precision not in ("float32", "float64"):
        raise InputError(f"precision: must be 'float32' or 'float64', got {precision!r}")
    tol = RTOL64 * cloth_size(x)
    if precision == "float32":
        problem, model = sim.problem(sim.state), sim.step_model()
        iterated = sim.solver.name != "newton"
        x_min = None if iterated else refine(model, problem, problem.initial_guess())
        tol = float32_tolerance(model, problem, sim.solver.iterations, tol, x=x_min,
                                iterated=iterated)
    return tol

def fixed_settings(sim) -> str:
    """"10 local/global iterations from y": the scene's fixed iteration count, or "".

    Parameters
    ----------
    sim : Simulation

    Returns
    -------
    str
        "" for a converged method (Newton) or a scene with a solver tolerance.
    """
    solver = sim.solver
    if solver.name == "newton" or solver.tolerance:
        return ""
    name = solver.name.replace("-", "/")
    return f"{solver.iterations} {name} iterations from {sim.initial_guess}"

def system_condition_number(sim) -> float:
    """κ(M + h²L) of the simulation's next step, with its penalty pins.

    Parameters
    ----------
    sim : Simulation

    Returns
    -------
    float
        The 2-norm condition number (:func:`clothsim.ports.compare.condition_number`).
    """
    p = sim.problem(sim.state)
    return condition_number(sim.model, sim.h, anchor_vertices=p.anchor_vertices,
                            anchor_stiffness=p.anchor_stiffness)

def float32_report(scenes=("hanging", "jacobson-net", "jacobson-flag", "drop-on-square")) -> None:
    """Print, per scene, the first step's float32 deviation, tolerance and κ bound, and the
    converged float32 floor beside where a float32 Newton iteration from the minimizer
    stagnates (a converged step's tolerance is ``MARGIN`` × the floor).

    The numbers of docs/ports.md ("float32 ports") are this function's output.

    Parameters
    ----------
    scenes : sequence of str
        Scene names or ``.toml`` paths. A scene whose data set cannot be got (the
        assignment's files, offline) gets a line saying so instead.
    """
    from ..scene import load_scene

    print(f"{'scene':16} {'n':>5} {'K':>4} {'deviation':>10} {'tolerance':>10} "
          f"{'kappa bound':>11} {'floor':>9} {'stagnation':>10}")
    for name in scenes:
        try:
            sim = as_simulation(load_scene(name))
        except InputError as exc:
            if "`clothsim data fetch " not in str(exc):
                raise
            print(f"{name:16} skipped: {getattr(exc, 'detail', exc)}")
            continue
        x = sim.state.positions
        problem = sim.problem(sim.state)
        K = sim.solver.iterations
        dev = float32_deviation(sim.step_model(), problem, K)
        tol = step_tolerance(sim, x, "float32")
        kappa = system_condition_number(sim) * EPS32 * float(np.abs(x).max())
        x_min = refine(sim.step_model(), problem, problem.initial_guess())
        floor = converged_float32_floor(sim.step_model(), problem, x_min)
        stag = float32_newton_stagnation(sim.step_model(), problem, x_min)
        print(f"{name:16} {sim.model.vertex_count:5d} {K:4d} {dev:10.2e} {tol:10.2e} "
              f"{kappa:11.2e} {floor:9.2e} {stag:10.2e}")
