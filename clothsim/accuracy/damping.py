"""Implicit Euler's own damping: closed form for one spring, energy and height curves."""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence

import numpy as np

from ..effects import Pin
from ..mesh import Mesh
from ..model import Model
from ..simulation import Simulation, State
from ..springs import Springs
from .trajectory import SimulationFactory, run_trajectory


def implicit_euler_amplitude(omega: float, h: float, steps) -> np.ndarray:
    """Amplitude factor (1 + ω²h²)^(−n/2) of a linear spring after n implicit Euler steps.

    Parameters
    ----------
    omega : float
        Natural angular frequency sqrt(k / m) [rad/s].
    h : float
        Time step [s].
    steps : array_like of int
        Step counts n.

    Returns
    -------
    ndarray, shape of ``steps``
        (1 + ω²h²)^(−n/2), the amplitude relative to the initial one (dimensionless).
    """
    return (1.0 + (omega * h) ** 2) ** (-0.5 * np.asarray(steps, dtype=np.float64))


def single_spring(*, stiffness: float = 100.0, mass: float = 1.0, rest_length: float = 1.0,
                  amplitude: float = 0.1):
    """A mass hanging on one spring below a pinned vertex (no gravity), pulled down.

    Parameters
    ----------
    stiffness : float, default 100
        k [N/m].
    mass : float, default 1
        Mass of each vertex [kg].
    rest_length : float, default 1
        r [m].
    amplitude : float, default 0.1
        Initial stretch [m].

    Returns
    -------
    model : Model
        Two vertices (0 pinned at the origin, 1 the mass), one spring along −y.
    pin : Pin
        Exact pin of vertex 0.
    state : State
        Vertex 1 displaced by ``amplitude`` [m] below rest, at rest.
    omega : float
        sqrt(k / m) [rad/s].
    """
    x0 = np.array([[0.0, 0.0, 0.0], [0.0, -rest_length, 0.0]])
    mesh = Mesh(x0, strands=[[0, 1]])
    springs = Springs(np.array([[0, 1]]), np.array([stiffness]), np.array([rest_length]), 0)
    model = Model(mesh, springs, np.array([mass, mass]))
    state = State(x0 + [[0.0, 0.0, 0.0], [0.0, -amplitude, 0.0]], np.zeros((2, 3)))
    return model, Pin([0]), state, math.sqrt(stiffness / mass)


def _runs(factory: SimulationFactory, *, h: float, frames: int, frame_time: float,
          settings: Sequence[tuple[str, int | None, float | None]],
          record_energy: bool = False) -> dict:
    """One run per (method, iterations, tolerance), keyed by its label
    (``"local-global, 10 it"`` or ``"newton, tol 1e-10"``); warnings silenced."""
    out = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for method, its, tol in settings:
            label = f"{method}, " + (f"tol {tol:g}" if tol else f"{its} it")
            out[label] = run_trajectory(factory(method, h, its, tol), frames=frames,
                                        frame_time=frame_time, record_energy=record_energy)
    return out


def damping_curves(factory: SimulationFactory, *, h: float, frames: int, frame_time: float,
                   settings: Sequence[tuple[str, int | None, float | None]], vertex: int
                   ) -> dict[str, np.ndarray]:
    """Height (y) of ``vertex`` at every frame for a few (method, iterations, tolerance).

    Parameters
    ----------
    factory : callable
        ``factory(method, h, iterations, tolerance) -> Simulation``, a fresh simulation.
    h : float
        Time step [s].
    frames : int
        Frames to run.
    frame_time : float
        Time between frames [s]; h must divide it.
    settings : sequence of (str, int or None, float or None)
        (method, iterations, tolerance) per curve.
    vertex : int
        The vertex whose height is recorded.

    Returns
    -------
    dict of str to ndarray, shape (frames + 1,)
        Label (e.g. ``"local-global, 10 it"``) → y coordinate per frame [m].
    """
    runs = _runs(factory, h=h, frames=frames, frame_time=frame_time, settings=settings)
    return {label: traj.frames[:, vertex, 1] for label, traj in runs.items()}


def energy_curves(factory: SimulationFactory, *, h: float, frames: int, frame_time: float,
                  settings: Sequence[tuple[str, int | None, float | None]],
                  reference: np.ndarray | None = None) -> dict[str, np.ndarray]:
    """Mechanical energy (:func:`mechanical_energy`) at every frame for a few (method,
    iterations, tolerance); ``reference`` (shape (frames + 1,)) is added as-is.

    Parameters
    ----------
    factory : callable
        ``factory(method, h, iterations, tolerance) -> Simulation``, a fresh simulation.
    h : float
        Time step [s].
    frames : int
        Frames to run.
    frame_time : float
        Time between frames [s]; h must divide it.
    settings : sequence of (str, int or None, float or None)
        (method, iterations, tolerance) per curve.
    reference : ndarray, shape (frames + 1,), optional
        A reference energy curve [J].

    Returns
    -------
    dict of str to ndarray, shape (frames + 1,)
        Label → mechanical energy per frame [J].
    """
    runs = _runs(factory, h=h, frames=frames, frame_time=frame_time, settings=settings,
                 record_energy=True)
    out = {label: traj.energy for label, traj in runs.items()}
    if reference is not None:
        out["reference (small h, converged)"] = np.asarray(reference)
    return out


def single_spring_heights(*, h: float, steps: int, stiffness: float = 100.0,
                          mass: float = 1.0, amplitude: float = 0.1
                          ) -> tuple[np.ndarray, dict[str, np.ndarray], np.ndarray]:
    """Displacement of the single spring's mass over ``steps`` steps.

    Parameters
    ----------
    h : float
        Time step [s].
    steps : int
        Steps to run.
    stiffness : float, default 100
        k [N/m].
    mass : float, default 1
        m [kg].
    amplitude : float, default 0.1
        Initial stretch [m].

    Returns
    -------
    t : ndarray, shape (steps + 1,) [s]
    curves : dict
        Label → displacement from rest [m] for implicit Euler (converged) and symplectic
        Euler.
    envelope : ndarray, shape (steps + 1,)
        amplitude × (1 + ω²h²)^(−n/2), the closed-form implicit Euler amplitude.
    """
    curves = {}
    omega = math.sqrt(stiffness / mass)
    for label, method, kw in (("implicit Euler (converged)", "newton", {"tolerance": 1e-12}),
                              ("symplectic Euler", "symplectic-euler", {})):
        model, pin, state, omega = single_spring(stiffness=stiffness, mass=mass,
                                                 amplitude=amplitude)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            sim = Simulation(model, h=h, effects=[pin], solver=method, state=state, **kw)
            ys = [state.positions[1, 1]]
            for _ in range(steps):
                sim.step()
                ys.append(sim.state.positions[1, 1])
        curves[label] = np.asarray(ys) + 1.0  # displacement from rest (rest at y = −1)
    n = np.arange(steps + 1)
    return n * h, curves, -amplitude * implicit_euler_amplitude(omega, h, n)

