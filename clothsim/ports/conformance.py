"""The conformance set: tiny scenes that each isolate one effect, with reference data.

:func:`write_conformance` writes one folder per case (``scene.toml`` plus everything
:func:`clothsim.ports.export.export_port` writes: matrices, model files, trajectory and the
local/global iterates of the first steps) and a ``README.md`` a porter reads first. A port
passes a case when ``clothsim check CASE/scene.toml PORT_OUTPUT`` passes; every case is
checkable step by step because each scene file is a complete clothsim scene.
"""

from __future__ import annotations

import json

import numpy as np

from ..io.common import atomic_path, write_text
from ..io.folders import CONFORMANCE_HEADING
from ..io.outfolder import OutputFolder
from ..scene import Scene
from ..simulation import State
from .export import export_port

GRAVITY = {"kind": "gravity", "acceleration": [0.0, -9.81, 0.0]}
_TOP = [20, 24]  # top corners of the 5 × 5 grid in the xy plane


def _base(name: str, description: str, effects: list, plane: str = "xy") -> dict:
    return {
        "scene": {"name": name, "description": description, "frames": 20, "fps": 30},
        "cloth": {"shape": "grid", "size": [1.0, 1.0], "resolution": [5, 5],
                  "center": [0.0, 1.0, 0.0], "plane": plane, "mass": 0.1},
        "springs": {"structural": 100.0, "shear": 100.0, "bending": 10.0},
        "solver": {"method": "local-global", "iterations": 10},
        # the obstacle cases: the projection after the solve that ports of the seed do
        "contact": {"mode": "post-solve"},
        "effects": effects,
    }


def _pins(method="constraint", **extra):
    return {"kind": "pin", "vertices": _TOP, "method": method, **extra}


CASES = {
    "springs-stretch": _base("springs-stretch", "Springs only: the sheet starts stretched by "
                             "20 % about its centre and oscillates (initial-state.txt)", []),
    "gravity-exact-pins": _base("gravity-exact-pins", "Gravity, two corners pinned exactly "
                                "(removed from the unknowns)", [GRAVITY, _pins()]),
    "penalty-pins": _base("penalty-pins", "Gravity, two corners held by penalty springs of "
                          "1000 N/m (in L and the right-hand side)",
                          [GRAVITY, _pins("penalty", stiffness=1000.0)]),
    "plane": _base("plane", "A horizontal sheet falls onto a plane (projection after the "
                   "solve)", [GRAVITY, {"kind": "plane", "point": [0.0, 0.8, 0.0],
                                        "normal": [0.0, 1.0, 0.0]}], plane="xz"),
    "sphere": _base("sphere", "A horizontal sheet falls onto a sphere",
                    [GRAVITY, {"kind": "sphere", "center": [0.0, 0.5, 0.0], "radius": 0.4}],
                    plane="xz"),
    "box": _base("box", "A horizontal sheet falls onto a box",
                 [GRAVITY, {"kind": "box", "min": [-0.2, 0.0, -0.2], "max": [0.2, 0.9, 0.2]}],
                 plane="xz"),
    "impulse": _base("impulse", "No gravity; a disk of the sheet is pushed up for 0.2 s",
                     [{"kind": "impulse", "center": [0.0, 1.0, 0.0], "radius": 0.3,
                       "force": [0.0, 1.0, 0.0], "start": 0.0, "duration": 0.2}], plane="xz"),
    "damping-velocity": _base("damping-velocity", "Hanging sheet with v <- (1 - c) v, c = 0.05",
                              [GRAVITY, _pins(), {"kind": "damping", "model": "velocity",
                                                  "coefficient": 0.05}]),
    "damping-inertial": _base("damping-inertial", "Hanging sheet with y = x + a h v, a = 0.993",
                              [GRAVITY, _pins(), {"kind": "damping", "model": "inertial",
                                                  "coefficient": 0.993}]),
    "damping-rigid": _base("damping-rigid", "Hanging sheet, velocities blended toward the "
                           "rigid-body motion, c = 0.1",
                           [GRAVITY, _pins(), {"kind": "damping", "model": "rigid",
                                               "coefficient": 0.1}]),
    "strain-limit": _base("strain-limit", "Soft hanging sheet with springs shortened to at "
                          "most 10 % stretch after each step",
                          [GRAVITY, _pins(), {"kind": "strain-limit", "max_strain": 0.1}]),
    "wind": _base("wind", "Hanging sheet in a steady wind (drag on each triangle)",
                  [GRAVITY, _pins(), {"kind": "wind", "velocity": [0.0, 0.0, 5.0]}]),
}
CASES["strain-limit"]["springs"] = {"structural": 5.0, "shear": 5.0, "bending": 1.0}


def _toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)
    return "[" + ", ".join(_toml_value(x) for x in v) + "]"


def to_toml(doc: dict) -> str:
    """A scene document as TOML.

    Parameters
    ----------
    doc : dict
        Tables of scalars and arrays; a list value (``effects``) is an array of tables.
        Numbers are in SI units, as in scene files.

    Returns
    -------
    str
        The TOML text.
    """
    out = []
    for table, body in doc.items():
        rows = body if isinstance(body, list) else [body]
        for row in rows:
            out.append(f"[[{table}]]" if isinstance(body, list) else f"[{table}]")
            out += [f"{k} = {_toml_value(v)}" for k, v in row.items()]
            out.append("")
    return "\n".join(out)


def case_simulation(name: str, scene: Scene):
    """A fresh Simulation of case ``name`` (the stretched case starts from its stretch).

    Parameters
    ----------
    name : str
        A key of :data:`CASES`; "springs-stretch" starts 1.2 times stretched, at rest.
    scene : Scene
        The case's scene.

    Returns
    -------
    Simulation
    """
    sim = scene.build_simulation(scene.build_model())
    if name == "springs-stretch":
        x = sim.model.mesh.vertices
        c = x.mean(axis=0)
        sim.state = State(c + 1.2 * (x - c), np.zeros_like(x))
    return sim


README = CONFORMANCE_HEADING + """

Each folder isolates one effect on a 5 × 5 sheet (25 vertices, h = 1/30 s, 10 local/global
iterations per step, y = x_n + h v_n). Start with `springs-stretch` (springs only), then
`gravity-exact-pins` and `penalty-pins`; then the effect your port has.

Per folder:
- `scene.toml`: the clothsim scene (`initial-state.txt` overrides frame 0 where present).
- `manifest.json`: h, solver settings, effects with their parameters, pins (method,
  stiffness), κ(M + h²L) and what each file is.
- Matrices (Matrix Market, 3n rows interleaved x y z per vertex): `M.mtx`, `L.mtx` and
  `A.mtx` = M + h²L **with** penalty pins, `L_springs.mtx` without, `J.mtx` (springs only),
  `A_scalar.mtx` (n × n).
- Model: `vertices.txt`, `x0.txt`, `triangles.txt`, `springs.txt` (a b k r, 0-based),
  `masses.txt`, `pins.txt`, `forces.txt`.
- Reference trajectory: `trajectory.npz`, `positions.txt` / `velocities.txt` (one frame a
  line of 3n numbers), `positions.f64` / `velocities.f64` (raw little-endian float64).
- `iterates/step_0000.npz` …: every local/global iterate x_k and local step d_k of the first
  steps, to check a port one half step at a time.

Check a port that wrote its frames as `positions.txt` and `velocities.txt` into `PORT/`:

    clothsim check CASE/scene.toml PORT/                    # step by step
    clothsim check CASE/scene.toml PORT/ --precision float32
    clothsim compare PORT/ CASE/                            # whole trajectory
    clothsim diff-model CASE/ PORT_MODEL_FOLDER/            # when steps disagree

Cases:
"""


def write_conformance(out_dir, *, frames: int = 20, iterate_steps: int = 2,
                      cases=None, force: bool = False) -> list[str]:
    """Write the conformance set into ``out_dir``; returns the case names written.

    Parameters
    ----------
    out_dir : path
    frames : int, default 20
        Steps of each reference trajectory.
    iterate_steps : int, default 2
        Steps whose iterates are written.
    cases : sequence of str, optional
        A subset of :data:`CASES`.
    force : bool
        Write into ``out_dir`` even when it holds files that are not a conformance set's,
        e.g. the coursework profile (:func:`clothsim.io.folders.claim_folder`).

    Returns
    -------
    list of str
        The case names written, one folder each.
    """
    with OutputFolder(out_dir, "conformance", force=force) as folder:
        folder.mark("writing")  # its README says so until every case is written
        return _write_cases(folder, frames, iterate_steps,
                            list(CASES) if cases is None else list(cases))


def _write_cases(folder: OutputFolder, frames: int, iterate_steps: int,
                 names: list[str]) -> list[str]:
    out = folder.path
    lines = []
    for name in names:
        doc = CASES[name]
        d = out / name
        scene = Scene.from_dict(doc, source=str(d / "scene.toml"), base_dir=d)
        export_port(lambda n=name, s=scene: case_simulation(n, s), d, frames=frames,
                    iterate_steps=iterate_steps)  # an export folder: then the scene beside it
        write_text(d / "scene.toml", to_toml(doc))
        if name == "springs-stretch":
            with atomic_path(d / "initial-state.txt") as tmp:
                np.savetxt(tmp, np.load(d / "trajectory.npz")["positions"][0], fmt="%.17g")
        lines.append(f"- `{name}`: {doc['scene']['description']}")
    folder.mark("complete", README + "\n".join(lines) + "\n")
    return names
