"""How far float32 arithmetic alone moves a step: clothsim's own step, run in float32.

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
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from .. import matrices
from .compare import EPS32

#: Allowed ratio of a port's float32 error to clothsim's own float32 deviation: another
#: solver ordering (LDLᵀ instead of LU, other sums) rounds differently by a small factor.
#: Measured: the paper authors' code built in float32 errs by up to 1.9 × the deviation,
#: the project's C++/Eigen port (examples/ports/cpp, float) by up to 2.6 ×.
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


def float32_tolerance(model, problem, iterations: int, floor64: float) -> float:
    """Allowed per-vertex distance of a float32 port's step [m].

    ``MARGIN`` × :func:`float32_deviation`, and at least the float64 tolerance and the
    rounding of the answer itself (4 ε₃₂ max|x|).

    Parameters
    ----------
    model : Model
    problem : StepProblem
    iterations : int
        The step's local/global iterations.
    floor64 : float
        The float64 tolerance [m].

    Returns
    -------
    float
        Tolerance [m].
    """
    x = problem.initial_guess()
    return max(floor64, 4 * EPS32 * float(np.abs(x).max()),
               MARGIN * float32_deviation(model, problem, iterations))

