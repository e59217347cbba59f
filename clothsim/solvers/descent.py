"""Pieces the descent-type solvers share: an exact energy difference and a line search.

Newton, Anderson and L-BFGS compare g at two nearby points. Forming g(x_new) − g(x_old)
from two evaluations of g loses everything below eps |g|: at a relative residual of 1e-8
the true decrease is ~1e-16 |g| and the comparison is noise. :func:`objective_difference`
computes the difference from the *displacement* δ = x_new − x_old and the spring-length
changes directly, so its relative accuracy is that of δ itself, at any depth.
"""

from __future__ import annotations

import numpy as np

from ..model import Model
from .base import StepProblem

ARMIJO_C = 1e-4
MAX_HALVINGS = 60


def objective_difference(model: Model, problem: StepProblem, x: np.ndarray,
                         dx: np.ndarray) -> float:
    """g(x + δ) − g(x) without cancellation [J·s²].

    Parameters
    ----------
    model : Model
    problem : StepProblem
    x : ndarray, shape (n, 3)
        The old point [m].
    dx : ndarray, shape (n, 3)
        The displacement δ [m] (zero on fixed vertices).

    Returns
    -------
    float
        ½ δᵀM(2(x − y) + δ) + h² [Σ_i ½ k_i (l'_i − l_i)(l'_i + l_i − 2 r_i)
        + Σ_anchors k δ·(x − q + ½ δ) − δᵀf], with l'_i − l_i = (2 p_i·δp_i + |δp_i|²) /
        (l'_i + l_i) evaluated from spring vectors p and their changes δp.
    """
    m = model.vertex_mass[:, None]
    out = float(np.sum(m * dx * (x - problem.y + 0.5 * dx)))
    a, b = model.springs.spring_vertices.T
    k, r = model.springs.spring_stiffness, model.springs.spring_rest_length
    p = x[a] - x[b]
    dp = dx[a] - dx[b]
    l_old = np.linalg.norm(p, axis=1)
    l_new = np.linalg.norm(p + dp, axis=1)
    s = l_old + l_new
    num = 2.0 * np.einsum("ij,ij->i", p, dp) + np.einsum("ij,ij->i", dp, dp)
    dl = np.divide(num, s, out=np.zeros_like(s), where=s > 0)
    e = 0.5 * float(np.sum(k * dl * (s - 2.0 * r)))
    if len(problem.anchor_vertices):
        av = problem.anchor_vertices
        q = x[av] - problem.anchor_positions
        e += float(np.sum(problem.anchor_stiffness[:, None] * dx[av] * (q + 0.5 * dx[av])))
    if problem.f_ext is not None:
        e -= float(np.sum(dx * problem.f_ext))
    return out + problem.h ** 2 * e


def armijo(model: Model, problem: StepProblem, x: np.ndarray, direction: np.ndarray,
           slope: float, *, alpha: float = 1.0, c: float = ARMIJO_C,
           max_halvings: int = MAX_HALVINGS) -> tuple[float, float] | None:
    """Backtracking line search: the largest α = alpha 2^(−j) with sufficient decrease.

    Parameters
    ----------
    model, problem : Model, StepProblem
    x : ndarray, shape (n, 3)
        Current point [m].
    direction : ndarray, shape (n, 3)
        Search direction [m] (zero on fixed vertices).
    slope : float
        ∇g(x)ᵀ direction (negative for a descent direction).
    alpha : float
        First step length tried.
    c : float
        Armijo constant: accept when g(x + α p) − g(x) ≤ c α slope.
    max_halvings : int

    Returns
    -------
    (alpha, decrease) or None
        The step length and g(x + α p) − g(x) (≤ 0), or None when ``slope`` is not
        negative or no step length decreases g (x is optimal to rounding along p).
    """
    if not slope < 0.0:
        return None
    for _ in range(max_halvings):
        dg = objective_difference(model, problem, x, alpha * direction)
        if dg <= c * alpha * slope:
            return alpha, dg
        alpha *= 0.5
    return None
