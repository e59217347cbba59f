"""Compare a port's matrices with clothsim's: sparse all the way, never densified.

A port may store its penalty pins ("attachments") as extra constraint columns of J, first;
:func:`attachment_columns` finds them so that the spring columns can be compared
(docs/ports.md).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .. import io
from ..errors import InputError
from ..io.folders import require_complete


@dataclass
class MatrixComparison:
    """Outcome of :func:`compare_matrices`.

    Attributes
    ----------
    passed : bool
        True when max |A − B| ≤ atol + rtol · max |B|.
    error : float
        max |A − B| / max |B| over the union of the sparsity patterns (the absolute error
        when B is zero).
    shape : tuple of int
        Shape of the compared matrices (after dropping columns).
    dropped : int
        Columns of the port's matrix left out first (its attachment columns).
    """

    passed: bool
    error: float
    shape: tuple
    dropped: int = 0

    def summary(self) -> str:
        """One line: PASS or FAIL, the shape, dropped columns and the relative error.

        Returns
        -------
        str
        """
        extra = f" after dropping {self.dropped} attachment columns" if self.dropped else ""
        return (f"{'PASS' if self.passed else 'FAIL'}: {self.shape[0]} x {self.shape[1]}"
                f"{extra}, max |A - B| / max |B| = {self.error:.3e}")


def compare_matrices(path, reference, *, rtol: float = 1e-12, atol: float = 0.0,
                     drop_columns=None) -> MatrixComparison:
    """Compare two sparse matrices (Matrix Market files or scipy.sparse), never densified.

    Parameters
    ----------
    rtol, atol : float
        Pass when max |A − B| ≤ atol + rtol · max |B| (entries over the union of patterns).
    drop_columns : "attachments" or sequence of int, optional
        Columns of ``path`` to leave out first. ``"attachments"`` drops the leading columns
        that each touch a single vertex (one nonzero 3 × 3 block): a port storing penalty
        pins as extra constraint columns of J, first (see docs/ports.md).

    Returns
    -------
    MatrixComparison
    """
    for p in (path, reference):
        if not sp.issparse(p):
            require_complete(p)  # an export being written may hold an earlier one's matrices
    A = sp.csr_matrix(io.read_matrix(path) if not sp.issparse(path) else path)
    B = sp.csr_matrix(io.read_matrix(reference) if not sp.issparse(reference) else reference)
    dropped = 0
    if drop_columns is not None:
        if isinstance(drop_columns, str):
            drop_columns = attachment_columns(A)
        dropped = len(drop_columns)
        keep = np.setdiff1d(np.arange(A.shape[1]), np.asarray(drop_columns, np.int64))
        A = A[:, keep]
    if A.shape != B.shape:
        raise InputError(f"matrix: shapes differ: {A.shape} vs reference {B.shape}")
    D = (A - B).tocoo()
    scale = abs(B).max() if B.nnz else 0.0
    err = float(np.abs(D.data).max()) if D.nnz else 0.0
    rel = err / scale if scale else err
    return MatrixComparison(bool(err <= atol + rtol * scale), rel, A.shape, dropped)


def attachment_columns(J) -> np.ndarray:
    """Leading columns of a 3n × 3c J whose column triple touches one vertex only.

    Spring columns touch two vertices (+k at a, −k at b); an attachment (zero-rest-length
    spring to a fixed point) touches one.

    Parameters
    ----------
    J : sparse matrix or array_like, shape (3n, 3c)
        A port's J in the paper's 3n form (interleaved x y z per vertex) [N/m].

    Returns
    -------
    ndarray of int
        The indices of the leading attachment columns (three per attachment), to drop
        before comparing J with clothsim's.
    """
    J = sp.csc_matrix(J)
    out = []
    for c in range(0, J.shape[1], 3):
        rows = J[:, c:c + 3].tocoo().row
        if len(np.unique(rows // 3)) != 1:
            break
        out.extend(range(c, c + 3))
    return np.asarray(out, np.int64)
