"""A certified reference solution x* per step problem.

Newton (:class:`~clothsim.solvers.NewtonSolver`) is run to its rounding floor from y, and
again from a second start: the point plain local/global reaches (1e-6 relative residual,
then Newton to the floor). The certificate reports

- the final relative residual ‖∇g(x*)‖ / ‖∇g(y)‖ and ‖∇g(x*)‖ over its rounding floor;
- the smallest eigenvalue of H = ∇²g(x*) over the free degrees of freedom, divided by the
  smallest vertex mass (Lanczos, :func:`scipy.sparse.linalg.eigsh`): > 0 certifies a strict
  local minimum;
- the distance between the two solutions, relative to ‖x* − x_n‖: the reference's
  uncertainty when they agree, or — beyond :data:`SAME_POINT` — two different stationary
  points (e.g. two buckling minima), with g(x₂) − g(x₁). Then no single "error" exists for
  this step; the study says so and leaves the step out of the error distribution.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

from ..model import Model
from ..solvers import LocalGlobalSolver, NewtonSolver, StepProblem, objective_gradient
from ..solvers.descent import objective_difference

SAME_POINT = 1e-6


@dataclass
class CertifiedReference:
    """x* of one step with its certificate (see the module text).

    Attributes
    ----------
    x : ndarray, shape (n, 3)
        Newton's solution from y [m].
    residual : float
        Final relative residual ‖∇g(x*)‖ / ‖∇g(y)‖.
    floor_ratio : float
        ‖∇g(x*)‖ over its rounding floor.
    min_eigenvalue : float
        Smallest eigenvalue of ∇²g(x*) / min mass (dimensionless; M alone gives 1). NaN if
        Lanczos did not converge.
    uncertainty : float
        ‖x* − x₂‖ / ‖x* − x_n‖ between the two starts (when they agree).
    two_minima : bool
        The two starts reached different stationary points.
    objective_difference : float
        g(x₂) − g(x*) [J·s²] (negative: the local/global start found a lower point).
    """

    x: np.ndarray
    residual: float
    floor_ratio: float
    min_eigenvalue: float
    uncertainty: float
    two_minima: bool
    objective_difference: float


def smallest_eigenvalue(newton: NewtonSolver, problem: StepProblem, x: np.ndarray) -> float:
    """Smallest eigenvalue of ∇²g(x) over free degrees of freedom / min vertex mass.

    ∇²g(x) = M + h² ∇²E(x); a negative value means g is not convex at x (buckling).

    Parameters
    ----------
    newton : NewtonSolver
        Builds the Hessian (:meth:`~clothsim.solvers.NewtonSolver.hessian`).
    problem : StepProblem
        The step (h, pins).
    x : ndarray, shape (n, 3)
        Where to evaluate [m].

    Returns
    -------
    float
        λ_min(∇²g) / min m_i (dimensionless; 1 for M alone); NaN when there is no free
        degree of freedom or ARPACK does not converge.
    """
    from scipy.sparse.linalg import ArpackNoConvergence, eigsh

    free = np.repeat(problem.free_mask(newton.model.vertex_count), 3)
    H = newton.hessian(problem, x)[free][:, free]
    if H.shape[0] == 0:
        return math.nan
    m = float(newton.model.vertex_mass.min())
    if H.shape[0] <= 400:
        return float(np.linalg.eigvalsh(H.toarray())[0]) / m
    try:
        return float(eigsh(H, k=1, which="SA", tol=1e-8, maxiter=5000,
                           return_eigenvectors=False)[0]) / m
    except ArpackNoConvergence:
        return math.nan


def certified_reference(model: Model, problem: StepProblem, *, backend: str = "auto",
                        second_start: bool = True) -> CertifiedReference:
    """Newton to the rounding floor, certified (see the module text).

    Parameters
    ----------
    model : Model
        The cloth.
    problem : StepProblem
        The step.
    backend : {"auto", "cholmod", "splu"}
        Factorization backend.
    second_start : bool
        Also solve from the converged local/global point (the uncertainty check).

    Returns
    -------
    CertifiedReference
    """
    from ..solvers.base import gradient_noise_floor

    newton = NewtonSolver(model, iterations=200, tolerance=1e-15, backend=backend)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = newton.solve(problem)
        x = res.x
        g_norm = float(np.linalg.norm(objective_gradient(model, problem, x)))
        floor = gradient_noise_floor(model, problem, x)
        scale = float(np.linalg.norm(x - problem.x)) or 1.0
        dist, dg = 0.0, 0.0
        if second_start:
            lg = LocalGlobalSolver(model, iterations=5000, tolerance=1e-6, backend=backend,
                                   check_conditioning=False)
            x2 = NewtonSolver(model, iterations=200, tolerance=1e-15,
                              backend=backend).solve(problem, x0=lg.solve(problem).x).x
            dist = float(np.linalg.norm(x2 - x)) / scale
            dg = objective_difference(model, problem, x, x2 - x)
    two = dist > SAME_POINT
    return CertifiedReference(x, res.residual, g_norm / floor if floor > 0 else math.inf,
                              smallest_eigenvalue(newton, problem, x),
                              math.nan if two else dist, two, dg)
