"""Symplectic (semi-implicit) Euler: the explicit baseline.

One step, with y = x_n + h v_n the inertial target (a damping effect may have changed it):

    v_{n+1} = v_n + h M⁻¹ (f_ext − ∇E(x_n))
    x_{n+1} = x_n + h v_{n+1} = y + h² M⁻¹ (f_ext − ∇E(x_n))

∇E includes the springs and the penalty anchors (zero-rest-length springs to their
targets); exactly pinned vertices are put at their targets. This is a *different*
integrator from implicit Euler: it solves no optimization (one force evaluation per step,
no residual) and does not damp, but it is only stable for small steps. For a linear spring
network the limit is

    h < 2 / ω_max,   ω_max² = λ_max(M⁻¹ (L + K_anchor)),

and because each spring's Hessian k [u uᵀ + (1 − r/l)⁺ (I − u uᵀ)] is at most k I, the
same bound holds for the nonlinear springs. :func:`stable_time_step` computes it with
``scipy.sparse.linalg.eigsh`` on the symmetric M^{-1/2} L M^{-1/2}; the solver warns
(:class:`StabilityWarning`) once when h is above it.

References
----------
E. Hairer, C. Lubich, G. Wanner. Geometric Numerical Integration, 2nd ed., Springer 2006,
Section I.1 (symplectic Euler) and the stability of the Störmer–Verlet family.
"""

from __future__ import annotations

import logging
import warnings

import numpy as np
import scipy.sparse as sp

from .. import energy, matrices
from ..errors import ClothsimWarning
from ..model import Model
from .base import Iterate, Solver, StepProblem

log = logging.getLogger(__name__)


class StabilityWarning(ClothsimWarning):
    """An explicit time step is above its estimated stability limit."""


def stable_time_step(model: Model, *, anchor_vertices=None, anchor_stiffness=None) -> float:
    """The explicit stability limit h_max = 2 / ω_max [s], ω_max² = λ_max(M⁻¹ L).

    Over the vertices of positive mass: one of mass 0 is pinned (it does not move).

    Parameters
    ----------
    model : Model
    anchor_vertices : array_like of int, optional
        Penalty-pinned vertices; their stiffness adds to L's diagonal.
    anchor_stiffness : array_like, optional
        Penalty stiffness [N/m] of each anchor.

    Returns
    -------
    float
        2 / sqrt(λ_max) [s] (inf when there are no springs).
    """
    Ls = matrices.stiffness_matrix(model, expand=False).tocsr()
    n = model.vertex_count
    if anchor_vertices is not None and len(anchor_vertices):
        k = np.broadcast_to(np.asarray(anchor_stiffness, np.float64), np.shape(anchor_vertices))
        Ls = Ls + sp.csr_matrix((k, (anchor_vertices, anchor_vertices)), shape=(n, n))
    m = np.asarray(model.vertex_mass, np.float64)
    massive = np.flatnonzero(m > 0)  # a vertex of mass 0 is pinned: it does not oscillate
    s = 1.0 / np.sqrt(m[massive])
    K = sp.diags(s) @ Ls[massive][:, massive] @ sp.diags(s)
    n = len(massive)
    if K.nnz == 0:
        return float("inf")
    if n <= 50:
        lam = float(np.linalg.eigvalsh(K.toarray())[-1])
    else:
        from scipy.sparse.linalg import eigsh  # loaded here only: it brings scipy.linalg
        lam = float(eigsh(K, k=1, which="LA", return_eigenvectors=False, tol=1e-6)[0])
    return float("inf") if lam <= 0 else 2.0 / np.sqrt(lam)


class SymplecticEulerSolver(Solver):
    """Explicit symplectic Euler step (baseline; not implicit Euler).

    Parameters
    ----------
    model : Model
    iterations, tolerance
        Accepted for interface compatibility and ignored: a step is one force evaluation
        (one iterate); results report 1 iteration, residual 0 and ``converged`` None.
    backend
        Ignored (no linear system).
    check_stability : bool, default True
        Warn once per (h, anchor set) when h exceeds :func:`stable_time_step`.

    Attributes
    ----------
    stable_h : float or None
        The last computed stability limit [s].
    """

    name = "symplectic-euler"

    def __init__(self, model: Model, *, iterations: int = 1, tolerance: float | None = None,
                 backend: str = "auto", check_stability: bool = True):
        super().__init__(model, iterations=iterations, tolerance=None, backend=backend)
        self.iterations = 1  # one force evaluation per step, whatever was asked
        self.check_stability = check_stability
        self.stable_h: float | None = None
        self._checked = None
        m = np.asarray(model.vertex_mass, np.float64)
        # mass 0 means pinned exactly (the simulation pins it): an inverse mass of 0
        self._inv_mass = np.divide(1.0, m, out=np.zeros_like(m), where=m > 0)

    def _check(self, problem: StepProblem) -> None:
        key = (problem.h, problem.anchor_vertices.tobytes(), problem.anchor_stiffness.tobytes())
        if key == self._checked:
            return
        self._checked = key
        self.stable_h = stable_time_step(self.model, anchor_vertices=problem.anchor_vertices,
                                         anchor_stiffness=problem.anchor_stiffness)
        log.info("symplectic Euler: h=%g, stability limit %g", problem.h, self.stable_h)
        if problem.h >= self.stable_h:
            warnings.warn(f"symplectic-euler: h={problem.h:.4g} s is above the stability limit "
                          f"2/omega_max={self.stable_h:.4g} s; expect the cloth to blow up",
                          StabilityWarning, stacklevel=3)

    def force(self, problem: StepProblem, x: np.ndarray) -> np.ndarray:
        """The total force f(x) = f_ext − ∇E(x) (springs and penalty anchors).

        Parameters
        ----------
        problem : StepProblem
            Supplies f_ext [N] and the anchors.
        x : ndarray, shape (n, 3)
            Positions [m].

        Returns
        -------
        ndarray, shape (n, 3)
            Force on each vertex [N].
        """
        f = -energy.spring_gradient(self.model, x)
        if problem.f_ext is not None:
            f += problem.f_ext
        problem.anchors.add_gradient(f, x, -1.0)
        return f

    def iterates(self, problem: StepProblem, x0: np.ndarray | None = None):
        """The explicit step as one "iteration": k = 0 is x_n, k = 1 is x_{n+1}.

        x_{n+1} = y + h² M⁻¹ (f_ext − ∇E(x_n)), fixed vertices at their targets. There is
        no objective to minimize, so every gradient norm is reported as 0 (no residual);
        the method can make no progress after its one step and then returns. ``x0`` is
        ignored (the step starts from x_n by definition).

        Parameters
        ----------
        problem : StepProblem
            The step: h [s], x_n [m], v_n [m/s], y [m], f_ext [N], pins.
        x0 : ndarray, shape (n, 3), optional
            Ignored.

        Yields
        ------
        Iterate
            k = 0 with x_n, then k = 1 with x_{n+1} (n, 3) [m]; gradient_norm 0.
        """
        if self.check_stability:
            self._check(problem)
        yield Iterate(0, problem.x, 0.0)
        x = problem.y + problem.h ** 2 * self._inv_mass[:, None] * self.force(problem, problem.x)
        x[problem.fixed_vertices] = problem.fixed_positions
        problem.hold(x)   # held contacts: onto their planes (the explicit step's projection)
        yield Iterate(1, x, 0.0)
