"""Newton's method with backtracking line search on g(x): the exact reference.

Each iteration solves (M + h² ∇²E(x_k)) Δ = −∇g(x_k) over the free degrees of freedom (3n
form, interleaved) and takes x_{k+1} = x_k + α Δ with the largest α ∈ {1, ½, ¼, …} that
satisfies Armijo's condition g(x + αΔ) ≤ g(x) + c α ∇gᵀΔ, c = 1e-4. The exact Hessian is
used whenever M + h² ∇²E is positive definite (then convergence is quadratic). Compressed
springs can make it indefinite; then (the Cholesky factorization fails) their transverse
stiffness factor (1 − r/l) is clamped at 0 (:func:`clothsim.energy.spring_hessian`), which
makes the system positive definite and Δ a descent direction. Iterations stop at the
tolerance, or when the step no longer changes x in floating point (the gradient has reached
its rounding floor; this counts as converged). Converged, it gives the implicit Euler step
x_{n+1} that the local/global iterations approach (Liu et al. 2013, Section 5 compares the two).

References
----------
J. Nocedal, S. J. Wright. Numerical Optimization, 2nd ed., Springer 2006, Alg. 3.1.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .. import energy
from ..errors import FactorizationError
from ..factorization import Factor
from ..model import Model
from .base import (
    Solver,
    StepProblem,
    StepResult,
    gradient_noise_floor,
    objective,
    objective_gradient,
    relative,
)

ARMIJO_C = 1e-4
MAX_HALVINGS = 60


class NewtonSolver(Solver):
    """Newton's method with line search on the implicit Euler objective g.

    Parameters
    ----------
    model : Model
    iterations : int, default 50
        Maximum Newton iterations per step.
    tolerance : float, optional, default 1e-12
        Stop once ‖∇g(x_k)‖ / ‖∇g(x_0)‖ is at most this.
    backend : {"auto", "cholmod", "splu"}
        Factorization of each Newton system (refactored every iteration).
    """

    name = "newton"

    def __init__(self, model: Model, *, iterations: int = 50, tolerance: float | None = 1e-12,
                 backend: str = "auto"):
        super().__init__(model, iterations=iterations, tolerance=tolerance, backend=backend)
        self.backend: str | None = None
        self._M3 = np.repeat(model.vertex_mass, 3)

    def hessian(self, problem: StepProblem, x: np.ndarray, *,
                definite: bool = False) -> sp.csr_matrix:
        """∇²g(x) = M + h² (∇²E_springs(x) + K_anchor), shape (3n, 3n).

        ``definite=True`` clamps compressed springs' transverse stiffness at 0.
        """
        n = self.model.vertex_count
        H = (problem.h ** 2) * energy.spring_hessian(self.model, x, definite=definite)
        diag = self._M3.copy()
        if len(problem.anchor_vertices):
            idx = (3 * problem.anchor_vertices[:, None] + np.arange(3)).ravel()
            np.add.at(diag, idx, problem.h ** 2 * np.repeat(problem.anchor_stiffness, 3))
        return (H + sp.diags(diag, shape=(3 * n, 3 * n))).tocsr()

    def solve(self, problem: StepProblem, x0: np.ndarray | None = None) -> StepResult:
        n = self.model.vertex_count
        x = problem.initial_guess() if x0 is None else np.array(x0, dtype=np.float64)
        free = np.repeat(problem.free_mask(n), 3)
        grad = objective_gradient(self.model, problem, x).ravel()
        g = objective(self.model, problem, x)
        r0 = float(np.linalg.norm(grad))
        history = [relative(r0, r0)]
        floor = gradient_noise_floor(self.model, problem, x) if self.tolerance else 0.0
        it = 0
        self.stalled = False
        while it < self.iterations and not (self.tolerance is not None and (
                history[-1] <= self.tolerance or history[-1] * r0 <= floor)):
            try:
                factor = Factor(self.hessian(problem, x)[free][:, free],
                                backend=self.backend_requested, check_conditioning=False)
            except FactorizationError:  # indefinite: clamp compressed springs
                factor = Factor(self.hessian(problem, x, definite=True)[free][:, free],
                                backend=self.backend_requested, check_conditioning=False)
            self.backend = factor.backend
            step = np.zeros(3 * n)
            step[free] = -factor.solve(grad[free])
            slope = float(grad @ step)
            alpha = 1.0
            # Near the solution the decrease −slope/2 is below g's rounding error and Armijo
            # cannot be verified: take the full Newton step (quadratic convergence region).
            unverifiable = -slope <= 64 * np.finfo(float).eps * abs(g)
            for _ in range(0 if unverifiable else MAX_HALVINGS):
                x_try = x + alpha * step.reshape(n, 3)
                g_try = objective(self.model, problem, x_try)
                if g_try <= g + ARMIJO_C * alpha * slope:
                    break
                alpha *= 0.5
            else:
                if not unverifiable:  # no decrease at working precision: optimal to rounding
                    self.stalled = True
                    break
                x_try = x + step.reshape(n, 3)
                g_try = objective(self.model, problem, x_try)
            moved = float(np.abs(alpha * step).max())
            x, g = x_try, g_try
            grad = objective_gradient(self.model, problem, x).ravel()
            history.append(relative(float(np.linalg.norm(grad)), r0))
            it += 1
            if moved <= 4 * np.finfo(float).eps * max(float(np.abs(x).max()), 1e-300):
                self.stalled = True  # x no longer changes: the gradient is at rounding level
                break
        return self._finish(x, it, history, at_floor=self.stalled or history[-1] * r0 <= floor)
