"""∇²g over the free degrees of freedom, assembled straight into one fixed sparsity pattern.

Newton factors a Hessian every iteration. :class:`FreeHessian` precomputes, once per set of
free degrees of freedom, where each entry of every spring's 3 × 3 blocks (±H_i at (a,a),
(b,b), (a,b), (b,a), :func:`clothsim.energy.spring_hessian`) lands in the CSC data of the
free Hessian; an iteration then only computes the blocks and sums them with one
``bincount``. Entries that happen to be zero (axis-aligned springs of a flat grid) stay in
the pattern, so one CHOLMOD symbolic analysis serves every Hessian of the cloth.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..energy import spring_hessian_blocks
from ..model import Model
from ..problem import StepProblem


class FreeHessian:
    """Assembler of ∇²g = M + h² (∇²E_springs + K_anchor) over the free degrees of freedom.

    Parameters
    ----------
    model : Model
        The cloth (masses [kg], springs [N/m, m]).

    Attributes
    ----------
    diagonal : ndarray of int, shape (m,)
        Positions of the diagonal entries in the data of the matrices returned (for a
        shift τM added in place), after :meth:`matrix` was called.
    """

    def __init__(self, model: Model):
        self.model = model
        self._key = None

    def _setup(self, free: np.ndarray) -> None:
        n = self.model.vertex_count
        a, b = self.model.springs.spring_vertices.T
        index = np.full(3 * n, -1, dtype=np.int64)
        index[free] = np.arange(int(free.sum()))
        m = int(free.sum())
        ri, ci = np.meshgrid(np.arange(3), np.arange(3), indexing="ij")
        rows = np.concatenate([(3 * i[:, None, None] + ri).ravel() for i in (a, b, a, b)])
        cols = np.concatenate([(3 * j[:, None, None] + ci).ravel() for j in (a, b, b, a)])
        fr, fc = index[rows], index[cols]
        valid = (fr >= 0) & (fc >= 0)
        diag = np.arange(m, dtype=np.int64)
        keys_all = np.concatenate([fc[valid] * m + fr[valid], diag * (m + 1)])
        keys = np.unique(keys_all)
        pattern = sp.csc_matrix((np.zeros(len(keys)), (keys % m, keys // m)), shape=(m, m))
        pattern.sort_indices()
        self._pattern = pattern
        self._valid = valid
        self._positions = np.searchsorted(keys, fc[valid] * m + fr[valid])
        self.diagonal = np.searchsorted(keys, diag * (m + 1))
        self._free = free
        self._key = free.tobytes()

    def matrix(self, problem: StepProblem, x: np.ndarray, free: np.ndarray, *,
               definite: bool = False) -> sp.csc_matrix:
        """The free Hessian at x, CSC, in the fixed pattern.

        Parameters
        ----------
        problem : StepProblem
            The step's h [s] and penalty pins.
        x : ndarray, shape (n, 3)
            Where to evaluate [m].
        free : ndarray of bool, shape (3n,)
            Free degrees of freedom (interleaved layout).
        definite : bool
            Clamp compressed springs' transverse factor 1 − r/l at 0.

        Returns
        -------
        csc_matrix, shape (m, m)
            ∇²g(x) over the free degrees of freedom [kg], m = free.sum().
        """
        if self._key != free.tobytes():
            self._setup(free)
        model = self.model
        H = spring_hessian_blocks(model, x, definite=definite)
        H *= problem.h ** 2
        vals = np.concatenate([H.ravel(), H.ravel(), -H.ravel(), -H.ravel()])[self._valid]
        data = np.bincount(self._positions, weights=vals,
                           minlength=self._pattern.nnz).astype(np.float64, copy=False)
        diag = np.repeat(model.vertex_mass, 3)
        if len(problem.anchor_vertices):
            idx = (3 * problem.anchor_vertices[:, None] + np.arange(3)).ravel()
            np.add.at(diag, idx, problem.h ** 2 * np.repeat(problem.anchor_stiffness, 3))
        data[self.diagonal] += diag[free]
        out = self._pattern.copy()
        out.data = data
        return out
