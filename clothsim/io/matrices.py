"""Matrices and vectors for other implementations: Matrix Market (exact float64) and text
vectors (``%.17g``). 3n-sized objects use the interleaved layout x0 y0 z0 x1 … ."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import InputError
from .common import refuse_special


def write_matrix(path, A) -> None:
    """Write a sparse or dense matrix in Matrix Market format, float64 round-trip exact.

    Use a ``.mtx`` name. The 3n × 3n matrices (M, L, M + h²L) and the 3n × 3s matrix J use
    the interleaved layout of docs/ports.md: row 3 i + c is coordinate c of vertex i.

    Parameters
    ----------
    path : str or path-like
        The ``.mtx`` file to write (overwritten).
    A : scipy.sparse matrix or array_like, shape (r, c)
        The matrix, in the units of what it holds (e.g. M in [kg], L in [N/m]).
    """
    import scipy.io

    with open(path, "wb") as f:
        scipy.io.mmwrite(f, A, precision=17)


def read_matrix(path):
    """Read a Matrix Market file: a ``scipy.sparse`` CSR matrix if stored sparse, else an
    ndarray.

    Parameters
    ----------
    path : str or path-like
        A ``.mtx`` file, e.g. written by :func:`write_matrix`.

    Returns
    -------
    scipy.sparse.csr_matrix or ndarray, shape (r, c)
        The matrix as stored (float64 for real files).

    Raises
    ------
    InputError
        When the file does not exist.
    """
    import scipy.io
    import scipy.sparse

    path = Path(path)
    refuse_special(path)
    if not path.is_file():
        raise InputError(f"matrix: file not found: {path}")
    A = scipy.io.mmread(path)
    return scipy.sparse.csr_matrix(A) if scipy.sparse.issparse(A) else np.asarray(A)


def write_vector(path, v) -> None:
    """Write a vector as text, one number per line with ``%.17g`` (exact float64).

    Parameters
    ----------
    path : str or path-like
        The text file to write (overwritten).
    v : array_like
        The values; flattened in C order, so an (n, 3) array gives the interleaved
        layout x0 y0 z0 x1 ... .
    """
    np.savetxt(path, np.asarray(v, dtype=np.float64).ravel(), fmt="%.17g")


def read_vector(path) -> np.ndarray:
    """Read a vector written by :func:`write_vector`, shape (k,).

    Parameters
    ----------
    path : str or path-like
        A text file with one number per line.

    Returns
    -------
    ndarray, shape (k,)
        The float64 values (k = 1 for a single number).
    """
    refuse_special(path)
    return np.atleast_1d(np.loadtxt(path, dtype=np.float64))
