"""The stability suite's long-run measurement (docs/stability.md, case 9): the flag scene run
for 10⁴ steps, its bounding volume and the trend of its step time. Shared by
tests/test_stability_long.py (asserts on it) and ``python -m benchmarks.stability_figures``
(prints it); the other measurements are in :mod:`benchmarks.measure_stability`.
"""

from __future__ import annotations

import time

import numpy as np
from scipy.stats import theilslopes

from clothsim.scene import Scene, load_scene

TEST_RESOLUTION = (7, 5)    # the coarse flag the test runs (the scene has 31 × 21)


def flag_scene(resolution=None) -> Scene:
    """The built-in flag scene, optionally with ``cloth.resolution`` overridden."""
    scene = load_scene("flag")
    if resolution is None:
        return scene
    data = scene.to_dict()
    data["cloth"]["resolution"] = [int(r) for r in resolution]
    return Scene.from_dict(data, source=f"flag[{resolution[0]}x{resolution[1]}]")


def segment_distance(x: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance [m] of each point of x (n, 3) to the segment from a to b (3,)."""
    ab = b - a
    t = np.clip((x - a) @ ab / (ab @ ab), 0.0, 1.0)
    return np.linalg.norm(x - (a + t[:, None] * ab), axis=1)


def relative_trend(seconds: np.ndarray, chunk: int, control=None) -> dict:
    """Theil–Sen slope of per-chunk medians of step times, relative, per 1000 steps.

    Parameters
    ----------
    seconds : (N,) array
        Time of each step [s].
    chunk : int
        Steps per chunk.
    control : (N // chunk, k) array, optional
        Times of k control steps taken during each chunk [s]; the chunk medians are then
        divided by the control medians (machine speed changes cancel).
    """
    count = len(seconds) // chunk
    medians = np.median(seconds[:count * chunk].reshape(count, chunk), axis=1)
    if control is not None:
        medians = medians / np.median(control[:count], axis=1)
    centre = (np.arange(count) + 0.5) * chunk
    slope = theilslopes(medians, centre)[0]                  # per step, per step
    typical = float(np.median(medians))
    return {"chunk_medians": medians, "median": typical,
            "relative_slope_per_1000": float(slope * 1000.0 / typical),
            "last_over_first": float(medians[-1] / medians[0])}


def measure_long_run(*, resolution=TEST_RESOLUTION, steps: int = 10_000,
                     chunk: int = 500, control_every: int = 10) -> dict:
    """Run the flag scene ``steps`` steps; check every step; time each step.

    The machine's speed drifts (other processes, clock), so a control simulation of the
    same scene, put back to its first state every ``chunk // control_every`` steps so that
    it never runs long, takes one step every ``control_every`` steps, interleaved; the
    normalized trend divides each chunk's median by the control's median in that chunk.

    Parameters
    ----------
    resolution : (2,) ints or None
        ``cloth.resolution`` override; None runs the scene as shipped (31 × 21).
    steps : int
        Steps of h = 1/30 s.
    chunk : int
        Steps per chunk of the trend fit.
    control_every : int
        One control step per this many steps.

    Returns
    -------
    dict
        ``finite`` (every position and velocity after every step), ``steps_done``,
        ``max_pole_ratio`` (largest distance to the pole / W over all steps), ``width`` W [m],
        ``max_speed`` [m/s], ``time_drift`` |t_N − N h| [s], ``cpu``, ``wall`` and
        ``normalized`` (CPU time / control CPU time) trend dicts of :func:`relative_trend`,
        ``wall_total`` [s], ``vertex_count``.
    """
    scene = flag_scene(resolution)
    sim, control = scene.build_simulation(), scene.build_simulation()
    control_start = control.state
    rest = sim.model.mesh.vertices
    pole = rest[sim.pinned_vertices(sim.h)]
    a, b = pole.min(axis=0), pole.max(axis=0)          # the pinned edge is axis-aligned
    width = float(segment_distance(rest, a, b).max())
    cpu, wall = np.empty(steps), np.empty(steps)
    per_chunk = chunk // control_every
    control_cpu = np.empty((steps // chunk + 1, per_chunk))
    finite, done, max_ratio, max_speed = True, 0, 0.0, 0.0
    for i in range(steps):
        c0, w0 = time.process_time(), time.perf_counter()
        sim.step()
        cpu[i], wall[i] = time.process_time() - c0, time.perf_counter() - w0
        x, v = sim.state.positions, sim.state.velocities
        if not (np.isfinite(x).all() and np.isfinite(v).all()):
            finite = False
            break
        done = i + 1
        max_ratio = max(max_ratio, float(segment_distance(x, a, b).max()) / width)
        max_speed = max(max_speed, float(np.sqrt((v * v).sum(axis=1).max())))
        if i % control_every == 0:
            k = (i % chunk) // control_every
            if k == 0:
                control.state = control_start
            c0 = time.process_time()
            control.step()
            control_cpu[i // chunk, k] = time.process_time() - c0
    return {"finite": finite, "steps_done": done, "max_pole_ratio": max_ratio, "width": width,
            "max_speed": max_speed, "time_drift": abs(sim.state.time - done * sim.h),
            "cpu": relative_trend(cpu[:done], chunk), "wall": relative_trend(wall[:done], chunk),
            "normalized": relative_trend(cpu[:done], chunk, control_cpu),
            "wall_total": float(wall[:done].sum()), "vertex_count": sim.model.vertex_count}
