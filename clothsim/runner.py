"""Run a scene into a folder: frames, trajectory, previews and a run record that never lies.

:func:`run_scene` writes into one output folder (what is written when, what an interruption
leaves and what ``resume`` guarantees: ``docs/reliability.md``):

===================  ==============================================================
file                 content
===================  ==============================================================
``frame_%06d.vtu``   one VTK file per frame (frame 0 = initial state), written as
                     soon as the frame is computed (:class:`clothsim.io.FrameWriter`);
                     zlib-compressed or raw by ``[output] frame_compression``
``trajectory.pvd``   ParaView collection of the frames with their times
``trajectory.npz``   ``positions``, ``velocities`` (frames+1, n, 3), ``time``
                     (frames+1,), ``triangles`` (m, 3), ``springs`` (s, 2),
                     ``strands`` (e, 2), ``vertex_mass`` (n,); float64 / int64;
                     assembled from a store streamed to disk, never held in memory,
                     once: at the end (while the last frame is written) or at an
                     interruption
``preview.gif``      small animation (at most ~60 frames), ``final.png`` last frame,
                     both drawing the obstacles and pins; drawn while the last frame
                     is written (a large cloth's by a second process,
                     :mod:`clothsim.pictures`), written once the run is complete
``obstacles.vtu``    the scene's obstacles as triangles (only when it has some)
``state/``           ``frame_%06d.npz``: what the effects carry into the next step
                     (held contacts), written before the frame's ``.vtu`` and
                     restored by ``resume`` (:mod:`clothsim.io.effectstate`)
``run.json``         resolved scene and its hash, effects built, solver, backend and
                     solver state, package versions, per-frame records, and status
                     (``running``, ``completed``, ``interrupted``, ``failed``) with
                     the last complete frame; rewritten atomically after every frame
===================  ==============================================================

Frame k holds the state at t_k = k / fps. The runner sets each frame's start time to
exactly (k − 1) / fps and restores the effects' state saved with frame k, so a run resumed
from frame k (``resume=True``) repeats, bit for bit, what an uninterrupted run computes.
"""

from __future__ import annotations

import logging
import mmap
from collections.abc import Callable
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from .display import pinned_mask, write_obstacles
from .effects.base import effect_states
from .errors import InputError, NonFiniteStateError
from .interrupts import SignalInterrupt, handle_signals, signals_deferred
from .io.background import BackgroundJob
from .io.effectstate import restore_state, state_path
from .io.frames import OBSTACLES_NAME, PVD_NAME
from .io.runfiles import package_versions, write_json, write_trajectory
from .io.runfolder import RESULT_FILES, STALE_FILES, RunFolder, completed_frames
from .pictures import PictureProcess
from .plotting import draw_run_pictures, write_run_pictures
from .scene import Scene, load_scene
from .scene.hashing import digest_model, scene_digest, scene_hash
from .scene.inputs import input_hashes
from .scene.schema import MAX_FRAMES
from .simulation import State

log = logging.getLogger(__name__)

@dataclass
class RunResult:
    """What :func:`run_scene` did.

    Attributes
    ----------
    out_dir : Path
    status : {"completed", "interrupted", "failed"}
        How the run ended (as in run.json).
    last_frame : int
        Index of the last complete frame written.
    frames : list of dict
        Per computed frame: ``frame``, ``time`` [s], ``iterations``, ``residual``,
        ``seconds``, ``converged`` (None when no tolerance was set), ``residual_history``.
    files : list of Path
        Result files written.
    """

    out_dir: Path
    status: str
    last_frame: int
    frames: list[dict] = field(default_factory=list)
    files: list[Path] = field(default_factory=list)


def run_scene(scene, out_dir, *, frames: int | None = None,
              progress: Callable[[int, int], None] | None = None, resume: bool = False,
              preview: bool = True, force: bool = False) -> RunResult:
    """Simulate ``scene`` and write every result file into ``out_dir``.

    Parameters
    ----------
    scene : Scene or str or Path
        A scene, or what :func:`clothsim.scene.load_scene` takes.
    out_dir : str or Path
        Created if missing. Locked for the whole run. A fresh run replaces the files of an
        earlier run there (recognised by its ``run.json``) and refuses to delete frame files
        no run record describes.
    frames : int, optional
        Frames after the initial one (default ``scene.frames``).
    progress : callable, optional
        ``progress(frame, frames)`` after each frame is written (the CLI's progress bar; a
        frame is written on a background thread during the next frame's steps).
    resume : bool
        Continue from the last complete frame in ``out_dir`` (positions and velocities read
        back from its .vtu file, time = index / fps, the solver's saved state and the
        effects' state of that frame restored: :mod:`clothsim.io.effectstate`).
        Refuses a folder holding another scene's run; starts afresh when there is nothing.
        With fewer ``frames`` than on disk, the index and trajectory are cut to ``frames``
        (frame files are kept).
    preview : bool
        Write preview.gif and final.png (matplotlib) after a completed run.
    force : bool
        Write into a folder clothsim does not own (files with the names of a run's files
        are replaced); without it such a folder is refused
        (:func:`clothsim.io.folders.claim_folder`).

    Returns
    -------
    RunResult
        Status, last complete frame, per-frame records and the files written.

    Raises
    ------
    SceneError, InputError
        Bad scene, a folder locked by another run, or one that cannot be resumed or
        replaced (before anything is written).
    NonFiniteStateError
        A frame's state became non-finite: frames 0..k−1 stay, run.json says ``failed``.
    KeyboardInterrupt, Exception
        Propagated after frames 0..k−1, trajectory.npz and run.json (status
        ``"interrupted"``, ``last_frame`` k − 1 and the error) are written.
    """
    if not isinstance(scene, Scene):
        scene = load_scene(scene)
    if frames is not None and (isinstance(frames, bool) or not isinstance(frames, int | np.integer)
                               or not 0 <= frames <= MAX_FRAMES):
        raise InputError(f"frames: must be an integer between 0 and {MAX_FRAMES:.0e}, got "
                         f"{frames!r}"[:200])
    frames = scene.frames if frames is None else int(frames)
    model = scene.build_model()
    # the model's hash (100 MB of arrays at 513²) on a thread, beside the simulation's build
    digest, hashing = scene_digest(scene), BackgroundJob()
    hashing.start(digest_model, digest, model, name="clothsim scene hash")
    sim = scene.build_simulation(model)
    touch_pages(sim.solver)   # its work arrays' first writes, before the factorization
    hashing.wait()
    shash = digest.hexdigest()[:16]
    # a large cloth's pictures are drawn by a second process (clothsim.pictures)
    with PictureProcess(model.vertex_count if preview else 0) as pictures, \
            RunFolder(out_dir, force=force, guard=signals_deferred) as folder:
        return _run_in(folder, scene, model, sim, shash, frames, progress, resume,
                       pictures if preview else None)


#: Arrays of at least this many bytes are touched by :func:`touch_pages`.
TOUCH_FROM = 1 << 22


def touch_pages(owner) -> int:
    """Write one byte of each memory page of ``owner``'s large arrays back unchanged (each
    gets itself plus 0): a solver's work arrays, allocated unmapped when it is built, were
    first written in the first step, after the factorization, where at 513² the faults took
    0.3 s of system time (huge pages the kernel compacts memory for); right after the build
    they take 0.02 s. Every step stays bit for bit the same.

    Parameters
    ----------
    owner : object
        Its attributes that are writable, C-contiguous ndarrays of :data:`TOUCH_FROM` bytes
        or more are touched (nothing else may write them meanwhile).

    Returns
    -------
    int
        The arrays touched.
    """
    big = [a for a in list(vars(owner).values()) if isinstance(a, np.ndarray)
           and a.nbytes >= TOUCH_FROM and a.flags.writeable and a.flags.c_contiguous]
    for a in big:
        page = a.reshape(-1).view(np.uint8)[::mmap.PAGESIZE]
        page += 0
    return len(big)


def _run_in(folder: RunFolder, scene, model, sim, shash: str, frames: int, progress,
            resume: bool, pictures: PictureProcess | None) -> RunResult:
    """The run, once ``folder`` is claimed and locked: frames computed here, written there
    (``shash``: :func:`scene_hash`)."""
    fps, substeps, n = scene.fps, scene.substeps, model.vertex_count
    inputs = input_hashes(scene)  # every file the scene reads, by content
    start = (folder.resume_point(shash, frames, inputs, scene=scene.to_dict()) if resume
             else None)
    previous = folder.previous
    resuming = start is not None
    if resume and not resuming:
        log.info("nothing to resume in %s; starting from frame 0", folder.path)
    info = {
        "clothsim_run": 1, "scene": scene.to_dict(), "scene_hash": shash,
        "overrides": list(scene.overrides),
        "source": scene.source, "inputs": inputs, "out_dir": str(folder.path.resolve()),
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
        "resumed_from": start if resuming else None,
    }
    if resuming:   # before anything is written: an unreadable state file changes nothing
        info["effect_state_restored"] = restore_state(folder, start, sim.effects)
    get_state = getattr(sim.solver, "get_state", lambda: {})
    folder.state_bytes = sum(e.state_bytes(n) for e in sim.effects)   # planned per frame
    read_back = folder.begin(info, model, fps, frames=frames,
                             pinned=lambda t: pinned_mask(sim.effects, n, t),
                             compression=scene.data["output"]["frame_compression"],
                             start=start)
    if resuming:
        x, v = read_back
        saved = previous.get("solver_state")
        if saved:
            getattr(sim.solver, "set_state", lambda state: None)(saved)
        log.info("resuming %s from frame %d", scene.name, start)
    else:
        x, v = sim.state.positions, sim.state.velocities
    # before frame 0, which lists it in trajectory.pvd (the scene shown whole)
    obstacles = write_obstacles(folder.path / OBSTACLES_NAME, sim.effects, model.mesh.vertices)
    if obstacles is not None:
        folder.add_static(OBSTACLES_NAME)
    # the factorization mode weighs the run's solves: the first run's count, kept by a
    # resumed run so that it factors in the same mode (and repeats it bit for bit)
    sim.expect_steps(frames * substeps)
    if resuming and isinstance(previous.get("expected_solves"), int):
        sim.solver.expected_solves = previous["expected_solves"]
    info["expected_solves"] = getattr(sim.solver, "expected_solves", None)
    info["solver_state"] = get_state()
    if resuming:
        folder.save_npz()   # frames 0..start: what run.json's trajectory_frames then says
        folder.mark("writing")
    else:   # frame 0 and run.json: written while frame 1 is computed, once its system is
        if frames >= 1:   # factored (a large cloth's factorization takes both cores)
            sim.prepare()
        folder.write_frame(0, x, v, wait=False, state=effect_states(sim.effects))
    first = start + 1 if resuming else 1
    for k in range(first, frames + 1):
        # canonical start time of the frame: identical in fresh and resumed runs
        sim.state = State(x.copy(), v.copy(), (k - 1) / fps, (k - 1) * substeps)
        steps = _advance(sim, substeps, k)   # meanwhile frame k - 1 is written (background)
        x, v = sim.state.positions, sim.state.velocities
        if pictures is not None and k == first and k < frames:
            pictures.start(sim.model.mesh)   # it imports beside the next frames' solves
        record = _frame_record(k, fps, steps, sim.solver.tolerance)
        folder.wait()
        if progress is not None and k > first:
            progress(k - 1, frames)          # frame k - 1 is on disk
        with signals_deferred():
            info["backend"] = info["solver"]["backend"] = getattr(sim.solver, "backend", None)
            info["factorization"] = getattr(sim.solver, "factorization", None)
            info["solver_state"] = get_state()
            folder.write_frame(k, x, v, record, wait=False, state=effect_states(sim.effects))
    # the pictures are drawn while the last frame is written (by the second process, or
    # here), and written once the run is complete; an error drawing them is raised then
    # (the run is complete all the same)
    last = x if frames >= first else None
    drawing = pictures is not None and _request_previews(pictures, folder, scene, sim, fps,
                                                         frames)
    drawn = _draw_previews(folder, scene, sim, fps, frames, last) if (
        pictures is not None and not drawing) else None
    folder.wait_last()   # trajectory.npz built meanwhile, moved into place by end
    if progress is not None and frames >= first:
        progress(frames, frames)
    with signals_deferred():
        folder.end("complete", None)
    if drawing:
        drawn = pictures.answer()
        if drawn is None:   # the process failed: drawn here, every frame now in the store
            drawn = _draw_previews(folder, scene, sim, fps, frames, None)
    files = folder.frame_files()
    files += [folder.path / PVD_NAME, folder.path / "trajectory.npz", folder.path / "run.json"]
    files += [obstacles] if obstacles is not None else []
    files += [p for j in range(folder.done + 1) if (p := state_path(folder.path, j)).exists()]
    if isinstance(drawn, Exception):
        raise drawn
    if drawn is not None:
        files += write_run_pictures(folder.path, drawn)
    return RunResult(folder.path, "completed", folder.done, folder.records, files)


def _advance(sim, substeps: int, k: int) -> list:
    """The substeps of frame k; a blow-up raises :class:`NonFiniteStateError` naming frame k."""
    steps = []
    for _ in range(substeps):
        try:
            steps.append(sim.step())
        except NonFiniteStateError as exc:
            raise NonFiniteStateError(_blowup_message(k, str(exc))) from None
    return steps


def _blowup_message(k: int, detail: str) -> str:
    """One line for a blow-up in frame k (``detail``: the simulation's message)."""
    detail = detail.removeprefix("the state became non-finite at ")
    what = (f"{detail}; a smaller time step, more substeps or softer springs may help; frame "
            f"{k - 1} is the last one kept")
    return f"frame {k}: the state became non-finite ({what})"


def _frame_record(k: int, fps: float, steps: list, tolerance) -> dict:
    flags = [getattr(r, "converged", None) for r in steps]
    # converged means "a tolerance was met": None ("not checked") without a tolerance
    converged = None if tolerance is None or any(f is None for f in flags) else all(flags)
    return {"frame": k, "time": k / fps,
            "iterations": int(sum(r.iterations for r in steps)),
            "residual": float(steps[-1].residual),
            "seconds": float(sum(r.seconds for r in steps)),
            "converged": converged,
            "residual_history": [float(r) for r in steps[-1].residual_history]}


def _draw_previews(folder: RunFolder, scene, sim, fps: float, frames: int, last):
    """preview.gif and final.png of frames 0..frames, drawn in memory: frame ``frames`` is
    ``last`` (None: in the store), the others are in the store (memory-mapped: only the
    frames drawn load). Returns :func:`clothsim.plotting.draw_run_pictures`' dict, or the
    error that drawing raised."""
    stored = frames + 1 if last is None else frames
    positions = list(folder.trajectory("positions", stored))
    positions += [] if last is None else [last]
    times = np.arange(frames + 1) / fps
    try:
        return draw_run_pictures(positions, sim.model.mesh, times=times, effects=sim.effects,
                                 title=_title(scene, times))
    except Exception as exc:  # noqa: BLE001 - raised once the run is marked complete
        return exc


def _request_previews(pictures: PictureProcess, folder: RunFolder, scene, sim, fps: float,
                      frames: int) -> bool:
    """Hand :func:`_draw_previews`' frames to the picture process; False: draw them here.
    Every frame is in the store (the last one too: appended when it was handed over), so
    only the store's name crosses, not the last frame's positions."""
    times = np.arange(frames + 1) / fps
    return pictures.request(folder.store.paths["positions"], frames + 1, None, sim.model.mesh,
                            times=times, effects=sim.effects, title=_title(scene, times))


def _title(scene, times) -> str:
    """final.png's title."""
    return f"{scene.name}, t = {times[-1]:.2f} s"


__all__ = ["run_scene", "RunResult", "completed_frames", "package_versions", "scene_hash",
           "write_json", "write_trajectory", "handle_signals", "NonFiniteStateError",
           "SignalInterrupt", "RESULT_FILES", "STALE_FILES"]
