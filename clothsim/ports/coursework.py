"""The coursework conformance profile: cases any solution of the mass-spring assignment runs.

The assignment (A. Jacobson's CSC317/CSC418 mass-spring exercise, whose scenes are in
``../shared/data/jacobson-a8``) fixes what a solution can take: one stiffness k for every
spring, pins held by a penalty of one w (1e10 N/m in its ``main.cpp``), −9.8 N on every
vertex (a force, not m g), iterations started from x_n, 50 iterations at h = 1/30 s. The
general conformance set (:mod:`clothsim.ports.conformance`) mixes stiffnesses and exact
pins, which no solution of the assignment can express; every case here stays inside the
assignment's program.

:func:`write_coursework` writes one folder per case:

``case.json`` and ``case.obj``
    The case in the assignment's own format (``b`` 1-based, as the assignment reads it).
``scene.toml``
    The clothsim scene of that program (shape ``jacobson`` reading ``case.json``).
the export
    Everything :func:`clothsim.ports.export.export_port` writes: the plain model files
    (``vertices.txt``, ``springs.txt``, ``masses.txt``, ``pins.txt``, ``forces.txt``,
    ``settings.txt``) and the expected output (``positions.txt``, ``velocities.txt``).

A solution passes a case when ``clothsim check CASE/scene.toml ITS_OUTPUT`` passes.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..io.assignment import scene_dict
from ..io.common import write_text
from ..io.folders import COURSEWORK_HEADING, claim_folder
from ..io.outfolder import OutputFolder
from ..scene import Scene
from .conformance import to_toml
from .export import export_port


def _grid(nx: int, ny: int, size: float):
    """Vertices of an nx × ny grid in the xy plane, top row at y = 0, index j nx + i."""
    i, j = np.meshgrid(np.arange(nx), np.arange(ny))
    x = np.column_stack([i.ravel() * size / (nx - 1), -j.ravel() * size / (ny - 1),
                         np.zeros(nx * ny)])
    return x, i.ravel(), j.ravel()


def _chain(count: int, length: float):
    x = np.column_stack([np.linspace(0.0, length, count), np.zeros(count), np.zeros(count)])
    return x, [[a, a + 1] for a in range(count - 1)]


def _net(nx: int, ny: int, size: float):
    x, i, j = _grid(nx, ny, size)
    v = j * nx + i
    edges = [[a, a + 1] for a in v[i < nx - 1]] + [[a, a + nx] for a in v[j < ny - 1]]
    return x, edges


def _quads(nx: int, ny: int, size: float):
    x, i, j = _grid(nx, ny, size)
    v = (j * nx + i)[(i < nx - 1) & (j < ny - 1)]
    return x, [[a, a + nx, a + nx + 1, a + 1] for a in v]


def _cases() -> dict:
    spring = (np.array([[0.0, 0.0, 0.0], [0.5, 0.0, 0.0]]), [[0, 1]])
    return {
        "spring": (spring, {"k": 500.0, "m": 1.0, "b": [0]},
                   "One spring of 0.5 m, one end pinned, swinging down"),
        "chain": (_chain(10, 1.0), {"k": 500.0, "m": 1.0, "b": [0, 9]},
                  "A chain of 10 unit masses pinned at both ends, sagging"),
        "net": (_net(6, 6, 1.0), {"k": 300.0, "m": 1.0, "b": [0, 5]},
                "A 6 × 6 net of strands hanging from its top corners"),
        "free-fall": (_net(4, 4, 1.0), {"k": 300.0, "m": 1.0, "b": []},
                      "A 4 × 4 net without pins, falling"),
        "sheet-voronoi": (_quads(6, 6, 1.0), {"k": 1000.0, "b": [0, 5]},
                          "A 6 × 6 quad sheet without m: libigl Voronoi masses, −9.8 N per "
                          "vertex on them"),
        "stiff-chain": (_chain(10, 1.0), {"k": 1e5, "m": 1.0, "b": [0]},
                        "A chain of 10 unit masses, k = 1e5 N/m, one end pinned"),
    }


#: Case names, in the order a student should try them.
CASES = tuple(_cases())


def _write_obj(path: Path, x: np.ndarray, faces) -> None:
    lines = [f"v {a:.17g} {b:.17g} {c:.17g}" for a, b, c in x]
    lines += ["f " + " ".join(str(v + 1) for v in f) for f in faces]
    write_text(path, "\n".join(lines) + "\n")


README = COURSEWORK_HEADING + """

Cases of the mass-spring assignment that every solution can run without edits: one
stiffness k for all springs, pins held by a penalty w = 1e10 N/m, -9.8 N on every vertex,
each step's 50 local/global iterations started from the previous positions x_n, h = 1/30 s.

Per folder: `case.json` + `case.obj` (the assignment's format; `b` is 1-based),
`scene.toml` (the clothsim scene), the plain model files (`vertices.txt`, `springs.txt`,
`masses.txt`, `pins.txt`, `forces.txt`, `settings.txt`) and the expected output
(`positions.txt`, `velocities.txt`: frame 0 first, one frame a line of 3n numbers).

Run your solution on a case (the driver in clothsim's `examples/ports/cpp` reads the plain
files), write its frames as `positions.txt` and `velocities.txt` into `OUT/`, then

    clothsim check CASE/scene.toml OUT/

Cases:
"""


def write_coursework(out_dir, *, frames: int = 30, cases=None,
                     force: bool = False) -> list[str]:
    """Write the coursework profile into ``out_dir``; returns the case names written.

    Parameters
    ----------
    out_dir : path
    frames : int, default 30
        Steps of each expected trajectory.
    cases : sequence of str, optional
        A subset of :data:`CASES`.
    force : bool
        Write into ``out_dir`` even when it holds files that are not a coursework
        profile's, e.g. the general conformance set (:func:`clothsim.io.folders.claim_folder`).

    Returns
    -------
    list of str
        The case names written, one folder each.
    """
    with OutputFolder(out_dir, "coursework", force=force) as folder:
        folder.mark("writing")  # its README says so until every case is written
        return _write_cases(folder, frames, list(CASES) if cases is None else list(cases))


def _write_cases(folder: OutputFolder, frames: int, names: list[str]) -> list[str]:
    table = _cases()
    out = folder.path
    lines = []
    for name in names:
        (x, faces), spec, description = table[name]
        d = claim_folder(out / name, "export")   # new, empty, or an earlier case's export
        d.mkdir(exist_ok=True)
        _write_obj(d / "case.obj", x, faces)
        doc = {"obj": "case.obj", **spec, "b": [v + 1 for v in spec["b"]]}
        write_text(d / "case.json", json.dumps(doc, indent=1) + "\n")
        scene_doc = scene_dict(d / "case.json", frames=frames)
        scene_doc["scene"].update(name=f"coursework-{name}", description=description)
        scene_doc["cloth"]["file"] = "case.json"
        write_text(d / "scene.toml", to_toml(scene_doc))
        scene = Scene.from_dict(scene_doc, source=str(d / "scene.toml"), base_dir=d)
        export_port(scene, d, frames=frames, iterate_steps=0, force=True)  # beside case.*
        lines.append(f"- `{name}`: {description}")
    folder.mark("complete", README + "\n".join(lines) + "\n")
    return names
