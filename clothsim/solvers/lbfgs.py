"""L-BFGS on g with the local/global matrix as initial Hessian (Liu, Bouaziz, Kavan 2017).

Quasi-Newton with the two-loop recursion (Nocedal and Wright Alg. 7.4) over the last m
pairs s_j = x_{j+1} − x_j, t_j = ∇g(x_{j+1}) − ∇g(x_j). The initial inverse Hessian is
H₀ = (M + h² L)⁻¹ — the global-step matrix, applied through the cached sparse Cholesky
factor of :class:`~clothsim.solvers.LocalGlobalSolver` (two triangular solves). Without any
pair the direction −H₀ ∇g(x) is exactly the local/global step; the pairs add the
curvature the fixed matrix misses. The step length comes from a backtracking Armijo line
search on the cancellation-free difference
:func:`~clothsim.solvers.descent.objective_difference`, so g never increases (beyond
rounding) and the search still works at residuals far below 1e-8. Pairs with
sᵀt ≤ 0 (negative curvature, buckling) are skipped, keeping the implicit inverse positive
definite.

References
----------
T. Liu, S. Bouaziz, L. Kavan. Quasi-Newton Methods for Real-Time Simulation of
Hyperelastic Materials. ACM Transactions on Graphics 36(3), 23, 2017.
J. Nocedal, S. J. Wright. Numerical Optimization, 2nd ed., Springer 2006, Alg. 7.4.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterator

import numpy as np

from ..errors import InputError
from ..model import Model
from .base import Iterate, StepProblem
from .descent import ARMIJO_C, MAX_HALVINGS
from .fused import FusedStep
from .local_global import LocalGlobalSolver


class LBFGSSolver(LocalGlobalSolver):
    """L-BFGS with H₀ = (M + h² L)⁻¹ and Armijo line search (Liu et al. 2017).

    Parameters
    ----------
    model : Model
    iterations : int, default 10
        Iterations per step (each one gradient, one H₀ solve, ≥ 1 energy difference); the
        maximum when ``tolerance`` is set.
    tolerance : float, optional
        Stop once ‖∇g(x_k)‖ / ‖∇g(x_0)‖ is at most this.
    window : int, default 7
        m: curvature pairs kept (Liu et al. use 5–10).
    backend : {"auto", "cholmod", "splu"}
        Sparse factorization of H₀⁻¹ = M + h² L (:class:`~clothsim.factorization.Factor`).
    check_conditioning : bool, default True
        Warn when a new factor's condition estimate passes 1e12.

    Attributes
    ----------
    window : int
        m, as given.
    """

    name = "lbfgs"

    def __init__(self, model: Model, *, iterations: int = 10, tolerance: float | None = None,
                 backend: str = "auto", check_conditioning: bool = True, window: int = 7):
        super().__init__(model, iterations=iterations, tolerance=tolerance, backend=backend,
                         check_conditioning=check_conditioning)
        if not isinstance(window, (int, np.integer)) or window < 1:
            raise InputError(f"solver.window: must be an integer >= 1, got {window!r}")
        self.window = int(window)

    def iterates(self, problem: StepProblem, x0: np.ndarray | None = None) -> Iterator[Iterate]:
        """Yield the initial guess, then each L-BFGS iterate, g never increasing.

        The direction is p = −H ∇g(x_k), H the L-BFGS inverse Hessian built by the
        two-loop recursion from H₀ = (M + h² L)⁻¹ and the pairs (s_j, t_j) with
        ρ_j = 1 / (s_jᵀ t_j) > 0; then x_{k+1} = x_k + α p with α from a backtracking
        Armijo search (Liu, Bouaziz, Kavan 2017; Nocedal and Wright Alg. 7.4). Returns when
        no step length along p decreases g. Runs on local/global's fused iteration
        (:class:`~.fused.FusedStep`): ∇g(x) = A_FF δ − rhs(x) from the local step that
        the energy comparison of the accepted trial has already begun.

        Parameters
        ----------
        problem : StepProblem
            The step's h [s], y [m], f_ext [N] and pins.
        x0 : ndarray, shape (n, 3), optional
            Initial guess [m]; default y with the pins applied.

        Yields
        ------
        Iterate
            k, x of shape (n, 3) [m] (the solver's array: copy it to keep it) and
            ‖∇g(x)‖ over the free degrees of freedom [N·s²].
        """
        step = FusedStep(self, problem, x0, energy=True)
        grad = step.a0 - step.rhs          # ∇g over the free vertices, coordinate-major
        k = 0
        yield Iterate(k, step.x, step.norm0)
        pairs: deque[tuple[np.ndarray, np.ndarray, float]] = deque(maxlen=self.window)
        while True:
            q = grad.copy()
            alphas = []
            for s, t, rho in reversed(pairs):
                a = rho * float(np.vdot(s, q))
                alphas.append(a)
                q -= a * t
            r = step.solve_columns(q)
            for (s, t, rho), a in zip(pairs, reversed(alphas)):
                r += (a - rho * float(np.vdot(t, r))) * s
            slope = -float(np.vdot(grad, r))
            if not slope < 0.0:
                return  # no descent direction at working precision: optimal to rounding
            delta, alpha = step.delta, 1.0
            for _ in range(MAX_HALVINGS):   # backtracking Armijo (descent.armijo), fused
                if step.trial(delta - alpha * r) <= ARMIJO_C * alpha * slope:
                    break
                alpha *= 0.5
            else:
                return  # no decrease at working precision: optimal to rounding
            step.accept()
            grad_new = step.apply(step.delta)
            grad_new -= step.rhs
            s, t = -alpha * r, grad_new - grad
            st = float(np.vdot(s, t))
            if st > 0.0:
                pairs.append((s, t, 1.0 / st))
            grad = grad_new
            k += 1
            yield Iterate(k, step.x, float(np.linalg.norm(grad)))
