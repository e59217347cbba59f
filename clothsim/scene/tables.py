"""Plain-text model files named in a scene: vertices, triangles, spring tables, values.

Every file is whitespace-separated numbers, one record a line; blank lines and everything
after ``#`` are ignored. Errors name the scene key and the file's line, e.g.
``cloth.vertices: line 3 of x0.txt: expected 3 numbers, got 2``.

Examples
--------
>>> import tempfile, pathlib
>>> p = pathlib.Path(tempfile.mkdtemp()) / "x.txt"
>>> _ = p.write_text("0 0 0  1 0 0  0 1 0\\n")
>>> read_vertices(p, "cloth.vertices").shape
(3, 3)
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from ..io.common import file_stamp
from .checks import Invalid
from .effects import MAX_LENGTH


def _rows(path, key: str) -> list[tuple[int, list[float]]]:
    """(line number, numbers) of every non-empty line."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise Invalid(key, f"cannot read {p.name}: {exc}") from None
    out = []
    for i, line in enumerate(text.splitlines(), start=1):
        words = line.split("#", 1)[0].split()
        if not words:
            continue
        try:
            values = [float(w) for w in words]
        except ValueError:
            bad = next(w for w in words if not _is_float(w))
            raise Invalid(key, f"line {i} of {p.name}: not a number: {_token(bad)}") from None
        for w, v in zip(words, values):
            if not np.isfinite(v):
                raise Invalid(key, f"line {i} of {p.name}: must be a finite number, got "
                                   f"{w if len(w) <= 24 else _token(w)}")
        out.append((i, values))
    if not out:
        raise Invalid(key, f"{p.name} holds no numbers")
    return out


def _token(w: str) -> str:
    """The offending word for a message: short printable words as they are, others by
    length only (a file that is no table, e.g. ``/proc/self/environ``, is not echoed)."""
    return repr(w) if len(w) <= 24 and w.isprintable() else f"a {len(w)}-character word"


def _is_float(w: str) -> bool:
    try:
        float(w)
    except ValueError:
        return False
    return True


def read_vertices(path, key: str) -> np.ndarray:
    """Positions from n lines of 3 numbers, or one line of 3n numbers.

    Parameters
    ----------
    path : str or Path
        The text file (blank lines and ``#`` comments skipped).
    key : str
        The scene key naming the file, for error messages.

    Returns
    -------
    ndarray, shape (n, 3), float64
        [m].
    """
    rows = _rows(path, key)
    name = Path(path).name
    if len(rows) == 1:
        line, values = rows[0]
        if len(values) % 3:
            raise Invalid(key, f"line {line} of {name}: one line must hold 3n numbers "
                               f"(x y z per vertex), got {len(values)}")
        x = np.asarray(values, dtype=np.float64).reshape(-1, 3)
        lines = [line] * len(x)
    else:
        for line, values in rows:
            if len(values) != 3:
                raise Invalid(key, f"line {line} of {name}: expected 3 numbers (x y z), got "
                                   f"{len(values)}")
        x, lines = np.asarray([v for _, v in rows], dtype=np.float64), [r[0] for r in rows]
    far = np.flatnonzero((np.abs(x) > MAX_LENGTH).any(axis=1))
    if len(far):  # squares of such coordinates overflow float64 in every step
        raise Invalid(key, f"line {lines[far[0]]} of {name}: coordinates must be within "
                           f"±{MAX_LENGTH:g} m, got {float(np.abs(x[far[0]]).max()):.3g}")
    return x


def _indices(values, line: int, name: str, key: str, base: int, count: int | None,
             allow=()) -> list[int]:
    out = []
    for v in values:
        if v != int(v) or abs(v) > 2**62:
            raise Invalid(key, f"line {line} of {name}: vertex indices must be integers, got "
                               f"{v!r}")
        i = int(v)
        if i in allow:
            out.append(i)
            continue
        j = i - base
        if j < 0 or (count is not None and j >= count):
            hi = "" if count is None else f"..{count - 1 + base}"
            raise Invalid(key, f"line {line} of {name}: vertex {i} out of range {base}{hi} "
                               f"(index_base = {base})")
        out.append(j)
    return out


def read_triangles(path, key: str, base: int, vertex_count: int) -> np.ndarray:
    """Triangles from lines of 3 vertex indices numbered from ``base``.

    Parameters
    ----------
    path : str or Path
        The text file (blank lines and ``#`` comments skipped).
    key : str
        The scene key naming the file, for error messages.
    base : int
        Number of the first vertex in the file (0 or 1).
    vertex_count : int
        n; every index must be in range.

    Returns
    -------
    ndarray, shape (t, 3), int64
        0-based.
    """
    name = Path(path).name
    tris = []
    for line, values in _rows(path, key):
        if len(values) != 3:
            raise Invalid(key, f"line {line} of {name}: expected 3 vertex indices, got "
                               f"{len(values)}")
        tris.append(_indices(values, line, name, key, base, vertex_count))
    return np.asarray(tris, dtype=np.int64).reshape(-1, 3)


def read_values(path, key: str) -> np.ndarray:
    """Every number of a file, in order (e.g. one mass per vertex), shape (m,).

    Parameters
    ----------
    path : str or Path
        The text file (blank lines and ``#`` comments skipped).
    key : str
        The scene key naming the file, for error messages.

    Returns
    -------
    ndarray, shape (m,), float64
        The numbers, in the unit the key gives (e.g. [kg]).
    """
    return np.asarray([v for _, vs in _rows(path, key) for v in vs], dtype=np.float64)


def read_index_list(path, key: str, base: int, vertex_count: int) -> np.ndarray:
    """Vertex indices (numbered from ``base``), any number a line; 0-based, shape (p,).

    Parameters
    ----------
    path : str or Path
        The text file (blank lines and ``#`` comments skipped).
    key : str
        The scene key naming the file, for error messages.
    base : int
        Number of the first vertex in the file (0 or 1).
    vertex_count : int
        n; every index must be in range.

    Returns
    -------
    ndarray, shape (p,), int64
        0-based vertex indices, in file order.
    """
    name = Path(path).name
    out = []
    for line, values in _rows(path, key):
        out += _indices(values, line, name, key, base, vertex_count)
    return np.asarray(out, dtype=np.int64)


@dataclass(frozen=True, eq=False)
class SpringTable:
    """A spring table as read.

    Attributes
    ----------
    pairs : ndarray, shape (s, 2), int64
        0-based end vertices.
    stiffness : ndarray, shape (s,)
        k [N/m].
    rest : ndarray, shape (s,)
        Rest length [m]; NaN where the table has no ``rest`` column (use the initial length).
    attached : ndarray, shape (p,), int64
        Vertices of the attachment rows (``b`` = −1), in file order.
    attached_stiffness : ndarray, shape (p,)
        Their stiffness [N/m].
    damping : ndarray, shape (s,)
        Damping c [N·s/m] of each spring (0 without a ``damping`` column).
    """

    pairs: np.ndarray
    stiffness: np.ndarray
    rest: np.ndarray
    attached: np.ndarray
    attached_stiffness: np.ndarray
    damping: np.ndarray


def read_spring_table(path, key: str, columns: list[str], base: int,
                      vertex_count: int) -> SpringTable:
    """Read a spring table (see :class:`SpringTable`); checks every row.

    Parameters
    ----------
    path : str or Path
        The text file (blank lines and ``#`` comments skipped).
    key : str
        The scene key naming the file, for error messages.
    columns : list of str
        The meaning of each column: ``"a"``, ``"b"``, ``"stiffness"`` [N/m] and optionally
        ``"rest"`` [m]; ``b`` = −1 marks an attachment of ``a``.
    base : int
        Number of the first vertex in the file (0 or 1).
    vertex_count : int
        n; every index must be in range.

    Returns
    -------
    SpringTable
        Springs (s, 2), stiffness (s,) [N/m], rest lengths (s,) [m] and attachments
        (cached by path and :func:`~clothsim.io.common.file_stamp`: an edit is read again).
    """
    p = Path(path).resolve()
    return _read_table(str(p), file_stamp(p), key, tuple(columns), base, vertex_count)


@lru_cache(maxsize=8)
def _read_table(path: str, stamp: tuple | None, key: str, columns: tuple, base: int,
                vertex_count: int) -> SpringTable:
    name = Path(path).name
    col = {c: i for i, c in enumerate(columns)}
    pairs, ks, rests, att, att_k, cs = [], [], [], [], [], []
    for line, values in _rows(path, key):
        if len(values) != len(columns):
            raise Invalid(key, f"line {line} of {name}: expected {len(columns)} numbers "
                               f"({' '.join(columns)}), got {len(values)}")
        a, b = _indices([values[col["a"]], values[col["b"]]], line, name, key, base,
                        vertex_count, allow=(-1,))
        if a == -1:
            raise Invalid(key, f"line {line} of {name}: a = -1; only b may mark an "
                               f"attachment")
        k = values[col["stiffness"]]
        if k < 0:
            raise Invalid(key, f"line {line} of {name}: stiffness must be non-negative, got "
                               f"{k!r}")
        rest = values[col["rest"]] if "rest" in col else float("nan")
        c = values[col["damping"]] if "damping" in col else 0.0
        if c < 0:
            raise Invalid(key, f"line {line} of {name}: damping must be non-negative, got "
                               f"{c!r}")
        if b == -1:
            if "rest" in col and rest != 0:
                raise Invalid(key, f"line {line} of {name}: an attachment (b = -1) must have "
                                   f"rest length 0, got {rest!r}")
            if k <= 0:
                raise Invalid(key, f"line {line} of {name}: an attachment needs a positive "
                                   f"stiffness, got {k!r}")
            if a in att:
                raise Invalid(key, f"line {line} of {name}: vertex {a + base} is attached "
                                   f"twice")
            att.append(a)
            att_k.append(k)
            continue
        if a == b:
            raise Invalid(key, f"line {line} of {name}: a spring joins vertex {a + base} to "
                               f"itself")
        if "rest" in col and rest < 0:
            raise Invalid(key, f"line {line} of {name}: rest length must be non-negative, "
                               f"got {rest!r}")
        pairs.append((a, b))
        ks.append(k)
        rests.append(rest)
        cs.append(c)
    out = SpringTable(np.asarray(pairs, np.int64).reshape(-1, 2), np.asarray(ks, float),
                      np.asarray(rests, float), np.asarray(att, np.int64),
                      np.asarray(att_k, float), np.asarray(cs, float))
    for a in (out.pairs, out.stiffness, out.rest, out.attached, out.attached_stiffness,
              out.damping):
        a.flags.writeable = False
    return out


__all__ = ["read_vertices", "read_triangles", "read_values", "read_index_list",
           "read_spring_table", "SpringTable"]
