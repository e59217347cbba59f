"""Contact that keeps the cloth whole: both contact modes on the two obstacle scenes.

Run from the repository root::

    .venv/bin/python -m benchmarks contact                       # 25², 65² (minutes)
    .venv/bin/python -m benchmarks.contact --sizes 129           # one size more (~10 min)
    .venv/bin/python -m benchmarks.contact --sizes 257           # the largest (~1 h)
    .venv/bin/python -m benchmarks.contact --sizes 49 --scenes drape-sphere --modes hold
    .venv/bin/python -m benchmarks.contact --options --sizes 25 65   # the option not chosen

Each run is the built-in scene (``drop-on-square``: a 1 m cloth dropped onto a 0.5 m box;
``drape-sphere``: onto a 0.3 m sphere) at n × n vertices, its default 90 frames of
h = 1/30 s and 10 local/global iterations, in ``[contact] mode = "hold"`` (the default)
or ``"post-solve"`` (the seed's projection after the solve). Measured per run
(:func:`measure_contact`): the largest spring stretch |p|/r and the largest 99th
percentile of the stretch over the springs, both over the frames of the last second; the
deepest any vertex ended a step inside an obstacle (whole run); the largest |v| over the
last second, of all vertices and of those in contact with an obstacle; the deepest any
obstacle lies in front of the cloth's triangles over the last second (an edge of the box
or the sphere's cap between vertices, :func:`through_cloth`); vertices ending on the
sphere below its equator; wall seconds per frame.

Runs are stored one per row in ``docs/data/contact.json`` (a run replaces the row of the
same scene, size and mode), and ``docs/data/contact.md`` is rewritten from all rows, so
sizes can be run separately (the large ones on a quiet machine) and the page collects them.
"""

from __future__ import annotations

import argparse
import json
import os
import time
import tomllib
import warnings

import numpy as np

from clothsim import energy
from clothsim.io.common import atomic_path
from clothsim.scene import Scene, builtin_scene_text

from . import ROOT
from .cloth_depth import depth_through_cloth
from .iteration_cost import commit

SCENES = ("drop-on-square", "drape-sphere")
MODES = ("hold", "post-solve")
SIZES = (25, 65, 129, 257)
DEFAULT_SIZES = (25, 65)
JSON = ROOT / "docs" / "data" / "contact.json"
PAGE = ROOT / "docs" / "data" / "contact.md"


def _depth(effect, x: np.ndarray) -> float:
    """How deep the deepest vertex is inside the obstacle [m] (0 when none is)."""
    inside = np.flatnonzero(effect.inside(x))
    if not len(inside):
        return 0.0
    q, _ = effect.closest(x[inside])
    return float(np.linalg.norm(x[inside] - q, axis=1).max())


def through_cloth(obstacles, x: np.ndarray, triangles: np.ndarray) -> float:
    """How far the obstacles lie in front of the cloth's triangles [m] (0 when none do).

    Parameters
    ----------
    obstacles : list of Obstacle
    x : ndarray, shape (n, 3)
        Cloth positions [m].
    triangles : ndarray, shape (T, 3), int

    Returns
    -------
    float
        The largest :func:`~benchmarks.cloth_depth.depth_through_cloth` over the obstacles:
        measured against each solid as declared, without its contact thickness.
    """
    return max([0.0] + [depth_through_cloth(e, x, triangles) for e in obstacles])


def measure_contact(scene: str, resolution: int, contact: str, *, frames: int | None = None,
                    last: int | None = None, thickness=None) -> dict:
    """Run a built-in obstacle scene at ``resolution``² in a contact mode; measure it.

    Parameters
    ----------
    scene : {"drop-on-square", "drape-sphere"}
    resolution : int
        Vertices per side.
    contact : {"hold", "post-solve"}
        ``[contact] mode``.
    frames : int, optional
        Frames to run (default: the scene's, 90).
    last : int, optional
        Frames of the final window (default: one second).
    thickness : float or "auto", optional
        The box's and the sphere's ``thickness`` [m] (default: the scene's, ``"auto"``).

    Returns
    -------
    dict
        ``max_stretch`` and ``p99_stretch`` (largest over the last window), ``max_inside``
        [m] (whole run), ``through_cloth`` [m] (:func:`through_cloth`, over the last
        window), ``margins`` (each obstacle's contact thickness in use [m]),
        ``max_speed`` [m/s] and ``max_contact_speed`` (of the vertices in
        contact) over the last window, ``below_equator`` (vertices on
        the sphere below its centre at the end; 0 without a sphere), ``seconds_per_frame``
        [s], ``factorizations`` and the run's settings.
    """
    doc = tomllib.loads(builtin_scene_text(scene))
    doc["cloth"]["resolution"] = [resolution, resolution]
    doc["contact"] = {"mode": contact}
    if thickness is not None:
        for e in doc["effects"]:
            if e["kind"] in ("box", "sphere"):
                e["thickness"] = thickness
    sc = Scene.from_dict(doc, source=f"{scene}.toml")
    sim = sc.build_simulation()
    frames = sc.frames if frames is None else frames
    last = round(sc.fps) if last is None else last
    rest = sim.model.springs.spring_rest_length
    obstacles = [e for e in sim.effects if hasattr(e, "inside")]
    sim.expect_steps(frames * sc.substeps)
    stretch = p99 = speed = inside = contact_speed = through = 0.0
    triangles = sim.model.mesh.triangles
    seconds = 0.0
    for f in range(frames):
        t0 = time.perf_counter()
        for _ in range(sc.substeps):
            sim.step()
        seconds += time.perf_counter() - t0
        x = sim.state.positions
        inside = max([inside] + [_depth(e, x) for e in obstacles])
        if f >= frames - last:
            ratio = energy.spring_lengths(sim.model, x) / rest
            stretch = max(stretch, float(ratio.max()))
            p99 = max(p99, float(np.percentile(ratio, 99)))
            through = max(through, through_cloth(obstacles, x, triangles))
            v = np.linalg.norm(sim.state.velocities, axis=1)
            speed = max(speed, float(v.max()))
            touching = np.unique(np.concatenate([np.zeros(0, np.int64)] + [
                e.contact_vertices for e in obstacles]))
            if len(touching):
                contact_speed = max(contact_speed, float(v[touching].max()))
    below = 0
    for e in obstacles:
        if e.kind == "sphere":
            gap = np.linalg.norm(x - e.center, axis=1) - e.radius - e.margin
            below += int(np.count_nonzero((gap < 1e-6) & (x[:, 1] < e.center[1])))
    return {"scene": scene, "resolution": resolution, "contact": contact, "frames": frames,
            "max_stretch": stretch, "p99_stretch": p99, "max_inside": inside,
            "through_cloth": through, "margins": [e.margin for e in obstacles],
            "max_speed": speed, "max_contact_speed": contact_speed, "below_equator": below,
            "seconds_per_frame": seconds / frames,
            "factorizations": int(getattr(sim.solver, "factor_count", 0))}


def measure_projected_iterations(scene: str, resolution: int, iterations: int = 10) -> float:
    """The option held contacts were chosen over, measured: the obstacles' projection
    (``"post-solve"``) applied after *every* global step of local/global, the factor of
    M + h² L unchanged (projective dynamics' way with collision constraints). Returns the
    largest spring stretch over the last second of the scene's 90 frames."""
    doc = tomllib.loads(builtin_scene_text(scene))
    doc["cloth"]["resolution"] = [resolution, resolution]
    doc["contact"] = {"mode": "post-solve"}
    sim = Scene.from_dict(doc, source=f"{scene}.toml").build_simulation()
    obstacles = [e for e in sim.effects if hasattr(e, "inside")]
    solver, rest, worst = sim.solver, sim.model.springs.spring_rest_length, 0.0
    for f in range(90):
        s, p = sim.state, sim.problem()
        x, t1 = p.initial_guess(), s.time + sim.h
        for _ in range(iterations):
            x = solver.global_step(p, solver.local_step(x))
            for e in obstacles:
                x = e.correct_positions(t1, s, x)
        v = (x - s.positions) / sim.h
        for e in obstacles:
            v = e.correct_velocities(t1, s, x, v)
        sim.state = type(s)(x, v, t1, s.step + 1)
        if f >= 60:
            worst = max(worst, float((energy.spring_lengths(sim.model, x) / rest).max()))
    return worst


def _load() -> list[dict]:
    if JSON.is_file():
        return json.loads(JSON.read_text(encoding="utf-8"))["runs"]
    return []


def page(runs: list[dict]) -> str:
    """The Markdown table of ``runs`` (sorted by scene, size, mode)."""
    order = {s: i for i, s in enumerate(SCENES)}
    runs = sorted(runs, key=lambda r: (order.get(r["scene"], 9), r["resolution"],
                                       MODES.index(r["contact"])))
    out = ["Printed by `.venv/bin/python -m benchmarks contact` (sizes run separately with "
           "`--sizes`; each row names the commit it was measured at).", "",
           "| scene | n² | mode | max stretch | 99th pct stretch | max depth inside [m] | "
           "obstacle through cloth [m] | "
           "max \\|v\\| last second [m/s] | in contact [m/s] | on sphere below equator | "
           "s per frame | factorizations | commit |",
           "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in runs:
        out.append(f"| {r['scene']} | {r['resolution']}² | {r['contact']} | "
                   f"{r['max_stretch']:.3f} | {r['p99_stretch']:.3f} | {r['max_inside']:.1e} | "
                   f"{_cell(r.get('through_cloth'))} | "
                   f"{r['max_speed']:.3f} | {r.get('max_contact_speed', float('nan')):.3f} | "
                   f"{r['below_equator']} | "
                   f"{r['seconds_per_frame']:.3f} | {r['factorizations']} | {r['commit']} |")
    return "\n".join(out) + "\n"


def store(runs: list[dict], row: dict, key: tuple, json_path, page_path, page_of) -> list:
    """``runs`` with ``row`` in place of the run of the same ``key`` fields, written at
    once to ``json_path`` and, as ``page_of(runs)``, to ``page_path`` (atomically)."""
    runs = [q for q in runs if [q[k] for k in key] != [row[k] for k in key]] + [row]
    with atomic_path(json_path) as tmp:
        tmp.write_text(json.dumps({"runs": runs}, indent=1) + "\n", encoding="utf-8")
    with atomic_path(page_path) as tmp:
        tmp.write_text(page_of(runs), encoding="utf-8")
    return runs


def _cell(value) -> str:
    return "—" if value is None else f"{value:.1e}"


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=list(DEFAULT_SIZES),
                        help=f"vertices per side (default {' '.join(map(str, DEFAULT_SIZES))};"
                             f" the page's table has {' '.join(map(str, SIZES))})")
    parser.add_argument("--scenes", nargs="+", choices=SCENES, default=list(SCENES))
    parser.add_argument("--modes", nargs="+", choices=MODES, default=list(MODES))
    parser.add_argument("--options", action="store_true",
                        help="print the alternative measured instead (projection in every "
                             "iteration), writing nothing")
    args = parser.parse_args([] if argv is None else argv)
    warnings.simplefilter("ignore")
    if args.options:
        for n in args.sizes:
            for scene in args.scenes:
                print(f"{scene} {n}^2, projection after every global step: largest stretch "
                      f"over the last second {measure_projected_iterations(scene, n):.3f}",
                      flush=True)
        return
    runs = _load()
    where = commit()
    for n in args.sizes:
        for scene in args.scenes:
            for mode in args.modes:
                r = measure_contact(scene, n, mode)
                r["commit"] = where
                r["load"] = round(os.getloadavg()[0], 2)
                print(f"{scene} {n}^2 {mode}: max stretch {r['max_stretch']:.3f}, 99th pct "
                      f"{r['p99_stretch']:.3f}, max depth {r['max_inside']:.1e} m, obstacle "
                      f"through cloth {r['through_cloth']:.1e} m, max |v| "
                      f"{r['max_speed']:.3f} m/s ({r['max_contact_speed']:.3f} in contact), "
                      f"below equator {r['below_equator']}, "
                      f"{r['seconds_per_frame']:.3f} s/frame, {r['factorizations']} factors",
                      flush=True)
                runs = store(runs, r, ("scene", "resolution", "contact"), JSON, PAGE, page)


if __name__ == "__main__":
    import sys

    main(sys.argv[1:])
