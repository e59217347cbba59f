"""Converged runs in less time: Newton warm-started by L-BFGS.

The study's converged runs — the recording run (:func:`~clothsim.accuracy.problems.
record_problems`), the time-step study's runs and its small-h reference — need each step
solved to a certified minimum, not Newton's path to it. On contact and crumpling, Newton
from y takes 40–100 damped, shifted iterations (2–3 factorizations each); L-BFGS reaches
1e-6 relative residual in a few hundred cheap iterations, and Newton from there needs a
handful to the caller's tolerance (relative to ‖∇g(x_0)‖, as always) or its rounding
floor, and reports its certificate (λ_min > 0) as before.
:func:`warm_started` swaps this solver into a converged Newton simulation. The references
(:mod:`clothsim.accuracy.reference`) still run Newton from y and x_n: those starts are the
point of the several-minima check.
"""

from __future__ import annotations

import warnings

import numpy as np

from ..simulation import Simulation
from ..solvers import LBFGSSolver, NewtonSolver, StepProblem, objective_gradient
from ..solvers.newton import NewtonResult
from .trajectory import Trajectory, run_trajectory

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

    The single run behind :func:`~clothsim.accuracy.trajectory.reference_runs` and the
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
