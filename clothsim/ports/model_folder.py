"""One side of ``diff-model``: a model, its external forces and its step settings, as tables.

A side is a scene (name, ``.toml`` path or :class:`~clothsim.scene.Scene`), a Simulation (or
a function returning one), or a folder of plain files, the **port model folder** that
:func:`clothsim.ports.export.export_port` writes and a port may write too:

``vertices.txt`` (n lines x y z) or ``x0.txt`` (one line of 3n numbers)
    Initial positions [m]; vertices are paired by them, so the two sides may number them
    differently.
``springs.txt``
    ``a b k r`` (0-based vertices, N/m, m), optionally a fifth column ``damping`` [N·s/m]
    when the header names it; or a port's dump like the shared ``liu13-port`` data,
    ``type a b k rest`` with type 0 an attachment (a penalty pin: a zero-rest-length spring
    of vertex a to its initial position, b = −1), recognised by its header ``# type``.
``masses.txt`` (optional)
    n vertex masses [kg].
``pins.txt`` (optional)
    ``vertex method stiffness x y z``: method 0 exact (stiffness 0), 1 penalty [N/m].
``forces.txt`` (optional)
    n lines ``fx fy fz``: the external force on each vertex at the first step [N], gravity
    included.
``settings.txt`` (optional)
    ``key value`` lines: ``h``, ``iterations``, ``tolerance``, ``initial_guess``,
    ``method``, ``precision``, ``damping``.

A malformed file is an :class:`~clothsim.errors.InputError` naming the file and the line.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..io.common import is_number
from ..io.folders import require_complete
from .check import as_simulation

#: The step settings diff-model compares, with their units.
SETTING_UNITS = {"h": "s", "iterations": "", "tolerance": "", "initial_guess": "",
                 "method": "", "precision": "", "damping": ""}


@dataclass
class ModelTables:
    """A model as plain tables (what two implementations can agree on).

    Attributes
    ----------
    x0 : ndarray, shape (n, 3)
        Initial positions [m].
    springs : ndarray, shape (s, 2), int
        End vertices (a_i, b_i).
    stiffness, rest : ndarray, shape (s,)
        k_i [N/m] and r_i [m].
    masses : ndarray, shape (n,) or None
        Vertex masses [kg] (None: unknown).
    pins : dict
        vertex → (method, stiffness [N/m]); stiffness None for exact pins.
    source : str
    forces : ndarray, shape (n, 3) or None
        External force on each vertex at the first step [N], gravity included (None:
        unknown).
    damping : ndarray, shape (s,) or None
        Per-spring damping [N·s/m] (None: unknown, read as 0).
    settings : dict
        Step settings (keys of :data:`SETTING_UNITS`) that this side states.
    """

    x0: np.ndarray
    springs: np.ndarray
    stiffness: np.ndarray
    rest: np.ndarray
    masses: np.ndarray | None
    pins: dict
    source: str = ""
    forces: np.ndarray | None = None
    damping: np.ndarray | None = None
    settings: dict = field(default_factory=dict)


def damping_text(effects) -> str:
    """The velocity-changing damping effects as one token: ``model:coefficient,…`` or none.

    Parameters
    ----------
    effects : sequence of Effect

    Returns
    -------
    str
    """
    parts = [f"{e.damping_model}:{e.coefficient:.17g}" for e in effects
             if getattr(e, "kind", "") == "damping"]
    return ",".join(parts) if parts else "none"


def _from_simulation(sim, source: str) -> ModelTables:
    m = sim.model
    p = sim.problem(sim.state)
    pins = {int(v): ("constraint", None) for v in p.fixed_vertices}
    pins |= {int(v): ("penalty", float(k)) for v, k in zip(p.anchor_vertices, p.anchor_stiffness)}
    forces = np.zeros((m.vertex_count, 3)) if p.f_ext is None else np.array(p.f_ext, float)
    settings = {"h": float(sim.h), "iterations": int(sim.solver.iterations),
                "tolerance": float(sim.solver.tolerance or 0.0),
                "initial_guess": sim.initial_guess, "method": sim.solver.name,
                "precision": "float64", "damping": damping_text(sim.effects)}
    return ModelTables(m.mesh.vertices, m.springs.spring_vertices, m.springs.spring_stiffness,
                       m.springs.spring_rest_length, m.vertex_mass, pins, source, forces,
                       np.array(m.springs.spring_damping, float), settings)


def read_table(path: Path, columns, what: str, *, empty: bool = False) -> np.ndarray:
    """Rows of numbers of a plain file, ``#`` comments and blank lines skipped.

    Parameters
    ----------
    path : Path
    columns : int, tuple of int or None
        The allowed numbers per line (None: any; every line must have the same).
    what : str
        What a line holds, for the error message ("a b k r").
    empty : bool, default False
        Allow a file without rows (``pins.txt`` of an unpinned cloth).

    Returns
    -------
    ndarray, shape (rows, columns)

    Raises
    ------
    InputError
        ``path: line N: …`` naming the first bad token, or the count of numbers.
    """
    allowed = (columns,) if isinstance(columns, int) else columns
    rows, width = [], None
    try:
        text = path.read_text()
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: cannot be read ({exc.__class__.__name__}: {exc})") from None
    for number, line in enumerate(text.splitlines(), 1):
        body = line.split("#", 1)[0].strip()
        if not body:
            continue
        tokens = body.split()
        try:
            row = [float(t) for t in tokens]
        except ValueError:
            bad = next(t for t in tokens if not is_number(t))
            raise InputError(f"{path}: line {number}: not a number: {bad[:40]!r} (a line "
                             f"holds {what})") from None
        if (allowed is not None and len(row) not in allowed) or (width is not None
                                                                and len(row) != width):
            want = width if width is not None else " or ".join(map(str, allowed))
            raise InputError(f"{path}: line {number}: {len(row)} numbers, expected {want} "
                             f"({what})")
        if not np.all(np.isfinite(row)):
            bad = next(t for t, v in zip(tokens, row) if not np.isfinite(v))
            raise InputError(f"{path}: line {number}: not a finite number: {bad[:40]!r}")
        width = len(row)
        rows.append(row)
    if not rows and not empty:
        raise InputError(f"{path}: no rows ({what})")
    if not rows:
        return np.zeros((0, allowed[0] if allowed else 0))
    return np.array(rows, dtype=np.float64)


def _read_settings(path: Path) -> dict:
    out = {}
    for number, line in enumerate(path.read_text().splitlines(), 1):
        body = line.split("#", 1)[0].strip()
        if not body:
            continue
        parts = body.split()
        if len(parts) != 2:
            raise InputError(f"{path}: line {number}: expected 'key value', got "
                             f"{len(parts)} words")
        key, value = parts
        if key not in SETTING_UNITS:
            continue   # frames and keys of other tools: not part of the step
        try:
            out[key] = (float(value) if key in ("h", "tolerance") else
                        int(float(value)) if key == "iterations" else value)
        except ValueError:
            raise InputError(f"{path}: line {number}: {key}: expected a number, got "
                             f"{value[:40]!r}") from None
    return out


def _header(path: Path) -> str:
    with path.open() as f:
        first = f.readline()
    return first.lstrip("#").strip().lower() if first.startswith("#") else ""


def _count_check(path: Path, rows: np.ndarray, n: int) -> None:
    if len(rows) != n:
        raise InputError(f"{path}: {len(rows)} rows for {n} vertices")


def _from_folder(d: Path) -> ModelTables:
    require_complete(d)  # an export being written may hold an earlier one's model files
    if (d / "vertices.txt").is_file():
        x0 = read_table(d / "vertices.txt", 3, "x y z")
    elif (d / "x0.txt").is_file():
        flat = read_table(d / "x0.txt", None, "3n coordinates").ravel()
        if len(flat) % 3:
            raise InputError(f"{d / 'x0.txt'}: {len(flat)} numbers, not a multiple of 3")
        x0 = flat.reshape(-1, 3)
    else:
        raise InputError(f"{d}: no vertices.txt or x0.txt")
    n = len(x0)
    path = d / "springs.txt"
    if not path.is_file():
        raise InputError(f"{d}: no springs.txt")
    header = _header(path)
    pins, damping = {}, None
    if header.startswith("type"):
        rows = read_table(path, 5, "type a b k rest")
        att = rows[rows[:, 0] == 0]
        pins = {int(r[1]): ("penalty", float(r[3])) for r in att}
        rows = rows[rows[:, 0] != 0][:, 1:]
    elif "damping" in header:
        rows = read_table(path, 5, "a b k r damping")
        damping = rows[:, 4]
    else:
        rows = read_table(path, 4, "a b k r")
    ends = rows[:, :2]
    if np.any(ends != np.round(ends)) or ends.min() < 0 or ends.max() >= n:
        bad = int(np.flatnonzero(np.any((ends != np.round(ends)) | (ends < 0) | (ends >= n),
                                        axis=1))[0])
        raise InputError(f"{path}: spring {bad}: end vertices must be integers in "
                         f"[0, {n}), got {ends[bad].tolist()}")
    if (d / "pins.txt").is_file():
        for r in read_table(d / "pins.txt", 6, "vertex method stiffness x y z",
                            empty=True):
            if r[0] != round(r[0]) or not 0 <= r[0] < n:
                raise InputError(f"{d / 'pins.txt'}: vertex {r[0]:g} is not in [0, {n})")
            pins[int(r[0])] = ("penalty", float(r[2])) if r[1] else ("constraint", None)
    masses = forces = None
    if (d / "masses.txt").is_file():
        masses = read_table(d / "masses.txt", 1, "mass").ravel()
        _count_check(d / "masses.txt", masses, n)
        if np.any(masses < 0):
            i = int(np.flatnonzero(masses < 0)[0])
            raise InputError(f"{d / 'masses.txt'}: vertex {i}: mass {masses[i]:g} kg is "
                             f"negative (0 means pinned)")
    if (d / "forces.txt").is_file():
        forces = read_table(d / "forces.txt", 3, "fx fy fz")
        _count_check(d / "forces.txt", forces, n)
    settings = _read_settings(d / "settings.txt") if (d / "settings.txt").is_file() else {}
    return ModelTables(x0, ends.astype(np.int64), rows[:, 2], rows[:, 3], masses, pins,
                       str(d), forces, damping, settings)


def model_tables(source) -> ModelTables:
    """Read one side (see the module docstring).

    Parameters
    ----------
    source : ModelTables, str, Path, Scene, Simulation or callable
        A folder of model files, a scene (name or ``.toml`` path, or object), a
        Simulation or a function returning one.

    Returns
    -------
    ModelTables
    """
    if isinstance(source, ModelTables):
        return source
    if isinstance(source, (str, Path)) and Path(source).is_dir():
        return _from_folder(Path(source))
    if isinstance(source, (str, Path)):
        from ..scene import load_scene

        source = load_scene(source)
    return _from_simulation(as_simulation(source), str(getattr(source, "source", source)))
