"""Contact that keeps the cloth whole: both contact modes on the two obstacle scenes.

Run from the repository root::

    .venv/bin/python -m benchmarks contact                       # 25², 65² (minutes)
    .venv/bin/python -m benchmarks.contact --sizes 129           # one size more (~10 min)
    .venv/bin/python -m benchmarks.contact --sizes 257           # the largest (~1 h)
    .venv/bin/python -m benchmarks.contact --sizes 49 --scenes drape-sphere --modes hold
    .venv/bin/python -m benchmarks.contact --options --sizes 25 65   # the option not chosen
    .venv/bin/python -m benchmarks.contact --trace --sizes 25 --scenes drape-sphere --modes hold

Each run is the built-in scene (``drop-on-square``: a 1 m cloth dropped onto a 0.5 m box;
``drape-sphere``: onto a 0.3 m sphere) at n × n vertices, h = 1/30 s, in
``[contact] mode = "hold"`` (the default) as shipped (120 frames of 30 Anderson-accelerated
local/global iterations, its declared damping) or ``"post-solve"`` (the seed's projection
after the solve) as the seed ran it (:data:`SEED`: 90 frames of 10 local/global
iterations, no damping). Measured per run
(:func:`measure_contact`): the largest spring stretch |p|/r and the largest 99th
percentile of the stretch over the springs, both over the frames of the last second; the
deepest any vertex ended a step inside an obstacle (whole run); the largest |v| over the
last second, of all vertices and of those in contact with an obstacle, and whether the
first is below :data:`REST_SPEED` ("at rest"); the deepest any obstacle lies in front of
the cloth's triangles over the last second (an edge of the box or the sphere's cap between
vertices, :func:`through_cloth`); vertices ending on the sphere below its equator; the
frames whose contact set changed (each refactors the held-contact system); wall seconds
per frame. ``--trace`` prints, frame by frame, what the contacts do
(:func:`trace_contact`); ``--rest`` compares the solver and damping settings the scenes
were chosen from (:mod:`benchmarks.contact_rest`).

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
#: The seed's solve: 10 local/global iterations (the paper's), 90 frames, no damping.
SEED = {"damping": False, "solver": {"method": "local-global", "iterations": 10}, "frames": 90}
#: How each mode's runs are set up: "hold" runs the scene as shipped; "post-solve"
#: reproduces the seed (:data:`SEED`: its scenes declared no damping and ran 3 s of the
#: paper's 10 local/global iterations).
AS_RUN = {"hold": {}, "post-solve": SEED}
#: "At rest": every vertex slower than this [m/s] over the last second of the scene.
REST_SPEED = 0.02
JSON = ROOT / "docs" / "data" / "contact.json"
PAGE = ROOT / "docs" / "data" / "contact.md"


def _depth(effect, x: np.ndarray) -> float:
    """How deep the deepest vertex is inside the obstacle [m] (0 when none is)."""
    inside = np.flatnonzero(effect.inside(x))
    if not len(inside):
        return 0.0
    q, _ = effect.closest(x[inside])
    return float(np.linalg.norm(x[inside] - q, axis=1).max())


def _scene(scene: str, resolution: int, contact: str, damping=None,
           solver: dict | None = None, thickness=None) -> Scene:
    """The built-in ``scene`` at ``resolution``² in ``contact`` mode; ``damping``: None keeps
    the scene's own damping, False removes it, a dict replaces it (``[[effects]]`` keys);
    ``solver``: ``[solver]`` keys replacing the scene's (a new ``method`` starts from that
    method's defaults); ``thickness``: the box's and the sphere's, when given."""
    doc = tomllib.loads(builtin_scene_text(scene))
    doc["cloth"]["resolution"] = [resolution, resolution]
    doc["contact"] = {"mode": contact}
    if thickness is not None:
        for e in doc["effects"]:
            if e["kind"] in ("box", "sphere"):
                e["thickness"] = thickness
    if solver:
        doc["solver"] = {**({} if "method" in solver else doc["solver"]), **solver}
    if damping is not None:
        doc["effects"] = [e for e in doc["effects"] if e["kind"] != "damping"]
        if damping:
            doc["effects"].append({"kind": "damping", **damping})
    return Scene.from_dict(doc, source=f"{scene}.toml")


def _held(obstacles) -> tuple[set, set, bytes]:
    """The held vertices, the sticking ones and the contact set's key (what a change of
    refactors the held-contact system), as the obstacles hand them to the next step."""
    held, stick, key = set(), set(), b""
    for e in obstacles:
        h = e._holding
        held.update(h.vertices.tolist())
        stick.update(h.vertices[h.stick].tolist())
        key += h.planes.vertices.tobytes() + h.planes.normals.tobytes()
    return held, stick, key


def _fastest(speed: np.ndarray, vertices: set) -> float:
    return float(speed[sorted(vertices)].max()) if len(vertices) else 0.0


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


def trace_contact(scene: str, resolution: int, contact: str = "hold", *,
                  frames: int | None = None, damping=None, solver: dict | None = None,
                  thickness=None):
    """Run an obstacle scene frame by frame and say what its contacts do (a diagnostic).

    Parameters
    ----------
    scene : {"drop-on-square", "drape-sphere"}
    resolution : int
        Vertices per side.
    contact : {"hold", "post-solve"}
    frames : int, optional
        Default: the scene's.
    damping : None, False or dict, optional
        The scene's damping (None), none (False), or this ``[[effects]]`` table.
    solver : dict, optional
        ``[solver]`` keys replacing the scene's (e.g. ``{"method": "local-global",
        "iterations": 10}``).
    thickness : float or "auto", optional
        The box's and the sphere's ``thickness`` [m] (default: the scene's, ``"auto"``).

    Yields
    ------
    dict
        Per frame: ``frame``, ``seconds`` (wall, of its steps), ``x`` and ``v`` (n, 3),
        ``touching`` (vertices in contact at its end), ``held`` (handed to the next step),
        ``entered`` and ``left`` (the held set against the previous frame's), ``sticking``
        and ``stick_changed`` (vertices held in all three directions, and how many switched
        between sticking and sliding), ``set_changed`` (whether the planes handed to the
        next step differ: a refactorization in "hold" mode), ``speed``, ``held_speed`` and
        ``stick_speed`` (max |v| of all, held and sticking vertices [m/s]),
        ``factorizations`` (so far).
    """
    sc = _scene(scene, resolution, contact, damping, solver, thickness)
    sim = sc.build_simulation()
    frames = sc.frames if frames is None else frames
    obstacles = [e for e in sim.effects if hasattr(e, "inside")]
    sim.expect_steps(frames * sc.substeps)
    held, stick, key = _held(obstacles)
    for f in range(frames):
        t0 = time.perf_counter()
        for _ in range(sc.substeps):
            sim.step()
        seconds = time.perf_counter() - t0
        x, v = sim.state.positions, sim.state.velocities
        speed = np.linalg.norm(v, axis=1)
        now, now_stick, now_key = _held(obstacles)
        touching = np.unique(np.concatenate([np.zeros(0, np.int64)] + [
            e.contact_vertices for e in obstacles]))
        yield {"frame": f, "seconds": seconds, "x": x, "v": v, "touching": touching,
               "held": len(now), "entered": len(now - held), "left": len(held - now),
               "sticking": len(now_stick), "stick_changed": len((now_stick ^ stick) & now & held),
               "set_changed": now_key != key, "speed": float(speed.max()),
               "held_speed": _fastest(speed, now), "stick_speed": _fastest(speed, now_stick),
               "factorizations": int(getattr(sim.solver, "factor_count", 0)),
               "model": sim.model, "obstacles": obstacles}
        held, stick, key = now, now_stick, now_key


def measure_contact(scene: str, resolution: int, contact: str, *, frames: int | None = None,
                    last: int | None = None, damping=None, solver: dict | None = None,
                    thickness=None) -> dict:
    """Run a built-in obstacle scene at ``resolution``² in a contact mode; measure it.

    Parameters
    ----------
    scene, resolution, contact, frames, damping, solver, thickness
        As :func:`trace_contact` (``contact`` is ``[contact] mode``; frames default to
        the scene's).
    last : int, optional
        Frames of the final window (default: one second).

    Returns
    -------
    dict
        ``max_stretch`` and ``p99_stretch`` (largest over the last window), ``max_inside``
        [m] (whole run), ``max_speed`` [m/s] and ``max_contact_speed`` (of the vertices in
        contact) over the last window, ``through_cloth`` [m] (:func:`through_cloth`, over
        the last window), ``margins`` (each obstacle's contact thickness in use [m]),
        ``at_rest`` (``max_speed`` below
        :data:`REST_SPEED`), ``set_changes`` (frames whose contact set changed, whole run),
        ``below_equator`` (vertices on the sphere below its centre at the end; 0 without a
        sphere), ``seconds_per_frame`` [s], ``factorizations`` and the run's settings.
    """
    sc = _scene(scene, resolution, contact, damping, solver, thickness)
    frames = sc.frames if frames is None else frames
    last = round(sc.fps) if last is None else last
    stretch = p99 = speed = inside = contact_speed = seconds = through = 0.0
    changes = 0
    for r in trace_contact(scene, resolution, contact, frames=frames, damping=damping,
                           solver=solver, thickness=thickness):
        x, obstacles = r["x"], r["obstacles"]
        seconds += r["seconds"]
        changes += r["set_changed"]
        inside = max([inside] + [_depth(e, x) for e in obstacles])
        if r["frame"] >= frames - last:
            model = r["model"]
            ratio = energy.spring_lengths(model, x) / model.springs.spring_rest_length
            stretch = max(stretch, float(ratio.max()))
            p99 = max(p99, float(np.percentile(ratio, 99)))
            through = max(through, through_cloth(obstacles, x, r["model"].mesh.triangles))
            speed = max(speed, r["speed"])
            if len(r["touching"]):
                v = np.linalg.norm(r["v"][r["touching"]], axis=1)
                contact_speed = max(contact_speed, float(v.max()))
    below = 0
    for e in obstacles:
        if e.kind == "sphere":
            gap = np.linalg.norm(x - e.center, axis=1) - e.radius - e.margin
            below += int(np.count_nonzero((gap < 1e-6) & (x[:, 1] < e.center[1])))
    return {"scene": scene, "resolution": resolution, "contact": contact, "frames": frames,
            "max_stretch": stretch, "p99_stretch": p99, "max_inside": inside,
            "through_cloth": through, "margins": [e.margin for e in obstacles],
            "max_speed": speed, "max_contact_speed": contact_speed,
            "at_rest": speed < REST_SPEED, "set_changes": changes, "below_equator": below,
            "seconds_per_frame": seconds / frames, "factorizations": r["factorizations"]}


def measure_projected_iterations(scene: str, resolution: int, iterations: int = 10) -> float:
    """The option held contacts were chosen over, measured: the obstacles' projection
    (``"post-solve"``) applied after *every* global step of local/global, the factor of
    M + h² L unchanged (projective dynamics' way with collision constraints). Returns the
    largest spring stretch over the last second of the seed's 90 frames."""
    doc = tomllib.loads(builtin_scene_text(scene))
    doc["cloth"]["resolution"] = [resolution, resolution]
    doc["contact"] = {"mode": "post-solve"}
    doc["solver"] = dict(SEED["solver"])
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


def _trace_line(r: dict) -> str:
    return (f"frame {r['frame']:3d}: held {r['held']:5d} +{r['entered']:<4d} -{r['left']:<4d} "
            f"sticking {r['sticking']:5d} (switched {r['stick_changed']:4d}) "
            f"set {'changed' if r['set_changed'] else 'same   '} max |v| {r['speed']:.3f}, "
            f"held {r['held_speed']:.3f}, sticking {r['stick_speed']:.3f} m/s, "
            f"factorizations {r['factorizations']}")


def _load() -> list[dict]:
    if JSON.is_file():
        return json.loads(JSON.read_text(encoding="utf-8"))["runs"]
    return []


def _rest(r: dict) -> str:
    return "yes" if r["max_speed"] < REST_SPEED else "no"


def _lengths() -> str:
    """Each scene's declared number of frames, as the page says it."""
    return ", ".join(f"{s} {tomllib.loads(builtin_scene_text(s))['scene']['frames']}"
                     for s in SCENES)


def page(runs: list[dict]) -> str:
    """The Markdown table of ``runs`` (sorted by scene, size, mode)."""
    order = {s: i for i, s in enumerate(SCENES)}
    runs = sorted(runs, key=lambda r: (order.get(r["scene"], 9), r["resolution"],
                                       MODES.index(r["contact"])))
    out = ["Printed by `.venv/bin/python -m benchmarks contact` (the default sizes; others "
           "run separately, e.g. `.venv/bin/python -m benchmarks.contact --sizes 257 --scenes "
           "drape-sphere --modes hold`; each row names the commit it was measured at).", "",
           f"At rest means every vertex slower than {REST_SPEED} m/s over the last second. "
           "\"hold\" runs the scene as it is (its own frames: " + _lengths() + ", "
           "declared solver and damping); "
           "\"post-solve\" runs the seed's scene as the seed did (90 frames of 10 local/global "
           "iterations, no damping). Contact set changes: frames whose held planes differ from "
           "the previous frame's (each one refactors the held-contact system).", "",
           "| scene | n² | mode | max stretch | 99th pct stretch | max depth inside [m] | "
           "obstacle through cloth [m] | "
           "max \\|v\\| last second [m/s] | at rest | in contact [m/s] | "
           "on sphere below equator | contact set changes | s per frame | factorizations | "
           "commit |",
           "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in runs:
        out.append(f"| {r['scene']} | {r['resolution']}² | {r['contact']} | "
                   f"{r['max_stretch']:.3f} | {r['p99_stretch']:.3f} | {r['max_inside']:.1e} | "
                   f"{_cell(r.get('through_cloth'))} | "
                   f"{r['max_speed']:.3f} | {_rest(r)} | "
                   f"{r.get('max_contact_speed', float('nan')):.3f} | "
                   f"{r['below_equator']} | {r.get('set_changes', '')} | "
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
    parser.add_argument("--trace", action="store_true",
                        help="print what the contacts do in every frame (held set, vertices "
                             "entering and leaving it, sticking, speeds), writing nothing")
    parser.add_argument("--rest", action="store_true",
                        help="compare solver and damping settings by when the scenes come "
                             "to rest (default sizes 25 49; benchmarks/contact_rest.py) and "
                             "write docs/data/contact-rest.md")
    args = parser.parse_args([] if argv is None else argv)
    warnings.simplefilter("ignore")
    if args.rest:
        from .contact_rest import write_rest_page

        write_rest_page(args.sizes if argv and "--sizes" in argv else None)
        return
    if args.trace:
        for n in args.sizes:
            for scene in args.scenes:
                for mode in args.modes:
                    print(f"== {scene} {n}^2 {mode}", flush=True)
                    for r in trace_contact(scene, n, mode):
                        print(_trace_line(r), flush=True)
        return
    if args.options:
        for n in args.sizes:
            for scene in args.scenes:
                print(f"{scene} {n}^2, projection after every global step: largest stretch "
                      f"over the last second {measure_projected_iterations(scene, n):.3f}",
                      flush=True)
        return
    where = commit()
    for n in args.sizes:
        for scene in args.scenes:
            for mode in args.modes:
                r = measure_contact(scene, n, mode, **AS_RUN[mode])
                r["commit"] = where
                r["load"] = round(os.getloadavg()[0], 2)
                print(f"{scene} {n}^2 {mode}: max stretch {r['max_stretch']:.3f}, 99th pct "
                      f"{r['p99_stretch']:.3f}, max depth {r['max_inside']:.1e} m, obstacle "
                      f"through cloth {r['through_cloth']:.1e} m, max |v| "
                      f"{r['max_speed']:.3f} m/s ({r['max_contact_speed']:.3f} in contact), "
                      f"below equator {r['below_equator']}, at rest {_rest(r)}, "
                      f"contact set changed in {r['set_changes']} frames, "
                      f"{r['seconds_per_frame']:.3f} s/frame, {r['factorizations']} factors",
                      flush=True)
                # Read again: other sizes may be run at the same time in other processes.
                store(_load(), r, ("scene", "resolution", "contact"), JSON, PAGE, page)


if __name__ == "__main__":
    import sys

    main(sys.argv[1:])
