"""Linear algebra of a saddle-free Newton: reused Cholesky analyses and negative curvature.

:class:`ReusedCholesky` factors a sequence of symmetric matrices that share one sparsity
pattern (the Newton Hessians ∇²g(x_k), shifted or not, of one cloth) with a single CHOLMOD
symbolic analysis (``sksparse.cholmod.analyze`` once, ``cholesky_inplace`` for every
numeric factorization). Without CHOLMOD it falls back to :class:`~clothsim.factorization.Factor`
(SuperLU with its pivot check). Either way a matrix that is not positive definite raises
:class:`~clothsim.errors.FactorizationError`: it is never factored by an LU and used.

:func:`negative_curvature` finds a direction v with vᵀHv < 0 by inverse iteration on the
pencil (H, M) with the factor of the positive definite H + τM, and :func:`smallest_eigenvalue`
gives λ_min of (H, M) for the certificate of small systems.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp

from ..errors import FactorizationError, InputError
from ..factorization import Factor, resolve_backend


class ReusedCholesky:
    """Cholesky factorizations of same-pattern SPD matrices with one symbolic analysis.

    Parameters
    ----------
    backend : {"auto", "cholmod", "splu"}
        See :func:`clothsim.factorization.resolve_backend`.

    Attributes
    ----------
    backend : str
        The backend that runs ("cholmod" or "splu").
    analyses : int
        Symbolic analyses done (one per distinct sparsity pattern met).
    """

    def __init__(self, backend: str = "auto"):
        self.backend = resolve_backend(backend)
        self.analyses = 0
        self._symbolic = None
        self._pattern: tuple[np.ndarray, np.ndarray] | None = None

    def reset(self) -> None:
        """Forget the symbolic analysis (the next matrix is analyzed afresh)."""
        self._symbolic, self._pattern = None, None

    def factor(self, A: sp.spmatrix):
        """Factor the symmetric matrix A, which must be positive definite.

        Parameters
        ----------
        A : sparse matrix, shape (m, m)
            Symmetric [kg].

        Returns
        -------
        object with ``solve(b)``
            Valid until the next call of :meth:`factor` (the CHOLMOD factor is reused in place).

        Raises
        ------
        FactorizationError
            When A is not positive definite (or not finite).
        """
        A = sp.csc_matrix(A)
        if self.backend != "cholmod" or A.shape[0] == 0:
            return Factor(A, backend=self.backend, check_conditioning=False)
        from sksparse.cholmod import CholmodNotPositiveDefiniteError, analyze

        if not np.all(np.isfinite(A.data)):
            raise FactorizationError("system matrix is not finite")
        A.sort_indices()
        if (self._pattern is None or not np.array_equal(self._pattern[0], A.indptr)
                or not np.array_equal(self._pattern[1], A.indices)):
            self._symbolic = analyze(A, mode="auto")
            self._pattern = (A.indptr.copy(), A.indices.copy())
            self.analyses += 1
        try:
            self._symbolic.cholesky_inplace(A)
        except CholmodNotPositiveDefiniteError as exc:
            raise FactorizationError(f"system matrix is not positive definite: {exc}") from exc
        D = self._symbolic.D()  # LDLᵀ (simplicial) does not raise: check the pivots
        if not (np.all(np.isfinite(D)) and float(D.min()) > 0.0):
            raise FactorizationError("system matrix is not positive definite (CHOLMOD found "
                                     f"a non-positive pivot {float(np.min(D))!r})")
        return _Solve(self._symbolic)


class _Solve:
    """``solve(b)`` of a CHOLMOD factor, in the interface of :class:`Factor`."""

    backend = "cholmod"

    def __init__(self, factor):
        self._factor = factor

    def solve(self, b: np.ndarray) -> np.ndarray:
        return self._factor(np.ascontiguousarray(b, dtype=np.float64))


def negative_curvature(H: sp.spmatrix, mass: np.ndarray, shifted, *, iterations: int = 60,
                       seed: int = 0,
                       start: np.ndarray | None = None) -> tuple[np.ndarray, float] | None:
    """A direction of negative curvature of H in the metric M = diag(mass).

    Inverse iteration v ← (H + τM)⁻¹ M v with the factor of the positive definite H + τM
    converges to the eigenvector of H v = λ M v with the smallest λ; it stops once the
    Rayleigh quotient vᵀHv / vᵀMv is negative and has settled to 1e-3.

    Parameters
    ----------
    H : sparse matrix, shape (m, m)
        The (indefinite) Hessian over the free degrees of freedom [kg].
    mass : ndarray, shape (m,)
        Diagonal of M [kg].
    shifted : object with ``solve(b)``
        Factor of H + τM (positive definite).
    iterations : int
        Most inverse iterations.
    seed : int
        Seed of the random start vector (reproducible runs).
    start : ndarray, shape (m,), optional
        Start vector instead (the previous iteration's direction: a warm start).

    Returns
    -------
    (v, λ) or None
        v with vᵀMv = 1 and λ = vᵀHv < 0 (dimensionless: λ in units of M); None when no
        negative curvature was found.
    """
    if start is None:
        v = np.random.default_rng(seed).standard_normal(H.shape[0])
    else:
        noise = np.random.default_rng(seed).standard_normal(H.shape[0])
        v = start + 1e-3 * float(np.sqrt(np.mean(start * start))) * noise
    lam_old = math.inf
    best = None
    for _ in range(iterations):
        v = shifted.solve(mass * v)
        norm = math.sqrt(float(v @ (mass * v)))
        if not (norm > 0.0 and math.isfinite(norm)):
            return best
        v /= norm
        lam = float(v @ (H @ v))
        if lam < 0.0:
            best = (v.copy(), lam)
            if abs(lam - lam_old) <= 1e-3 * abs(lam):
                break
        lam_old = lam
    return best


def smallest_eigenvalue(H: sp.spmatrix, mass: np.ndarray, *, dense_limit: int = 400) -> float:
    """λ_min of H v = λ M v (M = diag(mass)), dimensionless: 1 for H = M.

    Dense (LAPACK) up to ``dense_limit`` unknowns. Above, B = M^{-1/2} H M^{-1/2} is
    factored by CHOLMOD: when that succeeds (B ≻ 0), shift-invert Lanczos about 0 with that
    factor finds λ_min in a few iterations; otherwise (or without CHOLMOD) plain Lanczos
    for the smallest algebraic eigenvalue.

    Parameters
    ----------
    H : sparse matrix, shape (m, m)
        Symmetric [kg].
    mass : ndarray, shape (m,)
        Diagonal of M [kg], positive.
    dense_limit : int
        Largest m solved densely.

    Returns
    -------
    float
        λ_min; NaN when m = 0 or Lanczos does not converge.
    """
    from scipy.sparse.linalg import ArpackNoConvergence, LinearOperator, eigsh

    if H.shape[0] == 0:
        return math.nan
    s = 1.0 / np.sqrt(mass)
    S = sp.diags(s)
    B = sp.csc_matrix(S @ sp.csr_matrix(H) @ S)
    if H.shape[0] <= dense_limit:
        return float(np.linalg.eigvalsh(B.toarray())[0])
    factor = None
    try:
        factor = ReusedCholesky("cholmod").factor(B)
    except (FactorizationError, InputError):
        pass
    try:
        if factor is not None:
            op = LinearOperator(B.shape, matvec=factor.solve, dtype=np.float64)
            return float(eigsh(B, k=1, sigma=0.0, which="LM", OPinv=op, tol=1e-10,
                               return_eigenvectors=False)[0])
        return float(eigsh(B, k=1, which="SA", tol=1e-8, maxiter=5000,
                           return_eigenvectors=False)[0])
    except ArpackNoConvergence:
        return math.nan
