"""L-BFGS on g with the local/global matrix as initial Hessian (Liu, Bouaziz, Kavan 2017).

Quasi-Newton with the two-loop recursion (Nocedal and Wright Alg. 7.4) over the last m
pairs s_j = x_{j+1} − x_j, t_j = ∇g(x_{j+1}) − ∇g(x_j). The initial inverse Hessian is
H₀ = (M + h² L)⁻¹ — the global-step matrix, applied through the cached sparse Cholesky
factor of :class:`~clothsim.solvers.LocalGlobalSolver` (two triangular solves). Without any
pair the direction −H₀ ∇g(x) is exactly the local/global step; the pairs add the
curvature the fixed matrix misses. The step length comes from a backtracking Armijo line
search on the cancellation-free difference of g (:meth:`FusedStep.trial
<clothsim.solvers.fused.FusedStep.trial>`, as
:func:`~clothsim.solvers.descent.objective_difference`), so g never increases (beyond
rounding) and the search still works at residuals far below 1e-8. It runs on
local/global's fused iteration: the accepted trial's spring vectors start the local step,
and ∇g = A_FF δ − rhs with A_FF δ carried through the pairs (no product with A_FF). Pairs with
sᵀt ≤ 0 (negative curvature, buckling) are skipped, keeping the implicit inverse positive
definite.

References
----------
T. Liu, S. Bouaziz, L. Kavan. Quasi-Newton Methods for Real-Time Simulation of
Hyperelastic Materials. ACM Transactions on Graphics 36(3), 23, 2017.
J. Nocedal, S. J. Wright. Numerical Optimization, 2nd ed., Springer 2006, Alg. 7.4.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Iterator

import numpy as np

from ..errors import InputError
from ..model import Model
from .base import Iterate, StepProblem
from .descent import ARMIJO_C, MAX_HALVINGS
from .held_accel import fused_step
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
        # held contacts (.held_accel): gradients and directions projected onto the planes
        step = fused_step(self, problem, x0, energy=True)
        # held: the Armijo test measures the exact step s (limit runs go to 1e-10 there);
        # without contacts, x' − x as measured (docs/data counts)
        exact = problem.has_contacts
        shape = step.delta.shape
        a = step.a0.copy()                 # A_FF δ_F of the current iterate
        grad = step.gradient(a, np.empty(shape))   # ∇g over F, coordinate-major
        k = 0
        yield Iterate(k, step.x, step.norm0)
        hist = _Pairs(self.window, grad.size)
        # preallocated: the candidates' δ in turn (an accepted one becomes step.delta),
        # the next gradient, and the pair (s, t, A_FF s) of the step
        cands, grad_new = np.empty((2,) + shape), np.empty(shape)
        s, t, u = np.empty(shape), np.empty(shape), np.empty(shape)
        sf, tf, uf = s.reshape(-1), t.reshape(-1), u.reshape(-1)     # flat views
        while True:
            r, r_parts = hist.inverse_hessian_times(grad, step.solve_columns)
            r = step.tangential(r)   # exactly tangential: s = −α r stays in the planes
            slope = -float(np.dot(grad.reshape(-1), r.reshape(-1)))
            if not slope < 0.0:
                return  # no descent direction at working precision: optimal to rounding
            delta, alpha, cand = step.delta, 1.0, cands[k % 2]
            for _ in range(MAX_HALVINGS):   # backtracking Armijo (descent.armijo), fused
                np.multiply(r, -alpha, out=s)           # s = −α r: exact (α a power of 2)
                np.add(delta, s, out=cand)              # δ − α r
                armijo = step.trial(cand, s if exact else None) <= ARMIJO_C * alpha * slope
                if armijo if self.decisions is None else self.decisions(armijo):
                    break
                alpha *= 0.5
            else:
                return  # no decrease at working precision: optimal to rounding
            step.accept()
            # ∇g(x_{k+1}) = A_FF δ_{k+1} − rhs(x_{k+1}), A_FF δ_{k+1} = A_FF δ_k − α A_FF r
            # with A_FF r = q + Σ c_j A_FF s_j (H₀ = A_FF⁻¹; the pairs keep A_FF s_j)
            np.multiply(hist.apply_a(r_parts), -alpha, out=u)
            np.add(a, u, out=a)
            step.gradient(a, grad_new)
            np.subtract(grad_new, grad, out=t)
            st = float(np.dot(sf, tf))
            if st > 0.0:
                hist.append(sf, tf, 1.0 / st, uf, hist.t_dot_direction(r_parts) * -alpha)
            grad, grad_new = grad_new, grad
            k += 1
            g = grad.reshape(-1)
            yield Iterate(k, step.x, math.sqrt(float(np.dot(g, g))))


class _Pairs:
    """The last m pairs (s_j, t_j) with ρ_j and their products s_iᵀ t_j, for the two loops.

    The two-loop recursion (Nocedal and Wright Alg. 7.4) rewritten on the inner products
    it needs: with sᵢᵀ∇g, tᵢᵀ(H₀ q) and the kept matrix sᵢᵀtⱼ, each loop's scalars come
    from an m × m triangle, and each loop's vector update is one product with the m stored
    rows (instead of 2m dot products and 2m vector updates). Same H ∇g, to rounding.
    """

    def __init__(self, size: int, length: int):
        self.size, self.length = size, length
        # s_j and A_FF s_j side by side: one product with the coefficients gives both
        self.SU = np.zeros((size, 2 * length))
        self.S, self.U = self.SU[:, :length], self.SU[:, length:]
        self.T = np.zeros((size, length))
        self.ST = np.zeros((size, size))
        self.rho = [0.0] * size        # ρ_j, as Python floats: the loops are Python
        self.order: list[int] = []     # slots, oldest first
        self._loops = ([], [])         # per slot: the newer pairs, the older pairs
        self._q, self._v = np.empty(length), np.empty(2 * length)

    def append(self, s: np.ndarray, t: np.ndarray, rho: float, u: np.ndarray,
               ts: np.ndarray) -> None:
        """Keep the pair (s, t) with ρ = 1 / sᵀt and u = A_FF s; ``ts`` holds t_jᵀ s for
        the kept pairs (:meth:`t_dot_direction`), so only the sᵢᵀ t column is a product."""
        if len(self.order) < self.size:
            slot = len(self.order)
        else:
            slot = self.order.pop(0)
        self.order.append(slot)
        self._loops = _loops(tuple(self.order))
        self.S[slot], self.T[slot], self.U[slot] = s, t, u
        self.rho[slot] = float(rho)
        self.ST[slot, :] = ts
        self.ST[:, slot] = self.S @ t

    def inverse_hessian_times(self, gT: np.ndarray, solve) -> np.ndarray:
        """H ∇g by the two loops, H₀ applied by ``solve`` (coordinate-major, shape of gT),
        and what :meth:`apply_a` and :meth:`t_dot_direction` need."""
        order = self.order
        if not order:
            return solve(gT), (gT, None, None)
        g = gT.reshape(-1)
        sg, ST, rho = (self.S @ g).tolist(), self.ST.tolist(), self.rho
        newest_first, oldest_first = self._loops
        alpha = [0.0] * self.size
        for i, newer in newest_first:
            acc, row = sg[i], ST[i]
            for j in newer:
                acc -= alpha[j] * row[j]
            alpha[i] = rho[i] * acc
        q = np.dot(np.asarray(alpha), self.T, out=self._q)
        np.subtract(g, q, out=q)
        r = solve(q.reshape(gT.shape))
        tr_arr = self.T @ r.reshape(-1)
        tr = tr_arr.tolist()
        coef = [0.0] * self.size                        # α_j − β_j
        for i, older in oldest_first:
            acc = tr[i]
            for j in older:
                acc += coef[j] * ST[j][i]
            coef[i] = alpha[i] - rho[i] * acc
        coef = np.asarray(coef)
        su = np.dot(coef, self.SU, out=self._v)        # [Σ c_j s_j | Σ c_j A_FF s_j]
        r += su[:self.length].reshape(gT.shape)
        return r, (q.reshape(gT.shape), coef, tr_arr)

    def apply_a(self, parts) -> np.ndarray:
        """A_FF r for the r of :meth:`inverse_hessian_times`, from its ``parts``
        (q, the coefficients of the s_j): q + Σ c_j A_FF s_j, without a product with A_FF."""
        q, coef, _ = parts
        if coef is None:
            return q
        out = self._v[self.length:].reshape(q.shape)   # Σ c_j A_FF s_j, kept by the two loops
        return np.add(q, out, out=out)

    def t_dot_direction(self, parts) -> np.ndarray:
        """t_jᵀ r for every slot, r from :meth:`inverse_hessian_times`: t_jᵀ H₀ q + Σ_i c_i
        s_iᵀ t_j from the kept products (no pass over the vectors)."""
        _, coef, tr = parts
        if coef is None:
            return np.zeros(self.size)
        return tr + coef @ self.ST


@functools.lru_cache(maxsize=1024)
def _loops(order: tuple) -> tuple:
    """Per kept slot (oldest first in ``order``), the slots the two loops read: newest first
    with the newer pairs, oldest first with the older ones. A window of m pairs meets at
    most 2m orders (filling, then rotating), so they are built once and cached."""
    newest_first = tuple((i, order[len(order) - n:]) for n, i in enumerate(reversed(order)))
    oldest_first = tuple((i, order[:n]) for n, i in enumerate(order))
    return newest_first, oldest_first
