"""Compare two trajectories (or matrices) with tolerances: the regression check for ports.

A trajectory is a ``trajectory.npz`` written by ``clothsim run`` (or by another port in the
same format: ``positions`` (frames, n, 3), optional ``velocities``), a directory holding
one, or a ParaView ``.pvd`` collection of VTU frames. Two trajectories agree when, for every
frame and vertex, ``|a − b| <= atol + rtol * |b|`` (numpy's ``allclose`` rule, ``b`` the
reference).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import InputError


@dataclass
class Comparison:
    """Outcome of a comparison.

    Attributes
    ----------
    passed : bool
    max_abs_error : float
        max |a − b| over all compared entries.
    max_rel_error : float
        max |a − b| / |b| over entries with b ≠ 0.
    worst_frame, worst_vertex : int
        Where the tolerance is exceeded the most (largest excess over atol + rtol |b|).
    frames : int
        Frames compared.
    field : str
    """

    passed: bool
    max_abs_error: float
    max_rel_error: float
    worst_frame: int
    worst_vertex: int
    frames: int
    field: str

    def summary(self) -> str:
        verdict = "PASS" if self.passed else "FAIL"
        return (f"{verdict}: {self.field}, {self.frames} frames, max abs error "
                f"{self.max_abs_error:.3e}, max rel error {self.max_rel_error:.3e}, worst at "
                f"frame {self.worst_frame} vertex {self.worst_vertex}")


def load_trajectory(path, field: str = "positions") -> np.ndarray:
    """Read ``field`` of a trajectory (npz file, run directory or .pvd), shape (frames, n, 3)."""
    from . import io

    p = Path(path)
    if p.is_dir():
        if (p / "trajectory.npz").is_file():
            p = p / "trajectory.npz"
        elif (p / "trajectory.pvd").is_file():
            p = p / "trajectory.pvd"
        else:
            raise InputError(f"{path}: no trajectory.npz or trajectory.pvd in this directory")
    if not p.is_file():
        raise InputError(f"{path}: file not found")
    if p.suffix == ".npz":
        with np.load(p) as data:
            if field not in data:
                raise InputError(f"{p}: has no array {field!r} (has {', '.join(data.files)})")
            return np.asarray(data[field], dtype=np.float64)
    if p.suffix == ".pvd":
        if field not in ("positions", "velocities"):
            raise InputError(f"{p}: VTU frames hold positions and velocities, not {field!r}")
        frames = [io.read_frame(f)[0 if field == "positions" else 1] for _, f in io.read_pvd(p)]
        return np.stack(frames)
    raise InputError(f"{p}: expected a .npz or .pvd file")


def compare_arrays(a: np.ndarray, b: np.ndarray, *, rtol: float, atol: float,
                   field: str = "positions") -> Comparison:
    """Compare trajectory arrays (frames, n, 3): ``a`` tested against reference ``b``."""
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    if a.shape != b.shape:
        raise InputError(f"{field}: shapes differ: {a.shape} vs reference {b.shape}")
    if a.ndim == 2:
        a, b = a[None], b[None]
    diff = np.abs(a - b)
    diff = np.where(np.isnan(a) | np.isnan(b), np.inf, diff)
    excess = diff - (atol + rtol * np.abs(b))
    per_vertex = excess.max(axis=-1) if excess.ndim == 3 else excess
    f, v = np.unravel_index(int(np.argmax(per_vertex)), per_vertex.shape)
    nz = np.abs(b) > 0
    rel = float((diff[nz] / np.abs(b[nz])).max()) if nz.any() else 0.0
    return Comparison(bool(np.all(excess <= 0)), float(diff.max()) if diff.size else 0.0, rel,
                      int(f), int(v), int(a.shape[0]), field)


def compare_trajectories(path, reference, *, rtol: float = 1e-6, atol: float = 1e-9,
                         field: str = "positions", frames: int | None = None) -> Comparison:
    """Compare trajectory ``path`` against ``reference`` (see the module docstring).

    ``frames``: compare only the first this many frames (both must have them).
    """
    a, b = load_trajectory(path, field), load_trajectory(reference, field)
    if frames is not None:
        if frames < 1 or frames > min(len(a), len(b)):
            raise InputError(f"frames: must be between 1 and {min(len(a), len(b))}, got {frames}")
        a, b = a[:frames], b[:frames]
    return compare_arrays(a, b, rtol=rtol, atol=atol, field=field)


def compare_matrices(path, reference, *, rtol: float = 1e-12, atol: float = 0.0) -> Comparison:
    """Compare two Matrix Market files entry by entry (as dense, for modest sizes)."""
    from . import io

    def dense(p):
        A = io.read_matrix(p)
        return A.toarray() if hasattr(A, "toarray") else np.asarray(A)

    return compare_arrays(dense(path), dense(reference), rtol=rtol, atol=atol, field="matrix")
