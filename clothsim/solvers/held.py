"""Local/global iterations on a step with held contacts (:mod:`clothsim.contacts`).

A held vertex v stays on its contact plane n · x_v = o and slides in it. The local step is
unchanged; the global step minimizes ĝ(x, d) over the feasible set instead of all of
R^{3n}. With δ = x − y split as δ = z + P u, where z is a feasible displacement (pins at
their targets, held vertices on their planes) and P = I − Σ b bᵀ removes the constrained
directions b of each held vertex, the global step is

    (P A P + α D) u = P (b(d) − A y − A z)        over the free degrees of freedom,

with A = (M_s + h² L_s) ⊗ I3 and D = Σ b bᵀ (α D fixes the constrained components of u
at 0; α is the mean diagonal of A, for conditioning). It is solved in tangent coordinates
(:mod:`.tangent_system`): u = T w with T's columns the directions each free vertex may move
in, (Tᵀ A T) w = Tᵀ r, the same minimizer with a matrix whose coordinates couple only at
vertices held on oblique planes (three principal submatrices of M_s + h² L_s on box faces)
instead of the pattern of (M_s + h² L_s) ⊗ ones(3, 3). It is factored once per contact set
(held vertices and their normals) and cached while the set stays, its symbolic analysis
reused while the pattern does (the same vertices on oblique planes, the same free
directions elsewhere). Without held contacts the solvers use the n × n factor of the paper
(:mod:`clothsim.solvers.system`).

The iteration's residual is ‖P ∇g(x_k)‖ over the free vertices
(:func:`~clothsim.objective.objective_gradient`), zero at the constrained minimum.
"""

from __future__ import annotations

import logging

import numpy as np
import scipy.sparse as sp

from .. import contacts
from ..factorization import Factor
from . import tangent_system
from .system import system_key

log = logging.getLogger(__name__)


def projector_blocks(vertices: np.ndarray, basis) -> tuple[np.ndarray, np.ndarray]:
    """Each held vertex's 3 × 3 block of P, for projecting (n, 3) arrays in one pass.

    Parameters
    ----------
    vertices : ndarray, shape (c,), int
        The held contacts' vertices (repeated for a vertex on several planes).
    basis : list
        :func:`clothsim.contacts.contact_basis`.

    Returns
    -------
    held : ndarray, shape (h,), int
        The held vertices, increasing.
    blocks : ndarray, shape (h, 3, 3)
        I − Σ b bᵀ of each.
    """
    held = np.unique(vertices)
    blocks = np.broadcast_to(np.eye(3), (len(held), 3, 3)).copy()
    for v, b in basis:
        blocks[np.searchsorted(held, v)] -= b[:, :, None] * b[:, None, :]
    return held, blocks


class HeldSystem:
    """The factor of the global step with held contacts, for one contact set.

    Parameters
    ----------
    solver : LocalGlobalSolver
        Supplies the scalar system M_s + h² L_s (with the pins) and the backend.
    problem : StepProblem
        The step: h, pins and held contacts.
    previous : HeldSystem, optional
        The system this one replaces (its symbolic analysis is reused when the pattern of
        Tᵀ A T is the same).

    Attributes
    ----------
    As : csr_matrix, shape (n, n)
        M_s + h² L_s over all vertices [kg].
    free, fixed : ndarray of int
        The solver's free and exactly pinned vertices.
    held : ndarray of int
        The held vertices, increasing.
    A_FF : csr_matrix, shape (f, f)
        M_s + h² L_s over the free vertices [kg] (the fused held loops' gradient).
    tangent_factor : Factor
        The factor of Tᵀ A T (:mod:`.tangent_system`), m × m; :meth:`solve` applies
        (P A P + α D)⁻¹ with it.
    """

    def __init__(self, solver, problem, previous: HeldSystem | None = None):
        sysf = solver.system(problem)
        n = solver.model.vertex_count
        self.As = As = sp.csr_matrix(sysf.A)
        self.free = sysf.free
        self.fixed = sysf.fixed
        self.A_FF = As if not len(self.fixed) else As[self.free][:, self.free]
        self.basis = problem.contact_basis()
        self.held, self.blocks = projector_blocks(problem.contact_vertices, self.basis)
        self.alpha = float(As.diagonal().mean())
        dof, vectors, self.oblique = tangent_system.vertex_directions(n, self.free, self.basis)
        self.present = dof >= 0                 # (n, 3): the columns of T, by vertex and slot
        self.oblique_vectors = vectors[self.oblique]   # T's columns where they are not axes
        K = tangent_system.tangent_matrix(As, dof, vectors, self.oblique)
        self.tangent_factor = Factor(K, backend=solver.backend_requested,
                             check_conditioning=False,   # M + h² L's factor was checked
                             cholmod_mode="supernodal",   # measured: docs/data/held-factor.md
                             reuse=None if previous is None else previous.tangent_factor)
        log.info("factored the held-contact system: %d held vertices (%d on oblique planes), "
                 "%d unknowns", len(self.held), len(self.oblique), K.shape[0])

    def prepare(self, problem) -> tuple[np.ndarray, np.ndarray]:
        """The step's feasible displacement z and A z, constant over its iterations.

        Parameters
        ----------
        problem : StepProblem

        Returns
        -------
        z, Az : ndarray, shape (n, 3)
            z = x − y with pins at their targets and held vertices on their planes (zero
            elsewhere) [m]; A z [kg·m].
        """
        y = problem.y
        z = problem.hold(np.array(y, dtype=np.float64)) - y
        z[problem.fixed_vertices] = problem.fixed_positions - y[problem.fixed_vertices]
        return z, self.As @ z

    def global_step(self, problem, rhs: np.ndarray, z: np.ndarray,
                    Az: np.ndarray) -> np.ndarray:
        """x minimizing ĝ(x, d) on the feasible set [m], shape (n, 3).

        Parameters
        ----------
        problem : StepProblem
        rhs : ndarray, shape (n, 3)
            b(d) − A y for the local step's d [kg·m]
            (:meth:`LocalGlobalSolver.displacement_right_hand_side`).
        z, Az : ndarray, shape (n, 3)
            :meth:`prepare`.

        Returns
        -------
        ndarray, shape (n, 3)
        """
        return problem.y + z + self.solve(self.tangential(rhs - Az))

    def solve(self, r: np.ndarray) -> np.ndarray:
        """u = (P A P + α D)⁻¹ r over the free vertices (zero at the pins), via Tᵀ A T.

        Parameters
        ----------
        r : ndarray, shape (n, 3)
            A right-hand side [kg·m]; its rows at the pins are ignored.

        Returns
        -------
        u : ndarray, shape (n, 3)
            T (Tᵀ A T)⁻¹ Tᵀ r + D r / α: tangential at the held vertices when r is.
        """
        held, obl, V = self.held, self.oblique, self.oblique_vectors
        rt = np.array(r, dtype=np.float64)
        rt[obl] = np.einsum("vsi,vi->vs", V, rt[obl])     # Tᵀ r (axis columns: r's entries)
        w = np.zeros_like(rt)
        w[self.present] = self.tangent_factor.solve(rt[self.present])
        w[obl] = np.einsum("vsi,vs->vi", V, w[obl])       # T w
        r_held = np.asarray(r, dtype=np.float64)[held]
        normal = r_held - np.einsum("vij,vj->vi", self.blocks, r_held)   # D r
        w[held] = np.einsum("vij,vj->vi", self.blocks, w[held]) + normal / self.alpha
        return w

    def gradient_norm(self, problem, x: np.ndarray, rhs: np.ndarray) -> float:
        """The gradient on the feasible set, as the stop rule reads it.

        Parameters
        ----------
        problem : StepProblem
        x : ndarray, shape (n, 3)
            An iterate [m].
        rhs : ndarray, shape (n, 3)
            b(d(x)) − A y [kg·m].

        Returns
        -------
        float
            ‖P ∇g(x)‖ over the free vertices [N·s²].
        """
        return float(np.linalg.norm(self.tangential(self.As @ (x - problem.y) - rhs)[self.free]))

    def tangential(self, g: np.ndarray) -> np.ndarray:
        """P applied at the held vertices, in place.

        Parameters
        ----------
        g : ndarray, shape (n, 3)

        Returns
        -------
        g : ndarray, shape (n, 3)
            The same array, without its constrained components.
        """
        g[self.held] = np.einsum("vij,vj->vi", self.blocks, g[self.held])
        return g


def constrained_matrix(problem, H, free: np.ndarray):
    """P H P + α D over the free degrees of freedom (a Newton step with held contacts).

    Parameters
    ----------
    problem : StepProblem
        The step, with held contacts.
    H : sparse matrix, shape (3f, 3f)
        A Hessian over the free degrees of freedom (interleaved).
    free : ndarray of bool, shape (3n,)
        Which of the 3n degrees of freedom are unknowns.

    Returns
    -------
    csc_matrix, shape (3f, 3f)
        In H's pattern and data layout (the Newton solver shifts its diagonal in place).
        Solving it with a tangential right-hand side gives a step in the contact planes.
    """
    P, D = contacts.projector(len(free) // 3, problem.contact_basis())
    P, D = P[free][:, free], D[free][:, free]
    K = (P @ H @ P + float(H.diagonal().mean()) * D).tocsr()
    H = sp.csc_matrix(H, copy=True)          # same pattern and layout as H (held blocks are
    cols = np.repeat(np.arange(H.shape[1]), np.diff(H.indptr))   # dense 3 x 3 in it)
    H.data = np.asarray(K[H.indices, cols]).ravel()
    return H


def feasible(problem, x: np.ndarray) -> np.ndarray:
    """x with the pins at their targets and held vertices on their planes, in place.

    Parameters
    ----------
    problem : StepProblem
    x : ndarray, shape (n, 3)
        A point of the feasible set up to rounding [m].

    Returns
    -------
    x : ndarray, shape (n, 3)
    """
    x[problem.fixed_vertices] = problem.fixed_positions
    return problem.hold(x)


def held_start(solver, problem, x0: np.ndarray | None = None):
    """The :class:`HeldSystem` of the step's contact set (cached) and its feasible start.

    Parameters
    ----------
    solver : LocalGlobalSolver
        Caches the :class:`HeldSystem` of the current contact set.
    problem : StepProblem
        A step whose :attr:`~clothsim.problem.StepProblem.has_contacts`.
    x0 : ndarray, shape (n, 3), optional
        Initial guess [m]; moved onto the pins and contact planes. Default
        :meth:`StepProblem.initial_guess`.

    Returns
    -------
    held : HeldSystem
    x : ndarray, shape (n, 3)
        The start [m], a new array, on the pins and contact planes.
    """
    key = held_key(problem)
    if key != solver._held_key:
        solver._held = HeldSystem(solver, problem, previous=solver._held)
        solver._held_key = key
        solver.factor_count += 1
    held = solver._held
    x = (problem.initial_guess() if x0 is None
         else feasible(problem, np.array(x0, dtype=np.float64)))
    return held, x


def held_key(problem) -> tuple:
    """What of a problem the :class:`HeldSystem` depends on.

    Parameters
    ----------
    problem : StepProblem

    Returns
    -------
    tuple
        :func:`.system.system_key` (h, the pins) and the held contacts (their vertices and
        normals), as bytes.
    """
    return system_key(problem) + (problem.contact_vertices.tobytes(),
                                  problem.contact_normals.tobytes())
