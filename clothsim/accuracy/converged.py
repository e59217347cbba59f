"""Converged runs, in less time: Newton warm-started by L-BFGS.

The study's converged runs — the recording run (:func:`~clothsim.accuracy.problems.
record_problems`), the time-step study's runs and its small-h reference — need each step
solved to a certified minimum, not Newton's path to it. On contact and crumpling, Newton
from y takes 40–100 damped, shifted iterations (2–3 factorizations each); L-BFGS reaches
1e-6 relative residual in a few hundred cheap iterations, and Newton from there needs a
handful to the caller's tolerance (relative to ‖∇g(x_0)‖, as always) or its rounding
floor, and reports its certificate (λ_min > 0) as before. Steps with held contacts are
solved by Newton alone: its projected steps need 7–30 iterations there, less time than
L-BFGS's ~950 to 1e-6 (:meth:`WarmNewtonSolver.solve`).
:func:`warm_started` swaps this solver into a converged Newton simulation. The references
(:mod:`clothsim.accuracy.reference`) still run Newton from y and x_n: those starts are the
point of the several-minima check.

:func:`converged_run` is one such run at a given h; :func:`reference_runs` makes them at h
and 2h, and :func:`reference_trajectory` Richardson-extrapolates them into the reference of
trajectory errors (:mod:`clothsim.accuracy.trajectory`).
"""

from __future__ import annotations

import warnings

import numpy as np

from ..simulation import Simulation
from ..solvers import LBFGSSolver, NewtonSolver, StepProblem, objective_gradient
from ..solvers.newton import NewtonResult
from .trajectory import SimulationFactory, Trajectory, run_trajectory, trajectory_error

WARM_TOLERANCE = 1e-6
"""Relative residual at which L-BFGS hands over to Newton."""
WARM_CAP = 2000
"""L-BFGS iterations at most before Newton takes over anyway."""


class WarmNewtonSolver(NewtonSolver):
    """Newton (to its tolerance or rounding floor) from the point L-BFGS reaches at
    :data:`WARM_TOLERANCE` (module text). Same parameters as :class:`NewtonSolver`.

    ``solve`` returns Newton's result (its certificate, its iterations) with the residual
    and its history relative to ‖∇g(x_0)‖ of the caller's start, as any solver's.
    """

    def solve(self, problem: StepProblem, x0: np.ndarray | None = None) -> NewtonResult:
        """Minimize g: L-BFGS to :data:`WARM_TOLERANCE`, then Newton.

        Parameters
        ----------
        problem : StepProblem
            The step.
        x0 : ndarray, shape (n, 3), optional
            Initial guess [m] (default: the problem's).

        Returns
        -------
        NewtonResult
            x [m], Newton's iterations, the relative residual ‖∇g(x)‖ / ‖∇g(x_0)‖, its
            history (L-BFGS's, then Newton's), converged and the certificate.
        """
        if problem.has_contacts:
            # held contacts: Newton from the start is faster (measured on drop-on-square
            # 25²'s held steps against L-BFGS to 1e-6 and then Newton: commit 0012e1b)
            return super().solve(problem, x0=x0)
        start = problem.initial_guess() if x0 is None else np.asarray(x0, dtype=np.float64)
        lbfgs = self.__dict__.get("_lbfgs")   # one L-BFGS for the run: its factor is cached
        if lbfgs is None:
            lbfgs = self._lbfgs = LBFGSSolver(self.model, iterations=WARM_CAP,
                                              tolerance=WARM_TOLERANCE)
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            try:
                warm = lbfgs.solve(problem, x0=start)
                ok = bool(np.all(np.isfinite(warm.x)))
            except (FloatingPointError, ValueError, np.linalg.LinAlgError):
                ok = False
        if not ok:
            return super().solve(problem, x0=start)
        free = problem.free_mask(self.model.vertex_count)
        r0 = float(np.linalg.norm(objective_gradient(self.model, problem, start)[free]))
        r1 = float(np.linalg.norm(objective_gradient(self.model, problem, warm.x)[free]))
        scale = r1 / r0 if r0 > 0 else 0.0
        tolerance = self.tolerance
        if tolerance is not None and scale > 0:  # the caller's tolerance, relative to x_0
            self.tolerance = min(1.0, tolerance / scale)
        try:
            res = super().solve(problem, x0=warm.x)
        finally:
            self.tolerance = tolerance
        history = list(warm.residual_history) + [r * scale for r in res.residual_history[1:]]
        res.residual *= scale
        res.residual_history = history
        if self.tolerance is not None and res.residual <= self.tolerance:
            res.converged = True
        return res


def warm_started(sim: Simulation) -> Simulation:
    """Give a converged Newton simulation the warm-started solver (module text).

    Parameters
    ----------
    sim : Simulation
        Any simulation; only an undamped one whose solver is a plain
        :class:`NewtonSolver` with a tolerance is changed.

    Returns
    -------
    Simulation
        ``sim`` (changed in place).
    """
    s = sim.solver
    damped = bool(sim.model.springs.spring_damping.any())
    if type(s) is NewtonSolver and s.tolerance is not None and not damped:
        sim.solver = WarmNewtonSolver(sim.model, iterations=s.iterations,
                                      tolerance=s.tolerance, indefinite=s.indefinite)
    return sim


def converged_run(factory, h: float, frames: int, frame_time: float, method: str = "newton",
                  iterations: int = 50, tolerance: float = 1e-10) -> Trajectory:
    """One run at h solved to convergence every step, with its contact flags.

    The single run behind :func:`reference_runs` and the
    time-step study (:mod:`~clothsim.accuracy.timestep`): the factory's simulation, given
    the warm-started solver (:func:`warm_started`), run for ``frames`` frames.

    Parameters
    ----------
    factory : callable
        ``factory(method, h, iterations, tolerance) -> Simulation``.
    h : float
        Time step [s].
    frames : int
        Frames to run.
    frame_time : float
        Time between frames [s].
    method : str, default "newton"
        Converged solver.
    iterations : int, default 50
        Its iteration cap per step.
    tolerance : float, default 1e-10
        Its relative residual tolerance.

    Returns
    -------
    Trajectory
        The run (``Trajectory.contact`` recorded).
    """
    return run_trajectory(warm_started(factory(method, h, iterations, tolerance)),
                          frames=frames, frame_time=frame_time, record_contact=True)


def reference_trajectory(factory: SimulationFactory, *, h: float, frames: int,
                         frame_time: float, method: str = "newton",
                         tolerance: float = 1e-10, iterations: int = 50,
                         extrapolate: bool = True) -> tuple[np.ndarray, float]:
    """A converged, small-h reference trajectory for :func:`trajectory_error`.

    Implicit Euler solved to ``tolerance`` at h and at 2h. Its global error is
    X(h) − X_exact = C h + O(h²) (first order), so with ``extrapolate`` the returned
    frames are Richardson's 2 X(h) − X(2h), whose error is O(h²).

    Parameters
    ----------
    factory : callable
        ``factory(method, h, iterations, tolerance) -> Simulation``.
    h : float
        The reference time step [s] (2h must divide ``frame_time`` too).
    frames : int
        Frames to run.
    frame_time : float
        Time between frames [s].
    method : str, default "newton"
        Solver of the reference runs.
    tolerance : float, default 1e-10
        Relative residual per step.
    iterations : int, default 50
        Maximum iterations per step.
    extrapolate : bool, default True
        Return the Richardson extrapolation rather than X(h).

    Returns
    -------
    frames : ndarray, shape (frames + 1, n, 3) [m]
    error_estimate : float
        ‖X(h) − X(2h)‖ / ‖X(h) − X_0‖, about the relative error of the *unextrapolated*
        X(h) (an upper bound for the extrapolated one when the error is first order).
    """
    fine, coarse = (r.frames for r in reference_runs(
        factory, h=h, frames=frames, frame_time=frame_time, method=method,
        tolerance=tolerance, iterations=iterations))
    estimate = trajectory_error(coarse, fine)
    return (2.0 * fine - coarse if extrapolate else fine), estimate


def reference_runs(factory: SimulationFactory, *, h: float, frames: int, frame_time: float,
                   method: str = "newton", tolerance: float = 1e-10, iterations: int = 50
                   ) -> tuple[Trajectory, Trajectory]:
    """The runs at h and 2h of :func:`reference_trajectory`, with their contact flags.

    Parameters
    ----------
    factory : callable
        ``factory(method, h, iterations, tolerance) -> Simulation``.
    h : float
        The fine time step [s]; the coarse run uses 2h.
    frames : int
        Frames to run.
    frame_time : float
        Time between frames [s].
    method : str
        Converged solver of the reference runs.
    tolerance : float
        Its relative residual tolerance.
    iterations : int
        Its iteration cap per step.

    Returns
    -------
    fine, coarse : Trajectory
        The runs at h and 2h (``Trajectory.contact`` recorded).
    """
    return tuple(converged_run(factory, step, frames, frame_time, method, iterations, tolerance)
                 for step in (h, 2.0 * h))
