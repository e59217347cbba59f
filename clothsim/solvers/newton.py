"""Newton's method with a saddle-free step and a line search on g(x): the exact reference.

Each iteration solves (H + τM) Δ = −∇g(x_k) over the free degrees of freedom (3n form,
interleaved), H = M + h² ∇²E(x_k), and takes x_{k+1} = x_k + α Δ with the largest
α ∈ {1, ½, ¼, …} that satisfies Armijo's condition g(x + αΔ) − g(x) ≤ c α ∇gᵀΔ, c = 1e-4,
the difference computed without cancellation
(:func:`~clothsim.solvers.descent.objective_difference`), so the line search still works
at residuals of 1e-12.

Indefinite Hessians (compressed springs, buckling) are handled by ``indefinite``:

``"shift"`` (default)
    τ = 0 (the exact Newton step) when the Cholesky factorization of H succeeds; otherwise
    the smallest τ ∈ {τ₀, 4 τ₀, 16 τ₀, …} for which H + τM factors, τ₀ the last working
    shift, divided by 4 after each full (α = 1) shifted step and by 10 after an exact one
    (Levenberg–Marquardt; Nocedal and Wright Alg. 3.3 with M as metric).
    Every step is therefore a descent direction of a positive definite model, and no
    indefinite matrix is ever factored by an LU. Near a stationary point where H is still
    indefinite (a saddle: a flat strip under compression, a symmetric crumple) the
    iteration does not stop: it moves along a direction of negative curvature v
    (:func:`~clothsim.solvers.curvature.negative_curvature`), with the line search
    g(x + αv) − g(x) ≤ c (α ∇gᵀv + ½ α² vᵀHv), and continues to a minimum.
``"project"``
    Each spring's Hessian block is projected onto the positive semidefinite cone (its
    transverse factor 1 − r/l clamped at 0, :func:`clothsim.energy.spring_hessian`) —
    only when the exact Hessian is indefinite. It converges linearly on steps whose
    minimum has compressed springs; kept for comparison.

All factorizations of one solver share one CHOLMOD symbolic analysis while the sparsity
pattern of the free Hessian is unchanged (:class:`~clothsim.solvers.curvature.ReusedCholesky`).

Iterations stop under the base stop rule; the iterate generator returns when no step
length decreases g or the step no longer changes x in floating point. The result is
*certified* (:attr:`NewtonResult.certified`) when ‖∇g‖ is at its rounding floor (or x can
no longer be improved) and the free Hessian at x factors without shift (λ_min > 0): x is
then a strict local minimum of g, the implicit Euler step x_{n+1} that local/global
iterations approach (Liu et al. 2013, Section 5).

References
----------
J. Nocedal, S. J. Wright. Numerical Optimization, 2nd ed., Springer 2006, Alg. 3.1, 3.3;
Section 6.3 (negative curvature).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .. import energy
from ..errors import FactorizationError, InputError
from ..model import Model
from .base import Iterate, Solver, StepProblem, StepResult, gradient_noise_floor, objective_gradient
from .curvature import ReusedCholesky, negative_curvature, smallest_eigenvalue
from .descent import ARMIJO_C, MAX_HALVINGS, armijo, objective_difference  # noqa: F401
from .held import constrained_matrix
from .hessian import FreeHessian

INDEFINITE = ("shift", "project")
SHIFT_MIN = 1e-8
SHIFT_MAX = 1e12
ESCAPE_RATE = 0.5
"""At an indefinite H, negative curvature is tried when ‖∇g‖ fell by less than this factor
over the last iteration (the shifted steps crawl, e.g. towards a saddle), when the shifted
step finds no decrease, or when the gradient already meets the stop rule."""


@dataclass
class NewtonResult(StepResult):
    """A :class:`~clothsim.solvers.base.StepResult` with Newton's certificate.

    Attributes
    ----------
    positive_definite : bool
        The free Hessian ∇²g(x) factors without shift (λ_min > 0).
    at_floor : bool
        ‖∇g(x)‖ is at its rounding floor, or no step length improves x.
    certified : bool
        Both: x is a strict local minimum of g to rounding.
    """

    positive_definite: bool = False
    at_floor: bool = False
    certified: bool = False


class NewtonSolver(Solver):
    """Newton's method with a saddle-free step and line search on the objective g.

    Each iteration solves (H + τM) Δ = −∇g(x_k) over the free degrees of freedom with the
    smallest tried τ ≥ 0 that makes the matrix positive definite, and takes
    x_{k+1} = x_k + α Δ, α the largest of 1, ½, ¼, … with Armijo's decrease; at a saddle
    it follows negative curvature (see the module text).

    Parameters
    ----------
    model : Model
        The cloth (masses [kg], springs [N/m, m]).
    iterations : int, default 50
        Maximum Newton iterations per step.
    tolerance : float, optional, default 1e-12
        Stop once ‖∇g(x_k)‖ / ‖∇g(x_0)‖ is at most this (at a point where H ≻ 0).
    backend : {"auto", "cholmod", "splu"}
        Factorization of each Newton system (one CHOLMOD analysis, refactored in place).
    indefinite : {"shift", "project"}
        What to do when the exact Hessian is not positive definite (see the module text).

    Attributes
    ----------
    indefinite : str
        As given.
    backend : str or None
        The factorization backend that ran last.
    stalled : bool
        The last step ended because x could not be improved in floating point.
    factor_count : int
        Numeric factorizations done (failed shifts included).
    escapes : int
        Steps along negative curvature taken (saddles left).
    """

    name = "newton"

    def __init__(self, model: Model, *, iterations: int = 50, tolerance: float | None = 1e-12,
                 backend: str = "auto", indefinite: str = "shift"):
        super().__init__(model, iterations=iterations, tolerance=tolerance, backend=backend)
        if indefinite not in INDEFINITE:
            raise InputError(f"solver.indefinite: must be one of {', '.join(INDEFINITE)}, "
                             f"got {indefinite!r}")
        self.indefinite = indefinite
        self.backend: str | None = None
        self.stalled = False
        self.factor_count = 0
        self.escapes = 0
        self._M3 = np.repeat(model.vertex_mass, 3)
        self._shift = SHIFT_MIN
        self._cholesky: ReusedCholesky | None = None
        self._assembler = FreeHessian(model)
        self._definite_at_last = False
        self._curvature_start: np.ndarray | None = None

    def invalidate(self) -> None:
        """Forget the symbolic analysis and the masses (call after changing the model)."""
        self._cholesky = None
        self._assembler = FreeHessian(self.model)
        self._M3 = np.repeat(self.model.vertex_mass, 3)

    def hessian(self, problem: StepProblem, x: np.ndarray, *,
                definite: bool = False) -> sp.csr_matrix:
        """∇²g(x) = M + h² (∇²E_springs(x) + K_anchor), shape (3n, 3n).

        Parameters
        ----------
        problem : StepProblem
            The step's h [s] and penalty pins (K_anchor [N/m]).
        x : ndarray, shape (n, 3)
            Where to evaluate [m].
        definite : bool, default False
            Project each spring's block onto the positive semidefinite cone (transverse
            factor 1 − r/l clamped at 0).

        Returns
        -------
        csr_matrix, shape (3n, 3n)
            ∇²g(x) in the interleaved layout [kg] (= N·s²/m).
        """
        n = self.model.vertex_count
        H = (problem.h ** 2) * energy.spring_hessian(self.model, x, definite=definite)
        diag = self._M3.copy()
        if len(problem.anchor_vertices):
            idx = (3 * problem.anchor_vertices[:, None] + np.arange(3)).ravel()
            np.add.at(diag, idx, problem.h ** 2 * np.repeat(problem.anchor_stiffness, 3))
        return (H + sp.diags(diag, shape=(3 * n, 3 * n))).tocsr()

    def _factor(self, H: sp.spmatrix):
        if self._cholesky is None:
            self._cholesky = ReusedCholesky(self.backend_requested)
        self.factor_count += 1
        factor = self._cholesky.factor(H)
        self.backend = self._cholesky.backend
        return factor

    def _shifted(self, H: sp.csc_matrix, free: np.ndarray):
        """(factor of H + τM, τ) with the smallest tried τ > 0 that is positive definite:
        τ starts at the last working shift (lowered after full Newton steps) and grows 4×."""
        mass = self._M3[free]
        diag = self._assembler.diagonal
        tau = max(self._shift, SHIFT_MIN)
        while tau <= SHIFT_MAX:
            A = H.copy()
            A.data[diag] += tau * mass
            try:
                factor = self._factor(A)
            except FactorizationError:
                tau *= 4.0
                continue
            self._shift = tau
            return factor, tau
        raise FactorizationError("Hessian: no shift up to 1e12 M makes it positive definite")

    def newton_factor(self, problem: StepProblem, x: np.ndarray, free: np.ndarray,
                      grad: np.ndarray | None = None):
        """Factor of the (possibly shifted) Hessian over the free degrees of freedom.

        Parameters
        ----------
        problem : StepProblem
            The step's h [s] and pins.
        x : ndarray, shape (n, 3)
            The current iterate [m].
        free : ndarray of bool, shape (3n,)
            Mask of the free degrees of freedom in the interleaved 3n layout; 3f of them.
        grad : ndarray, shape (3f,), optional
            Unused; kept for callers of the earlier interface.

        Returns
        -------
        object with ``solve(b)``
            Applies the inverse of H + τM (τ = 0 when H ≻ 0; ``indefinite="project"``: of
            the projected Hessian) over the free degrees of freedom, shape (3f, 3f) [kg].
            Valid until the next factorization of this solver.
        """
        return self._prepare(problem, x, free)[0]

    def _prepare(self, problem, x, free, *, try_exact: bool = True):
        """(factor, τ, H): τ = 0 and ``factor`` of H itself when H ≻ 0. With ``try_exact``
        False (far from a stationary point, right after an indefinite H) the unshifted
        factorization, which would almost surely fail, is not attempted."""
        H = self._held(problem, self._assembler.matrix(problem, x, free), free)
        if try_exact:
            try:
                factor = self._factor(H)
                self._shift = max(self._shift / 10.0, SHIFT_MIN)
                return factor, 0.0, H
            except FactorizationError:
                pass
        if self.indefinite == "project":
            P = self._held(problem, self._assembler.matrix(problem, x, free, definite=True),
                           free)
            return self._factor(P), math.inf, H
        factor, tau = self._shifted(H, free)
        return factor, tau, H

    @staticmethod
    def _held(problem, H, free):
        """H, or with held contacts P H P + α D over the free degrees of freedom
        (:func:`clothsim.solvers.held.constrained_matrix`): the Newton step then stays on
        the contact planes."""
        return constrained_matrix(problem, H, free) if problem.has_contacts else H

    def _escape(self, problem, x, grad, H, factor, free):
        """(x + αv, g(x + αv) − g(x)) along negative curvature v of H, or None."""
        found = None
        if self.indefinite == "shift":
            start = self._curvature_start
            found = negative_curvature(H, self._M3[free], factor,
                                       start=start if start is not None
                                       and len(start) == H.shape[0] else None)
        if found is None:
            return None
        v_free, lam = found
        self._curvature_start = v_free
        g_free = grad.ravel()[free]
        if float(g_free @ v_free) > 0.0:
            v_free = -v_free
        n = self.model.vertex_count
        v = np.zeros(3 * n)
        v[free] = v_free
        v = v.reshape(n, 3)
        rest = self.model.springs.spring_rest_length
        length = float(np.median(rest)) if len(rest) else 1.0
        v *= length / float(np.abs(v).max())
        slope = float(np.sum(grad * v))
        curvature = float(v.ravel()[free] @ (H @ v.ravel()[free]))
        alpha = 1.0
        for _ in range(MAX_HALVINGS):
            dg = objective_difference(self.model, problem, x, alpha * v)
            if dg < 0.0 and dg <= ARMIJO_C * (alpha * slope + 0.5 * alpha ** 2 * curvature):
                return x + alpha * v, dg
            alpha *= 0.5
        return None

    def iterates(self, problem: StepProblem, x0: np.ndarray | None = None) -> Iterator[Iterate]:
        """Yield the initial guess, then each Newton iterate.

        An iterate whose gradient already meets the stop rule (the tolerance or the
        rounding floor) but whose Hessian is indefinite is not yielded: the iteration first
        leaves the saddle along negative curvature. Returns (sets :attr:`stalled`) when no
        step length decreases g or the step no longer changes x in floating point.

        Parameters
        ----------
        problem : StepProblem
            The step's h [s], y [m], f_ext [N] and pins.
        x0 : ndarray, shape (n, 3), optional
            Initial guess [m]; default y with the pins applied.

        Yields
        ------
        Iterate
            k, x of shape (n, 3) [m] and ‖∇g(x)‖ over the free degrees of freedom [N·s²].
        """
        n = self.model.vertex_count
        x = problem.initial_guess() if x0 is None else np.array(x0, dtype=np.float64)
        free = np.repeat(problem.free_mask(n), 3)
        self.stalled = False
        self._shift = SHIFT_MIN
        self._curvature_start = None
        grad = objective_gradient(self.model, problem, x)
        norm0 = float(np.linalg.norm(grad))
        small = gradient_noise_floor(self.model, problem, x)
        if self.tolerance is not None:
            small = max(small, self.tolerance * norm0)
        factor, tau, H = self._prepare(problem, x, free)
        self._definite_at_last = tau == 0.0
        k = hidden = 0
        previous = math.inf
        yield Iterate(k, x, norm0)
        while True:
            norm = float(np.linalg.norm(grad))
            x_new, dg = None, 0.0
            if not (tau > 0.0 and norm <= small):
                step = np.zeros(3 * n)
                step[free] = -factor.solve(grad.ravel()[free])
                step = step.reshape(n, 3)
                found = armijo(self.model, problem, x, step, float(np.sum(grad * step)))
                if found is not None:
                    x_new, dg = x + found[0] * step, found[1]
                    if tau > 0.0 and found[0] == 1.0:  # the shifted model was trusted
                        self._shift = max(self._shift / 4.0, SHIFT_MIN)
            if tau > 0.0 and (x_new is None or norm <= small or norm > ESCAPE_RATE * previous):
                # H indefinite and the shifted steps stall: negative curvature may descend
                escape = self._escape(problem, x, grad, H, factor, free)
                if escape is not None and escape[1] < dg:
                    x_new = escape[0]
                    self.escapes += 1
            if x_new is None:  # no decrease at working precision
                self.stalled = True
                return
            moved = float(np.abs(x_new - x).max())
            x = x_new
            grad = objective_gradient(self.model, problem, x)
            previous, norm = norm, float(np.linalg.norm(grad))
            factor, tau, H = self._prepare(
                problem, x, free, try_exact=tau == 0.0 or norm <= max(small, 1e-3 * norm0))
            self._definite_at_last = tau == 0.0
            if tau > 0.0 and norm <= small and hidden < self.iterations:
                hidden += 1
                continue  # not yielded: a consumer would stop at this saddle
            k += 1
            yield Iterate(k, x, norm)
            if moved <= 4 * np.finfo(float).eps * max(float(np.abs(x).max()), 1e-300):
                self.stalled = True  # x no longer changes: the gradient is at rounding level
                return

    def smallest_eigenvalue(self, problem: StepProblem, x: np.ndarray) -> float:
        """λ_min of ∇²g(x) v = λ M v over the free degrees of freedom (1 for M alone).

        Parameters
        ----------
        problem : StepProblem
            The step (h, pins).
        x : ndarray, shape (n, 3)
            Where to evaluate [m].

        Returns
        -------
        float
            λ_min, dimensionless; > 0 certifies a strict local minimum at a stationary x.
            NaN without free degrees of freedom or when Lanczos does not converge.
        """
        free = np.repeat(problem.free_mask(self.model.vertex_count), 3)
        return smallest_eigenvalue(self.hessian(problem, x)[free][:, free], self._M3[free])

    def _finish(self, x, iterations, history, *, at_floor: bool = False):
        # a stalled Newton step is optimal to rounding: converged, no warning
        at_floor = bool(at_floor or self.stalled)
        res = super()._finish(x, iterations, history, at_floor=at_floor)
        definite = bool(self._definite_at_last)
        return NewtonResult(res.x, res.iterations, res.residual, res.residual_history,
                            res.converged, positive_definite=definite, at_floor=at_floor,
                            certified=definite and at_floor)
