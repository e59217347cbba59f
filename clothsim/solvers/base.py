"""What every time-step solver shares: the step problem, its objective, the result.

One implicit Euler step (Liu et al. 2013, Eq. 4) asks for

    x_{n+1} = argmin_x g(x),   g(x) = ½ (x − y)ᵀ M (x − y) + h² E(x),

with y the inertial target (y = x_n + h v_n unless a damping effect changes it), external
forces f, exact pins (fixed vertices at prescribed positions, removed from the unknowns)
and penalty pins ("anchors": zero-rest-length springs of stiffness k to fixed points q).
:class:`StepProblem` holds exactly these data; every solver minimizes the same g.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Iterator
from dataclasses import dataclass, field

import numpy as np

from .. import energy
from ..errors import ConvergenceWarning, InputError, check_finite
from ..model import Model

_EMPTY_I = np.zeros(0, np.int64)
_EMPTY_X = np.zeros((0, 3))


@dataclass(eq=False)
class StepProblem:
    """Data of one implicit Euler step.

    Attributes
    ----------
    h : float
        Time step [s].
    x : ndarray, shape (n, 3)
        Positions x_n at the start of the step [m].
    v : ndarray, shape (n, 3)
        Velocities v_n [m/s].
    y : ndarray, shape (n, 3)
        Inertial target [m]; default x + h v.
    f_ext : ndarray, shape (n, 3) or None
        External force on each vertex [N]; None means none.
    fixed_vertices : ndarray, shape (p,), int
        Exact pins: vertices removed from the unknowns.
    fixed_positions : ndarray, shape (p, 3)
        Their positions at the end of the step [m].
    anchor_vertices, anchor_positions, anchor_stiffness : ndarray, shapes (q,), (q, 3), (q,)
        Penalty pins: zero-rest-length springs of stiffness k [N/m] to points q [m].
    """

    h: float
    x: np.ndarray
    v: np.ndarray
    y: np.ndarray | None = None
    f_ext: np.ndarray | None = None
    fixed_vertices: np.ndarray = field(default_factory=lambda: _EMPTY_I)
    fixed_positions: np.ndarray = field(default_factory=lambda: _EMPTY_X)
    anchor_vertices: np.ndarray = field(default_factory=lambda: _EMPTY_I)
    anchor_positions: np.ndarray = field(default_factory=lambda: _EMPTY_X)
    anchor_stiffness: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def __post_init__(self):
        h = float(check_finite("h", self.h))
        if h <= 0:
            raise InputError(f"h: the time step must be positive, got {h!r}")
        self.h = h
        # a NaN/inf in the state or forces (bad input, or a blow-up) is named, never solved
        self.x = check_finite("state.positions", self.x)
        self.v = check_finite("state.velocities", self.v)
        if self.y is None:
            self.y = self.x + h * self.v
        self.y = check_finite("inertial_target", self.y)
        if self.f_ext is not None:
            self.f_ext = check_finite("external_force", self.f_ext)
        self.fixed_vertices = np.asarray(self.fixed_vertices, np.int64).reshape(-1)
        self.fixed_positions = np.asarray(self.fixed_positions, np.float64).reshape(-1, 3)
        self.anchor_vertices = np.asarray(self.anchor_vertices, np.int64).reshape(-1)
        self.anchor_positions = np.asarray(self.anchor_positions, np.float64).reshape(-1, 3)
        check_finite("pins.fixed_positions", self.fixed_positions)
        check_finite("pins.anchor_positions", self.anchor_positions)
        self.anchor_stiffness = np.broadcast_to(
            np.asarray(self.anchor_stiffness, np.float64), self.anchor_vertices.shape)

    def initial_guess(self) -> np.ndarray:
        """y with fixed vertices at their prescribed positions (the paper's starting point)."""
        x0 = np.array(self.y, dtype=np.float64)
        x0[self.fixed_vertices] = self.fixed_positions
        return x0

    def free_mask(self, n: int) -> np.ndarray:
        mask = np.ones(n, bool)
        mask[self.fixed_vertices] = False
        return mask


@dataclass
class Iterate:
    """One iterate of a step solver (see :meth:`Solver.iterates`).

    Attributes
    ----------
    k : int
        Iterations done; 0 is the initial guess.
    x : ndarray, shape (n, 3)
        The iterate [m]; valid until the generator resumes (copy it to keep it).
    gradient_norm : float
        ‖∇g(x)‖ over the free degrees of freedom [N·s²] (absolute, not relative).
    """

    k: int
    x: np.ndarray
    gradient_norm: float


@dataclass
class StepResult:
    """Outcome of one step's solve.

    Attributes
    ----------
    x : ndarray, shape (n, 3)
        x_{n+1} [m].
    iterations : int
        Iterations done (global solves for local/global, Newton steps for Newton).
    residual : float
        Final relative residual ‖∇g(x)‖ / ‖∇g(x_0)‖ over the free degrees of freedom
        (0 when the initial guess already solves the step).
    residual_history : list of float
        Relative residual before each iteration and after the last.
    converged : bool
        True when a tolerance was set and met, or when ‖∇g‖ reached its rounding floor
        (:func:`gradient_noise_floor`); always True without a tolerance.
    """

    x: np.ndarray
    iterations: int
    residual: float
    residual_history: list[float] = field(default_factory=list)
    converged: bool = True


def _objective_without_springs(model: Model, problem: StepProblem, x: np.ndarray) -> float:
    """½ (x − y)ᵀ M (x − y) + h² (anchor energy − xᵀ f): the terms g and ĝ share."""
    dx = x - problem.y
    g = 0.5 * float(np.sum(model.vertex_mass[:, None] * dx * dx))
    e = 0.0
    if len(problem.anchor_vertices):
        q = x[problem.anchor_vertices] - problem.anchor_positions
        e += 0.5 * float(np.sum(problem.anchor_stiffness[:, None] * q * q))
    if problem.f_ext is not None:
        e -= float(np.sum(x * problem.f_ext))
    return g + problem.h ** 2 * e


def objective(model: Model, problem: StepProblem, x: np.ndarray) -> float:
    """g(x) = ½ (x − y)ᵀ M (x − y) + h² E(x), E with springs, anchors and −xᵀf [J·s²]."""
    return (_objective_without_springs(model, problem, x)
            + problem.h ** 2 * energy.spring_energy(model, x))


def augmented_objective(model: Model, problem: StepProblem, x: np.ndarray,
                        d: np.ndarray) -> float:
    """ĝ(x, d): g with |p_i| − r_i replaced by |p_i − d_i| (Eq. 9); ĝ(x, d(x)) = g(x)."""
    q = energy.spring_vectors(model, x) - d
    springs = 0.5 * float(np.sum(model.springs.spring_stiffness[:, None] * q * q))
    return _objective_without_springs(model, problem, x) + problem.h ** 2 * springs


def objective_gradient(model: Model, problem: StepProblem, x: np.ndarray) -> np.ndarray:
    """∇g(x), shape (n, 3); rows of fixed vertices are zero (they are not unknowns)."""
    h2 = problem.h ** 2
    grad = model.vertex_mass[:, None] * (x - problem.y) + h2 * energy.spring_gradient(model, x)
    if len(problem.anchor_vertices):
        k = problem.anchor_stiffness[:, None]
        np.add.at(grad, problem.anchor_vertices,
                  h2 * k * (x[problem.anchor_vertices] - problem.anchor_positions))
    if problem.f_ext is not None:
        grad -= h2 * problem.f_ext
    grad[problem.fixed_vertices] = 0.0
    return grad


class Solver:
    """Base class: iteration control shared by all step solvers.

    Parameters
    ----------
    model : Model
    iterations : int
        Iterations per step; the maximum when ``tolerance`` is set.
    tolerance : float or None
        Stop once the relative residual ‖∇g(x_k)‖ / ‖∇g(x_0)‖ is at most this. When the
        limit is hit above it, a :class:`ConvergenceWarning` names the residual.
    backend : {"auto", "cholmod", "splu"}
        Sparse factorization backend (see :mod:`clothsim.factorization`).
    """

    name = "base"

    def __init__(self, model: Model, *, iterations: int = 10, tolerance: float | None = None,
                 backend: str = "auto"):
        if not isinstance(iterations, (int, np.integer)) or iterations < 1:
            raise InputError(f"solver.iterations: must be an integer >= 1, got {iterations!r}")
        if tolerance is not None:
            tolerance = float(check_finite("solver.tolerance", tolerance))
            if tolerance <= 0:
                raise InputError(f"solver.tolerance: must be positive, got {tolerance!r}")
        self.model = model
        self.iterations = int(iterations)
        self.tolerance = tolerance
        self.backend_requested = backend

    def iterates(self, problem: StepProblem, x0: np.ndarray | None = None) -> Iterator[Iterate]:
        """Yield the initial guess (k = 0), then every iterate of the method.

        Runs until the consumer stops, or returns when the method can make no further
        progress. A yielded ``x`` is valid until the generator resumes: copy it to keep it.
        """
        raise NotImplementedError

    def solve(self, problem: StepProblem, x0: np.ndarray | None = None) -> StepResult:
        """Minimize g from ``x0`` (default: y with pins applied) under the one stop rule.

        Stops at ``iterations``, once the relative residual ‖∇g(x_k)‖ / ‖∇g(x_0)‖ is at
        most ``tolerance``, once ‖∇g‖ is at its rounding floor
        (:func:`gradient_noise_floor`, only with a tolerance), or on a non-finite residual.
        """
        history: list[float] = []
        floor = r0 = None
        last = None
        for last in self.iterates(problem, x0):
            rn = last.gradient_norm
            if floor is None:
                floor = gradient_noise_floor(self.model, problem, last.x) if self.tolerance else 0.0
                r0 = rn
            history.append(relative(rn, r0))
            if (last.k >= self.iterations or not math.isfinite(rn)
                    or (self.tolerance is not None
                        and (history[-1] <= self.tolerance or rn <= floor))):
                break
        return self._finish(np.array(last.x), last.k, history,
                            at_floor=last.gradient_norm <= floor)

    def invalidate(self) -> None:
        """Drop anything precomputed from the model (call after changing the model)."""

    def _finish(self, x, iterations, history, *, at_floor: bool = False) -> StepResult:
        residual = history[-1] if history else 0.0
        converged = self.tolerance is None or residual <= self.tolerance or at_floor
        if not converged:
            warnings.warn(
                f"{self.name}: relative residual {residual:.3e} after {iterations} iterations "
                f"is above the tolerance {self.tolerance:.1e}", ConvergenceWarning, stacklevel=3)
        return StepResult(x, iterations, residual, history, converged)


def gradient_noise_floor(model: Model, problem: StepProblem, x: np.ndarray) -> float:
    """‖∇g‖ below which the gradient is rounding noise: eps h² (‖k‖₂ ‖x‖∞ + ‖f‖₂).

    ∇g sums spring terms k_i (p_i − d_i) that cancel at the solution, and p_i = x_a − x_b
    carries a rounding error of about eps |x| (positions are stored absolutely), so ‖∇g‖
    cannot be computed more accurately than about eps h² ‖k‖ |x| (measured on a 41 × 41
    cloth at rest: 0.35 of this bound). A step that starts almost at its solution (a cloth
    at rest) can therefore not reduce ‖∇g‖ / ‖∇g(x_0)‖ to a tight tolerance; once ‖∇g‖ is
    below this floor the iterate is optimal to rounding, and the solvers stop and count the
    step as converged instead of warning.
    """
    force = float(np.linalg.norm(model.springs.spring_stiffness)) * float(np.abs(x).max())
    if problem.f_ext is not None:
        force += float(np.linalg.norm(problem.f_ext))
    return float(np.finfo(float).eps) * problem.h ** 2 * force


def relative(norm: float, norm0: float) -> float:
    """norm / norm0, with 0 when both vanish (the initial guess is already the solution)."""
    if norm0 == 0.0 or not math.isfinite(norm0):
        return 0.0 if norm == 0.0 else math.inf
    return norm / norm0
