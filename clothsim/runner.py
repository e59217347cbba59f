"""Run a scene and write its results: frames, trajectory, previews and a run record.

:func:`run_scene` writes into one output directory:

===================  ==============================================================
file                 content
===================  ==============================================================
``frame_%06d.vtu``   one VTK file per frame (frame 0 = initial state), written as
                     soon as the frame is computed (:class:`clothsim.io.FrameWriter`)
``trajectory.pvd``   ParaView collection of the frames with their times
``trajectory.npz``   ``positions``, ``velocities`` (frames+1, n, 3), ``time``
                     (frames+1,), ``triangles`` (m, 3), ``springs`` (s, 2),
                     ``strands`` (e, 2), ``vertex_mass`` (n,); float64 / int64
``preview.gif``      small animation (at most ~60 frames), ``final.png`` last frame
``obstacles.vtu``    the scene's obstacles as triangles (only when it has some)
``run.json``         resolved scene, effects built, solver and backend, package
                     versions, per-frame iterations/residuals/timings, and status
                     ``"completed"`` or ``"interrupted"`` with the last frame
===================  ==============================================================

Frame k holds the state at t_k = k / fps. The runner sets each frame's start time to
exactly (k − 1) / fps, so a run resumed from frame k (``resume=True``) repeats, bit for
bit, what an uninterrupted run computes.
"""

from __future__ import annotations

import json
import logging
import math
import platform
import re
import time as _time
from collections.abc import Callable
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from . import io
from .display import obstacle_surfaces, surfaces_mesh  # scene display (issue 12)
from .errors import InputError
from .mesh import Mesh  # scene display (issue 12)
from .scene import Scene, load_scene
from .simulation import State

log = logging.getLogger(__name__)

FRAME_PATTERN = re.compile(r"frame_(\d{6})\.vtu")
RESULT_FILES = ("trajectory.pvd", "trajectory.npz", "preview.gif", "final.png", "run.json")


@dataclass
class RunResult:
    """What :func:`run_scene` did.

    Attributes
    ----------
    out_dir : Path
    status : {"completed", "interrupted"}
    last_frame : int
        Index of the last complete frame written.
    frames : list of dict
        Per computed frame: ``frame``, ``time`` [s], ``iterations``, ``residual``,
        ``seconds``, ``converged``.
    files : list of Path
        Result files written.
    """

    out_dir: Path
    status: str
    last_frame: int
    frames: list[dict] = field(default_factory=list)
    files: list[Path] = field(default_factory=list)


def package_versions() -> dict[str, str | None]:
    """Versions of python and of the packages a run depends on (None if not installed)."""
    from importlib import metadata

    out: dict[str, str | None] = {"python": platform.python_version()}
    for dist in ("clothsim", "numpy", "scipy", "meshio", "matplotlib", "scikit-sparse", "tqdm"):
        try:
            out[dist] = metadata.version(dist)
        except metadata.PackageNotFoundError:
            out[dist] = None
    return out


def _json_default(obj):
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, Path):
        return str(obj)
    raise TypeError(f"not JSON serializable: {type(obj).__name__}")


def _clean(value):
    """Non-finite floats become strings so run.json stays strict JSON."""
    if isinstance(value, float) and not math.isfinite(value):
        return repr(value)
    if isinstance(value, dict):
        return {k: _clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    return value


def _atomic_write(path: Path, write: Callable) -> None:
    """Write through ``write(file)`` to a temporary file, then move it onto ``path``."""
    with io.atomic_path(path) as tmp, open(tmp, "wb") as f:
        write(f)


def write_json(path: Path, data: dict) -> None:
    """Atomically write ``data`` as indented JSON."""
    plain = json.loads(json.dumps(data, default=_json_default))  # numpy → python
    text = json.dumps(_clean(plain), indent=1, allow_nan=False)
    _atomic_write(path, lambda f: f.write(text.encode("utf-8") + b"\n"))


def write_trajectory(path: Path, model, positions, velocities, time) -> None:
    """Atomically write trajectory.npz (see the module docstring for its arrays)."""
    arrays = dict(positions=np.asarray(positions, np.float64),
                  velocities=np.asarray(velocities, np.float64),
                  time=np.asarray(time, np.float64),
                  triangles=np.asarray(model.mesh.triangles, np.int64),
                  springs=np.asarray(model.springs.spring_vertices, np.int64),
                  strands=np.asarray(model.mesh.strands, np.int64),
                  vertex_mass=np.asarray(model.vertex_mass, np.float64))
    _atomic_write(path, lambda f: np.savez(f, **arrays))


def completed_frames(out_dir) -> int | None:
    """Index of the last frame k such that frames 0..k all exist in ``out_dir`` (None: none).

    The frames listed in ``trajectory.pvd`` are used when it exists (it lists only
    complete files); otherwise the ``frame_%06d.vtu`` files on disk.
    """
    out = Path(out_dir)
    pvd = out / "trajectory.pvd"
    indices: set[int] = set()
    if pvd.is_file():
        from .io import read_pvd
        try:
            entries = read_pvd(pvd)
        except InputError:
            entries = []
        for _, p in entries:
            m = FRAME_PATTERN.fullmatch(p.name)
            if m and p.is_file():
                indices.add(int(m.group(1)))
    else:
        indices = {int(m.group(1)) for p in out.glob("frame_*.vtu")
                   if (m := FRAME_PATTERN.fullmatch(p.name))}
    k = -1
    while k + 1 in indices:
        k += 1
    return None if k < 0 else k


def run_scene(scene, out_dir, *, frames: int | None = None,
              progress: Callable[[int, int], None] | None = None, resume: bool = False,
              preview: bool = True) -> RunResult:
    """Simulate ``scene`` and write every result file into ``out_dir``.

    Parameters
    ----------
    scene : Scene or str or Path
        A scene, or what :func:`clothsim.scene.load_scene` takes.
    out_dir : str or Path
        Created if missing.
    frames : int, optional
        Frames after the initial one (default ``scene.frames``).
    progress : callable, optional
        ``progress(frame, frames)`` after each frame is written (the CLI's progress bar).
    resume : bool
        Continue from the last complete frame in ``out_dir`` (positions and velocities read
        back from its .vtu file, time = index / fps). Starts afresh when there is none.
    preview : bool
        Write preview.gif and final.png (matplotlib) after a completed run.

    Returns
    -------
    RunResult

    Raises
    ------
    SceneError
        Bad scene (before anything is written).
    KeyboardInterrupt, Exception
        Propagated after frames 0..k−1, trajectory.npz and run.json (status
        ``"interrupted"``, ``last_frame`` k − 1 and the error) are written.
    """
    if not isinstance(scene, Scene):
        scene = load_scene(scene)
    frames = scene.frames if frames is None else int(frames)
    if frames < 0:
        raise InputError(f"frames: must be >= 0, got {frames}")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    model = scene.build_model()
    sim = scene.build_simulation(model)
    fps, substeps = scene.fps, scene.substeps
    n = model.vertex_count
    positions = np.zeros((frames + 1, n, 3))
    velocities = np.zeros((frames + 1, n, 3))
    times = np.arange(frames + 1) / fps
    records: list[dict] = []
    start = 0

    last = completed_frames(out) if resume else None
    if last is not None:
        last = min(last, frames)
        for j in range(last + 1):
            x, v = io.read_frame(out / f"frame_{j:06d}.vtu")
            if x.shape != (n, 3):
                raise InputError(f"{out / f'frame_{j:06d}.vtu'}: has {len(x)} vertices, the "
                                 f"scene has {n}; not the same scene, cannot resume")
            positions[j], velocities[j] = x, v
        records = _previous_records(out / "run.json", last)
        start = last
        log.info("resuming %s from frame %d", scene.name, last)
    else:
        if resume:
            log.info("nothing to resume in %s; starting from frame 0", out)
        _remove_stale_frames(out)
        positions[0] = sim.state.positions
        velocities[0] = sim.state.velocities

    writer = io.FrameWriter(out, model.mesh)
    if start == 0:
        writer.write(0, 0.0, positions[0], velocities[0])
    # --- scene display (issue 12): obstacle surfaces for ParaView, beside the frames ---
    obstacles_file = write_obstacles(out / OBSTACLES_NAME, sim.effects, positions[0])
    info = {
        "clothsim_run": 1,
        "scene": scene.to_dict(),
        "source": scene.source,
        "out_dir": str(out.resolve()),
        "h": sim.h, "fps": fps, "substeps": substeps, "frames_requested": frames,
        "vertex_count": n, "spring_count": model.spring_count,
        "triangle_count": model.mesh.triangle_count, "total_mass": model.total_mass,
        "effects_built": sim.effects_built,
        "effects": [e.describe() for e in sim.effects],
        "solver": {"method": sim.solver.name,
                   "backend": getattr(sim.solver, "backend", None),
                   "backend_requested": sim.solver.backend_requested,
                   "iterations": sim.solver.iterations, "tolerance": sim.solver.tolerance},
        "versions": package_versions(),
        "started": datetime.now(UTC).isoformat(timespec="seconds"),
        "resumed_from": start if resume and start > 0 else None,
    }
    done = start
    status, error = "running", None
    wall = _time.perf_counter()
    _write_run_json(out, info, status, done, records, error, wall)
    try:
        for k in range(start + 1, frames + 1):
            # canonical start time of the frame: identical in fresh and resumed runs
            sim.state = State(positions[k - 1].copy(), velocities[k - 1].copy(),
                              (k - 1) / fps, (k - 1) * substeps)
            steps = [sim.step() for _ in range(substeps)]
            positions[k], velocities[k] = sim.state.positions, sim.state.velocities
            writer.write(k, times[k], positions[k], velocities[k])
            records.append({
                "frame": k, "time": float(times[k]),
                "iterations": int(sum(r.iterations for r in steps)),
                "residual": float(steps[-1].residual),
                "seconds": float(sum(r.seconds for r in steps)),
                "converged": bool(all(r.converged for r in steps)),
                "residual_history": [float(r) for r in steps[-1].residual_history],
            })
            done = k
            if progress is not None:
                progress(k, frames)
        status = "completed"
    except BaseException as exc:
        status = "interrupted"
        error = f"{type(exc).__name__}: {' '.join(str(exc).split())}".rstrip(": ")
        log.info("run of %s interrupted at frame %d: %s", scene.name, done + 1, error)
        raise
    finally:
        info["backend"] = getattr(sim.solver, "backend", None)
        info["solver"]["backend"] = info["backend"]
        write_trajectory(out / "trajectory.npz", model, positions[:done + 1],
                         velocities[:done + 1], times[:done + 1])
        _write_run_json(out, info, status, done, records, error, wall)

    files = [out / writer.filename(k) for k in range(frames + 1)]
    files += [out / "trajectory.pvd", out / "trajectory.npz", out / "run.json"]
    files += [obstacles_file] if obstacles_file is not None else []
    if preview:
        from .plotting import write_final_image, write_preview
        files.append(write_preview(out / "preview.gif", positions, model.mesh, times=times,
                                   effects=sim.effects))
        files.append(write_final_image(out / "final.png", positions[-1], model.mesh,
                                       title=f"{scene.name}, t = {times[-1]:.2f} s",
                                       effects=sim.effects, t=float(times[-1])))
    return RunResult(out, status, done, records, files)


# --- scene display (issue 12) ---------------------------------------------------------
OBSTACLES_NAME = "obstacles.vtu"


def write_obstacles(path: Path, effects, positions) -> Path | None:
    """Write the obstacles' surfaces as one triangle mesh (``obstacles.vtu`` for ParaView).

    Parameters
    ----------
    path : Path
        Output file (any format :func:`clothsim.io.write_mesh` writes).
    effects : iterable of Effect
        The simulation's effects; planes (a square framed on ``positions``), spheres and
        boxes are written, the others skipped.
    positions : ndarray, shape (n, 3)
        Cloth positions [m] the plane's square is framed on.

    Returns
    -------
    Path or None
        ``path``, or None (nothing written) when there is no obstacle. Point data
        ``obstacle`` holds the index of the surface each vertex belongs to.
    """
    surfaces = obstacle_surfaces(effects, positions)
    if not surfaces:
        return None
    x, tris, ids = surfaces_mesh(surfaces)
    io.write_mesh(path, Mesh(x, tris), point_data={"obstacle": ids})
    return path
# --- end scene display ------------------------------------------------------------------


def _write_run_json(out: Path, info: dict, status: str, done: int, records: list[dict],
                    error: str | None, wall: float) -> None:
    data = dict(info)
    data.update(status=status, last_frame=done, error=error,
                wall_seconds=_time.perf_counter() - wall,
                finished=(datetime.now(UTC).isoformat(timespec="seconds")
                          if status != "running" else None),
                frames=records)
    write_json(out / "run.json", data)


def _previous_records(path: Path, last: int) -> list[dict]:
    """Per-frame records 1..last of an earlier run.json (empty if unreadable)."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        return [r for r in data.get("frames", []) if 1 <= r.get("frame", 0) <= last]
    except (OSError, ValueError, AttributeError):
        return []


def _remove_stale_frames(out: Path) -> None:
    """A fresh run replaces an earlier one: drop its frame files (frame_%06d.vtu only)."""
    stale = [p for p in out.glob("frame_*.vtu") if FRAME_PATTERN.fullmatch(p.name)]
    for p in stale:
        p.unlink()
    if stale:
        log.info("removed %d frame files of an earlier run in %s", len(stale), out)


__all__ = ["run_scene", "RunResult", "completed_frames", "package_versions", "write_json",
           "write_trajectory", "RESULT_FILES"]
