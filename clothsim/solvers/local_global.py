"""The paper's solver: block coordinate descent on ĝ(x, d) (Liu et al. 2013, Section 4).

Each iteration is

1. local step (x fixed): d_i = r_i p_i / |p_i|, p_i = x_{a_i} − x_{b_i}   — :meth:`local_step`
2. global step (d fixed): (M + h² L) x = h² J d + M y + h² f             — :meth:`global_step`

M + h² L depends only on masses, stiffnesses, topology, h and the pins: its n × n scalar
form M_s + h² L_s is factored once and cached (:mod:`clothsim.solvers.system`), and each
global step solves for the three coordinate columns at once (M = M_s ⊗ I3, L = L_s ⊗ I3).

With exact pins the fixed vertices P are removed: the free vertices F solve
A_FF x_F = b_F − A_FP x_P. The solve is done for the displacement δ = x − y (same x,
translation invariant to rounding; see :meth:`LocalGlobalSolver.global_step`). Penalty pins
add their stiffness k to L_s's diagonal and h² k q to the right-hand side.

:meth:`LocalGlobalSolver.local_step`, :meth:`~LocalGlobalSolver.global_step` and
:meth:`~LocalGlobalSolver.gradient` are the half steps written plainly; the iteration
(:meth:`LocalGlobalSolver.iterates`) runs the same two half steps on preallocated,
coordinate-major buffers (docs/performance.md): per-step constants (p(y), forces, pins) are
computed once per step, the residual comes for free (after a global step
∇g(x_{k+1})_F = rhs(d_k)_F − rhs(d_{k+1})_F), and d − p(y) is formed before J is applied
(no cancellation: momentum is conserved to rounding). The result equals the plain half
steps and the dense iteration of :mod:`clothsim.reference` to rounding (tested). The
fused iteration is :class:`~clothsim.solvers.fused.FusedStep`, which Chebyshev, Anderson
and L-BFGS run on too.

References
----------
T. Liu, A. W. Bargteil, J. F. O'Brien, L. Kavan. Fast Simulation of Mass-Spring Systems.
ACM Transactions on Graphics 32(6), 214, 2013. DOI 10.1145/2508363.2508406.
"""

from __future__ import annotations

import logging

import numpy as np

from .. import matrices
from ..factor_mode import ModeChoice, choose_cholmod_mode, switched_reason
from ..factorization import single_threaded
from ..model import Model
from .base import Iterate, Solver, StepProblem, StepResult
from .directions import SpringDirections
from .held import held_key
from .held_accel import fused_step
from .system import SystemFactor, factor_system, system_key

log = logging.getLogger(__name__)


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
    cholmod_mode : {"auto", "simplicial", "supernodal"}
        CHOLMOD's mode for the next factorization (``[solver] cholmod_mode``); "auto"
        chooses by predicted cost (:func:`clothsim.factor_mode.choose_cholmod_mode`).
    expected_solves : int or None
        Solves the next factorization is expected to serve, for "auto" (set by
        :meth:`clothsim.Simulation.expect_steps`); None: unknown.
    expected_final : bool
        True when ``expected_solves`` is the whole run's count (``clothsim run``); False
        when it is a lower bound or unknown: then the ski-rental rule decides, and a factor
        in the mode cheaper to factor is refactored in the mode with the faster solves once
        it has served its switch point (:class:`~clothsim.factor_mode.ModeChoice`).
    solve_count : int
        Solves served by this solver's factors (one per iteration of :meth:`solve`).
    factorization : str or None
        The mode of the last factorization and why, e.g. "supernodal: 16639 free vertices,
        the run's count is unknown, at least 30: cheaper to factor (…); simplicial after …
        solves, …".
    analysis_count : int
        CHOLMOD symbolic analyses done: a refactorization with the same free vertices (h or
        the penalty pins changed) reuses the last one.
    """

    name = "local-global"
    cholmod_mode = "auto"
    expected_solves: int | None = None
    expected_final = False
    factorization: str | None = None
    analysis_count = 0
    solve_count = 0
    _factored_at = 0
    _switch_to: str | None = None

    def __init__(self, model: Model, *, iterations: int = 10, tolerance: float | None = None,
                 backend: str = "auto", check_conditioning: bool = True):
        super().__init__(model, iterations=iterations, tolerance=tolerance, backend=backend)
        self.check_conditioning = check_conditioning
        self.factor_count = 0
        self.backend: str | None = None
        self._cache_key = None
        self._cache: SystemFactor | None = None
        self._held_key = None   # the held-contact system (clothsim.solvers.held), cached
        self._held = None
        self._Ms = model.vertex_mass
        self._Js = matrices.spring_matrix(model, expand=False)
        # the local step's arithmetic and carried directions (clothsim.solvers.directions)
        self._dirs = SpringDirections(*model.springs.spring_vertices.T,
                                      model.springs.spring_rest_length,
                                      model.mesh.vertices.T)
        self._a, self._b = self._dirs.a, self._dirs.b
        # coordinate-major work buffers: p(y), and x's spring vectors turned into d − p(y)
        s = model.spring_count
        self._pyT = np.empty((3, s))
        self._eT = np.empty((3, s))

    # -- precomputation -------------------------------------------------------------------
    def invalidate(self) -> None:
        self._cache_key = None
        self._cache = None
        self._held_key = None
        self._held = None

    def system(self, problem: StepProblem) -> SystemFactor:
        """The factor for this problem's h and pins: cached, rebuilt only when they change.

        Parameters
        ----------
        problem : StepProblem
            The step's h [s], y [m], forces [N] and pins.

        Returns
        -------
        SystemFactor
            The factorization of M + h² L over the free vertices, with its buffers.
        """
        key = system_key(problem)
        if key != self._cache_key:
            self._cache = self._factor(problem)
            self._cache_key = key
        return self._cache

    def adopt_system(self, problem: StepProblem, system: SystemFactor, held=None) -> None:
        """Take a fresh solver's first factors of the same matrices (:meth:`system` and
        :func:`.held.held_start`'s) instead of factoring: every solve is bit for bit the one
        this solver's own would give (the port checker's replays share them).

        Parameters
        ----------
        problem : StepProblem
        system : SystemFactor
        held : HeldSystem, optional
        """
        self._cache, self._cache_key = system, system_key(problem)
        if held is not None:
            self._held, self._held_key = held, held_key(problem)

    def _factor(self, problem: StepProblem) -> SystemFactor:
        with single_threaded():   # CHOLMOD's OpenMP threads: gain nothing here (see solve)
            sysf = factor_system(self.model, problem, self._Js, self._a, self._b,
                                 backend=self.backend_requested,
                                 check_conditioning=self.check_conditioning,
                                 choose_mode=self._choose_mode, previous=self._cache)
        self._switch_to, self._factored_at = None, self.solve_count
        self.factor_count += 1
        self.analysis_count += sysf.A_FF_factor.analyzed
        self.backend = sysf.A_FF_factor.backend
        self.factorization = sysf.A_FF_factor.mode_reason
        return sysf

    def _choose_mode(self, free: int) -> ModeChoice:
        """CHOLMOD's mode for a factorization over ``free`` unknowns (:attr:`expected_final`)."""
        if self._switch_to is not None:
            served = self.solve_count - self._factored_at
            return ModeChoice(self._switch_to, switched_reason(free, self._switch_to, served))
        return choose_cholmod_mode(free, self.cholmod_mode, self.expected_solves,
                                   final=self.expected_final)

    def _count_solves(self, iterations: int) -> None:
        """Count a step's solves; past the factor's switch point, refactor in the other mode."""
        self.solve_count += iterations
        mode = None if self._cache is None else self._cache.mode
        if (mode is not None and mode.switch_after is not None
                and self.solve_count - self._factored_at >= mode.switch_after):
            log.info("the %s factor served %d solves, past its switch point (%d): refactoring in "
                     "%s mode", mode.mode, self.solve_count - self._factored_at,
                     mode.switch_after, mode.switch_to)
            self.invalidate()
            self._switch_to = mode.switch_to

    # -- the two half steps ---------------------------------------------------------------
    def local_step(self, x: np.ndarray) -> np.ndarray:
        """d_i = r_i (x_a − x_b) / |x_a − x_b| for all springs at once, shape (s, 3).

        Where a spring's two ends coincide, any d with |d| = r is optimal: the previous
        direction is kept (never a division by zero).

        Parameters
        ----------
        x : array_like, shape (n, 3)
            Positions [m].

        Returns
        -------
        ndarray, shape (s, 3)
            d [m] (a new array).
        """
        return self._dirs.local_step(np.ascontiguousarray(np.asarray(x, np.float64).T)).T.copy()

    def right_hand_side(self, problem: StepProblem, d: np.ndarray) -> np.ndarray:
        """The paper's right-hand side b = h² J d + M y + h² f + h² K_anchor q.

        Parameters
        ----------
        problem : StepProblem
            The step's h [s], y [m], forces [N] and pins.
        d : ndarray, shape (s, 3)
            Spring directions from the local step [m].

        Returns
        -------
        ndarray, shape (n, 3)
            b [kg·m].
        """
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

        Parameters
        ----------
        problem : StepProblem
            The step's h [s], y [m], forces [N] and pins.
        d : ndarray, shape (s, 3)
            Spring directions from the local step [m].

        Returns
        -------
        ndarray, shape (n, 3)
            b(d) − A y [kg·m].
        """
        h2 = problem.h ** 2
        y = problem.y
        b = h2 * (self._Js @ (d - (y[self._a] - y[self._b])))
        if problem.f_ext is not None:
            b += h2 * problem.f_ext
        problem.anchors.add_rhs(b, h2, origin=y)
        return b

    def global_step(self, problem: StepProblem, d: np.ndarray) -> np.ndarray:
        """The global step (M + h² L) x = h² J d + M y + h² f (+ penalty-pin terms) over free x.

        Solved for the displacement δ = x − y: A_FF δ_F = (b − A y)_F − A_FP δ_P, then
        x = y + δ. Same x as solving for x directly, but translation invariant to rounding
        (a cloth 1 km from the origin moves like one at the origin).

        Parameters
        ----------
        problem : StepProblem
            The step's h [s], y [m], f_ext [N] and pins.
        d : ndarray, shape (s, 3)
            Spring vectors from the local step [m].

        Returns
        -------
        ndarray, shape (n, 3)
            x after the global step [m]; exactly pinned vertices at their targets.
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

        Parameters
        ----------
        problem : StepProblem
            The step's h [s], y [m], forces [N] and pins.
        x : ndarray, shape (n, 3)
            Positions [m].
        d : ndarray, shape (s, 3)
            The local step's directions at x [m].

        Returns
        -------
        ndarray, shape (f, 3)
            ∇g(x) over the free vertices [N·s²].
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
    def solve(self, problem: StepProblem, x0: np.ndarray | None = None) -> StepResult:
        """:meth:`Solver.solve` with BLAS and OpenMP limited to one thread.

        (:func:`~clothsim.factorization.single_threaded`; a new factorization, done on the
        first step and when h or the pins change, runs inside the limit too.)

        Parameters
        ----------
        problem : StepProblem
            The step's h [s], y [m], forces [N] and pins.
        x0 : ndarray, shape (n, 3), optional
            Initial guess [m]; default y with the pins applied.

        Returns
        -------
        StepResult
        """
        with single_threaded():
            result = super().solve(problem, x0)
        self._count_solves(result.iterations)
        return result

    def iterates(self, problem: StepProblem, x0: np.ndarray | None = None):
        """Local/global iterates from ``x0`` (default: y, pins applied).

        Each iterate's gradient norm is ‖∇g(x_k)‖ over the free vertices with d = d(x_k):
        computed from its definition for x_0, and for k ≥ 1 as the difference of the
        right-hand sides of two consecutive global steps (see the module docstring). The
        yielded ``x`` is a view of the solver's buffer: copy it to keep it.

        Parameters
        ----------
        problem : StepProblem
            The step's h [s], y [m], forces [N] and pins.
        x0 : ndarray, shape (n, 3), optional
            Initial guess [m]; default :meth:`StepProblem.initial_guess` (y or x_n as the
            problem's ``start`` says, pins applied).

        Yields
        ------
        Iterate
            k, x_k (n, 3) [m] and ‖∇g(x_k)‖ [N·s²].
        """
        # held contacts: the constrained global step on the planes (.held_accel.HeldStep)
        step = fused_step(self, problem, x0)
        yield Iterate(0, step.x, step.norm0, d=step.current_directions())
        k = 0
        while True:
            # global step: A_FF δ_F = h² (J (d − p(y)))_F + c_F, x = y + δ; then the local
            # step at x_{k+1} and its rhs; ∇g(x_{k+1}) = rhs(x_k) − rhs(x_{k+1})
            step.advance(step.solve())
            k += 1
            yield Iterate(k, step.x, step.gradient_norm(step.rhs_previous),
                          d=step.current_directions())
