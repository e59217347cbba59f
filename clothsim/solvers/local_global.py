"""The paper's solver: block coordinate descent on ĝ(x, d) (Liu et al. 2013, Section 4).

Each iteration is

1. local step (x fixed): d_i = r_i p_i / |p_i|, p_i = x_{a_i} − x_{b_i}   — :meth:`local_step`
2. global step (d fixed): (M + h² L) x = h² J d + M y + h² f             — :meth:`global_step`

The matrix M + h² L depends only on masses, stiffnesses, topology, h and the pins, so it is
factored once (sparse Cholesky) and cached: every iteration is then two triangular solves.
Because M = M_s ⊗ I3 and L = L_s ⊗ I3, the solver factors the n × n matrix
M_s + h² L_s and solves for the three coordinate columns at once.

With exact pins the fixed vertices P are removed: the free vertices F solve
A_FF x_F = b_F − A_FP x_P. The solve is done for the displacement δ = x − y (same x,
translation invariant to rounding; see :meth:`LocalGlobalSolver.global_step`). Penalty pins
add their stiffness k to L_s's diagonal and h² k q to the right-hand side.

References
----------
T. Liu, A. W. Bargteil, J. F. O'Brien, L. Kavan. Fast Simulation of Mass-Spring Systems.
ACM Transactions on Graphics 32(6), 214, 2013. DOI 10.1145/2508363.2508406.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .. import matrices
from ..factorization import Factor
from ..model import Model
from .base import Iterate, Solver, StepProblem

log = logging.getLogger(__name__)


@dataclass(eq=False)
class SystemFactor:
    """The cached factorization for one pin configuration and time step.

    Attributes
    ----------
    A : csc_matrix, shape (n, n)
        M_s + h² (L_s + K_anchor) over all vertices.
    free : ndarray, shape (f,), int
        Free vertices (the unknowns).
    fixed : ndarray, shape (p,), int
        Exactly pinned vertices.
    A_FF_factor : Factor
        Factorization of A restricted to free rows and columns.
    A_FP : csr_matrix, shape (f, p)
        Coupling of free to fixed vertices (moves fixed positions to the right-hand side).
    """

    A: sp.csc_matrix
    free: np.ndarray
    fixed: np.ndarray
    A_FF_factor: Factor
    A_FP: sp.csr_matrix


class LocalGlobalSolver(Solver):
    """Local/global iterations with a cached sparse Cholesky factor of M + h² L.

    Parameters
    ----------
    model : Model
    iterations : int, default 10
        Iterations per step (the paper's default); the maximum when ``tolerance`` is set.
    tolerance : float, optional
        Stop a step once the relative residual ‖∇g(x_k)‖/‖∇g(x_0)‖ is at most this.
    backend : {"auto", "cholmod", "splu"}
    check_conditioning : bool, default True
        Warn (:class:`~clothsim.errors.ConditioningWarning`) when a new factor's condition
        estimate passes 1e12.

    Attributes
    ----------
    factor_count : int
        How many times the system matrix was factored (refactoring happens only when h,
        the exact-pin set or the penalty pins change, or after :meth:`invalidate`).
    backend : str or None
        The factorization backend that ran last.
    """

    name = "local-global"

    def __init__(self, model: Model, *, iterations: int = 10, tolerance: float | None = None,
                 backend: str = "auto", check_conditioning: bool = True):
        super().__init__(model, iterations=iterations, tolerance=tolerance, backend=backend)
        self.check_conditioning = check_conditioning
        self.factor_count = 0
        self.backend: str | None = None
        self._cache_key = None
        self._cache: SystemFactor | None = None
        self._Ms = model.vertex_mass
        self._Js = matrices.spring_matrix(model, expand=False)
        self._rest = model.springs.spring_rest_length
        self._a, self._b = model.springs.spring_vertices.T
        # previous directions, kept where a spring's ends coincide (any |d| = r is optimal)
        rest_dir = model.mesh.vertices[self._a] - model.mesh.vertices[self._b]
        self._d = self._directions(rest_dir, np.zeros_like(rest_dir))

    # -- precomputation -------------------------------------------------------------------
    def invalidate(self) -> None:
        self._cache_key = None
        self._cache = None

    def system(self, problem: StepProblem) -> SystemFactor:
        """The factor for this problem's h and pins: cached, rebuilt only when they change."""
        key = (problem.h, problem.fixed_vertices.tobytes(), problem.anchor_vertices.tobytes(),
               problem.anchor_stiffness.tobytes())
        if key != self._cache_key:
            self._cache = self._factor(problem)
            self._cache_key = key
        return self._cache

    def _factor(self, problem: StepProblem) -> SystemFactor:
        n = self.model.vertex_count
        A = matrices.system_matrix(self.model, problem.h, anchor_vertices=problem.anchor_vertices,
                                   anchor_stiffness=problem.anchor_stiffness)
        fixed = np.unique(problem.fixed_vertices)
        free = np.flatnonzero(problem.free_mask(n))
        A_csr = A.tocsr()
        A_FF = A_csr[free][:, free]
        A_FP = A_csr[free][:, fixed]
        factor = Factor(A_FF, backend=self.backend_requested,
                        check_conditioning=self.check_conditioning)
        self.factor_count += 1
        self.backend = factor.backend
        log.info("factored M + h^2 L: %d free of %d vertices, h=%g, backend=%s",
                 len(free), n, problem.h, factor.backend)
        return SystemFactor(A, free, fixed, factor, A_FP.tocsr())

    # -- the two half steps ---------------------------------------------------------------
    def _directions(self, p: np.ndarray, d_prev: np.ndarray) -> np.ndarray:
        length = np.linalg.norm(p, axis=1)
        ok = length > 0
        d = d_prev.copy()
        d[ok] = (self._rest[ok] / length[ok])[:, None] * p[ok]
        return d

    def local_step(self, x: np.ndarray) -> np.ndarray:
        """d_i = r_i (x_a − x_b) / |x_a − x_b| for all springs at once, shape (s, 3).

        Where a spring's two ends coincide, any d with |d| = r is optimal: the previous
        direction is kept (never a division by zero).
        """
        self._d = self._directions(x[self._a] - x[self._b], self._d)
        return self._d

    def right_hand_side(self, problem: StepProblem, d: np.ndarray) -> np.ndarray:
        """b = h² J d + M y + h² f + h² K_anchor q, shape (n, 3)."""
        h2 = problem.h ** 2
        b = self._Ms[:, None] * problem.y + h2 * (self._Js @ d)
        if problem.f_ext is not None:
            b += h2 * problem.f_ext
        problem.anchors.add_rhs(b, h2)
        return b

    def displacement_right_hand_side(self, problem: StepProblem, d: np.ndarray) -> np.ndarray:
        """b(d) − A y = h² J (d − p(y)) + h² f + h² K_anchor (q − y), shape (n, 3).

        Uses L y = J p(y), p(y)_i = y_{a_i} − y_{b_i}: only differences of positions enter,
        so the result does not depend on where the cloth is (no cancellation of large
        coordinates, unlike forming b and A y separately).
        """
        h2 = problem.h ** 2
        y = problem.y
        b = h2 * (self._Js @ (d - (y[self._a] - y[self._b])))
        if problem.f_ext is not None:
            b += h2 * problem.f_ext
        problem.anchors.add_rhs(b, h2, origin=y)
        return b

    def global_step(self, problem: StepProblem, d: np.ndarray) -> np.ndarray:
        """Solve (M + h² L) x = b(d) for the free vertices; fixed ones at their targets.

        Solved for the displacement δ = x − y: A_FF δ_F = (b − A y)_F − A_FP δ_P, then
        x = y + δ. Same x as solving for x directly, but translation invariant to rounding
        (a cloth 1 km from the origin moves like one at the origin).
        """
        sysf = self.system(problem)
        rhs_all = self.displacement_right_hand_side(problem, d)
        y = problem.y
        x = np.array(y, dtype=np.float64)
        x[problem.fixed_vertices] = problem.fixed_positions
        rhs = rhs_all[sysf.free]
        if len(sysf.fixed):
            rhs -= sysf.A_FP @ (x[sysf.fixed] - y[sysf.fixed])
        x[sysf.free] = y[sysf.free] + sysf.A_FF_factor.solve(rhs)
        return x

    def gradient(self, problem: StepProblem, x: np.ndarray, d: np.ndarray) -> np.ndarray:
        """∇g(x) over the free vertices, (A x − b(d))_F, valid when d = d(x).

        Evaluated as M (x − y) + h² J (p(x) − d) − h² f + h² K_anchor (x − q) (L x = J p(x)),
        from differences of positions only, so its rounding floor does not grow with the
        distance of the cloth from the origin.
        """
        sysf = self.system(problem)
        h2 = problem.h ** 2
        grad = (self._Ms[:, None] * (x - problem.y)
                + h2 * (self._Js @ ((x[self._a] - x[self._b]) - d)))
        if problem.f_ext is not None:
            grad -= h2 * problem.f_ext
        problem.anchors.add_gradient(grad, x, h2)
        return grad[sysf.free]

    # -- the iteration --------------------------------------------------------------------
    def iterates(self, problem: StepProblem, x0: np.ndarray | None = None):
        """Local/global iterates from ``x0`` (default: y, pins applied).

        Each iterate's gradient norm is ‖∇g(x_k)‖ with d = d(x_k) from the local step; the
        global step then gives x_{k+1}.
        """
        self.system(problem)
        x = problem.initial_guess() if x0 is None else np.array(x0, dtype=np.float64)
        k = 0
        while True:
            d = self.local_step(x)
            yield Iterate(k, x, float(np.linalg.norm(self.gradient(problem, x, d))))
            x = self.global_step(problem, d)
            k += 1
