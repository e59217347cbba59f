"""Newton's method with backtracking line search on g(x): the exact reference.

Each iteration solves (M + h² ∇²E(x_k)) Δ = −∇g(x_k) over the free degrees of freedom (3n
form, interleaved) and takes x_{k+1} = x_k + α Δ with the largest α ∈ {1, ½, ¼, …} that
satisfies Armijo's condition g(x + αΔ) − g(x) ≤ c α ∇gᵀΔ, c = 1e-4, the difference
computed without cancellation (:func:`~clothsim.solvers.descent.objective_difference`), so
the line search still works at residuals of 1e-12.

Indefinite Hessians (compressed springs, buckling) are handled by ``indefinite``:

``"shift"`` (default)
    When the Cholesky factorization of the exact Hessian fails, the exact Newton step is
    still taken (sparse LU) if it is a descent direction: on a symmetric cloth whose
    buckling directions the gradient does not excite (a planar curtain), the exact Hessian
    is indefinite only across the plane and this keeps Newton quadratic (the shift below
    would damp every direction and converge linearly: 70+ iterations to 1e-6). Otherwise,
    Levenberg–Marquardt: factor H + τ M with the smallest τ ∈ {τ₀, 10 τ₀, …} that
    succeeds (τ₀ starts at 1e-6 and follows the last successful shift; Nocedal and
    Wright Alg. 3.3 with M as metric). This stays as close to the exact Hessian as
    definiteness allows, so the iteration becomes quadratic as soon as it enters the
    region where g is convex.
``"project"``
    Each spring's Hessian block is projected onto the positive semidefinite cone (its
    transverse factor 1 − r/l clamped at 0, :func:`clothsim.energy.spring_hessian`) —
    only when the exact Hessian is indefinite. On buckling steps whose minimum has
    compressed springs this throws away true curvature and converges linearly; kept for
    comparison.

Iterations stop under the base stop rule; the iterate generator returns when no step
length decreases g or the step no longer changes x in floating point (the gradient is at
its rounding floor): such a step counts as converged. Converged, it gives the implicit
Euler step x_{n+1} that local/global iterations approach (Liu et al. 2013, Section 5).

References
----------
J. Nocedal, S. J. Wright. Numerical Optimization, 2nd ed., Springer 2006, Alg. 3.1, 3.3.
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import scipy.sparse as sp

from .. import energy
from ..errors import FactorizationError, InputError
from ..factorization import Factor
from ..model import Model
from .base import Iterate, Solver, StepProblem, objective_gradient
from .descent import ARMIJO_C, MAX_HALVINGS, armijo  # noqa: F401  (re-exported constants)

INDEFINITE = ("shift", "project")


class _Solved:
    """A sparse LU in the :class:`Factor` interface used here (``solve``)."""

    def __init__(self, lu):
        self.lu = lu
        self.backend = "splu"

    def solve(self, b: np.ndarray) -> np.ndarray:
        return self.lu.solve(b)


class NewtonSolver(Solver):
    """Newton's method with line search on the implicit Euler objective g.

    Each iteration solves (M + h² ∇²E(x_k)) Δ = −∇g(x_k) over the free degrees of freedom
    and takes x_{k+1} = x_k + α Δ, α the largest of 1, ½, ¼, … with Armijo's decrease.

    Parameters
    ----------
    model : Model
        The cloth (masses [kg], springs [N/m, m]).
    iterations : int, default 50
        Maximum Newton iterations per step.
    tolerance : float, optional, default 1e-12
        Stop once ‖∇g(x_k)‖ / ‖∇g(x_0)‖ is at most this.
    backend : {"auto", "cholmod", "splu"}
        Factorization of each Newton system (refactored every iteration).
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
        Factorizations done (one per iteration, more when shifts are tried).
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
        self._M3 = np.repeat(model.vertex_mass, 3)
        self._shift = 1e-6

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

    def _factor(self, H: sp.spmatrix) -> Factor:
        self.factor_count += 1
        factor = Factor(H, backend=self.backend_requested, check_conditioning=False)
        self.backend = factor.backend
        return factor

    def _exact_descends(self, H: sp.spmatrix, grad: np.ndarray) -> bool:
        """Solve with the exact indefinite H (sparse LU); True if −H⁻¹∇g is a descent
        direction (then it is kept in ``self._exact`` for :meth:`newton_factor`)."""
        from scipy.sparse.linalg import splu

        try:
            lu = splu(sp.csc_matrix(H))
        except RuntimeError:  # exactly singular
            return False
        self.factor_count += 1
        step = lu.solve(grad)
        if not (np.all(np.isfinite(step)) and float(grad @ step) > 0.0):
            return False
        self._exact = _Solved(lu)
        return True

    def newton_factor(self, problem: StepProblem, x: np.ndarray, free: np.ndarray,
                      grad: np.ndarray | None = None) -> Factor:
        """Factor of the (possibly modified) Hessian over the free degrees of freedom.

        ``grad`` (free entries of ∇g) lets an indefinite exact Hessian be used when its
        Newton step still descends (a saddle in symmetric directions the gradient does not
        excite: keeps quadratic convergence there). Otherwise, per ``indefinite``, the
        Levenberg–Marquardt shift H + τ M or the projected Hessian is factored.

        Parameters
        ----------
        problem : StepProblem
            The step's h [s] and pins.
        x : ndarray, shape (n, 3)
            The current iterate [m].
        free : ndarray of bool, shape (3n,)
            Mask (or indices) of the free degrees of freedom in the interleaved 3n layout;
            3f of them.
        grad : ndarray, shape (3f,), optional
            ∇g(x) over those degrees of freedom [N·s²].

        Returns
        -------
        Factor
            An object whose ``solve(b)`` applies the inverse of the (modified) Hessian over
            the free degrees of freedom, shape (3f, 3f) [kg].
        """
        H = self.hessian(problem, x)[free][:, free]
        try:
            factor = self._factor(H)
            self._shift = max(self._shift / 10.0, 1e-6)
            return factor
        except FactorizationError:
            pass
        if (self.indefinite == "shift" and grad is not None
                and self._exact_descends(H, grad)):
            return self._exact
        if self.indefinite == "project":
            return self._factor(self.hessian(problem, x, definite=True)[free][:, free])
        M = sp.diags(self._M3[free])
        tau = self._shift
        while True:
            try:
                factor = self._factor((H + tau * M).tocsc())
                self._shift = tau
                return factor
            except FactorizationError:
                tau *= 10.0
                if tau > 1e12:  # cannot happen for finite H; fall back to the projection
                    return self._factor(self.hessian(problem, x, definite=True)[free][:, free])

    def iterates(self, problem: StepProblem, x0: np.ndarray | None = None) -> Iterator[Iterate]:
        """Yield the initial guess, then each Newton iterate.

        Returns (sets :attr:`stalled`) when no step length decreases g or the step no longer
        changes x in floating point: x is then optimal to rounding.

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
        self._shift = 1e-6
        grad = objective_gradient(self.model, problem, x)
        k = 0
        yield Iterate(k, x, float(np.linalg.norm(grad)))
        while True:
            factor = self.newton_factor(problem, x, free, grad.ravel()[free])
            step = np.zeros(3 * n)
            step[free] = -factor.solve(grad.ravel()[free])
            step = step.reshape(n, 3)
            found = armijo(self.model, problem, x, step, float(np.sum(grad * step)))
            if found is None:  # no decrease at working precision: optimal to rounding
                self.stalled = True
                return
            alpha = found[0]
            moved = float(np.abs(alpha * step).max())
            x = x + alpha * step
            grad = objective_gradient(self.model, problem, x)
            k += 1
            yield Iterate(k, x, float(np.linalg.norm(grad)))
            if moved <= 4 * np.finfo(float).eps * max(float(np.abs(x).max()), 1e-300):
                self.stalled = True  # x no longer changes: the gradient is at rounding level
                return

    def _finish(self, x, iterations, history, *, at_floor: bool = False):
        # a stalled Newton step is optimal to rounding: converged, no warning
        return super()._finish(x, iterations, history, at_floor=at_floor or self.stalled)
