"""Trajectory accuracy: runs recorded frame by frame, compared with a converged small-h run.

Vertex positions at every frame of a run, against a reference run with a much smaller time
step solved to convergence and Richardson-extrapolated
(:func:`~clothsim.accuracy.converged.reference_trajectory`):
‖X − X_ref‖ / ‖X_ref − X_0‖ over all frames (Frobenius norms over frames × vertices);
:func:`convergence_slope` fits its log-log slope against h (implicit Euler: 1 once h is well
below the stiffest oscillation period 2π/ω_max).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from .. import energy
from ..effects import Gravity
from ..effects.base import overrides
from ..errors import InputError
from ..model import Model
from ..simulation import Simulation
from ..solvers import Solver, StepProblem, objective, stable_time_step
from .phases import advance
from .trace import EXPLICIT_METHODS, converged_solution

SimulationFactory = Callable[[str, float, "int | None", "float | None"], Simulation]
"""``factory(method, h, iterations, tolerance) -> Simulation`` for one configuration."""


@dataclass
class SweepRow:
    """One configuration of the sweep (a row of accuracy.csv, see :data:`CSV_FIELDS`).

    Attributes
    ----------
    method : str
        Solver name.
    h : float
        Time step [s] (NaN in a configuration before its stable explicit step is chosen).
    iterations : int or None
        Iterations per step (the maximum when ``tolerance`` is set).
    tolerance : float or None
        Relative-residual tolerance per step, or None (fixed iterations).
    steps_per_frame : int
        Steps per recorded frame.
    seconds_per_step, seconds_per_frame : float
        Median wall time per step and the corresponding time per frame [s].
    solver_error : float
        ‖x − x*‖ / ‖x* − x_n‖ on the probe step (NaN for explicit methods).
    objective_gap : float
        g(x) − g(x*) on the probe step [J·s²].
    trajectory_error : float
        ‖X − X_ref‖ / ‖X_ref − X_0‖ over all frames (:func:`trajectory_error`).
    """

    method: str
    h: float
    iterations: int | None
    tolerance: float | None
    steps_per_frame: int
    seconds_per_step: float
    seconds_per_frame: float
    solver_error: float
    objective_gap: float
    trajectory_error: float


@dataclass
class Trajectory:
    """Positions at every frame of a run, and the per-step wall times.

    Attributes
    ----------
    frames : ndarray, shape (f + 1, n, 3)
        Positions [m]; frame 0 is the initial state (NaN after a blow-up).
    step_seconds : list of float
        Wall time of every step [s].
    energy : ndarray, shape (f + 1,), optional
        Mechanical energy at each frame [J] (with gravity), when recorded.
    solver_error : float
        Relative error ‖x − x*‖ / ‖x* − x_n‖ on the probe step, NaN when not probed.
    objective_gap : float
        g(x) − g(x*) on the probe step [J·s²], NaN when not probed.
    """

    frames: np.ndarray                       # (f + 1, n, 3) [m], frame 0 the initial state
    step_seconds: list[float] = field(default_factory=list)
    energy: np.ndarray | None = None         # (f + 1,) [J] mechanical energy, with gravity
    solver_error: float = math.nan
    objective_gap: float = math.nan
    contact: np.ndarray | None = None        # (f,) bool: frame f → f + 1 had a correction


def steps_per_frame(frame_time: float, h: float) -> int:
    """frame_time / h as an integer; raise InputError when h does not divide the frame.

    Parameters
    ----------
    frame_time : float
        Time between frames [s].
    h : float
        Time step [s].

    Returns
    -------
    int
        Steps per frame (≥ 1).
    """
    ratio = frame_time / h
    steps = int(round(ratio))
    if steps < 1 or abs(ratio - steps) > 1e-6 * ratio:
        raise InputError(f"accuracy.time_steps: h={h:.6g} s must divide the frame time "
                         f"{frame_time:.6g} s")
    return steps


def mechanical_energy(sim: Simulation) -> float:
    """Kinetic + spring + gravitational potential energy of ``sim``'s state [J].

    Gravity is taken from the simulation's :class:`~clothsim.effects.Gravity` effects
    (none: no potential term). Pins and other effects store no energy.

    Parameters
    ----------
    sim : Simulation
        Its current positions [m] and velocities [m/s].

    Returns
    -------
    float
        ½ vᵀ M v + Σ_i ½ k_i (|p_i| − r_i)² − Σ m_i gᵀ x_i [J].
    """
    x, v = sim.state.positions, sim.state.velocities
    e = energy.kinetic_energy(sim.model, v) + energy.spring_energy(sim.model, x)
    for effect in sim.effects:
        if isinstance(effect, Gravity):
            e += energy.gravity_energy(sim.model, x, effect.acceleration)
    return e


def run_trajectory(sim: Simulation, *, frames: int, frame_time: float,
                   probe_frame: int | None = None, backend: str = "auto",
                   record_energy: bool = False, record_contact: bool = False) -> Trajectory:
    """Run ``sim`` for ``frames`` frames, recording positions at each frame.

    With ``probe_frame``, the first step of that frame is also solved to convergence by
    Newton and the simulation's solver error on it is recorded (relative error against
    x*, and objective gap). With ``record_energy``, :func:`mechanical_energy` at each
    frame is recorded in ``Trajectory.energy``. With ``record_contact``,
    ``Trajectory.contact[f]`` tells whether any effect's ``correct_positions`` (an obstacle,
    a strain limit) moved a vertex, or an obstacle held one on its contact plane, during
    frame f → f + 1 (:func:`watch_corrections`).

    Parameters
    ----------
    sim : Simulation
        A fresh simulation (advanced in place).
    frames : int
        Frames to run.
    frame_time : float
        Time between frames [s]; ``sim.h`` must divide it.
    probe_frame : int, optional
        Frame whose first step is compared with the converged step.
    backend : {"auto", "cholmod", "splu"}
        Factorization backend of the converged (Newton) solve.
    record_energy : bool, default False
        Record the mechanical energy at each frame.
    record_contact : bool, default False
        Record per frame whether a position correction moved a vertex.

    Returns
    -------
    Trajectory
        frames of shape (frames + 1, n, 3) [m]; NaN frames after a blow-up.
    """
    per_frame = steps_per_frame(frame_time, sim.h)
    touched = watch_corrections(sim) if record_contact else None
    contact = []
    out = [sim.state.positions.copy()]
    energies = [mechanical_energy(sim)] if record_energy else []
    seconds: list[float] = []
    traj = Trajectory(np.empty(0))
    with np.errstate(all="ignore"):
        for f in range(frames):
            if probe_frame is not None and f == probe_frame and _is_implicit(sim.solver):
                problem = sim.problem()
                x_star = converged_solution(sim.model, problem, backend=backend)
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    x = sim.solver.solve(problem).x
                scale = float(np.linalg.norm(x_star - problem.x)) or 1.0
                traj.solver_error = float(np.linalg.norm(x - x_star)) / scale
                traj.objective_gap = (objective(sim.model, problem, x)
                                      - objective(sim.model, problem, x_star))
            if touched is not None:
                touched.clear()
            for _ in range(per_frame):
                seconds.append(sim.step().seconds)
            contact.append(bool(touched))
            advance()
            x = sim.state.positions
            out.append(x.copy())
            if record_energy:
                energies.append(mechanical_energy(sim))
            if not np.all(np.isfinite(x)):
                out.extend([np.full_like(x, np.nan)] * (frames - f - 1))
                break
    traj.frames = np.stack(out)
    traj.step_seconds = seconds
    if record_contact:
        traj.contact = np.ones(frames, dtype=bool)
        traj.contact[:len(contact)] = contact
    if record_energy:
        e = np.full(len(out), np.nan)
        e[:len(energies)] = energies
        traj.energy = e
    return traj


def watch_corrections(sim: Simulation) -> list:
    """Record which effects move vertices in ``correct_positions`` from now on.

    Each of ``sim``'s effects with a ``correct_positions`` hook gets an instance-level
    wrapper that compares the solver's x with the corrected x; the returned list receives
    the effect's kind each time a correction moved a vertex, or the step held vertices on
    the effect's contact planes (an obstacle in ``[contact] mode = "hold"``: the solve
    itself kept them on the surface); clear it to start over.

    Parameters
    ----------
    sim : Simulation
        Its effects are wrapped in place (instance attributes; the classes are untouched).

    Returns
    -------
    list of str
    """
    touched: list = []
    for effect in sim.effects:
        if not overrides(effect, "correct_positions"):
            continue
        hook = effect.correct_positions

        def watched(t, state, x, _hook=hook, _kind=effect.kind, _effect=effect):
            held = overrides(_effect, "hold_contacts") and len(_effect.hold_contacts(t)) > 0
            corrected = _hook(t, state, x)
            if held or (corrected is not x and not np.array_equal(corrected, x)):
                touched.append(_kind)
            return corrected

        effect.correct_positions = watched
    return touched


def _is_implicit(solver: Solver) -> bool:
    return solver.name not in EXPLICIT_METHODS


def trajectory_error(frames: np.ndarray, reference: np.ndarray) -> float:
    """‖X − X_ref‖ / ‖X_ref − X_0‖ over all frames and vertices (inf if X is not finite).

    Parameters
    ----------
    frames : ndarray, shape (f + 1, n, 3)
        The run's positions X [m].
    reference : ndarray, shape (f + 1, n, 3)
        The reference X_ref [m].

    Returns
    -------
    float
        Relative error (dimensionless; Frobenius norms).
    """
    if not np.all(np.isfinite(frames)):
        return math.inf
    den = float(np.linalg.norm(reference - reference[0]))
    return float(np.linalg.norm(frames - reference)) / (den or 1.0)


def convergence_slope(rows: Sequence[SweepRow], *, method: str,
                      iterations: int | None) -> float:
    """Log-log slope of trajectory error against h for one (method, iterations) series.

    Implicit Euler solved to convergence is first order: the slope should be about 1.
    NaN when fewer than two finite points exist.

    Parameters
    ----------
    rows : sequence of SweepRow
        The sweep.
    method : str
        The series' solver.
    iterations : int or None
        The series' iterations per step.

    Returns
    -------
    float
        d log(error) / d log(h), a least-squares fit.
    """
    pts = [(r.h, r.trajectory_error) for r in rows
           if r.method == method and r.iterations == iterations
           and math.isfinite(r.trajectory_error) and r.trajectory_error > 0]
    if len(pts) < 2:
        return math.nan
    h, e = np.log(np.array(pts)).T
    return float(np.polyfit(h, e, 1)[0])


def _stable_explicit_step(model: Model, frame_time: float, problem: StepProblem) -> float:
    """The largest h = frame_time / 2^j below 0.9 × the explicit stability limit."""
    limit = stable_time_step(model, anchor_vertices=problem.anchor_vertices,
                             anchor_stiffness=problem.anchor_stiffness)
    h = frame_time
    while h >= 0.9 * limit:
        h /= 2.0
    return h
