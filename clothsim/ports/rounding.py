"""How far float32 arithmetic alone moves a step: the scene's own method, computed in float32.

A float32 port's answer differs from clothsim's float64 answer by its rounding. A bound
from the condition number alone (κ(M + h²L) ε₃₂ max|x|) fails both ways: it ignores the
iterations (each local and global step rounds again), and penalty pins inflate κ (a
w = 1e10 N/m pin gives κ ≈ 1e7) without making the free vertices any less accurate.
:func:`float32_deviation` measures the rounding instead: it runs the step's local/global
iterations twice from the same start, in float64 and in float32 (float32 matrices, a
float32 SuperLU factor, float32 local steps), the way a plain port computes them (the global
step solved for x itself, not for a displacement). The deviation of the two answers is the
rounding floor of this step; :func:`float32_tolerance` allows a margin over it for another
ordering of the same arithmetic (docs/ports.md, "float32 ports").

That measures a fixed number of local/global iterations. A converged step (Newton's
method, or any solver run to a tolerance) is the minimizer x* of g, and the best a float32
solver can do there is limited by the rounding of g's gradient, not by any iteration:
:func:`converged_float32_floor` evaluates ∇g at x* in float32, as a port does (the
inertial target, the spring forces, the sums), and maps the error δg of that evaluation
to positions through the Hessian, δx = ∇²g(x*)⁻¹ δg: a float32 Newton iteration from x*
stagnates there (its fixed point solves ∇g₃₂(x) = 0, i.e. H (x − x*) ≈ −δg to first order).
The rounding of x itself (½ ulp₃₂ per coordinate) is added. A solver that stops short of
that floor by more than a small factor (another order of the same sums) is not converged.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from .. import matrices
from ..errors import FactorizationError
from ..factorization import Factor
from ..objective import objective_gradient
from ..solvers.held import constrained_matrix
from ..solvers.newton import NewtonSolver
from .compare import EPS32

#: Allowed ratio of a port's float32 error to clothsim's own float32 deviation: another
#: solver ordering (LDLᵀ instead of LU, other sums) rounds differently by a small factor.
#: Measured when it was set (commit 617962f): the paper authors' code built in float32
#: and the project's C++/Eigen port (examples/ports/cpp, float) both err by less than this.
MARGIN = 4.0
#: Iterations run at most to measure a converged step's floor (a float32 fixed point
#: stagnates long before).
MAX_ITERATIONS = 200


class _Step:
    """The matrices of one step's local/global iterations, in one floating-point type."""

    def __init__(self, model, problem, dtype):
        n = model.vertex_count
        av, ak = problem.anchor_vertices, problem.anchor_stiffness
        A = matrices.system_matrix(model, problem.h, anchor_vertices=av, anchor_stiffness=ak)
        fixed = np.zeros(n, bool)
        fixed[problem.fixed_vertices] = True
        self.free, self.fixed = np.flatnonzero(~fixed), np.flatnonzero(fixed)
        A = sp.csc_matrix(A, dtype=dtype)
        self.lu = splu(A[self.free][:, self.free].tocsc())
        self.A_FP = A[self.free][:, self.fixed].tocsr()
        self.J = sp.csr_matrix(matrices.spring_matrix(model, expand=False), dtype=dtype)
        self.dtype = dtype
        sv = model.springs.spring_vertices
        self.a, self.b = sv[:, 0], sv[:, 1]
        self.r = model.springs.spring_rest_length.astype(dtype)[:, None]
        h2 = dtype(problem.h) ** 2
        c = (model.vertex_mass.astype(dtype)[:, None] * problem.y.astype(dtype))
        if problem.f_ext is not None:
            c = c + h2 * problem.f_ext.astype(dtype)
        if len(av):
            np.add.at(c, av, h2 * (ak.astype(dtype)[:, None]
                                   * problem.anchor_positions.astype(dtype)))
        self.c, self.h2 = c, h2
        self.x_fixed = problem.fixed_positions.astype(dtype)

    def iterate(self, x: np.ndarray, iterations: int) -> np.ndarray:
        x = x.astype(self.dtype)
        x[self.fixed] = self.x_fixed
        d = np.zeros((len(self.a), 3), self.dtype)
        for _ in range(iterations):
            p = x[self.a] - x[self.b]
            length = np.linalg.norm(p, axis=1, keepdims=True)
            ok = length[:, 0] > 0
            d[ok] = self.r[ok] * p[ok] / length[ok]
            rhs = self.c + self.h2 * (self.J @ d)
            rhs = rhs[self.free]
            if len(self.fixed):
                rhs = rhs - self.A_FP @ x[self.fixed]
            x[self.free] = self.lu.solve(np.asarray(rhs, self.dtype))
        return x.astype(np.float64)


def float32_deviation(model, problem, iterations: int) -> float:
    """max over vertices of |x₃₂ − x₆₄| after ``iterations`` local/global iterations [m].

    Parameters
    ----------
    model : Model
        Springs [N/m, m] and masses [kg] (springs only: per-spring damping is folded in by
        :meth:`~clothsim.simulation.Simulation.step_model` before).
    problem : StepProblem
        The step; both runs start from its initial guess (y or x_n) rounded to float32.
    iterations : int
        Local/global iterations (at most :data:`MAX_ITERATIONS`).

    Returns
    -------
    float
        The rounding floor of this step [m].
    """
    k = max(1, min(int(iterations), MAX_ITERATIONS))
    start = problem.initial_guess().astype(np.float32)
    x64 = _Step(model, problem, np.float64).iterate(start, k)
    x32 = _Step(model, problem, np.float32).iterate(start, k)
    return float(np.linalg.norm(x32 - x64, axis=1).max())


def float32_gradient(model, problem, x: np.ndarray) -> np.ndarray:
    """∇g(x) computed in float32 arithmetic, the way a float32 port evaluates it.

    M (x − y) + h² (Σ_i k_i (1 − r_i/|p_i|) p_i + anchors − f), every array, product and
    sum in float32 (y rounded to float32, as a port computing x_k + h v_k holds it).

    Parameters
    ----------
    model : Model
    problem : StepProblem
    x : ndarray, shape (n, 3)
        Positions [m] (rounded to float32 first).

    Returns
    -------
    ndarray, shape (n, 3), float64
        The float32 gradient [N·s²]; rows of exactly pinned vertices are zero.
    """
    f32 = np.float32
    x = x.astype(f32)
    h2 = f32(problem.h) ** 2
    sv = model.springs.spring_vertices
    p = x[sv[:, 0]] - x[sv[:, 1]]
    length = np.linalg.norm(p, axis=1)
    ok = length > 0
    coef = np.zeros(len(p), f32)
    coef[ok] = (model.springs.spring_stiffness.astype(f32)[ok]
                * (f32(1) - model.springs.spring_rest_length.astype(f32)[ok] / length[ok]))
    force = coef[:, None] * p
    grad_e = np.zeros_like(x)
    np.add.at(grad_e, sv[:, 0], force)
    np.add.at(grad_e, sv[:, 1], -force)
    av = problem.anchor_vertices
    if len(av):
        np.add.at(grad_e, av, problem.anchor_stiffness.astype(f32)[:, None]
                  * (x[av] - problem.anchor_positions.astype(f32)))
    if problem.f_ext is not None:
        grad_e = grad_e - problem.f_ext.astype(f32)
    grad = model.vertex_mass.astype(f32)[:, None] * (x - problem.y.astype(f32)) + h2 * grad_e
    grad[problem.fixed_vertices] = 0
    return grad.astype(np.float64)


def converged_float32_floor(model, problem, x: np.ndarray) -> float:
    """How close to the minimizer ``x`` a converged float32 solver can get [m], per vertex.

    max_v |(∇²g(x)⁻¹ δg)_v| + √3/2 ulp₃₂(max|x|), δg the error of :func:`float32_gradient`
    at x rounded to float32 (module docstring).

    Parameters
    ----------
    model : Model
        The step's model (damping folded in).
    problem : StepProblem
    x : ndarray, shape (n, 3)
        The minimizer of g (clothsim's converged answer) [m].

    Returns
    -------
    float
        The floor [m].
    """
    x32 = x.astype(np.float32).astype(np.float64)
    dg = (problem.tangential(float32_gradient(model, problem, x32))
          - objective_gradient(model, problem, x32))   # on the held planes: in them
    dx = _hessian_solve(model, problem, x)(dg)
    ulp = float(np.spacing(np.float32(np.abs(x).max())))
    return float(np.linalg.norm(dx, axis=1).max()) + np.sqrt(3.0) / 2 * ulp


def float32_newton_stagnation(model, problem, x: np.ndarray, iterations: int = 20) -> float:
    """Where Newton's method run in float32 from the minimizer ``x`` stagnates [m].

    x ← fl₃₂(x − ∇²g(x*)⁻¹ ∇g₃₂(x)), from x* rounded to float32: the gradient in float32
    (:func:`float32_gradient`), the small Newton step solved in float64 (its own rounding
    is relative to its size). The largest distance from x* over the iterations is what a
    converged float32 Newton can be off; :func:`converged_float32_floor` predicts it
    without iterating (docs/ports.md compares the two).

    Parameters
    ----------
    model : Model
    problem : StepProblem
    x : ndarray, shape (n, 3)
        The minimizer of g [m].
    iterations : int, default 20

    Returns
    -------
    float
        max over the iterations of max_v |x_v − x*_v| [m].
    """
    solve = _hessian_solve(model, problem, x)
    it = x.astype(np.float32)
    worst = float(np.linalg.norm(it - x, axis=1).max())
    for _ in range(iterations):
        step = solve(float32_gradient(model, problem, it.astype(np.float64)))
        it = (it.astype(np.float64) - step).astype(np.float32)
        worst = max(worst, float(np.linalg.norm(it - x, axis=1).max()))
    return worst


def _hessian_solve(model, problem, x: np.ndarray):
    """v ↦ ∇²g(x)⁻¹ v over the free vertices (0 on the pinned), for (n, 3) arrays; with
    held contacts on the feasible directions only, (P ∇²g P + α D)⁻¹ P v."""
    free = np.flatnonzero(problem.free_mask(model.vertex_count))
    dofs = (3 * free[:, None] + np.arange(3)).ravel()
    mask = np.zeros(3 * model.vertex_count, bool)
    mask[dofs] = True
    solver = NewtonSolver(model)
    factor = None
    for definite in (False, True):  # the exact Hessian; its projection if it is indefinite
        H = solver.hessian(problem, x, definite=definite).tocsc()[dofs][:, dofs]
        if problem.has_contacts:
            H = constrained_matrix(problem, H, mask)
        try:
            factor = Factor(H, check_conditioning=False)
            break
        except FactorizationError:
            continue

    def solve(v: np.ndarray) -> np.ndarray:
        out = np.zeros(3 * model.vertex_count)
        if factor is not None:
            v = problem.tangential(np.asarray(v, np.float64).reshape(-1, 3))
            out[dofs] = factor.solve(v.reshape(-1)[dofs])
        return out.reshape(-1, 3)

    return solve


def float32_tolerance(model, problem, iterations: int, floor64: float,
                      x: np.ndarray | None = None, iterated: bool = True) -> float:
    """Allowed per-vertex distance of a float32 port's step [m].

    ``MARGIN`` × the float32 floor of the scene's method: of ``iterations`` local/global
    iterations (:func:`float32_deviation`, when ``iterated``), and of a converged solve
    (:func:`converged_float32_floor` at ``x``, when given); at least the float64
    tolerance and, for iterations, the rounding of the answer itself (4 ε₃₂ max|x|).

    Parameters
    ----------
    model : Model
    problem : StepProblem
    iterations : int
        The step's local/global iterations.
    floor64 : float
        The float64 tolerance [m].
    x : ndarray, shape (n, 3), optional
        The step's minimizer (clothsim's converged answer) [m].
    iterated : bool, default True
        The scene's method is a fixed number of local/global iterations: their float32
        deviation counts. False for a converged method (Newton's), whose float32 port
        is held to the converged floor alone.

    Returns
    -------
    float
        Tolerance [m].
    """
    tol = floor64
    if iterated:
        x0 = problem.initial_guess()
        tol = max(tol, 4 * EPS32 * float(np.abs(x0).max()),
                  MARGIN * float32_deviation(model, problem, iterations))
    if x is not None:
        tol = max(tol, MARGIN * converged_float32_floor(model, problem, x))
    return tol

