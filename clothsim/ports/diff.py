"""Compare two models: which springs, stiffnesses, rest lengths, masses and pins differ.

A side is a scene (name, ``.toml`` path or :class:`~clothsim.scene.Scene`), a Simulation (or
a function returning one), or a folder of plain model files: an export of
:func:`clothsim.ports.export.export_port` (``vertices.txt``, ``springs.txt`` a b k r,
``masses.txt``, ``pins.txt``) or a port's dump like the shared ``liu13-port`` data
(``x0.txt`` one line of 3n numbers, ``springs.txt`` type a b k rest with type 0 an
attachment: a zero-rest-length spring of vertex a to its initial position, b = −1).
Vertices are paired by their initial positions, so the two may number them differently.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import InputError
from .check import as_simulation
from .compare import cloth_size, match_vertices


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
    """

    x0: np.ndarray
    springs: np.ndarray
    stiffness: np.ndarray
    rest: np.ndarray
    masses: np.ndarray | None
    pins: dict
    source: str = ""


@dataclass
class ModelDiff:
    """Differences between models A and B.

    Attributes
    ----------
    identical : bool
        True when springs, stiffnesses, rest lengths, masses and pins agree.
    cause : str
        The likely cause of the difference (or a confirmation).
    lines : list of str
        One line per difference found.
    """

    identical: bool
    cause: str
    lines: list[str] = field(default_factory=list)

    def report(self) -> str:
        """The verdict and cause, then the differences, one per line.

        Returns
        -------
        str
        """
        return "\n".join([("IDENTICAL" if self.identical else "DIFFERENT") + f": {self.cause}"]
                         + [f"  {t}" for t in self.lines])


def _from_simulation(sim, source: str) -> ModelTables:
    m = sim.model
    p = sim.problem(sim.state)
    pins = {int(v): ("constraint", None) for v in p.fixed_vertices}
    pins |= {int(v): ("penalty", float(k)) for v, k in zip(p.anchor_vertices, p.anchor_stiffness)}
    return ModelTables(m.mesh.vertices, m.springs.spring_vertices, m.springs.spring_stiffness,
                       m.springs.spring_rest_length, m.vertex_mass, pins, source)


def _from_folder(d: Path) -> ModelTables:
    if (d / "vertices.txt").is_file():
        x0 = np.loadtxt(d / "vertices.txt").reshape(-1, 3)
    elif (d / "x0.txt").is_file():
        x0 = np.loadtxt(d / "x0.txt").reshape(-1, 3)
    else:
        raise InputError(f"{d}: no vertices.txt or x0.txt")
    if not (d / "springs.txt").is_file():
        raise InputError(f"{d}: no springs.txt")
    rows = np.loadtxt(d / "springs.txt", comments="#", ndmin=2)
    pins = {}
    if rows.shape[1] == 5:
        att = rows[rows[:, 0] == 0]
        pins = {int(r[1]): ("penalty", float(r[3])) for r in att}
        rows = rows[rows[:, 0] != 0][:, 1:]
    elif rows.shape[1] != 4:
        raise InputError(f"{d / 'springs.txt'}: expected 4 columns (a b k r) or 5 "
                         f"(type a b k rest), got {rows.shape[1]}")
    if (d / "pins.txt").is_file():
        for r in np.loadtxt(d / "pins.txt", comments="#", ndmin=2):
            pins[int(r[0])] = ("penalty", float(r[2])) if r[1] else ("constraint", None)
    masses = np.loadtxt(d / "masses.txt").ravel() if (d / "masses.txt").is_file() else None
    return ModelTables(x0, rows[:, :2].astype(np.int64), rows[:, 2], rows[:, 3], masses, pins,
                       str(d))


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


def _listing(items, limit=6) -> str:
    items = list(items)
    text = ", ".join(str(i) for i in items[:limit])
    return text + (f", … ({len(items)} in all)" if len(items) > limit else "")


def _pairs_text(pairs) -> str:
    return _listing(f"{a}-{b}" for a, b in pairs)


def diff_models(a, b, *, rtol: float = 1e-12) -> ModelDiff:
    """Differences of model B from model A, vertices numbered as in A.

    Parameters
    ----------
    a, b : scene, Simulation, factory, folder or ModelTables
    rtol : float
        Relative tolerance of stiffness, rest length and mass comparisons.

    Returns
    -------
    ModelDiff
    """
    A, B = model_tables(a), model_tables(b)
    lines, causes = [], []
    if len(A.x0) != len(B.x0):
        msg = f"{len(A.x0)} vertices in A, {len(B.x0)} in B"
        return ModelDiff(False, msg, [msg])
    try:
        perm = match_vertices(B.x0, A.x0)
    except InputError as exc:
        return ModelDiff(False, f"the initial shapes differ: {exc}", [str(exc)])
    inv = np.empty_like(perm)
    inv[perm] = np.arange(len(perm))
    if np.any(perm != np.arange(len(perm))):
        lines.append("vertex numbering differs (matched by initial position)")
    bsp = inv[B.springs]

    def table(springs, k, r):
        keys = [tuple(sorted(map(int, p))) for p in springs]
        count = Counter(keys)
        ksum, rest = {}, {}
        for key, ki, ri in zip(keys, k, r):
            ksum[key] = ksum.get(key, 0.0) + float(ki)
            rest.setdefault(key, float(ri))
        return count, ksum, rest

    ca, ka, ra = table(A.springs, A.stiffness, A.rest)
    cb, kb, rb = table(bsp, B.stiffness, B.rest)
    for name, count in (("A", ca), ("B", cb)):
        dup = sorted(key for key, c in count.items() if c > 1)
        if dup:
            lines.append(f"{len(dup)} springs duplicated in {name} (stiffness counted twice): "
                         f"{_pairs_text(dup)}")
            causes.append(f"{len(dup)} duplicated springs in {name}")
    only_a, only_b = sorted(set(ca) - set(cb)), sorted(set(cb) - set(ca))
    for name, only in (("A", only_a), ("B", only_b)):
        if only:
            lines.append(f"{len(only)} springs only in {name}: {_pairs_text(only)}")
            causes.append(f"{len(only)} springs only in {name}")
    common = sorted(set(ca) & set(cb))
    dk = [key for key in common if abs(ka[key] - kb[key]) > rtol * max(abs(ka[key]), 1e-300)]
    dr = [key for key in common if abs(ra[key] - rb[key]) > rtol * max(ra[key], 1e-12)
          + 1e-15 * cloth_size(A.x0)]
    if dk:
        key = dk[0]
        lines.append(f"{len(dk)} springs with other stiffness, e.g. {key[0]}-{key[1]}: "
                     f"{ka[key]:.9g} vs {kb[key]:.9g} N/m")
        causes.append(f"{len(dk)} stiffnesses differ")
    if dr:
        key = dr[0]
        lines.append(f"{len(dr)} springs with other rest length, e.g. {key[0]}-{key[1]}: "
                     f"{ra[key]:.9g} vs {rb[key]:.9g} m")
        causes.append(f"{len(dr)} rest lengths differ")
    if A.masses is not None and B.masses is not None:
        mb = B.masses[perm]
        dm = np.abs(A.masses - mb) > rtol * np.abs(A.masses)
        if dm.any():
            i = int(np.argmax(np.abs(A.masses - mb)))
            lines.append(f"{int(dm.sum())} masses differ, e.g. vertex {i}: {A.masses[i]:.9g} vs "
                         f"{mb[i]:.9g} kg (totals {A.masses.sum():.9g} vs {mb.sum():.9g})")
            causes.append(f"{int(dm.sum())} masses differ")
    pa = A.pins
    pb = {int(inv[v]): val for v, val in B.pins.items()}
    for name, mine, other in (("A", pa, pb), ("B", pb, pa)):
        only = sorted(set(mine) - set(other))
        if only:
            kinds = {mine[v] for v in only}
            what = ("attachments (penalty pins" + (f", k = {mine[only[0]][1]:g} N/m)"
                                                   if len(kinds) == 1 else ")")
                    if all(m == "penalty" for m, _ in kinds) else "pins")
            text = (f"{len(only)} {what} only in {name}: vertices "
                    f"{' and '.join(map(str, only)) if len(only) <= 2 else _listing(only)}")
            lines.append(text)
            causes.insert(0, text)
    other_pins = [v for v in set(pa) & set(pb) if pa[v] != pb[v]]
    if other_pins:
        v = sorted(other_pins)[0]
        lines.append(f"{len(other_pins)} pins differ in method or stiffness, e.g. vertex {v}: "
                     f"{pa[v]} vs {pb[v]}")
        causes.append(f"{len(other_pins)} pins differ")
    if not causes and not lines:
        return ModelDiff(True, f"{len(A.x0)} vertices, {len(ca)} springs, pins and masses "
                               f"agree", [])
    if not causes:
        return ModelDiff(True, "same model up to vertex numbering", lines)
    return ModelDiff(False, causes[0] if len(causes) == 1 else "; ".join(causes[:3]), lines)
