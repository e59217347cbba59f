"""The contact planes a simulation holds, per step, as ``clothsim export`` writes them.

In ``[contact] mode = "hold"`` each step keeps some vertices on planes n · x = offset
(:mod:`clothsim.contacts`); a port implementing that mode reads them from the export's
``contacts.txt`` / ``contacts.npz`` and solves the same constrained steps. A port may write
its own planes in the same layout; ``clothsim check`` reads them
(:func:`read_held_planes`) and names every plane that differs from clothsim's.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import InputError
from .compare import EPS32
from .digits import FULL, float32_valued, significant_digits, unit
from .precision import MARGIN

#: The names ``check`` looks for in a port's folder.
CONTACT_FILES = ("contacts.npz", "contacts.txt")


def held_planes(obstacles, step: int, t: float) -> np.ndarray:
    """The contact planes ``obstacles`` hold in the step ending at ``t``, one row each.

    Parameters
    ----------
    obstacles : list of Obstacle
        In ``"hold"`` mode (``hold_contacts`` does not change them).
    step : int
        The step's index k (frame k → k + 1).
    t : float
        Time at the end of the step [s].

    Returns
    -------
    ndarray, shape (c, 6)
        ``step vertex nx ny nz offset``: the vertex stays on n · x = offset [m] in the step.
    """
    rows = [np.zeros((0, 6))]
    for e in obstacles:
        c = e.hold_contacts(t)
        rows.append(np.column_stack([np.full(len(c), step), c.vertices, c.normals, c.offsets]))
    return np.concatenate(rows)


def write_held_planes(put, files: dict, held: list) -> None:
    """Write ``contacts.txt`` and ``contacts.npz`` from the rows of :func:`held_planes`.

    Parameters
    ----------
    put : callable
        ``put(name, write, *args)``: the export folder's atomic writer.
    files : dict
        The manifest's file descriptions, added to.
    held : list of ndarray, shape (c_k, 6)
        One :func:`held_planes` per step.

    Returns
    -------
    None
    """
    H = np.concatenate([np.zeros((0, 6))] + held)
    put("contacts.txt", np.savetxt, H, fmt=["%d", "%d", "%.17g", "%.17g", "%.17g", "%.17g"],
        header="step vertex nx ny nz offset: in step k (frame k -> k+1) vertex stays "
               "on n . x = offset [m]")
    put("contacts.npz", lambda tmp: np.savez(tmp, step=H[:, 0].astype(np.int64),
                                             vertex=H[:, 1].astype(np.int64),
                                             normal=H[:, 2:5], offset=H[:, 5]))
    files["contacts.txt"] = ("held contact planes per step: step vertex nx ny nz offset "
                             "(obstacles in hold mode)")
    files["contacts.npz"] = "the same: step, vertex (c,), normal (c, 3), offset (c,)"


class PortPlanes:
    """A port's held planes, per step (``contacts.txt`` / ``contacts.npz``).

    Parameters
    ----------
    path : str or Path
        A ``.txt`` file of rows ``step vertex nx ny nz offset`` (``#`` starts a comment; a
        file of comments only holds no planes) or a ``.npz`` with arrays ``step``,
        ``vertex``, ``normal`` (c, 3), ``offset``.
    vertex_count : int
        The cloth's n (vertices out of range are an error naming the row).

    Attributes
    ----------
    path : Path
    normal_tolerance : float
        |n_port − n_clothsim| within which two normals are the same: 10 × the rounding of
        the normals as printed (at least 1e-9).
    offset_rounding : float
        How far printing (fewer than 15 digits) or float32 values move an offset [m]:
        ``MARGIN`` × the relative rounding × the largest |offset| (0 for float64 in full).
    """

    def __init__(self, path, vertex_count: int):
        self.path = Path(path)
        rows = _read_rows(self.path)
        step, vertex = rows[:, 0], rows[:, 1]
        for name, col in (("step", step), ("vertex", vertex)):
            bad = np.flatnonzero((col != np.round(col)) | (col < 0))
            if len(bad):
                raise InputError(f"{self.path}: row {bad[0] + 1}: {name} {col[bad[0]]:g} is not "
                                 f"a whole number >= 0")
        out = np.flatnonzero(vertex >= vertex_count)
        if len(out):
            raise InputError(f"{self.path}: row {out[0] + 1}: vertex {int(vertex[out[0]])} out "
                             f"of range 0..{vertex_count - 1}")
        normal = rows[:, 2:5]
        length = np.linalg.norm(normal, axis=1)
        bad = np.flatnonzero(np.abs(length - 1.0) > 1e-3)
        if len(bad):
            raise InputError(f"{self.path}: row {bad[0] + 1}: the normal has length "
                             f"{length[bad[0]]:.6g}, not a unit vector")
        digits = significant_digits(normal) if len(normal) else 17
        self.normal_tolerance = max(1e-9, 10 * unit(digits))
        offsets = rows[:, 5]
        digits = significant_digits(offsets) if len(offsets) else 17
        rounding = max(unit(digits) if digits < FULL else 0.0,
                       EPS32 if len(offsets) and float32_valued(offsets) else 0.0)
        self.offset_rounding = MARGIN * rounding * float(np.abs(offsets).max(initial=0.0))
        self._step = step.astype(np.int64)
        self._vertex = vertex.astype(np.int64)
        self._normal = normal / np.where(length > 0, length, 1.0)[:, None]
        self._offset = rows[:, 5]

    @property
    def steps(self) -> int:
        """One more than the last step with a plane (0 without planes)."""
        return int(self._step.max()) + 1 if len(self._step) else 0

    def step(self, k: int):
        """The planes of step k (frame k → k + 1).

        Parameters
        ----------
        k : int

        Returns
        -------
        vertices, normals, offsets : ndarray, shapes (c,), (c, 3), (c,)
        """
        rows = self._step == k
        return self._vertex[rows], self._normal[rows], self._offset[rows]


def _read_rows(path: Path) -> np.ndarray:
    """The (c, 6) rows of a contacts file, or an InputError naming the file."""
    from ..io.common import refuse_special

    refuse_special(path)
    if not path.is_file():
        raise InputError(f"{path}: no such contacts file")
    if path.suffix == ".npz":
        try:
            with np.load(path, allow_pickle=False) as z:
                missing = [k for k in ("step", "vertex", "normal", "offset") if k not in z]
                if missing:
                    raise InputError(f"{path}: no array {missing[0]!r} (a contacts .npz holds "
                                     f"step, vertex, normal, offset)")
                arrays = [np.asarray(z[k], np.float64) for k in ("step", "vertex", "normal",
                                                                  "offset")]
        except (OSError, ValueError, EOFError) as exc:
            raise InputError(f"{path}: not a contacts .npz ({type(exc).__name__})") from None
        step, vertex, normal, offset = arrays
        c = len(step)
        if vertex.shape != (c,) or normal.shape != (c, 3) or offset.shape != (c,):
            raise InputError(f"{path}: expected step (c,), vertex (c,), normal (c, 3), offset "
                             f"(c,), got {step.shape}, {vertex.shape}, {normal.shape}, "
                             f"{offset.shape}")
        rows = np.column_stack([step, vertex, normal, offset]) if c else np.zeros((0, 6))
    else:
        from .formats import _read_text

        text = path.read_bytes().decode("utf-8", errors="replace")
        if not any(line.split("#", 1)[0].strip() for line in text.splitlines()):
            return np.zeros((0, 6))
        rows = _read_text(path)
        if rows.shape[1] != 6:
            raise InputError(f"{path}: {rows.shape[1]} numbers a line, expected 6 (step vertex "
                             f"nx ny nz offset)")
    if not np.isfinite(rows).all():
        bad = int(np.flatnonzero(~np.isfinite(rows).all(axis=1))[0])
        raise InputError(f"{path}: row {bad + 1}: not a finite number")
    return rows


def port_contacts(port, contacts=None) -> Path | None:
    """The contacts file of a check: ``contacts`` if given, else one in the port's folder.

    Parameters
    ----------
    port : str or Path
        The port's output (a folder, or a trajectory file).
    contacts : str or Path, optional
        A contacts file; ``"none"`` ignores any.

    Returns
    -------
    Path or None
    """
    if contacts is not None:
        return None if str(contacts) == "none" else Path(contacts)
    folder = Path(port)
    if folder.is_dir():
        for name in CONTACT_FILES:
            if (folder / name).is_file():
                return folder / name
    return None


__all__ = ["CONTACT_FILES", "PortPlanes", "held_planes", "port_contacts", "write_held_planes"]
