"""The cached factorization of the global step's system for one time step and pin set.

The matrix M + h² L depends only on masses, stiffnesses, topology, h and the pins, so the
local/global solvers factor it once (sparse Cholesky, simplicial CHOLMOD: faster than
supernodal for three right-hand sides) and reuse it for every iteration of every step
until h or the pins change (Liu et al. 2013, Section 4).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .. import matrices
from ..factor_mode import ModeChoice
from ..factorization import Factor
from ..model import Model
from ..problem import StepProblem

try:  # y += A x for CSC A and several vectors, without A @ x's copies
    from scipy.sparse._sparsetools import csc_matvecs as _csc_matvecs
except ImportError:  # pragma: no cover
    _csc_matvecs = None

log = logging.getLogger(__name__)


@dataclass(eq=False)
class SystemFactor:
    """The cached factorization for one pin configuration and time step.

    Attributes
    ----------
    A : csc_matrix, shape (n, n)
        M_s + h² (L_s + K_anchor) over all vertices.
    free : ndarray, shape (f,), int
        Free vertices (the unknowns).
    fixed : ndarray, shape (p,), int
        Exactly pinned vertices.
    A_FF_factor : Factor
        Factorization of A restricted to free rows and columns.
    mode : ModeChoice or None
        CHOLMOD's mode, why, and when to change it (None: SuperLU).
    A_FP : csr_matrix, shape (f, p)
        Coupling of free to fixed vertices (moves fixed positions to the right-hand side).
    h2J_F : csr_matrix, shape (f, s)
        h² J_s restricted to the free rows (the right-hand side's d-dependent part).
    free_runs : list of (start, stop, offset) or None
        Free vertices as runs (vertices start..stop−1 are unknowns offset..), or None.
    pinned_springs : ndarray, shape (q,), int
        Springs with an end at an exact pin (their vectors differ between y and x_0).
    work : ndarray, shape (3, 3, f)
        Coordinate-major buffers: two consecutive right-hand sides (the older one turned into
        ∇g once the newer is formed) and the constant c_F.
    coupled : (ndarray of int, csr_matrix)
        The free vertices (positions in F) with a pinned neighbour, and their rows of A_FP:
        the only rows where − A_FP δ_P is not zero.
    """

    A: sp.csc_matrix
    free: np.ndarray
    fixed: np.ndarray
    A_FF_factor: Factor
    A_FP: sp.csr_matrix
    h2J_F: sp.csr_matrix
    free_runs: list | None = None
    pinned_springs: np.ndarray | None = None
    work: np.ndarray | None = None
    mode: ModeChoice | None = None
    coupled: tuple | None = None

    def free_product(self, delta: np.ndarray) -> np.ndarray:
        """A_FF δ_F, coordinate-major (the factor's A_FF, column by column).

        Parameters
        ----------
        delta : ndarray, shape (f, 3), C-contiguous
            δ over the free vertices, vertex-major [m].

        Returns
        -------
        ndarray, shape (3, f)
            A_FF δ [kg·m], a new array: each row's sum in the order of A δ̃ over all
            vertices with δ̃ zero on the pins (the same values).
        """
        A = self.A_FF_factor.A
        if _csc_matvecs is None or not delta.flags.c_contiguous:  # pragma: no cover
            return np.ascontiguousarray((A @ delta).T)
        out = np.zeros_like(delta)
        _csc_matvecs(A.shape[0], A.shape[1], 3, A.indptr, A.indices, A.data,
                     delta.reshape(-1), out.reshape(-1))
        return np.ascontiguousarray(out.T)


def factor_system(model: Model, problem: StepProblem, Js: sp.csr_matrix, a: np.ndarray,
                  b: np.ndarray, *, backend: str = "auto",
                  check_conditioning: bool = True,
                  choose_mode=None, previous: SystemFactor | None = None) -> SystemFactor:
    """Assemble and factor M_s + h² (L_s + K_anchor) for this problem's h and pins.

    Parameters
    ----------
    model : Model
    problem : StepProblem
        Gives h [s], the exact pins (removed from the unknowns) and the penalty anchors
        (added to L_s's diagonal).
    Js : csr_matrix, shape (n, s)
        The scalar spring matrix J_s [N/m].
    a, b : ndarray of int, shape (s,)
        The springs' end vertices.
    backend : {"auto", "cholmod", "splu"}
        Factorization backend (:class:`clothsim.factorization.Factor`).
    check_conditioning : bool
        Warn when the condition estimate passes the threshold.
    choose_mode : callable, optional
        ``choose_mode(free_vertex_count) -> ModeChoice``: CHOLMOD's mode and why
        (:func:`clothsim.factor_mode.choose_cholmod_mode`); default simplicial.
    previous : SystemFactor, optional
        The factor this one replaces: with the same free vertices (h or the penalty pins
        changed) its symbolic analysis is reused.

    Returns
    -------
    SystemFactor
    """
    n = model.vertex_count
    A = matrices.system_matrix(model, problem.h, anchor_vertices=problem.anchor_vertices,
                               anchor_stiffness=problem.anchor_stiffness)
    fixed = np.unique(problem.fixed_vertices)
    free = np.flatnonzero(problem.free_mask(n))
    # A_FF in CSC, the form CHOLMOD takes, from A's free columns (A is CSC: no conversion)
    A_FF = A[:, free][free]
    A_FP = A[:, fixed][free].tocsr()
    mode = (ModeChoice("simplicial", "simplicial") if choose_mode is None
            else choose_mode(len(free)))
    # h² (L + K_anchor) is positive semidefinite: A_FF's eigenvalues are at least the
    # smallest free mass, which bounds the condition number without a solve
    floor = float(model.vertex_mass[free].min()) if len(free) else None
    factor = Factor(A_FF, backend=backend, check_conditioning=check_conditioning,
                    cholmod_mode=mode.mode,
                    reuse=None if previous is None else previous.A_FF_factor,
                    eigenvalue_floor=floor)
    factor.mode_reason = mode.reason if factor.backend == "cholmod" else "SuperLU (no CHOLMOD)"
    log.info("factored M + h^2 L: %d free of %d vertices, h=%g, backend=%s (%s)",
             len(free), n, problem.h, factor.backend, factor.mode_reason)
    h2J_F = (problem.h ** 2 * Js[free]).tocsr()
    breaks = np.flatnonzero(np.diff(free) != 1) + 1
    runs = None
    if len(breaks) < 64:
        starts = np.concatenate([[0], breaks]).astype(int)
        stops = np.concatenate([breaks, [len(free)]]).astype(int)
        runs = [(int(free[i]), int(free[j - 1]) + 1, int(i)) for i, j in zip(starts, stops)
                if j > i]
    pinned_springs = np.flatnonzero(np.isin(a, fixed) | np.isin(b, fixed))
    coupled = np.flatnonzero(np.diff(A_FP.indptr))
    return SystemFactor(A, free, fixed, factor, A_FP, h2J_F, runs, pinned_springs,
                        np.empty((3, 3, len(free))),
                        mode if factor.backend == "cholmod" else None,
                        (coupled, A_FP[coupled]))


def system_key(problem: StepProblem) -> tuple:
    """What of a problem the factor of M + h² L over the free vertices depends on: h and
    the pins.

    Parameters
    ----------
    problem : StepProblem

    Returns
    -------
    tuple
        h and the pins (fixed vertices, anchors and their stiffness), as bytes.
    """
    return (problem.h, problem.fixed_vertices.tobytes(), problem.anchor_vertices.tobytes(),
            problem.anchor_stiffness.tobytes())
