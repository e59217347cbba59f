"""Compare a port's trajectory with a reference: per frame, per vertex, relative to the cloth.

The error of vertex i in frame f is the Euclidean distance e_fi = |a_fi − b_fi| [m] (``b`` the
reference). A frame passes when every e_fi ≤ atol + rtol · size, with size the diagonal of
the reference cloth's bounding box in frame 0: a tolerance on distances, not on coordinates
(a coordinate near 0 does not make an error look huge). Defaults by precision
(derivation in docs/ports.md):

float64
    rtol = 1e-9 (1.4e-8 m on the 14 m diagonal of a 10 m sheet): well above the 5e-11 m
    that two correct float64 builds differ by over 60 frames, well below float32 rounding.
float32
    tol_f = max(1, f) · κ(M + h²L) · ε₃₂ · max|x|: one step's float32 solve is accurate to
    κ ε₃₂ |x|, and a stable run adds one such error per step. κ comes from the model
    (:func:`condition_number`) or from an export's ``manifest.json``.

When the two files order the vertices differently, :func:`match_vertices` pairs them by
their positions in frame 0.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from .. import matrices
from ..errors import InputError
from .plots import plot_deviation  # noqa: F401 - its home before clothsim.ports.plots

EPS32 = float(np.finfo(np.float32).eps)
RTOL64 = 1e-9


@dataclass
class Comparison:
    """Outcome of a trajectory comparison.

    Attributes
    ----------
    passed : bool
    frames : int
        Frames compared.
    field : str
    size : float
        Cloth size [m] the relative numbers refer to.
    max_error, rms_error : ndarray, shape (frames,)
        Max and RMS over vertices of the Euclidean error [m].
    tolerance : ndarray, shape (frames,)
        Allowed error per frame [m].
    first_frame, first_vertex : int or None
        First failing frame and its worst vertex (None when passed).
    worst_frame, worst_vertex : int
        Where the error exceeds the tolerance the most.
    max_abs_error : float
        Largest coordinate difference [m].
    """

    passed: bool
    frames: int
    field: str
    size: float
    max_error: np.ndarray
    rms_error: np.ndarray
    tolerance: np.ndarray
    first_frame: int | None
    first_vertex: int | None
    worst_frame: int
    worst_vertex: int
    max_abs_error: float
    notes: list[str] = field(default_factory=list)
    frame_counts: tuple[int, int] | None = None
    """(trajectory, reference) frame counts when they differ: the verdict is FAIL."""

    def table(self) -> str:
        """The per-frame table: max and RMS error, absolute and relative to the size.

        Returns
        -------
        str
            One line per frame.
        """
        lines = [f"{'frame':>5}  {'max [m]':>10}  {'max/size':>9}  {'rms [m]':>10}  "
                 f"{'tol [m]':>9}  ok"]
        for f in range(self.frames):
            ok = "ok" if self.max_error[f] <= self.tolerance[f] else "FAIL"
            lines.append(f"{f:>5}  {self.max_error[f]:10.3e}  "
                         f"{self.max_error[f] / self.size:9.2e}  {self.rms_error[f]:10.3e}  "
                         f"{self.tolerance[f]:9.2e}  {ok}")
        return "\n".join(lines)

    def summary(self) -> str:
        """One line: verdict, largest error, the first failing frame and vertex.

        Returns
        -------
        str
        """
        worst = float(np.max(self.max_error)) if self.frames else 0.0
        u, what = ("m/s", "largest speed") if self.field == "velocities" else ("m", "cloth size")
        head = (f"{'PASS' if self.passed else 'FAIL'}: {self.field}, {self.frames} frames, "
                f"max error {worst:.3e} {u} ({worst / self.size:.2e} of the {what} "
                f"{self.size:.3g} {u})")
        if self.frame_counts is not None:
            got, want = self.frame_counts
            head = (f"FAIL: the trajectory has {got} frames, the reference has {want} "
                    f"(--frames N compares only the first N); in the {self.frames} common "
                    f"frames: " + head.split(": ", 1)[1])
        if self.passed or self.first_frame is None:
            return head
        f, v = self.first_frame, self.first_vertex
        return (f"{head}; first failing frame {f} vertex {v}: error "
                f"{self.max_error[f]:.3e} {u} > tolerance {self.tolerance[f]:.3e} {u}; worst "
                f"at frame {self.worst_frame} vertex {self.worst_vertex}")


def cloth_size(x: np.ndarray) -> float:
    """Diagonal of the bounding box of positions [m]; 1 for a single point.

    Parameters
    ----------
    x : ndarray, shape (n, 3)
        Positions [m].

    Returns
    -------
    float
    """
    x = np.asarray(x, dtype=np.float64).reshape(-1, 3)
    size = float(np.linalg.norm(x.max(axis=0) - x.min(axis=0))) if len(x) else 0.0
    return size if size > 0 else 1.0


def match_vertices(x: np.ndarray, reference: np.ndarray, *, tol: float | None = None
                   ) -> np.ndarray:
    """Indices ``perm`` with ``x[perm[i]]`` the vertex at ``reference[i]`` (frame-0 positions).

    Parameters
    ----------
    x, reference : ndarray, shape (n, 3)
        Initial positions in the two orders [m].
    tol : float, optional
        Largest distance of a match [m]; default 1e-6 of the cloth size.

    Raises
    ------
    InputError
        When a vertex has no partner within ``tol``, two partners (ambiguous), or two
        reference vertices claim the same vertex.

    Returns
    -------
    ndarray of int, shape (n,)
        ``perm`` such that ``x[perm]`` is in the reference's vertex order.
    """
    from scipy.spatial import cKDTree

    x = np.asarray(x, np.float64).reshape(-1, 3)
    ref = np.asarray(reference, np.float64).reshape(-1, 3)
    if len(x) != len(ref):
        raise InputError(f"vertices: {len(x)} vertices vs {len(ref)} in the reference")
    tol = 1e-6 * cloth_size(ref) if tol is None else float(tol)
    k = min(2, len(x))
    dist, idx = cKDTree(x).query(ref, k=k)
    dist, idx = dist.reshape(len(ref), k), idx.reshape(len(ref), k)
    far = np.flatnonzero(dist[:, 0] > tol)
    if len(far):
        raise InputError(f"vertices: reference vertex {far[0]} has no vertex within {tol:.3g} m "
                         f"(nearest {dist[far[0], 0]:.3g} m): the initial shapes differ")
    if k == 2:
        amb = np.flatnonzero(dist[:, 1] <= tol)
        if len(amb):
            raise InputError(f"vertices: reference vertex {amb[0]} matches vertices "
                             f"{idx[amb[0], 0]} and {idx[amb[0], 1]} (ambiguous)")
    perm = idx[:, 0]
    if len(np.unique(perm)) != len(perm):
        raise InputError("vertices: two reference vertices match the same vertex")
    return perm


def condition_number(model, h: float, *, anchor_vertices=(), anchor_stiffness=()) -> float:
    """κ(M_s + h²(L_s + K_pins)) in the 2-norm (the 3n matrix has the same κ).

    Parameters
    ----------
    model : Model
    h : float
        Time step [s].
    anchor_vertices, anchor_stiffness : array_like
        Penalty pins entering the diagonal.

    Returns
    -------
    float
        λ_max / λ_min by Lanczos (:func:`scipy.sparse.linalg.eigsh`); dense below 200
        vertices.
    """
    from scipy.sparse.linalg import eigsh

    A = matrices.system_matrix(model, h, anchor_vertices=np.asarray(anchor_vertices, np.int64),
                               anchor_stiffness=np.asarray(anchor_stiffness, np.float64))
    A = sp.csc_matrix(A)
    if A.shape[0] < 200:
        w = np.linalg.eigvalsh(A.toarray())
        return float(w[-1] / w[0])
    hi = eigsh(A, k=1, which="LA", return_eigenvectors=False, tol=1e-6)[0]
    lo = eigsh(A, k=1, sigma=0.0, which="LM", return_eigenvectors=False, tol=1e-6)[0]
    return float(hi / lo)


def _scale(reference: np.ndarray, field: str) -> float:
    """What relative tolerances refer to: the cloth size in frame 0, or for velocities the
    largest speed of the reference (1 when it never moves)."""
    if field == "velocities":
        speed = float(np.linalg.norm(reference, axis=-1).max()) if reference.size else 0.0
        return speed if speed > 0 else 1.0
    return cloth_size(reference[0])


def tolerances(reference: np.ndarray, *, precision: str = "float64", rtol: float | None = None,
               atol: float | None = None, kappa: float | None = None,
               field: str = "positions") -> np.ndarray:
    """Allowed per-vertex error per frame [m], shape (frames,) (see the module docstring).

    Parameters
    ----------
    reference : ndarray, shape (frames, n, 3)
        The reference trajectory [m] (or velocities [m/s]).
    precision : {"float64", "float32"}
        The port's floating-point precision.
    rtol, atol : float, optional
        Relative (to the cloth size) and absolute tolerance [m]; defaults by precision.
    kappa : float, optional
        κ(M + h²L), needed for ``precision="float32"``.
    field : {"positions", "velocities"}
        For velocities the scale is the reference's largest speed [m/s]; the float32 bound
        is for positions only.

    Returns
    -------
    ndarray, shape (frames,)
        The largest allowed per-vertex error in each frame.
    """
    if precision not in ("float32", "float64"):
        raise InputError(f"precision: must be 'float32' or 'float64', got {precision!r}")
    ref = np.asarray(reference)
    frames = len(ref)
    size = _scale(ref, field)
    base = np.full(frames, (atol or 0.0) + (RTOL64 if rtol is None else rtol) * size)
    if rtol is None and atol is not None:
        base = np.full(frames, float(atol))
    if precision == "float32":
        if kappa is None:
            raise InputError("precision: float32 tolerances need κ(M + h²L): give a scene "
                             "(--scene) or an export folder with manifest.json as reference")
        step = kappa * EPS32 * float(np.abs(ref).max())
        base = np.maximum(base, step * np.maximum(1, np.arange(frames)))
    return base


def _non_finite(x: np.ndarray, name: str, field: str) -> str | None:
    """A note naming where ``x`` (frames, n, 3) first holds NaN or inf (a port that blew
    up): its error there counts as inf, which alone would hide the cause."""
    bad = ~np.isfinite(x).all(axis=-1)
    if not bad.any():
        return None
    f, v = np.unravel_index(int(np.argmax(bad)), bad.shape)
    return (f"the {name}'s {field} are not finite (NaN or inf) at {int(bad.sum())} of "
            f"{bad.size} (frame, vertex) pairs, first at frame {f} vertex {v}; the error "
            "counts as inf there")


def compare_arrays(a, b, *, rtol: float | None = None, atol: float | None = None,
                   precision: str = "float64", kappa: float | None = None,
                   field: str = "positions", match: bool = False) -> Comparison:
    """Compare trajectories ``a`` and reference ``b``, each (frames, n, 3) (or one (n, 3) frame).

    Parameters
    ----------
    rtol : float, optional
        Tolerance relative to the cloth size (default :data:`RTOL64`).
    atol : float, optional
        Absolute tolerance [m] added to ``rtol · size`` (alone when ``rtol`` is not given).
    precision : {"float64", "float32"}
        float32 widens the tolerance to the κ ε₃₂ |x| bound (needs ``kappa``).
    match : bool
        Pair vertices by their frame-0 positions (:func:`match_vertices`) first.

    Returns
    -------
    Comparison
    """
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    if a.ndim == 2:
        a, b = a[None], b[None] if b.ndim == 2 else b
    if match and a.shape[1:] == b.shape[1:]:
        a = a[:, match_vertices(a[0], b[0])]
    if a.shape != b.shape:
        raise InputError(f"{field}: shapes differ: {a.shape} vs reference {b.shape}")
    err = np.linalg.norm(a - b, axis=-1)
    err = np.where(np.isfinite(err), err, np.inf)
    tol = tolerances(b, precision=precision, rtol=rtol, atol=atol, kappa=kappa, field=field)
    excess = err - tol[:, None]
    bad = np.flatnonzero((excess > 0).any(axis=1))
    f, v = np.unravel_index(int(np.argmax(excess)), excess.shape) if excess.size else (0, 0)
    first = int(bad[0]) if len(bad) else None
    diff = np.abs(a - b)
    with np.errstate(over="ignore", invalid="ignore"):
        rms = np.sqrt(np.mean(err ** 2, axis=1))
    notes = [_non_finite(x, name, field) for x, name in ((a, "trajectory"), (b, "reference"))]
    return Comparison(
        notes=[n for n in notes if n],
        passed=not len(bad), frames=len(a), field=field, size=_scale(b, field),
        max_error=err.max(axis=1), rms_error=rms,
        tolerance=tol, first_frame=first,
        first_vertex=None if first is None else int(np.argmax(err[first])),
        worst_frame=int(f), worst_vertex=int(v),
        max_abs_error=float(np.where(np.isnan(diff), np.inf, diff).max()) if diff.size else 0.0)


def compare_trajectories(path, reference, *, key: str = "positions", frames: int | None = None,
                         match: bool = False, kappa: float | None = None, fmt=None,
                         dtype=None, vertex_count=None, field: str | None = None,
                         kappa_vertices: int | None = None, **options) -> Comparison:
    """Read two trajectories (any format of :mod:`clothsim.ports.formats`) and compare them.

    Parameters
    ----------
    path, reference : path
        The port's trajectory and the reference (file or folder).
    key : str
        Array to compare (``"positions"`` or ``"velocities"``, or an npz key).
    frames : int, optional
        Compare only the first this many frames.
    match : bool
        Pair vertices by their frame-0 positions (:func:`match_vertices`) first.
    kappa : float, optional
        κ(M + h²L) for float32 tolerances; default: the reference export's
        ``manifest.json`` value when there is one.
    fmt, dtype, vertex_count
        How to read ``path`` (see :func:`clothsim.ports.formats.read_trajectory`).
    field : str, optional
        Alias of ``key``.
    kappa_vertices : int, optional
        Vertices of the scene ``kappa`` was computed from: it must be the trajectories'
        (a condition number of another size says nothing about this port).
    **options
        Passed to :func:`compare_arrays` (``precision``, ``rtol``, ``atol``).

    Returns
    -------
    Comparison
    """
    import json
    from pathlib import Path

    from .formats import read_trajectory

    key = field or key
    a = read_trajectory(path, key=key, fmt=fmt, dtype=dtype, vertex_count=vertex_count)
    b = read_trajectory(reference, key=key, vertex_count=vertex_count)
    if kappa_vertices is not None and b.shape[1] != kappa_vertices:
        raise InputError(f"scene: κ comes from a scene of {kappa_vertices} vertices, the "
                         f"trajectories have {b.shape[1]}: give the port's own scene")
    manifest = Path(reference) / "manifest.json"
    if kappa is None and manifest.is_file():
        kappa = json.loads(manifest.read_text()).get("condition_number")
    notes = []
    counts = None
    if frames is not None:  # on request: only the first `frames` frames
        if frames < 1 or frames > min(len(a), len(b)):
            raise InputError(f"frames: must be between 1 and {min(len(a), len(b))}, got {frames}")
        a, b = a[:frames], b[:frames]
    elif len(a) != len(b):  # a verdict is about the whole input: a short run fails
        counts = (len(a), len(b))
        n = min(len(a), len(b))
        notes.append(f"{path} has {len(a)} frames, {reference} has {len(b)}: FAIL (compared "
                     f"the first {n} only to report the error there)")
        a, b = a[:n], b[:n]
    if key == "velocities" and options.get("precision") == "float32":
        raise InputError("precision: the float32 bound is for positions; compare velocities "
                         "with --rtol/--atol")
    result = compare_arrays(a, b, kappa=kappa, field=key, match=match, **options)
    result.notes = notes + result.notes
    if counts is not None:
        result.frame_counts, result.passed = counts, False
    return result
