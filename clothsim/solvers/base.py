"""What every time-step solver shares: the iterate, the result and the one stop rule.

Every solver minimizes the same implicit Euler objective g(x) of a
:class:`~clothsim.problem.StepProblem` (defined with g, ĝ and ∇g in
:mod:`clothsim.problem`, re-exported here). A solver exposes its iterates through
:meth:`Solver.iterates`; :meth:`Solver.solve` consumes them under the one stop rule.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Iterator
from dataclasses import dataclass, field

import numpy as np

from ..errors import ConvergenceWarning, InputError, NonFiniteStateError, check_finite
from ..model import Model
from ..objective import (  # noqa: F401  (re-exported: the solvers' public vocabulary)
    augmented_objective,
    gradient_noise_floor,
    objective,
    objective_gradient,
    relative,
)
from ..problem import PenaltyAnchors, PinSet, StepProblem  # noqa: F401  (re-exported)


def overflow_cause(problem: StepProblem, x0: np.ndarray) -> str:
    """Why ‖∇g(x_0)‖ of a step is not finite: the step's largest magnitude, named.

    Parameters
    ----------
    problem : StepProblem
        The step: h [s], x_n [m], v_n [m/s], y [m], f_ext [N], pins.
    x0 : ndarray, shape (n, 3)
        The initial guess [m].

    Returns
    -------
    str
        One line naming the largest of h²|f_ext| [kg·m], |x_n|, |x_0|, h|v_n| [m] and the
        pins' targets [m], the magnitudes whose squares the gradient's norm sums.
    """
    h2 = problem.h ** 2
    with np.errstate(all="ignore"):
        parts = {"h²|f_ext| (the external forces: gravity, force, impulse, wind)":
                 h2 * _peak(problem.f_ext),
                 "|x_n| (the positions)": _peak(problem.x),
                 "h|v_n| (the velocities)": problem.h * _peak(problem.v),
                 "|x_0| (the iteration's start)": _peak(x0),
                 "|q| (the pins' targets)": max(_peak(problem.fixed_positions),
                                                _peak(problem.anchor_positions))}
    name, value = max(parts.items(), key=lambda kv: kv[1] if not math.isnan(kv[1]) else math.inf)
    return (f"the step's gradient |grad g| overflows float64 from its start: {name} reaches "
            f"{value:.3g}, beyond what double precision can square (about 1e154); without "
            f"this error the cloth would not move")


def _peak(a) -> float:
    if a is None or not np.size(a):
        return 0.0
    a = np.asarray(a, np.float64)
    return float(np.nanmax(np.abs(a))) if not np.isnan(a).all() else math.nan


class Iterate:
    """One iterate of a step solver (see :meth:`Solver.iterates`).

    Parameters
    ----------
    k : int
        Iterations done; 0 is the initial guess.
    x : ndarray, shape (n, 3)
        The iterate [m]; valid until the generator resumes (copy it to keep it).
    gradient_norm : float
        ‖∇g(x)‖ over the free degrees of freedom [N·s²] (absolute, not relative).
    d : ndarray, shape (s, 3), or callable, or None
        The local step's spring directions d(x) [m] (local/global solvers; None for the
        others), or a function returning them coordinate-major, shape (3, s): then they
        are built only when :attr:`d` is first read (the fast iteration does not keep d).

    Attributes
    ----------
    k, x, gradient_norm
        As given.
    d : ndarray, shape (s, 3), or None
        d(x) [m]; valid until the generator resumes, like ``x``.
    """

    __slots__ = ("k", "x", "gradient_norm", "_d")

    def __init__(self, k: int, x: np.ndarray, gradient_norm: float, d=None):
        self.k, self.x, self.gradient_norm, self._d = k, x, gradient_norm, d

    @property
    def d(self) -> np.ndarray | None:
        if callable(self._d):
            self._d = self._d().T
        return self._d

    def __repr__(self) -> str:
        return (f"Iterate(k={self.k}, gradient_norm={self.gradient_norm!r}, "
                f"x=<{self.x.shape}>)")


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
    converged : bool or None
        True when a tolerance was set and met, or when ‖∇g‖ reached its rounding floor
        (:func:`~clothsim.objective.gradient_noise_floor`); False when a tolerance was set
        and missed; None ("not checked") when no tolerance was set.
    """

    x: np.ndarray
    iterations: int
    residual: float
    residual_history: list[float] = field(default_factory=list)
    converged: bool | None = None


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

    Attributes
    ----------
    decisions : callable or None
        ``decisions(taken) -> taken``, consulted by a solver at each discrete choice of its
        iteration (Anderson's energy safeguard, L-BFGS's Armijo test; a solver without
        one never calls it) with the choice it made; the choice returned is followed. None
        (default): the solver's own. The port checker records a step's choices with it and
        replays a step along them (:mod:`clothsim.ports.solver_branches`).
    """

    name = "base"
    decisions = None

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
        Subclasses implement this; :meth:`solve` and the accuracy traces consume it.

        Parameters
        ----------
        problem : StepProblem
            The step: h [s], x_n [m], v_n [m/s], y [m], f_ext [N], pins.
        x0 : ndarray, shape (n, 3), optional
            Initial guess [m]; default :meth:`StepProblem.initial_guess` (y with pins applied).

        Yields
        ------
        Iterate
            k (iterations done), x (n, 3) [m], gradient_norm = ‖∇g(x)‖ over the free
            degrees of freedom [N·s²].
        """
        raise NotImplementedError

    def solve(self, problem: StepProblem, x0: np.ndarray | None = None) -> StepResult:
        """Minimize g from ``x0`` (default: y with pins applied) under the one stop rule.

        Stops at ``iterations``, once the relative residual ‖∇g(x_k)‖ / ‖∇g(x_0)‖ is at
        most ``tolerance``, once ‖∇g‖ is at its rounding floor
        (:func:`gradient_noise_floor`, only with a tolerance), or on a non-finite residual.

        Parameters
        ----------
        problem : StepProblem
            The step to solve.
        x0 : ndarray, shape (n, 3), optional
            Initial guess [m].

        Returns
        -------
        StepResult
            x_{n+1} (n, 3) [m], iterations done, the relative residual and its history,
            and ``converged`` (None when no tolerance was set). A missed tolerance also
            emits a :class:`ConvergenceWarning`.

        Raises
        ------
        NonFiniteStateError
            When ‖∇g(x_0)‖ is not finite: a force, velocity or position of the step is
            beyond what float64 can square (:func:`overflow_cause` names which).
        """
        history: list[float] = []
        floor = r0 = None
        last = None
        for last in self.iterates(problem, x0):
            rn = last.gradient_norm
            if floor is None:
                if not math.isfinite(rn):  # else 0 iterations, x = x_0: a silently frozen cloth
                    raise NonFiniteStateError(overflow_cause(problem, last.x))
                floor = gradient_noise_floor(self.model, problem, last.x) if self.tolerance else 0.0
                r0 = rn
            history.append(relative(rn, r0))
            if (last.k >= self.iterations or not math.isfinite(rn)
                    or (self.tolerance is not None
                        and (history[-1] <= self.tolerance or rn <= floor))):
                break
        return self._finish(np.array(last.x, order="C"), last.k, history,
                            at_floor=last.gradient_norm <= floor)

    def invalidate(self) -> None:
        """Drop anything precomputed from the model (call after changing the model)."""

    def get_state(self) -> dict:
        """Per-run state that affects results (for a bit-for-bit resume), JSON-able.

        Returns
        -------
        dict
            Floats, ints and lists only; the base class has none (``{}``).
        """
        return {}

    def set_state(self, state: dict) -> None:
        """Restore what :meth:`get_state` returned (the base class has nothing to restore).

        Parameters
        ----------
        state : dict
            A dictionary returned by :meth:`get_state` of a solver of the same kind.
        """

    def _finish(self, x, iterations, history, *, at_floor: bool = False) -> StepResult:
        residual = history[-1] if history else 0.0
        converged = None
        if self.tolerance is not None:
            converged = bool(residual <= self.tolerance or at_floor)
        if converged is False:
            warnings.warn(
                f"{self.name}: relative residual {residual:.3e} after {iterations} iterations "
                f"is above the tolerance {self.tolerance:.1e}", ConvergenceWarning, stacklevel=3)
        return StepResult(x, iterations, residual, history, converged)
