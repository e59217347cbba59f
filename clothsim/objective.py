"""The objective of one implicit Euler step and its gradient (Liu et al. 2013, Eqs. 4, 9).

Every solver minimizes the same g of a :class:`~clothsim.problem.StepProblem`:

- :func:`objective`: g(x) = ½ (x − y)ᵀ M (x − y) + h² E(x);
- :func:`augmented_objective`: ĝ(x, d) (Eq. 9), with ĝ(x, d(x)) = g(x);
- :func:`objective_gradient`: ∇g(x);
- :func:`gradient_noise_floor`: the norm of ∇g below which the gradient is rounding noise;
- :func:`relative`: a residual relative to the initial one.
"""

from __future__ import annotations

import math

import numpy as np

from . import energy
from .model import Model
from .problem import StepProblem


def _objective_without_springs(model: Model, problem: StepProblem, x: np.ndarray) -> float:
    """½ (x − y)ᵀ M (x − y) + h² (anchor energy − xᵀ f): the terms g and ĝ share."""
    dx = x - problem.y
    g = 0.5 * float(np.sum(model.vertex_mass[:, None] * dx * dx))
    e = 0.0
    if len(problem.anchors):
        e += problem.anchors.energy(x)
    if problem.f_ext is not None:
        e -= float(np.sum(x * problem.f_ext))
    return g + problem.h ** 2 * e


def objective(model: Model, problem: StepProblem, x: np.ndarray) -> float:
    """g(x) = ½ (x − y)ᵀ M (x − y) + h² E(x), E with springs, anchors and −xᵀf [J·s²].

    Parameters
    ----------
    model : Model
    problem : StepProblem
    x : ndarray, shape (n, 3), positions [m]

    Returns
    -------
    float, g(x) [J·s²] (= kg·m²)
    """
    return (_objective_without_springs(model, problem, x)
            + problem.h ** 2 * energy.spring_energy(model, x))


def augmented_objective(model: Model, problem: StepProblem, x: np.ndarray,
                        d: np.ndarray) -> float:
    """The augmented objective ĝ(x, d) of the local/global method (Eq. 9).

    ĝ(x, d) = ½ (x − y)ᵀ M (x − y) + h² (½ Σ_i k_i |p_i − d_i|² + E_anchor(x) − xᵀ f),
    with p_i = x_{a_i} − x_{b_i}: g with (|p_i| − r_i)² replaced by |p_i − d_i|², i.e.
    ½ xᵀ (M + h² L) x − h² xᵀ J d − xᵀ (M y + h² f) up to a constant. ĝ(x, d) ≥ g(x) when
    every |d_i| = r_i, with equality at the local step's d_i = r_i p_i / |p_i|.

    Parameters
    ----------
    model : Model
    problem : StepProblem
    x : ndarray, shape (n, 3), positions [m]
    d : ndarray, shape (s, 3), one auxiliary vector per spring [m]

    Returns
    -------
    float, ĝ(x, d) [J·s²]
    """
    q = energy.spring_vectors(model, x) - d
    springs = 0.5 * float(np.sum(model.springs.spring_stiffness[:, None] * q * q))
    return _objective_without_springs(model, problem, x) + problem.h ** 2 * springs


def objective_gradient(model: Model, problem: StepProblem, x: np.ndarray, *,
                       feasible: bool = True) -> np.ndarray:
    """The gradient of the objective g.

    ∇g(x) = M (x − y) + h² ∇E(x), with ∇E = Σ_i k_i (1 − r_i/|p_i|) p_i at a_i (minus at
    b_i) + Σ_j k_j (x_{v_j} − q_j) − f. Zero at the solution x_{n+1}.

    Parameters
    ----------
    model : Model
    problem : StepProblem
    x : ndarray, shape (n, 3), positions [m]
    feasible : bool, default True
        False: the whole ∇g, also at held contacts (its normal part there is the contact
        force times h²).

    Returns
    -------
    ndarray, shape (n, 3)
        ∇g(x) [N·s²]; rows of fixed vertices are zero (they are not unknowns), and at
        held contacts only the part in the contact plane is kept
        (:meth:`~clothsim.problem.StepProblem.tangential`): the gradient on the step's
        feasible set, zero at its solution.
    """
    h2 = problem.h ** 2
    grad = model.vertex_mass[:, None] * (x - problem.y) + h2 * energy.spring_gradient(model, x)
    problem.anchors.add_gradient(grad, x, h2)
    if problem.f_ext is not None:
        grad -= h2 * problem.f_ext
    grad[problem.fixed_vertices] = 0.0
    return problem.tangential(grad) if feasible else grad


def gradient_noise_floor(model: Model, problem: StepProblem, x: np.ndarray) -> float:
    """‖∇g‖ below which the gradient is rounding noise: eps h² (‖k‖₂ ‖x‖∞ + ‖f‖₂).

    ∇g sums spring terms k_i (p_i − d_i) that cancel at the solution, and p_i = x_a − x_b
    carries a rounding error of about eps |x| (positions are stored absolutely), so ‖∇g‖
    cannot be computed more accurately than about eps h² ‖k‖ |x| (measured on a 41 × 41
    cloth at rest: 0.35 of this bound). A step that starts almost at its solution (a cloth
    at rest) can therefore not reduce ‖∇g‖ / ‖∇g(x_0)‖ to a tight tolerance; once ‖∇g‖ is
    below this floor the iterate is optimal to rounding, and the solvers stop and count the
    step as converged instead of warning.

    Parameters
    ----------
    model : Model
    problem : StepProblem
    x : ndarray, shape (n, 3), positions [m] (usually the initial guess)

    Returns
    -------
    float, the floor [N·s²]
    """
    force = float(np.linalg.norm(model.springs.spring_stiffness)) * float(np.abs(x).max())
    if problem.f_ext is not None:
        force += float(np.linalg.norm(problem.f_ext))
    return float(np.finfo(float).eps) * problem.h ** 2 * force


def relative(norm: float, norm0: float) -> float:
    """Relative residual norm / norm0.

    Parameters
    ----------
    norm, norm0 : float
        Current and initial residual norms, e.g. of ∇g(x_k) and ∇g(x_0) [N·s²].

    Returns
    -------
    float
        norm / norm0 (dimensionless); 0 when both vanish (the initial guess is already the
        solution), inf when only norm0 vanishes or is not finite.
    """
    if norm0 == 0.0 or not math.isfinite(norm0):
        return 0.0 if norm == 0.0 else math.inf
    return norm / norm0
