"""The referee audited: ports × printings × planted faults × scenes, and whether ``check``
gives each the right verdict and names the right cause.

Each port is clothsim's own run of a small non-contact scene (a cloth hanging from its two
top corners, 10 local/global iterations from y, a few frames) with one fault planted: a
scene key changed (as ``--set`` changes it), the model changed (rest lengths), or the
output changed as a port might write it (a pin moved, the frames shifted, the vertices in
another order, the velocities of the frame before). Each is written to a folder as a port
writes it (``positions.txt``/``velocities.txt`` printed with a format, or an ``.npz``) and
read back and checked as ``clothsim check SCENE FOLDER`` does. A row is right when the
verdict passes or fails as it should and the summary names the cause (the words listed in
the row's ``expect``).

Writes docs/data/referee-matrix.md (included by docs/ports.md). Run from the repository
root: ``.venv/bin/python -m benchmarks referee_matrix`` (a few minutes);
``.venv/bin/python -m benchmarks.referee_matrix WORDS`` prints the rows whose scene,
printing and fault hold all the words, and writes nothing.
"""

from __future__ import annotations

import importlib.util
import re
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

import clothsim as cs
from clothsim.errors import InputError
from clothsim.ports.check import check_steps
from clothsim.ports.coursework import write_coursework
from clothsim.ports.export import export_port
from clothsim.ports.formats import read_trajectory, read_velocities, write_trajectory
from clothsim.scene import builtin_scene_text
from clothsim.springs import FAMILIES

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "docs" / "data" / "referee-matrix.md"

#: A hanging cloth as the built-in `hanging` (two top corners pinned exactly), with the
#: keys the scene rows vary.
SCENE = """
[scene]
name = "{name}"
frames = {frames}
fps = {fps}

[cloth]
shape = "grid"
size = [{sx}, 1.0]
resolution = [{nx}, {ny}]
center = [0.0, 1.0, 0.0]
plane = "xy"
mass = {mass}

[springs]
structural = {k}
shear = {k}
bending = {kb}

[solver]
method = "local-global"
iterations = 10

[[effects]]
kind = "gravity"
acceleration = [0.0, -9.81, 0.0]

[[effects]]
kind = "pin"
grid = [[-1, 0], [-1, -1]]
{extra}"""

DAMPING = """
[[effects]]
kind = "damping"
model = "rigid"
coefficient = 0.1
"""


def scene_text(nx=12, ny=12, frames=4, fps=30, mass=1.0, k=800.0, damping=False,
               sx=1.0) -> str:
    """The hanging scene's TOML with the given resolution, frames, fps, mass, stiffness."""
    return SCENE.format(name="hanging", nx=nx, ny=ny, frames=frames, fps=fps, mass=mass,
                        k=k, kb=k / 10, sx=sx, extra=DAMPING if damping else "")


def run(scene, model=None, start=None):
    """clothsim's trajectory of ``scene`` (positions, velocities: (frames + 1, n, 3)), from
    its state changed by ``start(state)`` when given."""
    sim = scene.build_simulation(scene.build_model() if model is None else model)
    if start is not None:
        start(sim.state)
    xs, vs = [sim.state.positions.copy()], [sim.state.velocities.copy()]
    for _ in range(scene.frames):
        sim.step()
        xs.append(sim.state.positions.copy())
        vs.append(sim.state.velocities.copy())
    return np.stack(xs), np.stack(vs)


# ---- faults: (scene path) -> (xs, vs) -------------------------------------------------

def keys(*overrides):
    """A port whose scene has ``overrides`` (``--set`` strings)."""
    return lambda path: run(cs.load_scene(path, list(overrides)))


def rest_lengths(scale, family=None):
    """A port whose springs' rest lengths (of one family, or all) are × ``scale``."""
    def port(path):
        scene = cs.load_scene(path)
        model = scene.build_model()
        s = model.springs
        r = s.spring_rest_length.copy()
        which = (np.ones(len(r), bool) if family is None
                 else s.spring_family == FAMILIES.index(family))
        r[which] *= scale
        springs = cs.Springs(s.spring_vertices, s.spring_stiffness, r, s.spring_family,
                             s.vertex_count, s.spring_damping)
        return run(scene, cs.Model(model.mesh, springs, model.vertex_mass))
    return port


def springs_changed(select):
    """A port whose springs are the scene's ``select(springs) -> indices`` (a spring left
    out where its index is missing, counted twice where it repeats)."""
    def port(path):
        scene = cs.load_scene(path)
        model = scene.build_model()
        s = model.springs
        i = np.asarray(select(s))
        springs = cs.Springs(s.spring_vertices[i], s.spring_stiffness[i],
                             s.spring_rest_length[i], s.spring_family[i], s.vertex_count,
                             None if s.spring_damping is None else s.spring_damping[i])
        return run(scene, cs.Model(model.mesh, springs, model.vertex_mass))
    return port


def one_diagonal(springs):
    """The springs but one shear diagonal of each quad (the grid's (1, −1) direction)."""
    v = springs.spring_vertices
    shear = springs.spring_family == FAMILIES.index("shear")
    step = v[:, 1] - v[:, 0]
    return np.flatnonzero(~(shear & (step == step[shear].min())))


def twice(*which):
    """The springs with those counted twice."""
    return lambda springs: np.concatenate([np.arange(springs.spring_count), which])


def without(*which):
    """The springs without those."""
    return lambda springs: np.setdiff1d(np.arange(springs.spring_count), which)


def _damped(path):
    """A port of the scene with the rigid damping 0.1 it has not."""
    damped = Path(path).with_name("port-damped.toml")
    damped.write_text(Path(path).read_text(encoding="utf-8") + DAMPING, encoding="utf-8")
    return run(cs.load_scene(damped))


def edited(edit):
    """A port whose right output is changed by ``edit(xs, vs, scene) -> (xs, vs)``."""
    def port(path):
        scene = cs.load_scene(path)
        xs, vs = run(scene)
        return edit(xs.copy(), vs.copy(), scene)
    return port


def _pin_moves(xs, vs, scene):
    pin = scene.build_simulation().problem(scene.build_simulation().state).fixed_vertices[0]
    xs[1:, pin, 0] += 1e-3 * np.arange(1, len(xs))
    vs[1:, pin, 0] += 1e-3 / scene.h
    return xs, vs


def _frame_late(xs, vs, scene):     # frame k printed as k + 1: the start written twice
    return np.concatenate([xs[:1], xs[:-1]]), np.concatenate([vs[:1], vs[:-1]])


def _no_first_frame(xs, vs, scene):   # the output starts at frame 1
    return xs[1:], vs[1:]


def _frames(count):
    """The output cut after ``count`` frames (a run stopped early)."""
    def cut(xs, vs, scene):
        return xs[:count], vs[:count]
    return cut


def _previous_velocities(xs, vs, scene):
    return xs, np.concatenate([vs[:1], vs[:-1]])


def _transposed(xs, vs, scene):       # vertex (i, j) written at (j, i)
    nx, ny = scene.data["cloth"]["resolution"]
    order = np.arange(nx * ny).reshape(ny, nx).T.ravel()
    return xs[:, order], vs[:, order]


def _reversed(xs, vs, scene):         # the rows written top to bottom
    nx, ny = scene.data["cloth"]["resolution"]
    order = np.arange(nx * ny).reshape(ny, nx)[::-1].ravel()
    return xs[:, order], vs[:, order]


def _reversed_all(xs, vs, scene):     # the vertices written last to first
    return xs[:, ::-1], vs[:, ::-1]


def _velocities_ahead(xs, vs, scene):   # v_{k+1} written at frame k
    return xs, np.concatenate([vs[1:], vs[-1:]])


def _frame0_up(xs, vs, scene):        # frame 0 written 1 cm up; the run from the scene's
    xs[0, :, 1] += 0.01
    return xs, vs


def _nan_from(frame):
    """NaN at vertex 5 from ``frame`` on (a run that blew up)."""
    def blown(xs, vs, scene):
        xs[frame:, 5] = np.nan
        vs[frame:, 5] = np.nan
        return xs, vs
    return blown


def _noise(scale, pins=True):
    """Independent noise of ``scale`` [m] per coordinate on x_1 …, the exactly pinned
    vertices included or not."""
    def noisy(xs, vs, scene):
        sim = scene.build_simulation()
        which = np.arange(xs.shape[1])
        if not pins:
            which = np.setdiff1d(which, sim.problem(sim.state).fixed_vertices)
        xs[1:, which] += scale * np.random.default_rng(0).standard_normal(
            xs[1:, which].shape)
        return xs, vs
    return noisy


def _float32_accumulated(xs, vs, scene):
    """The port keeps x and v in float32 and integrates x_{k+1} = x_k + h v_{k+1} in
    float32 (its rounding accumulates frame after frame)."""
    x = xs.astype(np.float32)
    for f in range(1, len(xs)):
        x[f] = x[f - 1] + np.float32(scene.h) * vs[f].astype(np.float32)
    return x, vs.astype(np.float32)


# ---- printings: (folder, xs, vs) -> folder to check -------------------------------------

def printed(spec, velocities=True):
    def write(folder, xs, vs):
        np.savetxt(folder / "positions.txt", xs.reshape(len(xs), -1), fmt=spec)
        if velocities:
            np.savetxt(folder / "velocities.txt", vs.reshape(len(vs), -1), fmt=spec)
        return folder
    return write


def npz(dtype="float64", velocities=True):
    def write(folder, xs, vs):
        arrays = {"positions": xs.astype(dtype)}
        if velocities:
            arrays["velocities"] = vs.astype(dtype)
        np.savez(folder / "port.npz", **arrays)
        return folder / "port.npz"
    return write


def csv(folder, xs, vs):
    write_trajectory(folder / "positions.csv", xs)
    return folder / "positions.csv"


PRINTINGS = {"%.17g": printed("%.17g"), "%g": printed("%g"), "%.4g": printed("%.4g"),
             "%.6e": printed("%.6e"), "%f": printed("%f"), "%.9g float32": None,
             "npz": npz(), "npz float32": npz("float32"), "csv, no velocities": csv,
             "%.17g, no velocities": printed("%.17g", velocities=False)}


@dataclass
class Row:
    """One check: a port, a printing, a fault, and what a right referee says."""

    scene: str
    printing: str
    fault: str
    port: object
    passes: bool
    expect: tuple = ()          # words the summary must hold (the cause named)
    precision: str = "float64"
    scene_kw: dict = field(default_factory=dict)


def _rows():
    right = keys()
    base = [
        # the right port, every printing
        *(Row("hanging 12²", p, "none", right, True,
              ("digits",) if p in ("%g", "%.4g", "%.6e", "%f") else ())
          for p in ("%.17g", "%g", "%.6e", "%f", "npz", "csv, no velocities",
                    "%.17g, no velocities")),
        Row("hanging 12²", "%.4g", "none", right, False, ("UNDECIDED", "too coarse")),
        Row("hanging 12²", "%.4g", "gravity sign", keys(
            "effects[0].acceleration=[0.0, 9.81, 0.0]"), False,
            ("FAIL", "too coarse for a replay to name the cause")),
        Row("hanging 12²", "npz float32", "none", right, True, (), "float32"),
        Row("hanging 12²", "npz float32", "none (checked as float64)", right, False,
            ("float32",)),
        # faults, printed with 17 digits
        Row("hanging 12²", "%.17g", "gravity sign", keys(
            "effects[0].acceleration=[0.0, 9.81, 0.0]"), False, ("+9.81, 0) m/s²",)),
        Row("hanging 12²", "%.17g", "gravity 9.8 for 9.81", keys(
            "effects[0].acceleration=[0.0, -9.8, 0.0]"), False,
            ("-9.8, 0) m/s² instead of (0, -9.81",)),
        Row("hanging 12²", "%.17g", "h × 2", keys("scene.fps=15"), False, ("h = 0.06667",)),
        Row("hanging 12²", "%.17g", "h / 2", keys("scene.fps=60"), False, ("h = 0.01667",)),
        Row("hanging 12²", "%.17g", "mass × 2", keys("cloth.mass=2.0"), False,
            ("every vertex mass × 2.000",)),
        Row("hanging 12²", "%.17g", "area mass lumping", keys(
            'cloth.mass_lumping="area"'), False, ('mass_lumping = "area"',)),
        Row("hanging 12²", "%.17g", "shear × 0.5", keys("springs.shear=400.0"), False,
            ("the shear springs only",)),
        Row("hanging 12²", "%.17g", "bending left out", keys("springs.bending=0"), False,
            ("the bending springs only",)),
        Row("hanging 12²", "%.17g", "rest lengths × 1.01", rest_lengths(1.01), False,
            ("rest lengths × 1.010",)),
        Row("hanging 12²", "%.17g", "structural rest lengths × 1.01",
            rest_lengths(1.01, "structural"), False,
            ("rest lengths × 1.010 (the structural springs only)",)),
        Row("hanging 12²", "%.17g", "a pinned vertex moves", edited(_pin_moves), False,
            ("pinned vertex moved",)),
        Row("hanging 12²", "%.17g", "one pin missing", keys(
            "effects[1].grid=[[-1, 0]]"), False, ("pinned vertex moved",)),
        Row("hanging 12²", "%.17g", "5 iterations, not 10", keys("solver.iterations=5"),
            False, ("iterations = 5",)),
        Row("hanging 12²", "%.17g", "20 iterations, not 10", keys("solver.iterations=20"),
            False, ("iterations = 20",)),
        Row("hanging 12²", "%.17g", "frame k printed as k + 1", edited(_frame_late), False,
            ("frame repeated", "frame 0 printed as 1")),
        Row("hanging 12²", "%.17g", "starts at frame 1", edited(_no_first_frame), False,
            ("the output starts at frame 1",)),
        *(Row("hanging 12²", "%.17g", f"only {c} frames written", edited(_frames(c)), False,
              (f"the port's output has {c} frames", "the scene asks for 4 steps"))
          for c in (2, 3, 4)),
        Row("hanging 12²", "%.17g", "velocities of the frame before",
            edited(_previous_velocities), False,
            ("its velocities are those of the frame before",)),
        Row("hanging 12²", "%.17g", "vertices transposed", edited(_transposed), False,
            ("the grid transposed",)),
        Row("hanging 12²", "%.17g", "rows reversed", edited(_reversed), False,
            ("rows in reverse order",)),
        Row("hanging 12²", "npz float32", "float32 accumulation (checked as float32)",
            edited(_float32_accumulated), True, (), "float32"),
        Row("hanging 12²", "%.17g", "NaN from frame 3", edited(_nan_from(3)), False,
            ("step 2 -> 3: not finite", "from frame 3 on")),
        Row("hanging 12²", "%.17g", "velocities of the frame after",
            edited(_velocities_ahead), False, ("start differs",)),
        Row("hanging 12²", "%.17g", "frame 0 written 1 cm up", edited(_frame0_up), False,
            ("start differs", "frame 0 holds other positions")),
        Row("hanging 12²", "%.17g", "noise 1e-6 m on the free vertices",
            edited(_noise(1e-6, pins=False)), False, ("noisy", "is noise")),
        Row("hanging 12²", "%.17g", "noise 1e-6 m, pins too", edited(_noise(1e-6)), False,
            ("noisy", "by the noise its free vertices carry too")),
        Row("hanging 12²", "%.17g", "noise 3e-10 m", edited(_noise(3e-10, pins=False)), True),
        Row("hanging 12² damped", "%.17g", "damping left out",
            keys("effects[2].coefficient=0"), False, ("left out",), scene_kw={"damping": True}),
        Row("hanging 12² damped", "%.17g", "velocity damping for rigid",
            keys('effects[2].model="velocity"'), False,
            ('another damping model: "velocity" with coefficient 0.1',),
            scene_kw={"damping": True}),
        Row("hanging 12²", "%.17g", "rigid damping 0.1 the scene has not", _damped, False,
            ('a damping the scene has not: model "rigid", coefficient 0.1',)),
        Row("hanging 12²", "%.17g", "one shear diagonal left out",
            springs_changed(one_diagonal), False,
            ("the shear springs along (0.707, -0.707, 0) missing",)),
        Row("hanging 12²", "%g", "one shear diagonal left out", springs_changed(one_diagonal),
            False, ("the shear springs along (0.707, -0.707, 0) missing",)),
        Row("hanging 12²", "%.17g", "5 springs counted twice",
            springs_changed(twice(26, 351, 380, 561, 708)), False,
            ("5 springs counted twice: springs 26, 351, 380, 561, 708",)),
        Row("hanging 12²", "%.17g", "3 springs missing", springs_changed(without(81, 194, 623)),
            False, ("3 springs missing: springs 81, 194, 623",)),
    ]
    yield from base
    gsign = keys("effects[0].acceleration=[0.0, 9.81, 0.0]")
    yield from [
        # clothsim's own export, checked as it is written
        Row("hanging 12²", "clothsim export", "none", exported(), True),
        Row("hanging 12²", "clothsim export", "h × 2", exported("scene.fps=15"), False,
            ("h = 0.06667",)),
        # faults printed as ports print them
        Row("hanging 12²", "%g", "gravity sign", gsign, False, ("+9.81, 0) m/s²",)),
        Row("hanging 12²", "%g", "rest lengths × 1.01", rest_lengths(1.01), False,
            ("rest lengths × 1.010",)),
        Row("hanging 12²", "%g", "bending left out", keys("springs.bending=0"), False,
            ("the bending springs only",)),
        Row("hanging 12²", "%g", "vertices transposed", edited(_transposed), False,
            ("the grid transposed",)),
        Row("hanging 12²", "%g", "frame k printed as k + 1", edited(_frame_late), False,
            ("frame repeated",)),
        Row("hanging 12²", "%g", "a pinned vertex moves", edited(_pin_moves), False,
            ("pinned vertex moved",)),
        Row("hanging 12²", "%.6e", "h × 2", keys("scene.fps=15"), False,
            ("h = 0.06667", "4 of 4 steps fail")),
        Row("hanging 12²", "%f", "gravity sign", gsign, False, ("+9.81, 0) m/s²",)),
        Row("hanging 12²", "csv, no velocities", "h / 2", keys("scene.fps=60"), False,
            ("h = 0.01667",)),
        Row("hanging 12²", "%.9g float32", "none", right, True, (), "float32"),
        Row("hanging 12²", "npz float32", "h × 2", keys("scene.fps=15"), False,
            ("h = 0.06667",), "float32"),
        Row("hanging 12²", "npz float32", "shear × 0.5", keys("springs.shear=400.0"), False,
            ("the shear springs only",), "float32"),
    ]
    flag = {"builtin": "flag", "frames": 3}
    yield from [
        Row("flag 31x21 (wind)", "%.17g", "none", right, True, scene_kw=flag),
        Row("flag 31x21 (wind)", "%g", "none", right, True, ("digits",), scene_kw=flag),
        Row("flag 31x21 (wind)", "%.17g", "h × 2", keys("scene.fps=15"), False,
            ("h = 0.06667",), scene_kw=flag),
        Row("flag 31x21 (wind)", "%.17g", "gravity sign", gsign, False,
            ("gravity (0, +9.81, 0) m/s² instead of (0, -9.81, 0) m/s²",), scene_kw=flag),
        Row("flag 31x21 (wind)", "%.17g", "wind left out", keys(
            "effects[2].velocity=[0.0, 0.0, 0.0]"), False,
            ("gravity alone: the scene's other external forces",), scene_kw=flag),
        Row("flag 31x21 (wind)", "%.17g", "drag × 2", keys("effects[2].drag=2.0"), False,
            ("external forces other than gravity × 2.000",), scene_kw=flag),
    ]
    impulse = {"builtin": "impulse", "frames": 6, "resolution": [13, 13]}
    yield from [
        Row("impulse 13²", "%.17g", "none", right, True, scene_kw=impulse),
        Row("impulse 13²", "%.17g", "impulse force × 2", keys(
            "effects[1].force=[0.0, 12.0, 0.0]"), False,
            ("external forces other than gravity × 2.000",), scene_kw=impulse),
        Row("impulse 13²", "%.17g", "impulse radius 0.2 m, not 0.15", keys(
            "effects[1].radius=0.2"), False,
            ("on a disk of radius between 0.1863 and 0.2357 m instead of 0.15 m",),
            scene_kw=impulse),
    ]
    net = {"coursework": "net", "frames": 3}
    yield from [
        Row("coursework net (1e10 N/m pins)", "%.17g", "none", right, True, scene_kw=net),
        Row("coursework net (1e10 N/m pins)", "%g", "none", right, True, ("digits",),
            scene_kw=net),
        Row("coursework net (1e10 N/m pins)", "%.17g", "h × 2", keys("scene.fps=15"), False,
            ("h = 0.06667",), scene_kw=net),
        Row("coursework net (1e10 N/m pins)", "%.17g", "force × 2", keys(
            "effects[0].per_vertex=[0.0, -19.6, 0.0]"), False, ("(0, -19.6, 0) N per vertex",),
            scene_kw=net),
        Row("coursework net (1e10 N/m pins)", "mass_springs.py", "none", example(), True,
            scene_kw=net),
        Row("coursework net (1e10 N/m pins)", "mass_springs.py", "gravity sign",
            example("gravity-sign"), False, ("(0, +9.8, 0) N per vertex",), scene_kw=net),
        Row("coursework net (1e10 N/m pins)", "mass_springs.py", "pins left out",
            example("unpinned"), False, ("the penalty pins missing",), scene_kw=net),
        Row("coursework net (1e10 N/m pins)", "mass_springs.py", "rest lengths × 0.9",
            example("rest-length"), False, ("rest lengths × 0.900",), scene_kw=net),
        Row("coursework net (1e10 N/m pins)", "%.17g", "vertices reversed",
            edited(_reversed_all), False, ("another vertex order",), scene_kw=net),
    ]
    scenes = {"hanging 9²": {"nx": 9, "ny": 9}, "hanging 17²": {"nx": 17, "ny": 17},
              "hanging 33²": {"nx": 33, "ny": 33, "frames": 3},
              "hanging 40x20": {"nx": 40, "ny": 20, "sx": 2.0},
              "hanging 12² stiff 1e5": {"k": 1e5},
              "hanging 12² tiny mass 1e-4 kg": {"mass": 1e-4},
              "hanging 12² huge h (2 fps)": {"fps": 2}}
    for name, kw in scenes.items():
        yield Row(name, "%.17g", "none", right, True, (), scene_kw=kw)
        yield Row(name, "%g", "none", right, True, ("digits",), scene_kw=kw)
        yield Row(name, "%.17g", "gravity sign", keys(
            "effects[0].acceleration=[0.0, 9.81, 0.0]"), False, ("+9.81, 0) m/s²",),
            scene_kw=kw)
        yield Row(name, "%.17g", "h × 2", keys(f"scene.fps={kw.get('fps', 30) / 2}"), False,
                  ("h = ",), scene_kw=kw)


def _scene_file(folder: Path, kw: dict) -> Path:
    """The row's scene as a file: the hanging template, a built-in scene or a coursework
    case, with ``frames`` frames."""
    kw = dict(kw)
    frames = kw.pop("frames", 4)
    path = folder / "scene.toml"
    if "builtin" in kw:
        text = builtin_scene_text(kw["builtin"])
        text = re.sub(r"(?m)^frames = \d+", f"frames = {frames}", text)
        if "resolution" in kw:
            text = re.sub(r"(?m)^resolution = .*$", f"resolution = {kw['resolution']}", text)
    elif "coursework" in kw:
        write_coursework(folder / "cases")
        path = folder / "cases" / kw["coursework"] / "scene.toml"
        text = re.sub(r"(?m)^frames = \d+", f"frames = {frames}", path.read_text())
    else:
        text = scene_text(frames=frames, **kw)
    path.write_text(text, encoding="utf-8")
    return path


def exported(*overrides):
    """``clothsim export`` of the scene with ``overrides``: the port is its output folder."""
    def port(path, folder):
        scene = cs.load_scene(path, list(overrides))
        export_port(scene, folder / "export", frames=scene.frames, iterate_steps=0)
        return folder / "export"
    port.exported = True
    return port


def example(fault=None):
    """examples/ports/mass_springs.py (the project's Python solution of the coursework) on
    the case beside the scene, with one of its ``--fault`` mistakes."""
    def port(path, folder):
        spec = importlib.util.spec_from_file_location(
            "mass_springs", ROOT / "examples" / "ports" / "mass_springs.py")
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        return module.run(path.parent, folder / "run", fault=fault,
                          frames=cs.load_scene(path).frames)
    port.exported = True
    return port


def check_row(row, tmp):
    folder = Path(tempfile.mkdtemp(dir=tmp))
    path = _scene_file(folder, row.scene_kw)
    if getattr(row.port, "exported", False):
        where = row.port(path, folder)
    else:
        xs, vs = row.port(path)
        if row.printing == "%.9g float32":
            xs, vs = xs.astype(np.float32), vs.astype(np.float32)
        where = (PRINTINGS[row.printing] or printed("%.9g"))(folder, xs, vs)
    scene = cs.load_scene(path)
    t0 = time.process_time()
    try:
        report = check_steps(scene, read_trajectory(where), read_velocities(where),
                             precision=row.precision, expected_steps=scene.frames)
        summary, passed = report.summary(), report.passed
        notes = "; ".join(report.notes)
    except InputError as exc:
        summary, passed, notes = f"error: {exc}", False, ""
    cpu = time.process_time() - t0
    named = all(w in summary or w in notes for w in row.expect)
    return passed, summary, notes, named, cpu


def main(only: str = "") -> None:
    """Check every row (or those whose scene, printing and fault hold all the words of
    ``only``, printed and not written to the page)."""
    lines = []
    with tempfile.TemporaryDirectory() as tmp:
        for row in _rows():
            if not all(w in f"{row.scene} {row.printing} {row.fault}" for w in only.split()):
                continue
            passed, summary, notes, named, cpu = check_row(row, tmp)
            right = passed == row.passes and named
            print(f"{'ok ' if right else 'BAD'} {row.scene} | {row.printing} | {row.fault} "
                  f"({cpu:.1f} s)\n    {summary}\n    notes: {notes}", flush=True)
            lines.append((row, passed, summary, right))
    if only:
        return
    _write(lines)


def _verdict(summary: str) -> str:
    """"FAIL: model differs" from a summary line."""
    word = summary.split(":")[0].split(" at ")[0]
    status = summary.split(": ", 1)[1].split(",")[0] if " at step " in summary.split(":")[0] \
        else ""
    return f"{word}: {status}" if status else word


def _write(lines):
    bad = [row for row, *_, right in lines if not right]
    text = ["Printed by `.venv/bin/python -m benchmarks referee_matrix`: each port is "
            "clothsim's own run of the scene (the `hanging` cloth: two corners pinned "
            "exactly, 800 N/m, 10 local/global iterations, 4 frames unless named) with the "
            "fault planted, written as the printing says and checked as `clothsim check "
            "SCENE PORT` checks it. *cause named*: the words the summary must hold; "
            "*right*: the verdict passes or fails as it should and names them. "
            f"{len(lines) - len(bad)} of {len(lines)} rows right.", "",
            "| scene | printed | fault | verdict | cause named | right |",
            "|---|---|---|---|---|---|"]
    for row, _, summary, right in lines:
        words = " / ".join(f"`{w}`" for w in row.expect) or "—"
        prec = " (`--precision float32`)" if row.precision == "float32" else ""
        text.append(f"| {row.scene} | {row.printing}{prec} | {row.fault} | "
                    f"{_verdict(summary)} | {words} | {'yes' if right else '**no**'} |")
    text += ["", "The summary lines:", "", "```text"]
    for row, _, summary, _ in lines:
        text += [f"{row.scene} | {row.printing} | {row.fault}", f"  {summary}"]
    text += ["```", ""]
    OUT.write_text("\n".join(text), encoding="utf-8")
    print(f"   written to {OUT.relative_to(ROOT)}")


if __name__ == "__main__":
    main(" ".join(sys.argv[1:]))
