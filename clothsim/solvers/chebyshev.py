"""Local/global iterations with Chebyshev semi-iterative acceleration (Wang 2015).

Plain local/global (:class:`~clothsim.solvers.LocalGlobalSolver`) converges linearly:
near the solution the error shrinks by about ρ per iteration, ρ < 1 the spectral radius
of the iteration. Wang treats the iteration as a fixed-point map x ↦ x̂(x) and applies the
Chebyshev semi-iterative method, which needs only an estimate of ρ:

    ω_k     = 1                        for k < S (the delay)
    ω_S     = 2 / (2 − ρ²)
    ω_{k+1} = 4 / (4 − ρ² ω_k)         for k > S
    x_{k+1} = ω_{k+1} (γ (x̂_{k+1} − x_k) + x_k − x_{k−1}) + x_{k−1}

where x̂_{k+1} is one local/global iteration from x_k and γ ≈ 0.9 under-relaxes it. With
ρ = 0 and γ = 1 the iteration is plain local/global. The method reuses the parent's cached
factor and half steps: one iteration costs one local step, one residual and one global
step, exactly like local/global.

Estimating ρ for a scene
------------------------
:func:`estimate_spectral_radius` runs plain local/global on a representative step and fits
the ratio of successive update norms ‖x_{k+1} − x_k‖ / ‖x_k − x_{k−1}‖ over the last
iterations (for a linearly converging iteration this ratio tends to ρ). Estimate once per
scene and time step and pass it as ``rho``; without ``rho`` the solver estimates it on the
first step it solves and keeps it. Too large a ρ makes the iteration oscillate; too small
a ρ only loses speed, so the estimate is slightly shrunk (``safety``).

References
----------
H. Wang. A Chebyshev Semi-Iterative Approach for Accelerating Projective and Position-based
Dynamics. ACM Transactions on Graphics 34(6), 246, 2015. DOI 10.1145/2816795.2818063.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Iterator

import numpy as np

from ..errors import InputError, check_finite
from ..model import Model
from .base import StepProblem, StepResult, gradient_noise_floor, relative
from .local_global import LocalGlobalSolver

log = logging.getLogger(__name__)

DEFAULT_DELAY = 10
DEFAULT_GAMMA = 0.9


def estimate_spectral_radius(model: Model, problem: StepProblem, *, iterations: int = 60,
                             fit_last: int = 20, safety: float = 0.999,
                             backend: str = "auto",
                             solver: LocalGlobalSolver | None = None) -> float:
    """Estimate the convergence rate ρ of local/global iterations on one step.

    Parameters
    ----------
    model : Model
    problem : StepProblem
        A representative step of the scene (e.g. one taken mid-motion).
    iterations : int, default 60
        Plain local/global iterations to run.
    fit_last : int, default 20
        Fit ρ as the geometric mean of ‖Δx_{k+1}‖ / ‖Δx_k‖ over the last ``fit_last``
        iterations, Δx_k = x_k − x_{k−1}.
    safety : float, default 0.999
        The returned value is ``safety * ρ``, capped below 1.
    backend : {"auto", "cholmod", "splu"}
    solver : LocalGlobalSolver, optional
        Reuse this solver's cached factor instead of building one.

    Returns
    -------
    float
        ρ in [0, 1).
    """
    if iterations < 3 or fit_last < 1:
        raise InputError(f"estimate_spectral_radius: need iterations >= 3 and fit_last >= 1, "
                         f"got {iterations} and {fit_last}")
    lg = solver if solver is not None else LocalGlobalSolver(model, backend=backend)
    lg.system(problem)
    x = problem.initial_guess()
    steps = []
    for _ in range(iterations):
        x_new = lg.global_step(problem, lg.local_step(x))
        steps.append(float(np.linalg.norm(x_new - x)))
        x = x_new
    steps = np.asarray(steps)
    ratios = steps[1:] / np.where(steps[:-1] > 0, steps[:-1], np.inf)
    ratios = ratios[np.isfinite(ratios) & (ratios > 0)][-fit_last:]
    if len(ratios) == 0:  # converged at once: nothing to accelerate
        return 0.0
    rho = float(np.exp(np.mean(np.log(ratios))))
    rho = min(safety * rho, 0.9999)
    log.info("estimated local/global spectral radius rho=%.5f from %d ratios", rho, len(ratios))
    return max(rho, 0.0)


class ChebyshevSolver(LocalGlobalSolver):
    """Local/global iterations accelerated by Chebyshev semi-iteration (Wang 2015).

    Parameters
    ----------
    model : Model
    iterations : int, default 10
        Iterations per step (each one local step + one global step); the maximum when
        ``tolerance`` is set.
    tolerance : float, optional
        Stop once ‖∇g(x_k)‖ / ‖∇g(x_0)‖ is at most this.
    rho : float, optional
        Spectral radius estimate ρ ∈ [0, 1) of plain local/global for this scene and h.
        Default: estimated by :func:`estimate_spectral_radius` on the first solved step.
    delay : int, default 10
        S: plain (under-relaxed) iterations before acceleration starts.
    gamma : float, default 0.9
        Under-relaxation γ ∈ (0, 1].
    backend : {"auto", "cholmod", "splu"}
    check_conditioning : bool, default True
    """

    name = "chebyshev"

    def __init__(self, model: Model, *, iterations: int = 10, tolerance: float | None = None,
                 backend: str = "auto", check_conditioning: bool = True,
                 rho: float | None = None, delay: int = DEFAULT_DELAY,
                 gamma: float = DEFAULT_GAMMA):
        super().__init__(model, iterations=iterations, tolerance=tolerance, backend=backend,
                         check_conditioning=check_conditioning)
        if rho is not None:
            rho = float(check_finite("solver.rho", rho))
            if not 0.0 <= rho < 1.0:
                raise InputError(f"solver.rho: must be in [0, 1), got {rho!r}")
        if not isinstance(delay, (int, np.integer)) or delay < 0:
            raise InputError(f"solver.delay: must be an integer >= 0, got {delay!r}")
        gamma = float(check_finite("solver.gamma", gamma))
        if not 0.0 < gamma <= 1.0:
            raise InputError(f"solver.gamma: must be in (0, 1], got {gamma!r}")
        self.rho = rho
        self.delay = int(delay)
        self.gamma = gamma

    def omega(self, k: int, omega_prev: float) -> float:
        """ω_{k+1} for iteration k (0-based) given ω_k (Wang 2015, Eq. 11 with delay S)."""
        rho2 = self.rho ** 2
        if k < self.delay:
            return 1.0
        if k == self.delay:
            return 2.0 / (2.0 - rho2)
        return 4.0 / (4.0 - rho2 * omega_prev)

    def iterates(self, problem: StepProblem,
                 x0: np.ndarray | None = None) -> Iterator[tuple[int, np.ndarray, float]]:
        """Yield (k, x_k, ‖∇g(x_k)‖) for k = 0, 1, 2, … without end (no stopping test).

        The gradient norm is over the free degrees of freedom; it costs what a residual
        check costs in :meth:`solve`. Used by :meth:`solve` and by accuracy measurements.
        """
        self.system(problem)
        if self.rho is None:
            self.rho = estimate_spectral_radius(self.model, problem, solver=self)
        x = problem.initial_guess() if x0 is None else np.array(x0, dtype=np.float64)
        x_prev = x
        omega = 1.0
        k = 0
        while True:
            d = self.local_step(x)
            yield k, x, float(np.linalg.norm(self.gradient(problem, x, d)))
            x_hat = self.global_step(problem, d)
            omega = self.omega(k, omega)
            x_next = omega * (self.gamma * (x_hat - x) + x - x_prev) + x_prev
            x_prev, x = x, x_next
            k += 1

    def solve(self, problem: StepProblem, x0: np.ndarray | None = None) -> StepResult:
        """Minimize g by accelerated local/global iterations from ``x0`` (default: y)."""
        history: list[float] = []
        r0 = None
        x = None
        it = 0
        floor = 0.0
        for it, x, rn in self.iterates(problem, x0):
            if r0 is None:
                r0 = rn
                floor = gradient_noise_floor(self.model, problem, x) if self.tolerance else 0.0
            history.append(relative(rn, r0))
            if not math.isfinite(rn):
                break
            if it >= self.iterations or (self.tolerance is not None
                                         and (history[-1] <= self.tolerance or rn <= floor)):
                break
        return self._finish(x, it, history, at_floor=rn <= floor)
