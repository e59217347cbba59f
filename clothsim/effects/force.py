"""A constant external force in newtons on each vertex: f_i, the same at every step.

Where :class:`~clothsim.effects.gravity.Gravity` applies m_i g (an acceleration), this
applies a force: the assignment's ``main.cpp`` adds −9.8 N to every vertex whatever its
mass, and a port's force file lists one force per vertex. The force enters the step's
objective as −h² xᵀ f (``docs/math.md``), like gravity's.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import InputError, check_finite
from .base import Effect


def read_forces(path) -> np.ndarray:
    """Forces from a text file: n lines of 3 numbers [N] (``#`` starts a comment).

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    ndarray, shape (n, 3), float64

    Raises
    ------
    InputError
        Naming the file, on an unreadable file, a line without 3 numbers or a non-finite
        value.
    """
    p = Path(path)
    rows = []
    if p.exists() and not p.is_file() and not p.is_dir():  # a FIFO blocks, /dev/zero never ends
        raise InputError(f"force.file: {p} is a FIFO or a device, not a regular file")
    try:
        lines = p.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"force.file: cannot read {p}: {exc}") from None
    for i, line in enumerate(lines, 1):
        words = line.split("#", 1)[0].replace(",", " ").split()
        if not words:
            continue
        try:
            row = [float(w) for w in words]
        except ValueError:
            raise InputError(f"force.file: {p}, line {i}: expected 3 numbers, got "
                             f"{line.strip()[:40]!r}") from None
        if len(row) != 3 or not np.all(np.isfinite(row)):
            raise InputError(f"force.file: {p}, line {i}: expected 3 finite numbers, got "
                             f"{line.strip()[:40]!r}")
        rows.append(row)
    return np.array(rows, dtype=np.float64).reshape(-1, 3)


class Force(Effect):
    """A constant force per vertex [N], e.g. the assignment's −9.8 N on every vertex.

    Parameters
    ----------
    per_vertex : array_like, shape (3,) or (p, 3), optional
        The force on each vertex [N]: one vector for every vertex (or every vertex of
        ``vertices``), or one row per vertex (per listed vertex).
    vertices : array_like of int, optional
        The vertices that carry the force (0-based); default every vertex.
    file : str or path, optional
        A text file of one force per vertex (n lines of 3 numbers) [N], instead of
        ``per_vertex``.

    Examples
    --------
    >>> import clothsim as cs
    >>> model = cs.Model.build(cs.grid(2, 2), cs.Springs.concatenate([]), total_mass=4.0)
    >>> sim = cs.Simulation(model, h=0.1, effects=[cs.Force([0.0, -9.8, 0.0])])
    >>> float(sim.problem().f_ext[:, 1].sum())   # newtons, whatever the masses
    -39.2
    """

    kind = "force"

    def __init__(self, per_vertex=None, *, vertices=None, file=None):
        if (per_vertex is None) == (file is None):
            raise InputError("force: give exactly one of 'per_vertex' or 'file'")
        self.file = None if file is None else str(file)
        f = read_forces(file) if file is not None else check_finite("force.per_vertex",
                                                                     per_vertex)
        if f.shape != (3,) and (f.ndim != 2 or f.shape[1] != 3):
            raise InputError(f"force.per_vertex: expected 3 numbers or rows of 3, got shape "
                             f"{f.shape}")
        self.per_vertex = f
        self.vertices = None
        if vertices is not None:
            v = np.asarray(vertices)
            if v.size and (not np.issubdtype(v.dtype, np.number)
                           or not np.all(np.mod(v, 1) == 0)):
                raise InputError("force.vertices: must be integer vertex indices")
            self.vertices = v.astype(np.int64).reshape(-1)
            if f.ndim == 2 and len(f) != len(self.vertices):
                raise InputError(f"force.per_vertex: {len(f)} rows for "
                                 f"{len(self.vertices)} vertices")

    def bind(self, model, h):
        super().bind(model, h)
        n = model.vertex_count
        where = np.arange(n) if self.vertices is None else self.vertices
        bad = np.flatnonzero((where < 0) | (where >= n))
        if len(bad):
            raise InputError(f"force.vertices[{bad[0]}]: vertex {where[bad[0]]} out of range "
                             f"0..{n - 1}")
        if self.per_vertex.ndim == 2 and len(self.per_vertex) != len(where):
            name = "file" if self.file is not None else "per_vertex"
            raise InputError(f"force.{name}: {len(self.per_vertex)} forces for {len(where)} "
                             f"vertices")
        self._force = np.zeros((n, 3))
        np.add.at(self._force, where, np.broadcast_to(self.per_vertex, (len(where), 3)))

    def add_force(self, t, state, f):
        f += self._force

    def describe(self):
        out = {"kind": self.kind, "unit": "N"}
        if self.file is not None:
            out["file"] = self.file
        else:
            out["per_vertex"] = self.per_vertex.tolist()
        if self.vertices is not None:
            out["vertices"] = self.vertices.tolist()
        return out


__all__ = ["Force", "read_forces"]
