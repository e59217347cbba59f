"""What accuracy costs in time: solver and trajectory accuracy against wall time.

Two kinds of accuracy are measured, both for the same implicit Euler problem
(Liu et al. 2013, Eq. 4: x_{n+1} = argmin g(x), g(x) = ½ (x − y)ᵀ M (x − y) + h² E(x)):

1. **Solver accuracy within a step** (:func:`trace_solver`, :func:`solver_accuracy`).
   After k iterations (or t seconds) of a method, the relative error
   ‖x_k − x*‖ / ‖x* − x_n‖ against the converged step x* (Newton to ‖∇g‖ ≤ 1e-12
   relative, :func:`converged_solution`) and the objective gap g(x_k) − g(x*) [J·s²].
   The wall time is cumulative over the iterations, with the error evaluation excluded.
2. **Trajectory accuracy** (:func:`run_sweep`). Vertex positions at every frame of a run,
   against a reference run with a much smaller time step solved to convergence and
   Richardson-extrapolated (:func:`reference_trajectory`):
   ‖X − X_ref‖ / ‖X_ref − X_0‖ over all frames (Frobenius norms over frames × vertices);
   :func:`convergence_slope` fits its log-log slope against h (implicit Euler: 1).
   Implicit Euler damps: a linear spring's amplitude shrinks by (1 + ω²h²)^(−½) per step
   (:func:`implicit_euler_amplitude`). Stopping the iterations early changes the energy
   loss too, in either direction (:func:`mechanical_energy`, :func:`energy_curves`;
   docs/accuracy.md shows both), so the sweep measures accuracy as trajectory error.

The sweep's core takes a *simulation factory* ``factory(method, h, iterations, tolerance)
-> Simulation``, so it runs on any scene; :func:`command` builds one from
:func:`clothsim.scene.load_scene` for ``clothsim accuracy``. Results: ``accuracy.csv``
(:data:`CSV_FIELDS`, one row per configuration), plots of error against iterations and
against wall time, the accuracy/time frontier with the cheapest configuration for each
accuracy level (:func:`cheapest`), trajectory error against h (:func:`plot_convergence`)
and the damping/energy plot.
"""

from __future__ import annotations

import csv
import logging
import math
import time
import warnings
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from . import energy
from .errors import InputError
from .model import Model
from .simulation import Simulation
from .solvers import (
    ChebyshevSolver,
    LocalGlobalSolver,
    NewtonSolver,
    Solver,
    StepProblem,
    make_solver,
    objective,
    objective_gradient,
)

log = logging.getLogger(__name__)

SimulationFactory = Callable[[str, float, "int | None", "float | None"], Simulation]
"""``factory(method, h, iterations, tolerance) -> Simulation`` for one configuration."""

ITERATIVE_METHODS = ("local-global", "chebyshev", "newton")
EXPLICIT_METHODS = ("symplectic-euler",)
ACCURACY_LEVELS = tuple(10.0 ** -p for p in range(1, 9))
"""Solver accuracy targets 1e-1 … 1e-8 (relative error within a step)."""
TRAJECTORY_LEVELS = (0.5, 0.2, 0.1, 0.05, 0.02, 0.01, 0.005, 0.002, 0.001)
"""Trajectory accuracy targets (time discretization dominates: implicit Euler is first order)."""
CSV_FIELDS = ("method", "h", "iterations", "tolerance", "steps_per_frame", "seconds_per_step",
              "seconds_per_frame", "solver_error", "objective_gap", "trajectory_error")


# -- solver accuracy within one step --------------------------------------------------------
def converged_solution(model: Model, problem: StepProblem, *, tolerance: float = 1e-12,
                       iterations: int = 200, backend: str = "auto") -> np.ndarray:
    """x* = argmin g for one step, by Newton's method to ‖∇g‖/‖∇g(x_0)‖ ≤ ``tolerance``.

    Returns
    -------
    ndarray, shape (n, 3)
        The converged implicit Euler step [m]. If Newton stops at its rounding floor above
        ``tolerance`` the result is still returned (no warning): it is optimal to rounding.
    """
    newton = NewtonSolver(model, iterations=iterations, tolerance=tolerance, backend=backend)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return newton.solve(problem).x


@dataclass
class IterateTrace:
    """Errors and cumulative wall time of one method's iterates on one step.

    Attributes
    ----------
    method : str
    iterations : ndarray, shape (k,), int
        Iteration count of each iterate (0 is the initial guess y).
    seconds : ndarray, shape (k,)
        Cumulative wall time to reach each iterate [s] (factorization of the cached local/
        global matrix excluded, as it is reused every step; Newton's factorizations
        included).
    error : ndarray, shape (k,)
        ‖x_k − x*‖ / ‖x* − x_n‖.
    objective_gap : ndarray, shape (k,)
        g(x_k) − g(x*) [J·s²].
    """

    method: str
    iterations: np.ndarray
    seconds: np.ndarray
    error: np.ndarray
    objective_gap: np.ndarray

    def first_below(self, level: float) -> tuple[int, float] | None:
        """(iterations, seconds) of the first iterate with error ≤ ``level``, or None."""
        hit = np.flatnonzero(self.error <= level)
        if len(hit) == 0:
            return None
        i = int(hit[0])
        return int(self.iterations[i]), float(self.seconds[i])


def _local_global_iterates(solver: LocalGlobalSolver, problem: StepProblem
                           ) -> Iterator[np.ndarray]:
    """The iterates of :meth:`LocalGlobalSolver.solve`, same work per iteration."""
    solver.system(problem)
    x = problem.initial_guess()
    while True:
        d = solver.local_step(x)
        solver.gradient(problem, x, d)  # the residual check solve() does every iteration
        yield x
        x = solver.global_step(problem, d)


def _chained_iterates(solver: Solver, problem: StepProblem) -> Iterator[np.ndarray]:
    """Iterates of a memoryless method (Newton): one-iteration solves chained from x_k."""
    x = problem.initial_guess()
    solver.iterations, solver.tolerance = 1, None
    while True:
        yield x
        x = solver.solve(problem, x0=x).x


def iterates(solver: Solver, problem: StepProblem) -> Iterator[np.ndarray]:
    """x_0, x_1, … of ``solver`` on ``problem`` (x_0 = y with pins applied), endless."""
    if isinstance(solver, ChebyshevSolver):
        return (x for _, x, _ in solver.iterates(problem))
    if type(solver) is LocalGlobalSolver:
        return _local_global_iterates(solver, problem)
    return _chained_iterates(solver, problem)


def representative_problem(sim: Simulation, *, steps: int) -> StepProblem:
    """The step, among the next ``steps`` of ``sim``, whose initial guess is farthest from
    optimal (largest ‖∇g(y)‖): a step with real motion, not one at rest.

    A step of a cloth at rest has ‖∇g(y)‖ near its rounding floor
    (:func:`clothsim.solvers.base.gradient_noise_floor`), where no method can show
    more than a few digits of accuracy. ``sim`` is advanced by ``steps`` steps.
    """
    import copy

    best, best_norm = None, -1.0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for _ in range(max(1, steps)):
            problem = sim.problem()
            norm = float(np.linalg.norm(objective_gradient(sim.model, problem,
                                                           problem.initial_guess())))
            if norm > best_norm:
                best, best_norm = copy.deepcopy(problem), norm
            sim.step()
    return best


def trace_solver(solver: Solver, problem: StepProblem, x_star: np.ndarray, *,
                 iterations: int, max_seconds: float | None = None,
                 min_error: float = 1e-13) -> IterateTrace:
    """Measure a solver's error and cumulative wall time at each iterate on one step.

    Parameters
    ----------
    solver : Solver
        Any solver; local/global and Chebyshev are traced in one run, other methods by
        chaining one-iteration solves (exact for memoryless methods such as Newton).
    problem : StepProblem
    x_star : ndarray, shape (n, 3)
        The converged step (:func:`converged_solution`).
    iterations : int
        Maximum iterations to trace.
    max_seconds : float, optional
        Stop once the cumulative solver time passes this [s].
    min_error : float, default 1e-13
        Stop once the relative error is below this (rounding level).
    """
    if isinstance(solver, LocalGlobalSolver):
        solver.system(problem)  # the cached factor: paid once per scene and h, not timed
    model = solver.model
    g_star = objective(model, problem, x_star)
    scale = float(np.linalg.norm(x_star - problem.x)) or 1.0
    its, secs, errs, gaps = [], [], [], []
    elapsed = 0.0
    gen = iterates(solver, problem)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        for k in range(iterations + 1):
            t0 = time.perf_counter()
            x = next(gen)
            elapsed += time.perf_counter() - t0
            err = float(np.linalg.norm(x - x_star)) / scale
            its.append(k)
            secs.append(elapsed)
            errs.append(err)
            gaps.append(objective(model, problem, x) - g_star)
            if not math.isfinite(err) or err <= min_error:
                break
            if max_seconds is not None and elapsed >= max_seconds:
                break
    gen.close()
    return IterateTrace(solver.name, np.asarray(its), np.asarray(secs), np.asarray(errs),
                        np.asarray(gaps))


def solver_accuracy(model: Model, problem: StepProblem, *,
                    methods: Sequence[str] = ITERATIVE_METHODS, iterations: int = 200,
                    newton_iterations: int = 30, max_seconds: float | None = None,
                    backend: str = "auto", x_star: np.ndarray | None = None,
                    solver_options: dict[str, dict] | None = None) -> dict[str, IterateTrace]:
    """Trace every method in ``methods`` on one step against the converged step x*.

    Parameters
    ----------
    model, problem
        The step to solve (a representative one: mid-motion, not from rest).
    methods : sequence of str
        Iterative methods (names in :data:`clothsim.solvers.SOLVERS`).
    iterations : int
        Iterations traced for local/global and Chebyshev.
    newton_iterations : int
        Iterations traced for Newton.
    max_seconds : float, optional
        Per-method wall-time budget [s].
    solver_options : dict, optional
        Extra constructor options per method, e.g. ``{"chebyshev": {"rho": 0.99}}``.

    Returns
    -------
    dict
        Method name → :class:`IterateTrace`.
    """
    if x_star is None:
        x_star = converged_solution(model, problem, backend=backend)
    options = solver_options or {}
    traces = {}
    for method in methods:
        if method in EXPLICIT_METHODS:
            continue
        solver = make_solver(method, model, backend=backend, **options.get(method, {}))
        if isinstance(solver, ChebyshevSolver) and solver.rho is None:
            from .solvers import estimate_spectral_radius
            solver.rho = estimate_spectral_radius(model, problem, solver=solver)
        n_it = newton_iterations if method == "newton" else iterations
        traces[method] = trace_solver(solver, problem, x_star, iterations=n_it,
                                      max_seconds=max_seconds)
        log.info("%s: error %.2e after %d iterations, %.3f s", method,
                 traces[method].error[-1], traces[method].iterations[-1],
                 traces[method].seconds[-1])
    return traces


# -- trajectory accuracy --------------------------------------------------------------------
@dataclass
class SweepRow:
    """One configuration of the sweep (a row of accuracy.csv, see :data:`CSV_FIELDS`)."""

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
    """Positions at every frame of a run, and the per-step wall times."""

    frames: np.ndarray                       # (f + 1, n, 3) [m], frame 0 the initial state
    step_seconds: list[float] = field(default_factory=list)
    energy: np.ndarray | None = None         # (f + 1,) [J] mechanical energy, with gravity
    solver_error: float = math.nan
    objective_gap: float = math.nan


def steps_per_frame(frame_time: float, h: float) -> int:
    """frame_time / h as an integer; raise InputError when h does not divide the frame."""
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
    """
    from .effects import Gravity

    x, v = sim.state.positions, sim.state.velocities
    e = energy.kinetic_energy(sim.model, v) + energy.spring_energy(sim.model, x)
    for effect in sim.effects:
        if isinstance(effect, Gravity):
            e += energy.gravity_energy(sim.model, x, effect.acceleration)
    return e


def run_trajectory(sim: Simulation, *, frames: int, frame_time: float,
                   probe_frame: int | None = None, backend: str = "auto",
                   record_energy: bool = False) -> Trajectory:
    """Run ``sim`` for ``frames`` frames, recording positions at each frame.

    With ``probe_frame``, the first step of that frame is also solved to convergence by
    Newton and the simulation's solver error on it is recorded (relative error against
    x*, and objective gap). With ``record_energy``, :func:`mechanical_energy` at each
    frame is recorded in ``Trajectory.energy``.
    """
    per_frame = steps_per_frame(frame_time, sim.h)
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
            for _ in range(per_frame):
                seconds.append(sim.step().seconds)
            x = sim.state.positions
            out.append(x.copy())
            if record_energy:
                energies.append(mechanical_energy(sim))
            if not np.all(np.isfinite(x)):
                out.extend([np.full_like(x, np.nan)] * (frames - f - 1))
                break
    traj.frames = np.stack(out)
    traj.step_seconds = seconds
    if record_energy:
        e = np.full(len(out), np.nan)
        e[:len(energies)] = energies
        traj.energy = e
    return traj


def _is_implicit(solver: Solver) -> bool:
    return solver.name not in EXPLICIT_METHODS


def trajectory_error(frames: np.ndarray, reference: np.ndarray) -> float:
    """‖X − X_ref‖ / ‖X_ref − X_0‖ over all frames and vertices (inf if X is not finite)."""
    if not np.all(np.isfinite(frames)):
        return math.inf
    den = float(np.linalg.norm(reference - reference[0]))
    return float(np.linalg.norm(frames - reference)) / (den or 1.0)


def reference_trajectory(factory: SimulationFactory, *, h: float, frames: int,
                         frame_time: float, method: str = "newton",
                         tolerance: float = 1e-10, iterations: int = 50,
                         extrapolate: bool = True) -> tuple[np.ndarray, float]:
    """A converged, small-h reference trajectory for :func:`trajectory_error`.

    Implicit Euler solved to ``tolerance`` at h and at 2h. Its global error is
    X(h) − X_exact = C h + O(h²) (first order), so with ``extrapolate`` the returned
    frames are Richardson's 2 X(h) − X(2h), whose error is O(h²).

    Returns
    -------
    frames : ndarray, shape (frames + 1, n, 3) [m]
    error_estimate : float
        ‖X(h) − X(2h)‖ / ‖X(h) − X_0‖, about the relative error of the *unextrapolated*
        X(h) (an upper bound for the extrapolated one when the error is first order).
    """
    fine = run_trajectory(factory(method, h, iterations, tolerance), frames=frames,
                          frame_time=frame_time).frames
    coarse = run_trajectory(factory(method, 2.0 * h, iterations, tolerance), frames=frames,
                            frame_time=frame_time).frames
    estimate = trajectory_error(coarse, fine)
    return (2.0 * fine - coarse if extrapolate else fine), estimate


def convergence_slope(rows: Sequence[SweepRow], *, method: str,
                      iterations: int | None) -> float:
    """Log-log slope of trajectory error against h for one (method, iterations) series.

    Implicit Euler solved to convergence is first order: the slope should be about 1.
    NaN when fewer than two finite points exist.
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
    from .solvers import stable_time_step

    limit = stable_time_step(model, anchor_vertices=problem.anchor_vertices,
                             anchor_stiffness=problem.anchor_stiffness)
    h = frame_time
    while h >= 0.9 * limit:
        h /= 2.0
    return h


def run_sweep(factory: SimulationFactory, *, time_steps: Sequence[float],
              frame_time: float, frames: int,
              methods: Sequence[str] = ("local-global", "chebyshev", "newton",
                                        "symplectic-euler"),
              iterations: Sequence[int] = (1, 2, 5, 10, 20, 50),
              newton_iterations: Sequence[int] = (1, 2, 3, 5),
              tolerances: Sequence[float] = (),
              reference_h: float | None = None, reference_method: str = "newton",
              reference_tolerance: float = 1e-10, reference_iterations: int = 50,
              reference: np.ndarray | None = None, probe_frame: int | None = None,
              backend: str = "auto", progress: bool = False) -> list[SweepRow]:
    """Run every configuration (method × iterations or tolerance × h) and measure it.

    Parameters
    ----------
    factory : callable
        ``factory(method, h, iterations, tolerance) -> Simulation``; each call must
        return a fresh simulation at the scene's initial state.
    time_steps : sequence of float
        Time steps h [s] for the implicit methods; each must divide ``frame_time``.
    frame_time : float
        Time between recorded frames [s] (1 / fps).
    frames : int
        Frames to run; trajectories are compared at every frame.
    methods : sequence of str
        ``"symplectic-euler"`` runs once, at the largest frame_time / 2^j below 0.9 × its
        stability limit.
    iterations : sequence of int
        Iterations per step for local/global and Chebyshev.
    newton_iterations : sequence of int
        Iterations per step for Newton.
    tolerances : sequence of float
        Extra configurations with a relative-residual tolerance (iterations up to 10000).
    reference_h : float, optional
        Reference time step; default min(time_steps) / 16.
    reference_method, reference_tolerance, reference_iterations
        The reference run (:func:`reference_trajectory`, Richardson-extrapolated) is
        solved by this method to this relative residual, with at most this many
        iterations per step.
    reference : ndarray, shape (frames + 1, n, 3), optional
        A precomputed reference trajectory (then ``reference_*`` are ignored).
    probe_frame : int, optional
        Frame at whose first step the solver error is measured (default frames // 2).
    progress : bool
        Show a tqdm progress bar.

    Returns
    -------
    list of SweepRow
    """
    if frames < 1:
        raise InputError(f"accuracy.frames: must be >= 1, got {frames}")
    probe = frames // 2 if probe_frame is None else probe_frame
    h_ref = min(time_steps) / 16.0 if reference_h is None else reference_h
    configs: list[tuple[str, float, int | None, float | None]] = []
    for method in methods:
        if method in EXPLICIT_METHODS:
            configs.append((method, math.nan, 1, None))
            continue
        its = newton_iterations if method == "newton" else iterations
        for h in time_steps:
            steps_per_frame(frame_time, h)
            configs += [(method, h, int(k), None) for k in its]
            configs += [(method, h, 10000, float(t)) for t in tolerances]
    bar = _progress(len(configs) + 1, progress)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if reference is None:
            reference, ref_error = reference_trajectory(
                factory, h=h_ref, frames=frames, frame_time=frame_time,
                method=reference_method, tolerance=reference_tolerance,
                iterations=reference_iterations)
            log.info("reference h=%.4g s: unextrapolated relative error about %.2e",
                     h_ref, ref_error)
    bar.update(1)
    rows = []
    for method, h, its, tol in configs:
        bar.set_description(f"{method} h={h:.4g} it={its}")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            if method in EXPLICIT_METHODS:
                probe_sim = factory(method, frame_time, 1, None)
                h = _stable_explicit_step(probe_sim.model, frame_time, probe_sim.problem())
            sim = factory(method, h, its, tol)
            traj = run_trajectory(sim, frames=frames, frame_time=frame_time,
                                  probe_frame=probe, backend=backend)
        per_step = float(np.median(traj.step_seconds[1:] or traj.step_seconds))
        spf = steps_per_frame(frame_time, h)
        rows.append(SweepRow(method, h, its, tol, spf, per_step, per_step * spf,
                             traj.solver_error, traj.objective_gap,
                             trajectory_error(traj.frames, reference)))
        bar.update(1)
    bar.close()
    return rows


class _NoBar:
    def update(self, n=1):
        pass

    def set_description(self, text):
        pass

    def close(self):
        pass


def _progress(total: int, enabled: bool):
    if not enabled:
        return _NoBar()
    from tqdm import tqdm

    return tqdm(total=total, unit="config")


def write_csv(rows: Iterable[SweepRow], path) -> Path:
    """Write the sweep to ``path`` (columns :data:`CSV_FIELDS`)."""
    path = Path(path)
    with path.open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=CSV_FIELDS)
        w.writeheader()
        for row in rows:
            w.writerow({k: ("" if v is None else v) for k, v in asdict(row).items()})
    return path


def cheapest(rows: Sequence[SweepRow], *, error: str = "trajectory_error",
             levels: Sequence[float] = ACCURACY_LEVELS) -> list[tuple[float, SweepRow | None]]:
    """For each accuracy level, the configuration with the least seconds per frame whose
    ``error`` column is at most the level (None when no configuration reaches it)."""
    out = []
    for level in levels:
        ok = [r for r in rows if math.isfinite(getattr(r, error))
              and getattr(r, error) <= level]
        out.append((level, min(ok, key=lambda r: r.seconds_per_frame) if ok else None))
    return out


def cheapest_in_step(traces: dict[str, IterateTrace], *,
                     levels: Sequence[float] = ACCURACY_LEVELS
                     ) -> list[tuple[float, str | None, int, float]]:
    """For each level, (level, method, iterations, seconds) of the fastest method to reach
    that relative error within the step (method None when none does)."""
    out = []
    for level in levels:
        best = (level, None, 0, math.inf)
        for name, tr in traces.items():
            hit = tr.first_below(level)
            if hit is not None and hit[1] < best[3]:
                best = (level, name, hit[0], hit[1])
        out.append(best)
    return out


def pareto_front(rows: Sequence[SweepRow], *, error: str = "trajectory_error") -> list[SweepRow]:
    """Configurations that no other is both cheaper and more accurate than, by cost."""
    pts = sorted((r for r in rows if math.isfinite(getattr(r, error))),
                 key=lambda r: (r.seconds_per_frame, getattr(r, error)))
    front, best = [], math.inf
    for r in pts:
        if getattr(r, error) < best:
            front.append(r)
            best = getattr(r, error)
    return front


# -- implicit Euler's own damping -----------------------------------------------------------
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
    """
    return (1.0 + (omega * h) ** 2) ** (-0.5 * np.asarray(steps, dtype=np.float64))


def single_spring(*, stiffness: float = 100.0, mass: float = 1.0, rest_length: float = 1.0,
                  amplitude: float = 0.1):
    """A mass hanging on one spring below a pinned vertex (no gravity), pulled down.

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
    from .effects import Pin
    from .mesh import Mesh
    from .simulation import State
    from .springs import Springs

    x0 = np.array([[0.0, 0.0, 0.0], [0.0, -rest_length, 0.0]])
    mesh = Mesh(x0, strands=[[0, 1]])
    springs = Springs(np.array([[0, 1]]), np.array([stiffness]), np.array([rest_length]), 0)
    model = Model(mesh, springs, np.array([mass, mass]))
    state = State(x0 + [[0.0, 0.0, 0.0], [0.0, -amplitude, 0.0]], np.zeros((2, 3)))
    return model, Pin([0]), state, math.sqrt(stiffness / mass)


# -- plots ----------------------------------------------------------------------------------
_COLORS = {"local-global": "C0", "chebyshev": "C1", "newton": "C2", "symplectic-euler": "C3"}


def _pyplot():
    try:
        import matplotlib
    except ImportError as exc:  # pragma: no cover - matplotlib is a dependency
        raise InputError("plots need matplotlib: pip install matplotlib") from exc
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _save(plt, fig, path) -> Path:
    """Lay out, write (110 dpi) and close a figure; returns its path."""
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)


def plot_solver_accuracy(traces: dict[str, IterateTrace], path, *, title: str = "") -> Path:
    """Two panels: relative error against iterations, and against cumulative wall time."""
    plt = _pyplot()
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.2))
    for name, tr in traces.items():
        keep = tr.error > 0
        c = _COLORS.get(name)
        a.semilogy(tr.iterations[keep], tr.error[keep], "-", color=c, label=name,
                   marker="o" if name == "newton" else None, ms=3)
        b.loglog(tr.seconds[keep][1:] * 1e3, tr.error[keep][1:], "-", color=c, label=name,
                 marker="o" if name == "newton" else None, ms=3)
    a.set_xlabel("iterations")
    b.set_xlabel("cumulative wall time [ms]")
    for ax in (a, b):
        ax.set_ylabel("relative error ‖x_k − x*‖ / ‖x* − x_n‖")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend()
    fig.suptitle(title or "solver accuracy within one implicit Euler step")
    return _save(plt, fig, path)


def plot_frontier(rows: Sequence[SweepRow], path, *, title: str = "") -> Path:
    """Trajectory and solver error against seconds per frame, with the Pareto front and
    the cheapest configuration for each accuracy level marked."""
    plt = _pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.4))
    for ax, col, levels in zip(axes, ("trajectory_error", "solver_error"),
                               (TRAJECTORY_LEVELS, ACCURACY_LEVELS)):
        for method in dict.fromkeys(r.method for r in rows):
            pts = [r for r in rows if r.method == method and math.isfinite(getattr(r, col))
                   and getattr(r, col) > 0]
            if pts:
                ax.loglog([r.seconds_per_frame * 1e3 for r in pts],
                          [getattr(r, col) for r in pts], "o", ms=4, alpha=0.6,
                          color=_COLORS.get(method), label=method)
        front = [r for r in pareto_front(rows, error=col) if getattr(r, col) > 0]
        if front:
            ax.loglog([r.seconds_per_frame * 1e3 for r in front],
                      [getattr(r, col) for r in front], "k-", lw=1, label="frontier")
        for level, r in cheapest(rows, error=col, levels=levels):
            if r is None:
                continue
            ax.axhline(level, color="0.85", lw=0.6, zorder=0)
            ax.plot(r.seconds_per_frame * 1e3, getattr(r, col), "*", ms=11,
                    color=_COLORS.get(r.method), mec="k")
        ax.set_xlabel("wall time per frame [ms]")
        ax.set_ylabel(col.replace("_", " "))
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    axes[0].set_title("trajectory vs. small-h converged reference")
    axes[1].set_title("solver error within a step (vs. Newton x*)")
    fig.suptitle(title or "accuracy/time frontier (★ = cheapest for each accuracy level)")
    return _save(plt, fig, path)


def plot_convergence(rows: Sequence[SweepRow], path, *, title: str = "") -> Path:
    """Trajectory error against h (log-log), one line per (method, iterations), with a
    slope-1 guide (implicit Euler is first order) and each line's fitted slope."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    series = dict.fromkeys((r.method, r.iterations) for r in rows
                           if r.method not in EXPLICIT_METHODS)
    styles = ["-", "--", ":", "-."]
    for i, (method, its) in enumerate(series):
        pts = sorted((r.h, r.trajectory_error) for r in rows
                     if (r.method, r.iterations) == (method, its)
                     and math.isfinite(r.trajectory_error))
        if len(pts) < 2:
            continue
        h, e = np.array(pts).T
        slope = convergence_slope(rows, method=method, iterations=its)
        ax.loglog(h, e, styles[i % 4], marker="o", ms=3, color=_COLORS.get(method),
                  label=f"{method} {its} it (slope {slope:.2f})")
    h_all = np.array(sorted({r.h for r in rows if math.isfinite(r.h)}))
    if len(h_all):
        best = min((r for r in rows if r.h == h_all[0] and math.isfinite(r.trajectory_error)),
                   key=lambda r: r.trajectory_error, default=None)
        if best is not None:
            ax.loglog(h_all, best.trajectory_error * h_all / h_all[0], "k:", lw=1,
                      label="slope 1")
    ax.set_xlabel("time step h [s]")
    ax.set_ylabel("trajectory error ‖X − X_ref‖ / ‖X_ref − X_0‖")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    ax.set_title(title or "trajectory error against h")
    return _save(plt, fig, path)


def damping_curves(factory: SimulationFactory, *, h: float, frames: int, frame_time: float,
                   settings: Sequence[tuple[str, int | None, float | None]], vertex: int
                   ) -> dict[str, np.ndarray]:
    """Height (y) of ``vertex`` at every frame for a few (method, iterations, tolerance)."""
    out = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for method, its, tol in settings:
            sim = factory(method, h, its, tol)
            traj = run_trajectory(sim, frames=frames, frame_time=frame_time)
            label = f"{method}, " + (f"tol {tol:g}" if tol else f"{its} it")
            out[label] = traj.frames[:, vertex, 1]
    return out


def energy_curves(factory: SimulationFactory, *, h: float, frames: int, frame_time: float,
                  settings: Sequence[tuple[str, int | None, float | None]],
                  reference: np.ndarray | None = None) -> dict[str, np.ndarray]:
    """Mechanical energy (:func:`mechanical_energy`) at every frame for a few (method,
    iterations, tolerance); ``reference`` (shape (frames + 1,)) is added as-is."""
    out = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for method, its, tol in settings:
            sim = factory(method, h, its, tol)
            traj = run_trajectory(sim, frames=frames, frame_time=frame_time,
                                  record_energy=True)
            out[f"{method}, " + (f"tol {tol:g}" if tol else f"{its} it")] = traj.energy
    if reference is not None:
        out["reference (small h, converged)"] = np.asarray(reference)
    return out


def single_spring_heights(*, h: float, steps: int, stiffness: float = 100.0,
                          mass: float = 1.0, amplitude: float = 0.1
                          ) -> tuple[np.ndarray, dict[str, np.ndarray], np.ndarray]:
    """Displacement of the single spring's mass over ``steps`` steps.

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


def plot_damping(path, *, h: float = 1 / 30, steps: int = 90,
                 cloth_curves: dict[str, np.ndarray] | None = None,
                 frame_time: float = 1 / 30, cloth_ylabel: str = "mechanical energy [J]",
                 cloth_title: str = "cloth: energy, iterations per step") -> Path:
    """Implicit Euler's damping: the single spring against its closed-form envelope, and
    (optionally) a cloth quantity (:func:`energy_curves`) for a few iteration counts."""
    plt = _pyplot()
    panels = 2 if cloth_curves else 1
    fig, axes = plt.subplots(1, panels, figsize=(5.6 * panels, 4.2), squeeze=False)
    t, curves, env = single_spring_heights(h=h, steps=steps)
    ax = axes[0, 0]
    for label, y in curves.items():
        ax.plot(t, y, "-", lw=1.2, label=label)
    ax.plot(t, env, "k--", lw=1, label="(1 + ω²h²)^(−n/2), closed form")
    ax.plot(t, -env, "k--", lw=1)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("displacement [m]")
    ax.set_title(f"one spring, ω = 10 rad/s, h = {h:.4g} s")
    ax.legend(fontsize=8)
    if cloth_curves:
        ax = axes[0, 1]
        for label, y in cloth_curves.items():
            ax.plot(np.arange(len(y)) * frame_time, y, lw=1.1, label=label)
        ax.set_xlabel("time [s]")
        ax.set_ylabel(cloth_ylabel)
        ax.set_title(cloth_title)
        ax.legend(fontsize=8)
    return _save(plt, fig, path)


# -- command line ---------------------------------------------------------------------------
def add_arguments(parser) -> None:
    """Add ``clothsim accuracy`` arguments to an argparse parser."""
    parser.add_argument("scene", nargs="?", default="hanging",
                        help="scene name or TOML path (default: hanging)")
    parser.add_argument("--out", default="accuracy-out", help="output directory")
    parser.add_argument("--quick", action="store_true",
                        help="few configurations and frames (a minute or so)")
    parser.add_argument("--frames", type=int, default=None, help="frames per run")


def scene_factory(scene) -> tuple[SimulationFactory, Model]:
    """A simulation factory for a :class:`clothsim.scene.Scene` (h = scene.h / substeps)."""
    model = scene.build_model()

    def factory(method, h, iterations, tolerance):
        substeps = steps_per_frame(scene.h, h)
        return scene.build_simulation(model, method=method, iterations=iterations,
                                      tolerance=tolerance, substeps=substeps)

    return factory, model


def command(args) -> int:
    """Run ``clothsim accuracy``: the sweep, accuracy.csv and the plots. Returns 0."""
    from .scene import load_scene

    scene = load_scene(args.scene)
    factory, model = scene_factory(scene)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    h = scene.h
    if args.quick:
        frames = args.frames or 15
        kw = dict(time_steps=(h, h / 2), iterations=(1, 5, 20),
                  newton_iterations=(1, 3), methods=("local-global", "chebyshev", "newton"))
    else:
        frames = args.frames or 60
        kw = dict(time_steps=(h, h / 2, h / 4), iterations=(1, 2, 5, 10, 20, 50, 100),
                  newton_iterations=(1, 2, 3, 5, 10))
    rows = run_sweep(factory, frame_time=h, frames=frames, progress=True, **kw)
    write_csv(rows, out / "accuracy.csv")
    sim = factory("local-global", h, 10, None)
    problem = representative_problem(sim, steps=max(1, frames // 2))
    traces = solver_accuracy(model, problem, iterations=100 if args.quick else 500,
                             newton_iterations=10 if args.quick else 30)
    plot_solver_accuracy(traces, out / "error_vs_iterations_time.png",
                         title=f"{args.scene}: the step of largest ‖∇g(y)‖ "
                               f"in the first {max(1, frames // 2)}")
    plot_frontier(rows, out / "frontier.png")
    plot_convergence(rows, out / "convergence.png", title=f"{args.scene}: trajectory error")
    curves = energy_curves(factory, h=h, frames=frames, frame_time=h,
                           settings=[("local-global", 1, None), ("local-global", 10, None),
                                     ("newton", 50, 1e-10)])
    plot_damping(out / "damping.png", h=h, cloth_curves=curves, frame_time=h)
    for level, r in cheapest(rows, levels=TRAJECTORY_LEVELS):
        if r is not None:
            log.info("trajectory error <= %.0e: %s h=%.4g it=%s, %.3g ms/frame", level,
                     r.method, r.h, r.iterations, r.seconds_per_frame * 1e3)
    print(f"wrote {out / 'accuracy.csv'} ({len(rows)} configurations) and plots to {out}")
    return 0
