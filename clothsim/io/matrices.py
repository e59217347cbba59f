"""Matrices and vectors for other implementations: Matrix Market (exact float64) and text
vectors (``%.17g``). 3n-sized objects use the interleaved layout x0 y0 z0 x1 … ."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import InputError
from .common import atomic_path, is_number, refuse_special


def _ascii_lines(path, what: str) -> list[str]:
    """The lines of an ASCII text file; a one-line InputError saying ``what`` it is not
    (with the first non-ASCII byte) or why it cannot be read."""
    try:
        return Path(path).read_bytes().decode("ascii").splitlines()
    except UnicodeDecodeError as exc:
        raise InputError(f"{path}: {what}: byte {exc.start} is not ASCII") from None
    except (OSError, MemoryError) as exc:
        raise InputError(f"{path}: cannot read ({getattr(exc, 'strerror', None) or exc})"
                         ) from None


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

    with atomic_path(path) as tmp, open(tmp, "wb") as f:
        scipy.io.mmwrite(f, A, precision=17)


def read_matrix(path):
    """Read a Matrix Market file: a ``scipy.sparse`` CSR matrix if stored sparse, else an
    ndarray.

    clothsim's own strict reader (scipy's ``mmread`` can crash the process on some malformed
    files): the header ``%%MatrixMarket matrix coordinate|array real|integer|pattern
    general|symmetric|skew-symmetric``, ``%`` comment lines, the size line, then exactly the
    entries it announces, each checked (1-based indices within the size, numbers).

    Parameters
    ----------
    path : str or path-like
        A ``.mtx`` file, e.g. written by :func:`write_matrix`.

    Returns
    -------
    scipy.sparse.csr_matrix or ndarray, shape (r, c)
        The matrix as stored (float64).

    Raises
    ------
    InputError
        A missing or special file, or a malformed one: one line naming the file and, where
        there is one, the line.
    """
    import scipy.sparse

    path = Path(path)
    refuse_special(path)
    if not path.is_file():
        raise InputError(f"matrix: file not found: {path}")
    lines = _ascii_lines(path, "not a Matrix Market file")
    head = lines[0].split() if lines else []
    if (len(head) != 5 or head[0].lower() != "%%matrixmarket" or head[1].lower() != "matrix"
            or head[2].lower() not in ("coordinate", "array")
            or head[3].lower() not in ("real", "integer", "pattern")
            or head[4].lower() not in ("general", "symmetric", "skew-symmetric")):
        raise InputError(f"{path}: line 1: not a real Matrix Market header (expected "
                         "'%%MatrixMarket matrix coordinate real general')")
    layout, field, symmetry = head[2].lower(), head[3].lower(), head[4].lower()
    if layout == "array" and field == "pattern":
        raise InputError(f"{path}: line 1: an array matrix cannot be 'pattern'")
    i = 1
    while i < len(lines) and (not lines[i].strip() or lines[i].lstrip().startswith("%")):
        i += 1
    if i == len(lines):
        raise InputError(f"{path}: no size line")
    size = lines[i].split()
    want = 3 if layout == "coordinate" else 2
    if len(size) != want or not all(t.isdigit() for t in size):
        raise InputError(f"{path}: line {i + 1}: expected {want} non-negative integers "
                         f"(rows columns{' entries' if want == 3 else ''})")
    rows, cols = int(size[0]), int(size[1])
    count = int(size[2]) if want == 3 else rows * cols
    if rows > 1 << 31 or cols > 1 << 31 or count > 1 << 31:
        raise InputError(f"{path}: line {i + 1}: size {rows} x {cols} ({count} entries) is "
                         "too large")
    if symmetry != "general" and rows != cols:
        raise InputError(f"{path}: line {i + 1}: a {symmetry} matrix must be square")
    per = (2 if field == "pattern" else 3) if layout == "coordinate" else 1
    body = [(n + 1, ln.split()) for n, ln in enumerate(lines[i + 1:], start=i)
            if ln.strip() and not ln.lstrip().startswith("%")]
    if len(body) != count:
        raise InputError(f"{path}: the size line announces {count} entries, the file holds "
                         f"{len(body)}")
    for n, tokens in body:
        if len(tokens) != per:
            raise InputError(f"{path}: line {n}: expected {per} numbers, got {len(tokens)}")
    flat = [t for _, tokens in body for t in tokens]
    try:
        values = np.array(flat, dtype=np.float64).reshape(count, per)
    except ValueError:
        n, bad = next((n, t) for n, tokens in body for t in tokens if not is_number(t))
        raise InputError(f"{path}: line {n}: not a number: {bad[:40]!r}") from None
    if layout == "array":
        if symmetry != "general":
            raise InputError(f"{path}: a {symmetry} array matrix is not supported")
        return values.reshape(cols, rows).T.copy()  # column-major
    ij = values[:, :2]
    if not np.all(ij == np.round(ij)):
        n = body[int(np.flatnonzero((ij != np.round(ij)).any(axis=1))[0])][0]
        raise InputError(f"{path}: line {n}: indices must be integers")
    r, c = ij[:, 0].astype(np.int64) - 1, ij[:, 1].astype(np.int64) - 1
    out = (r < 0) | (r >= rows) | (c < 0) | (c >= cols)
    if out.any():
        n = body[int(np.flatnonzero(out)[0])][0]
        raise InputError(f"{path}: line {n}: index outside the {rows} x {cols} matrix")
    v = np.ones(count) if field == "pattern" else values[:, 2]
    if symmetry != "general":
        off = r != c
        sign = -1.0 if symmetry == "skew-symmetric" else 1.0
        r, c, v = (np.concatenate([r, c[off]]), np.concatenate([c, r[off]]),
                   np.concatenate([v, sign * v[off]]))
    return scipy.sparse.csr_matrix((v, (r, c)), shape=(rows, cols))


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
    with atomic_path(path) as tmp:
        np.savetxt(tmp, np.asarray(v, dtype=np.float64).ravel(), fmt="%.17g")


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
    if not Path(path).is_file():
        raise InputError(f"vector: file not found: {path}")
    lines = _ascii_lines(path, "not a text file of numbers")
    values = []
    for n, line in enumerate(lines, start=1):
        for token in line.split("#", 1)[0].split():
            if not is_number(token):
                raise InputError(f"{path}: line {n}: not a number: {token[:40]!r}")
            values.append(float(token))
    if not values:
        raise InputError(f"{path}: no numbers")
    return np.array(values, dtype=np.float64)
