"""Sparse factorizations of the global step's matrix, chosen by backend name.

=============  ==========================================================================
backend        what runs
=============  ==========================================================================
``"cholmod"``  CHOLMOD (SuiteSparse) sparse Cholesky through scikit-sparse 0.4.x. Fails
               loudly if the matrix is not positive definite. ``cholmod_mode`` picks
               "simplicial" (LDLᵀ, column by column), "supernodal" (dense blocks on the
               system BLAS) or "auto" (CHOLMOD's own choice: supernodal for the cloth
               matrices from about 30 × 30 vertices up).
``"splu"``     scipy's SuperLU (``scipy.sparse.linalg.splu``); the fallback where CHOLMOD is
               missing. Positive definiteness is checked from the LU factor's pivots.
``"auto"``     CHOLMOD when importable, else SuperLU with a logged warning.
=============  ==========================================================================

:class:`Factor` records which backend ran (``factor.backend``) and can estimate the
matrix's 1-norm condition number.

Which CHOLMOD mode is faster depends on the size and on how many solves the factor serves;
:mod:`clothsim.factor_mode` decides it for :class:`~clothsim.solvers.LocalGlobalSolver`
(``[solver] cholmod_mode`` overrides it).

Helpers of the iterations that run around a factor: :func:`spmv_add` (a sparse product
accumulated in place, no temporary), :func:`single_threaded` (BLAS and OpenMP limited to
one thread with threadpoolctl; see docs/performance.md) and :func:`cholmod_threads` (a large
factorization on two threads within that limit).
"""

from __future__ import annotations

import contextlib
import logging
import os
import warnings
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from .errors import ConditioningWarning, FactorizationError, InputError

try:  # y += A x for CSR A without temporaries; the public A @ x is the fallback
    from scipy.sparse._sparsetools import csr_matvec as _csr_matvec
except ImportError:  # pragma: no cover
    _csr_matvec = None

log = logging.getLogger(__name__)

BACKENDS = ("auto", "cholmod", "splu")
CHOLMOD_MODES = ("auto", "simplicial", "supernodal")
CONDITION_WARNING_THRESHOLD = 1e12
_warned_fallback = False


def cholmod_available() -> bool:
    """Whether scikit-sparse's CHOLMOD binding imports.

    Returns
    -------
    bool
        True when ``sksparse.cholmod`` imports.
    """
    try:
        from sksparse.cholmod import cholesky  # noqa: F401
    except ImportError:
        return False
    return True


def resolve_backend(backend: str) -> str:
    """Map ``"auto"`` to the backend that will run; check the name.

    Parameters
    ----------
    backend : {"auto", "cholmod", "splu"}
        The requested backend.

    Returns
    -------
    str
        ``"cholmod"`` or ``"splu"``.

    Raises
    ------
    InputError
        For an unknown name, or ``"cholmod"`` without scikit-sparse.
    """
    global _warned_fallback
    if backend not in BACKENDS:
        raise InputError(f"solver.backend: must be one of {', '.join(map(repr, BACKENDS))}, "
                         f"got {backend!r}")
    if backend == "auto":
        if cholmod_available():
            return "cholmod"
        if not _warned_fallback:
            log.warning("CHOLMOD (scikit-sparse) is not installed; falling back to scipy's "
                        "SuperLU. Install it with `pip install scikit-sparse==0.4.16` after "
                        "`apt-get install libsuitesparse-dev`.")
            _warned_fallback = True
        return "splu"
    if backend == "cholmod" and not cholmod_available():
        raise InputError("solver.backend: 'cholmod' needs scikit-sparse (pip install "
                         "scikit-sparse==0.4.16; apt-get install libsuitesparse-dev)")
    return backend


class Factor:
    """A factorization of a symmetric positive definite sparse matrix A.

    Parameters
    ----------
    A : sparse matrix, shape (n, n)
        Symmetric positive definite.
    backend : {"auto", "cholmod", "splu"}
        See the module docstring and :func:`resolve_backend`.
    check_conditioning : bool
        Estimate cond₁(A) and warn (:class:`ConditioningWarning`) above
        :data:`CONDITION_WARNING_THRESHOLD`.
    cholmod_mode : {"auto", "simplicial", "supernodal"}
        CHOLMOD's factorization (ignored by SuperLU); see the module docstring.
    reuse : Factor, optional
        An earlier CHOLMOD factor of a matrix with the same sparsity pattern and mode: its
        symbolic analysis (ordering, elimination tree, supernodes) is reused and only the
        numeric factorization runs (ignored when the pattern or mode differs).
    eigenvalue_floor : float, optional
        A known lower bound λ > 0 of A's smallest eigenvalue (for the global step's
        M + h² L over the free vertices: the smallest free mass, since h² L is positive
        semidefinite). Then √n ‖A‖₁ / λ bounds cond₁(A) from above (‖A⁻¹‖₁ ≤ √n ‖A⁻¹‖₂),
        and when that bound is at most :data:`CONDITION_WARNING_THRESHOLD` the condition
        estimate (several solves: at 1025² about as long as a step's worth of them) is
        not needed and is skipped.

    Attributes
    ----------
    A : scipy.sparse.csc_matrix, shape (n, n)
        The factored matrix.
    shape : tuple of int
        ``(n, n)``.
    backend : str
        The backend that ran ("cholmod" or "splu").
    analyzed : bool
        True when this factorization ran its own symbolic analysis (False: reused).
    condition_bound : float or None
        The upper bound √n ‖A‖₁ / λ of cond₁(A) from ``eigenvalue_floor`` (None without it).

    Raises
    ------
    FactorizationError
        When A is singular or not positive definite.
    """

    def __init__(self, A, *, backend: str = "auto", check_conditioning: bool = True,
                 cholmod_mode: str = "auto", reuse: Factor | None = None,
                 eigenvalue_floor: float | None = None):
        if cholmod_mode not in CHOLMOD_MODES:
            raise InputError(f"cholmod_mode: must be one of "
                             f"{', '.join(map(repr, CHOLMOD_MODES))}, got {cholmod_mode!r}")
        self.A = sp.csc_matrix(A)
        self.shape = self.A.shape
        self.backend = resolve_backend(backend)
        self.mode_reason = cholmod_mode if self.backend == "cholmod" else "SuperLU"
        self.cholmod_mode, self.analyzed = cholmod_mode, True
        if self.backend == "cholmod":
            from sksparse.cholmod import CholmodNotPositiveDefiniteError, cholesky

            self.A.sort_indices()
            same = (reuse is not None and reuse.backend == "cholmod"
                    and reuse.cholmod_mode == cholmod_mode and reuse.shape == self.shape
                    and np.array_equal(reuse.A.indptr, self.A.indptr)
                    and np.array_equal(reuse.A.indices, self.A.indices))
            try:
                with cholmod_threads(self.shape[0]):
                    if same:   # the earlier symbolic analysis, a new numeric factorization
                        self._factor, self.analyzed = reuse._factor.cholesky(self.A), False
                    elif cholmod_mode == "supernodal":   # AMD: faster to factor (factor_mode.py)
                        self._factor = cholesky(self.A, mode=cholmod_mode,
                                                ordering_method="amd")
                    else:
                        self._factor = cholesky(self.A, mode=cholmod_mode)
            except CholmodNotPositiveDefiniteError as exc:
                raise FactorizationError(f"system matrix is not positive definite: {exc}") from exc
            # For small or very sparse matrices CHOLMOD picks a simplicial LDLᵀ, which does not
            # fail on an indefinite matrix: check the signs of D (L's squared diagonal for LLᵀ).
            D = self._factor.D() if self.shape[0] else np.ones(0)
            if np.any(D <= 0) or not np.all(np.isfinite(D)):
                raise FactorizationError("system matrix is not positive definite (CHOLMOD found "
                                         f"a non-positive pivot {float(np.min(D))!r})")
            self._solve = self._factor
        else:
            if self.shape[0] == 0:
                self._solve = lambda b: np.zeros_like(b)
            else:
                # Diagonal pivots only (diag_pivot_thresh=0): then, when the row and column
                # permutations agree, U's diagonal is D of a symmetric LDLᵀ and its signs
                # decide definiteness. Off-diagonal pivots would hide an indefinite matrix.
                from scipy.sparse.linalg import splu  # loaded here only (scipy.linalg)
                try:
                    lu = splu(self.A, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                              options={"SymmetricMode": True})
                except RuntimeError as exc:  # "Factor is exactly singular"
                    raise FactorizationError(f"system matrix is singular: {exc}") from exc
                pivots = lu.U.diagonal()
                if not np.array_equal(lu.perm_r, lu.perm_c):
                    raise FactorizationError("system matrix is not positive definite "
                                             "(SuperLU needed an off-diagonal pivot)")
                if np.any(pivots <= 0) or not np.all(np.isfinite(pivots)):
                    raise FactorizationError("system matrix is not positive definite "
                                             "(SuperLU found a non-positive pivot)")
                self._solve = lu.solve
        log.debug("factored %d x %d matrix with %s", *self.shape, self.backend)
        self.condition_bound = None
        if eigenvalue_floor is not None and eigenvalue_floor > 0 and self.shape[0] > 0:
            norm_A = _norm1(self.A)
            self.condition_bound = np.sqrt(self.shape[0]) * norm_A / float(eigenvalue_floor)
        proven = (self.condition_bound is not None
                  and self.condition_bound <= CONDITION_WARNING_THRESHOLD)
        if check_conditioning and self.shape[0] > 0 and not proven:
            cond = self.condition_estimate
            if cond > CONDITION_WARNING_THRESHOLD:
                warnings.warn(f"system matrix is badly conditioned: cond1 estimate {cond:.3g} "
                              f"> {CONDITION_WARNING_THRESHOLD:.0e}; expect lost digits",
                              ConditioningWarning, stacklevel=3)

    def solve(self, b: np.ndarray) -> np.ndarray:
        """x = A⁻¹ b.

        Parameters
        ----------
        b : ndarray, shape (n,) or (n, k)
            Right-hand side(s), in the units of A x.

        Returns
        -------
        ndarray, float64, shape of b
            The solution x.
        """
        if self.shape[0] == 0:
            return np.zeros_like(b, dtype=np.float64)
        with cholmod_threads(self.shape[0] if self.backend == "cholmod" else 0, "solve"):
            return self._solve(np.ascontiguousarray(b, dtype=np.float64))

    __call__ = solve

    def solve_columns(self, bT: np.ndarray) -> np.ndarray:
        """x = A⁻¹ b for right-hand sides stored coordinate-major, bT of shape (k, n).

        Returns xᵀ, shape (k, n). CHOLMOD works on column-major (n, k) blocks, so passing
        the transpose of a C-ordered (k, n) array avoids the copy :meth:`solve` makes.

        Parameters
        ----------
        bT : ndarray, shape (k, n)
            The right-hand sides as rows (for the global step, the x, y, z columns).

        Returns
        -------
        ndarray, float64, shape (k, n)
            The solutions as rows.
        """
        if self.shape[0] == 0:
            return np.zeros_like(bT, dtype=np.float64)
        if self.backend == "cholmod":
            with cholmod_threads(self.shape[0], "solve"):
                return self._factor(bT.T).T
        return np.ascontiguousarray(self._solve(np.ascontiguousarray(bT.T)).T)

    @cached_property
    def condition_estimate(self) -> float:
        """Estimate of the 1-norm condition number ‖A‖₁ ‖A⁻¹‖₁ (‖A‖₁ exact, ‖A⁻¹‖₁ by
        Higham's onenormest)."""
        n = self.shape[0]
        if n <= 3:
            Ad = self.A.toarray()
            return float(np.linalg.cond(Ad, 1))
        import scipy.sparse.linalg as spla  # loaded here only: it brings scipy.linalg

        inv = spla.LinearOperator(self.shape, matvec=self.solve, rmatvec=self.solve,
                                  matmat=self.solve, dtype=np.float64)
        norm_A = _norm1(self.A)   # exact, and cheaper than estimated
        return norm_A * float(spla.onenormest(inv))


def _norm1(A: sp.csc_matrix) -> float:
    """‖A‖₁, the largest column sum of |A| of a CSC matrix without duplicates: the sums
    ``abs(A).sum(axis=0)`` forms (``np.add.reduceat`` over each non-empty column), without
    its copy of A (duplicates summed first, in place, as it does)."""
    A.sum_duplicates()
    nonempty = np.flatnonzero(np.diff(A.indptr))
    if not len(nonempty):
        return 0.0
    return float(np.add.reduceat(np.abs(A.data), A.indptr[nonempty]).max())


# -- helpers of the iterations around a factor --------------------------------------------
def spmv_add(A: sp.csr_matrix, v: np.ndarray, out: np.ndarray) -> None:
    """out += A v in place, for a CSR matrix A and contiguous float64 vectors.

    Parameters
    ----------
    A : csr_matrix, shape (m, n)
    v : ndarray, shape (n,), float64, contiguous
    out : ndarray, shape (m,), float64, contiguous
        Accumulated into (no temporary is allocated).
    """
    if _csr_matvec is None:  # pragma: no cover
        out += A @ v
    else:
        _csr_matvec(A.shape[0], A.shape[1], A.indptr, A.indices, A.data, v, out)


_controller = None

#: Threads of CHOLMOD's BLAS and OpenMP in the factorizations (``"factor"``) and solves
#: (``"solve"``) of matrices of :data:`THREADED_FROM` rows or more, at most the cores this
#: process may use. A large supernodal factorization is dense blocks, and CHOLMOD holds the
#: GIL while it works: the run's other threads wait, and a second core would stay idle.
#: The three-column solves are memory-bound and gained nothing from a second thread
#: (docs/performance.md, "Large cloths"). The iteration's vector operations stay on one
#: thread (:func:`single_threaded`).
CHOLMOD_THREADS = {"factor": 2, "solve": 1}
#: Rows from which CHOLMOD runs on :data:`CHOLMOD_THREADS` threads (a 317² cloth).
THREADED_FROM = 100_000


def _cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not on Linux
        return os.cpu_count() or 1


def cholmod_threads(rows: int, work: str = "factor"):
    """A context running CHOLMOD's BLAS and OpenMP on ``CHOLMOD_THREADS[work]`` threads (at
    most the cores available) for a matrix of ``rows`` >= :data:`THREADED_FROM` rows; for a
    smaller one, or one thread, it changes nothing (the caller's limit, e.g.
    :func:`single_threaded`, holds).

    The thread count is fixed by the machine, never by its load, so a run and its resumed
    continuation factor alike, bit for bit; one and two threads agree to rounding.

    Parameters
    ----------
    rows : int
        Rows of the matrix factored or solved.
    work : {"factor", "solve"}
        What CHOLMOD is about to do.

    Returns
    -------
    contextlib.AbstractContextManager
    """
    threads = min(CHOLMOD_THREADS[work], _cores()) if rows >= THREADED_FROM else 1
    controller = _pools() if threads > 1 else False
    if controller is False:
        return contextlib.nullcontext()
    return controller.limit(limits=threads, user_api=None)


def _pools():
    """The thread pools (threadpoolctl), looked up once CHOLMOD's libraries are loaded;
    False without threadpoolctl."""
    global _controller
    if _controller is None:
        try:
            from threadpoolctl import ThreadpoolController
        except ImportError:  # pragma: no cover
            _controller = False
        else:
            cholmod_available()       # load CHOLMOD's libraries first: their pools count
            _controller = ThreadpoolController()
    return _controller


def single_threaded():
    """A context limiting BLAS and OpenMP to one thread (threadpoolctl), or a no-op without it.

    An iteration's vector operations are small (microseconds to a millisecond); on a shared
    machine, BLAS worker threads that spin or wait for a busy core can stall them for far
    longer than they take. CHOLMOD's OpenMP workers gain nothing on the simplicial factor's
    three-column solves, and when left spinning they slow the main thread's memory-bound
    work (docs/performance.md). :class:`~clothsim.solvers.LocalGlobalSolver` therefore runs
    each step, its factorization included, with one thread.

    The thread pools are looked up once, after CHOLMOD's libraries (its OpenMP runtime and
    BLAS) are loaded, so they are limited too.

    Returns
    -------
    contextlib.AbstractContextManager
        ``with single_threaded(): ...`` runs its body with one BLAS and one OpenMP thread.
    """
    controller = _pools()
    if controller is False:  # pragma: no cover
        return contextlib.nullcontext()
    return controller.limit(limits=1, user_api=None)
