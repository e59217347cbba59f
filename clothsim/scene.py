"""Scene files: parse, validate, then build a model, its effects and a simulation.

A scene is a TOML file (read with :mod:`tomllib`) with the tables ``[scene]``, ``[cloth]``,
``[springs]``, ``[solver]`` and an array ``[[effects]]``; every key is documented in
``docs/scenes.md``. The whole file is validated before anything is built; every problem
is a :class:`SceneError`, whose message is one line::

    <file>: <key.path>: <what is wrong>

Built-in scenes live in ``clothsim/scenes/*.toml`` and are loaded by name
(:func:`list_builtin_scenes`). A ``.json`` file is read as an assignment scene
(:mod:`clothsim.io.assignment`).

Examples
--------
>>> from clothsim.scene import Scene
>>> scene = Scene.from_dict({"scene": {"frames": 2}, "cloth": {"resolution": [3, 3]},
...                          "springs": {"structural": 10.0}})
>>> scene.h, scene.build_model().vertex_count
(0.03333333333333333, 9)
"""

from __future__ import annotations

import copy
import difflib
import inspect
import math
import os
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .errors import InputError
from .io.assignment import AssignmentError, read_assignment, read_pins, scene_dict
from .io.meshes import load_mesh
from .polygon import polygon

DEFAULT_SCENE = "drop-on-square"
SHAPES = ("grid", "mesh", "polygon", "jacobson")
DATA_PREFIX = "data:"
BUILTIN_DIR = Path(__file__).with_name("scenes")

_COMMON_CLOTH_KEYS = ("shape", "mass", "vertex_mass", "mass_lumping")
_SHAPE_KEYS = {
    "grid": ("size", "resolution", "center", "plane"),
    "mesh": ("mesh",),
    "polygon": ("outline", "spacing", "center", "plane"),
    "jacobson": ("file",),
}
_TABLE_KEYS = {
    "scene": ("name", "description", "frames", "fps", "substeps"),
    "cloth": tuple(dict.fromkeys(_COMMON_CLOTH_KEYS + sum(_SHAPE_KEYS.values(), ()))),
    "springs": ("structural", "shear", "bending", "bending_pattern"),
    "solver": ("method", "iterations", "tolerance", "backend"),
}
_TOP_KEYS = ("scene", "cloth", "springs", "solver", "effects")


class SceneError(InputError):
    """A scene file is wrong; the message is ``"<file>: <key.path>: <what is wrong>"``.

    Attributes
    ----------
    source : str
        The scene file (or ``"<dict>"``).
    path : str
        Key path inside it, e.g. ``"effects[2].radius"`` (may be empty).
    detail : str
        What is wrong.
    """

    def __init__(self, source: str, path: str, detail: str):
        self.source, self.path = str(source), path
        self.detail = " ".join(str(detail).split())  # always one line
        where = f"{self.source}: {path}: " if path else f"{self.source}: "
        super().__init__(where + self.detail)


class _Invalid(Exception):
    """Internal: a validation failure at a key path (turned into a SceneError)."""

    def __init__(self, path: str, detail: str):
        super().__init__(detail)
        self.path, self.detail = path, detail


# ---------------------------------------------------------------------------- checkers
def _type_name(value) -> str:
    names = {bool: "boolean", int: "integer", float: "float", str: "string", list: "array",
             tuple: "array", dict: "table"}
    text = repr(value)
    text = text if len(text) <= 40 else text[:37] + "..."
    return f"{names.get(type(value), type(value).__name__)} {text}"


def _suggest(key: str, known) -> str:
    close = [k for k in known if len(key) >= 3 and k.startswith(key)]
    close = close or difflib.get_close_matches(key, list(known), n=1, cutoff=0.6)
    return f"; did you mean '{close[0]}'?" if close else f"; expected one of {', '.join(known)}"


def _is_number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _number(v, path, *, positive=False, nonnegative=False) -> float:
    if not _is_number(v):
        raise _Invalid(path, f"expected a number, got {_type_name(v)}")
    v = float(v)
    if positive and v <= 0:
        raise _Invalid(path, f"must be positive, got {v!r}")
    if nonnegative and v < 0:
        raise _Invalid(path, f"must be non-negative, got {v!r}")
    return v


def _integer(v, path, *, minimum=None) -> int:
    if isinstance(v, float) and v.is_integer():
        v = int(v)
    if not isinstance(v, int) or isinstance(v, bool):
        raise _Invalid(path, f"expected an integer, got {_type_name(v)}")
    if minimum is not None and v < minimum:
        raise _Invalid(path, f"must be an integer >= {minimum}, got {v}")
    return v


def _string(v, path, *, choices=None) -> str:
    if not isinstance(v, str):
        raise _Invalid(path, f"expected a string, got {_type_name(v)}")
    if choices is not None and v not in choices:
        close = difflib.get_close_matches(v, list(choices), n=1)
        hint = f"; did you mean '{close[0]}'?" if close else ""
        raise _Invalid(path, f"must be one of {', '.join(map(repr, choices))}, got {v!r}{hint}")
    return v


def _vector(v, path, length, *, positive=False) -> list[float]:
    if not isinstance(v, (list, tuple)) or len(v) != length:
        raise _Invalid(path, f"expected an array of {length} numbers, got {_type_name(v)}")
    return [_number(x, f"{path}[{i}]", positive=positive) for i, x in enumerate(v)]


def _name(v) -> str:
    v = _string(v, "scene.name")
    if not re.fullmatch(r"[\w.-]+", v):
        raise _Invalid("scene.name", f"use letters, digits, '_', '.' and '-' only (it names the "
                                     f"output folder), got {v!r}")
    return v


def _table(v, path) -> dict:
    if not isinstance(v, dict):
        raise _Invalid(path, f"expected a table, got {_type_name(v)}")
    return v


def _check_keys(table: dict, path: str, known) -> None:
    for key in table:
        if key not in known:
            raise _Invalid(f"{path}.{key}" if path else key,
                           f"unknown key '{key}'" + _suggest(key, known))


def _check_finite_everywhere(value, path: str) -> None:
    """TOML allows nan and inf literals: reject them anywhere in the document."""
    if isinstance(value, float) and not math.isfinite(value):
        raise _Invalid(path, f"must be a finite number, got {value!r}")
    if isinstance(value, dict):
        for k, v in value.items():
            _check_finite_everywhere(v, f"{path}.{k}" if path else str(k))
    elif isinstance(value, (list, tuple)):
        for i, v in enumerate(value):
            _check_finite_everywhere(v, f"{path}[{i}]")


# ---------------------------------------------------------------------------- paths
def data_dir() -> Path:
    """Directory of the assignment data (``data:`` paths in scene files).

    ``$CLOTHSIM_DATA`` when set (either the ``jacobson-a8`` folder itself or a folder
    that contains it), else ``<repo>/../shared/data/jacobson-a8``.
    """
    env = os.environ.get("CLOTHSIM_DATA")
    if env:
        p = Path(env).expanduser()
        return p / "jacobson-a8" if (p / "jacobson-a8").is_dir() else p
    repo = Path(__file__).resolve().parent.parent
    return repo.parent / "shared" / "data" / "jacobson-a8"


def _resolve_path(value: str, base_dir: Path, path: str) -> Path:
    if value.startswith(DATA_PREFIX):
        root = data_dir()
        if not root.is_dir():
            raise _Invalid(path, f"data directory {root} not found; set CLOTHSIM_DATA to the "
                                 f"folder holding the jacobson-a8 files")
        p = root / value[len(DATA_PREFIX):]
    else:
        p = Path(value).expanduser()
        p = p if p.is_absolute() else base_dir / p
    if not p.is_file():
        raise _Invalid(path, f"file not found: {p}")
    return p.resolve()


# ---------------------------------------------------------------------------- validation
def _validate(raw: dict, base_dir: Path, default_name: str) -> dict:
    """Check every key of a scene document; return it resolved (defaults, absolute paths)."""
    _table(raw, "")
    _check_finite_everywhere(raw, "")
    _check_keys(raw, "", _TOP_KEYS)
    out: dict[str, Any] = {}

    # [scene]
    s = _table(raw.get("scene", {}), "scene")
    _check_keys(s, "scene", _TABLE_KEYS["scene"])
    out["scene"] = {
        "name": _name(s.get("name", default_name)),
        "description": _string(s.get("description", ""), "scene.description"),
        "frames": _integer(s.get("frames", 60), "scene.frames", minimum=0),
        "fps": _number(s.get("fps", 30.0), "scene.fps", positive=True),
        "substeps": _integer(s.get("substeps", 1), "scene.substeps", minimum=1),
    }
    try:  # h = 1 / (fps · substeps) must not underflow to 0
        rate = out["scene"]["fps"] * out["scene"]["substeps"]
    except OverflowError:
        rate = math.inf
    if not math.isfinite(rate):
        raise _Invalid("scene.fps", f"fps · substeps = {out['scene']['fps']!r} · "
                                    f"{out['scene']['substeps']} overflows: the time step "
                                    f"h = 1 / (fps · substeps) would be 0")

    # [cloth]
    c = _table(raw.get("cloth", {}), "cloth")
    _check_keys(c, "cloth", _TABLE_KEYS["cloth"])
    shape = _string(c.get("shape", "grid"), "cloth.shape", choices=SHAPES)
    allowed = _COMMON_CLOTH_KEYS + _SHAPE_KEYS[shape]
    for key in c:
        if key not in allowed:
            users = [sh for sh, keys in _SHAPE_KEYS.items() if key in keys]
            raise _Invalid(f"cloth.{key}", f"not used with cloth.shape = '{shape}' (only with "
                                           f"{' or '.join(repr(u) for u in users)})")
    cloth: dict[str, Any] = {"shape": shape}
    vertex_count = None
    if shape == "grid":
        from .mesh import PLANES
        cloth["size"] = _vector(c.get("size", [1.0, 1.0]), "cloth.size", 2, positive=True)
        res = c.get("resolution", [21, 21])
        if not isinstance(res, (list, tuple)) or len(res) != 2:
            raise _Invalid("cloth.resolution", f"expected an array of 2 integers, got "
                                               f"{_type_name(res)}")
        cloth["resolution"] = [_integer(r, f"cloth.resolution[{i}]", minimum=2)
                               for i, r in enumerate(res)]
        cloth["center"] = _vector(c.get("center", [0.0, 0.0, 0.0]), "cloth.center", 3)
        cloth["plane"] = _string(c.get("plane", "xz"), "cloth.plane", choices=PLANES)
        vertex_count = cloth["resolution"][0] * cloth["resolution"][1]
    elif shape == "mesh":
        if "mesh" not in c:
            raise _Invalid("cloth.mesh", "missing: give the mesh file (relative to the scene)")
        cloth["mesh"] = str(_resolve_path(_string(c["mesh"], "cloth.mesh"), base_dir,
                                          "cloth.mesh"))
    elif shape == "polygon":
        from .mesh import PLANES
        if "outline" not in c:
            raise _Invalid("cloth.outline", "missing: give at least 3 [x, y] points")
        outline = c["outline"]
        if not isinstance(outline, (list, tuple)) or len(outline) < 3:
            raise _Invalid("cloth.outline", f"expected an array of at least 3 [x, y] points, "
                                            f"got {_type_name(outline)}")
        cloth["outline"] = [_vector(p, f"cloth.outline[{i}]", 2) for i, p in enumerate(outline)]
        cloth["spacing"] = _number(c.get("spacing", 0.05), "cloth.spacing", positive=True)
        cloth["center"] = _vector(c.get("center", [0.0, 0.0, 0.0]), "cloth.center", 3)
        cloth["plane"] = _string(c.get("plane", "xz"), "cloth.plane", choices=PLANES)
    else:  # jacobson
        if "file" not in c:
            raise _Invalid("cloth.file", "missing: give the assignment .json file")
        cloth["file"] = str(_resolve_path(_string(c["file"], "cloth.file"), base_dir,
                                          "cloth.file"))
        for key in ("mass", "vertex_mass", "mass_lumping"):
            if key in c:
                raise _Invalid(f"cloth.{key}", "not used with cloth.shape = 'jacobson' (masses "
                                               "come from the JSON file)")
    if shape != "jacobson":
        from .model import MASS_LUMPINGS
        if "mass" in c and "vertex_mass" in c:
            raise _Invalid("cloth.vertex_mass", "give either 'mass' or 'vertex_mass', not both")
        if "vertex_mass" in c:
            vm = c["vertex_mass"]
            if isinstance(vm, (list, tuple)):
                vm = [_number(m, f"cloth.vertex_mass[{i}]", positive=True)
                      for i, m in enumerate(vm)]
                if vertex_count is not None and len(vm) != vertex_count:
                    raise _Invalid("cloth.vertex_mass", f"expected {vertex_count} values (one "
                                                        f"per vertex), got {len(vm)}")
            else:
                vm = _number(vm, "cloth.vertex_mass", positive=True)
            cloth["vertex_mass"] = vm
        else:
            cloth["mass"] = _number(c.get("mass", 1.0), "cloth.mass", positive=True)
        cloth["mass_lumping"] = _string(c.get("mass_lumping", "uniform"), "cloth.mass_lumping",
                                        choices=MASS_LUMPINGS)
    out["cloth"] = cloth

    # [springs]
    from .springs import BENDING_PATTERNS
    sp = _table(raw.get("springs", {}), "springs")
    _check_keys(sp, "springs", _TABLE_KEYS["springs"])
    if shape == "jacobson" and sp:
        raise _Invalid(f"springs.{next(iter(sp))}", "not used with cloth.shape = 'jacobson' "
                                                    "(the JSON's k sets every spring)")
    if shape in ("mesh", "polygon"):
        for key in ("shear", "bending_pattern"):
            if key in sp:
                raise _Invalid(f"springs.{key}", f"only grid cloths have it; a '{shape}' cloth "
                                                 f"gets structural (edges) and bending springs")
    springs = {}
    for fam in ("structural", "shear", "bending"):
        if fam in sp:
            springs[fam] = _number(sp[fam], f"springs.{fam}", nonnegative=True)
    if shape == "grid":
        springs["bending_pattern"] = _string(sp.get("bending_pattern", "every"),
                                             "springs.bending_pattern", choices=BENDING_PATTERNS)
    out["springs"] = springs

    # [solver]
    so = _table(raw.get("solver", {}), "solver")
    _check_keys(so, "solver", _TABLE_KEYS["solver"])
    out["solver"] = _validate_solver(so.get("method", "local-global"),
                                     so.get("iterations", 10), so.get("tolerance"),
                                     so.get("backend", "auto"))

    # [[effects]]
    effects = raw.get("effects", [])
    if not isinstance(effects, list):
        raise _Invalid("effects", f"expected an array of tables ([[effects]]), got "
                                  f"{_type_name(effects)}")
    out["effects"] = [_validate_effect(e, f"effects[{i}]", vertex_count)
                      for i, e in enumerate(effects)]
    pinned: dict[int, int] = {}
    for i, e in enumerate(out["effects"]):
        if e["kind"] == "pin" and "vertices" in e:
            for v in e["vertices"]:
                if v in pinned:
                    raise _Invalid(f"effects[{i}].vertices", f"vertex {v} is already pinned by "
                                                             f"effects[{pinned[v]}]")
                pinned[v] = i
    return out


def _validate_solver(method, iterations, tolerance, backend) -> dict:
    from .factorization import BACKENDS
    from .solvers import SOLVERS
    return {
        "method": _string(method, "solver.method", choices=tuple(SOLVERS)),
        "iterations": _integer(iterations, "solver.iterations", minimum=1),
        "tolerance": None if tolerance is None else _number(tolerance, "solver.tolerance",
                                                            positive=True),
        "backend": _string(backend, "solver.backend", choices=BACKENDS),
    }


def _effect_keys(cls) -> tuple[list[str], bool]:
    """Constructor keyword names of an effect class, and whether it takes **kwargs."""
    params = inspect.signature(cls).parameters.values()
    names = [p.name for p in params if p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)]
    return names, any(p.kind is p.VAR_KEYWORD for p in params)


def _rekey(message: str, kind: str, path: str) -> tuple[str, str]:
    """Map an effect's own message "<kind>.<key>: text" to ("<path>.<key>", "text")."""
    m = re.match(rf"^(?:effects\.)?{re.escape(kind)}((?:[.\[][^:\s]*)?):\s*(.*)$", message)
    if m:
        return path + m.group(1), m.group(2)
    return path, message


_PYTHON_ONLY_KEYS = {"pin": ("motion",)}  # callables: Python API only, not in scene files


def _validate_effect(e, path: str, vertex_count: int | None) -> dict:
    from .effects import EFFECTS
    e = _table(e, path)
    if "kind" not in e:
        raise _Invalid(f"{path}.kind", f"missing: every effect needs a kind ({', '.join(EFFECTS)})")
    kind = _string(e["kind"], f"{path}.kind")
    if kind not in EFFECTS:
        raise _Invalid(f"{path}.kind", f"unknown effect kind '{kind}'" + _suggest(kind, EFFECTS))
    names, any_key = _effect_keys(EFFECTS[kind])
    names = [k for k in names if k not in _PYTHON_ONLY_KEYS.get(kind, ())]
    if not any_key:
        _check_keys(e, path, ["kind"] + names)
    params = {k: v for k, v in e.items() if k != "kind"}
    if kind == "pin" and "vertices" in params:
        vs = params["vertices"]
        if not isinstance(vs, (list, tuple)):
            raise _Invalid(f"{path}.vertices", f"expected an array of vertex indices, got "
                                               f"{_type_name(vs)}")
        vs = [_integer(v, f"{path}.vertices[{i}]", minimum=0) for i, v in enumerate(vs)]
        seen = set()
        for i, v in enumerate(vs):
            if vertex_count is not None and v >= vertex_count:
                raise _Invalid(f"{path}.vertices[{i}]", f"vertex {v} out of range "
                                                        f"0..{vertex_count - 1}")
            if v in seen:
                raise _Invalid(f"{path}.vertices[{i}]", f"vertex {v} is listed twice")
            seen.add(v)
        params["vertices"] = vs
    try:  # the constructor checks its own parameters; nothing is bound to a model here
        EFFECTS[kind](**params)
    except (InputError, TypeError, ValueError) as exc:
        raise _Invalid(*_rekey(str(exc), kind, path)) from None
    return {"kind": kind, **params}


_CLOTH_FIELDS = ("vertex_mass", "mass_lumping", "mass", "resolution", "size", "center", "plane",
                 "outline", "spacing", "vertices", "triangles", "strands")


def _split_message(message: str, default: str) -> tuple[str, str]:
    """Split a core error "field: text" into a scene key path and the text."""
    head, sep, rest = message.partition(": ")
    if sep and re.fullmatch(r"[\w.\[\], ]+", head):
        if head.split(".")[0] in _TOP_KEYS:
            return head, rest
        if re.split(r"[.\[]", head)[0] in _CLOTH_FIELDS:
            return f"cloth.{head}", rest
    return default, message


# ---------------------------------------------------------------------------- the scene
@dataclass(frozen=True, eq=False)
class Scene:
    """A validated scene.

    Attributes
    ----------
    data : dict
        The resolved document: every table with defaults filled in and file paths made
        absolute (see ``docs/scenes.md``).
    source : str
        Where it came from (file path, or ``"<dict>"``); starts every error message.
    base_dir : Path
        Directory that relative paths were resolved against.
    """

    data: dict
    source: str = "<dict>"
    base_dir: Path = field(default_factory=Path.cwd)

    @classmethod
    def from_dict(cls, d: dict, *, source: str = "<dict>", base_dir=None) -> Scene:
        """Validate a scene document (as parsed from TOML) and return the scene.

        Raises
        ------
        SceneError
            ``"<source>: <key.path>: <what is wrong>"`` for the first problem found.
        """
        base = Path.cwd() if base_dir is None else Path(base_dir)
        default_name = Path(source).stem if source != "<dict>" else "scene"
        default_name = re.sub(r"[^\w.-]+", "-", default_name) or "scene"
        try:
            data = _validate(d, base, default_name)
        except _Invalid as exc:
            raise SceneError(source, exc.path, exc.detail) from None
        return cls(data, str(source), base)

    # -- plain properties
    @property
    def name(self) -> str:
        return self.data["scene"]["name"]

    @property
    def description(self) -> str:
        return self.data["scene"]["description"]

    @property
    def frames(self) -> int:
        """Frames written after the initial one."""
        return self.data["scene"]["frames"]

    @property
    def fps(self) -> float:
        """Frames per second [1/s]."""
        return self.data["scene"]["fps"]

    @property
    def substeps(self) -> int:
        """Implicit Euler steps per frame."""
        return self.data["scene"]["substeps"]

    @property
    def h(self) -> float:
        """Time step h = 1 / (fps · substeps) [s]."""
        return 1.0 / (self.fps * self.substeps)

    def to_dict(self) -> dict:
        """The resolved document (JSON-ready deep copy; ``tolerance`` may be None)."""
        return copy.deepcopy(self.data)

    # -- building
    def build_model(self):
        """Build the mesh, springs and masses of ``[cloth]`` and ``[springs]``.

        Returns
        -------
        Model
        """
        from . import mesh as mesh_mod
        from .model import Model
        from .springs import grid_springs, mesh_springs, springs_from_pairs

        c, sp = self.data["cloth"], self.data["springs"]
        shape = c["shape"]
        try:
            if shape == "jacobson":
                a = read_assignment(c["file"])
                springs = springs_from_pairs(a.mesh, a.spring_pairs, a.stiffness)
                return Model(a.mesh, springs, a.vertex_mass)
            if shape == "grid":
                nx, ny = c["resolution"]
                mesh = mesh_mod.grid(nx, ny, size=tuple(c["size"]), center=c["center"],
                                     plane=c["plane"])
                springs = grid_springs(mesh, structural=sp.get("structural"),
                                       shear=sp.get("shear"), bending=sp.get("bending"),
                                       bending_pattern=sp["bending_pattern"])
            else:
                if shape == "mesh":
                    mesh = load_mesh(c["mesh"], field="cloth.mesh")
                else:
                    mesh = polygon(c["outline"], spacing=c["spacing"],
                                   center=c["center"], plane=c["plane"])
                springs = mesh_springs(mesh, structural=sp.get("structural"),
                                       bending=sp.get("bending"))
            return Model.build(mesh, springs, total_mass=c.get("mass"),
                               vertex_mass=c.get("vertex_mass"),
                               mass_lumping=c["mass_lumping"])
        except SceneError:
            raise
        except AssignmentError as exc:
            raise SceneError(exc.source, exc.path, exc.detail) from None
        except InputError as exc:
            raise SceneError(self.source, *_split_message(str(exc), "cloth")) from None

    def build_effects(self) -> list:
        """Fresh effect objects for exactly the declared ``[[effects]]``, in order.

        A ``jacobson`` cloth adds first the exact pins of its JSON's ``b`` list.
        """
        from .effects import EFFECTS
        out = []
        if self.data["cloth"]["shape"] == "jacobson":
            from .effects import Pin
            out.append(Pin(read_pins(self.data["cloth"]["file"])))
        for i, e in enumerate(self.data["effects"]):
            params = {k: v for k, v in e.items() if k != "kind"}
            try:
                out.append(EFFECTS[e["kind"]](**params))
            except (InputError, TypeError, ValueError) as exc:
                raise SceneError(self.source, *_rekey(str(exc), e["kind"],
                                                      f"effects[{i}]")) from None
        return out

    def build_simulation(self, model=None, *, method: str | None = None,
                         iterations: int | None = None, tolerance: float | None = None,
                         substeps: int | None = None):
        """A :class:`~clothsim.simulation.Simulation` of this scene, ready to step.

        Parameters
        ----------
        model : Model, optional
            Default: :meth:`build_model`.
        method, iterations, tolerance
            Override ``[solver]``.
        substeps : int, optional
            Override ``scene.substeps`` (h = 1 / (fps · substeps)).
        """
        from .simulation import Simulation

        so = self.data["solver"]
        try:
            solver = _validate_solver(so["method"] if method is None else method,
                                      so["iterations"] if iterations is None else iterations,
                                      so["tolerance"] if tolerance is None else tolerance,
                                      so["backend"])
            if substeps is not None:
                substeps = _integer(substeps, "scene.substeps", minimum=1)
        except _Invalid as exc:
            raise SceneError(self.source, exc.path, exc.detail) from None
        h = self.h if substeps is None else 1.0 / (self.fps * substeps)
        model = self.build_model() if model is None else model
        effects = self.build_effects()
        try:
            return Simulation(model, h=h, effects=effects, solver=solver["method"],
                              iterations=solver["iterations"], tolerance=solver["tolerance"],
                              backend=solver["backend"])
        except InputError as exc:
            raise self._locate(exc, model, h) from None

    def _locate(self, exc: InputError, model, h: float) -> SceneError:
        """Name the effect whose binding failed (bind each one alone to find it)."""
        offset = 1 if self.data["cloth"]["shape"] == "jacobson" else 0
        for j, effect in enumerate(self.build_effects()):
            try:
                effect.bind(model, h)
            except InputError as err:
                if j < offset:
                    return SceneError(self.source, "cloth.file", f"b: {err}")
                return SceneError(self.source, *_rekey(str(err), effect.kind,
                                                       f"effects[{j - offset}]"))
        msg = str(exc)
        path, _, rest = msg.partition(": ")
        if rest and path.startswith("solver."):
            return SceneError(self.source, path, rest)
        if rest and path.startswith("effects."):
            return SceneError(self.source, "effects", rest)
        return SceneError(self.source, "", msg)


# ---------------------------------------------------------------------------- loading
def list_builtin_scenes() -> dict[str, str]:
    """Built-in scene names and their one-line descriptions."""
    out = {}
    for p in sorted(BUILTIN_DIR.glob("*.toml")):
        try:
            with open(p, "rb") as f:
                desc = tomllib.load(f).get("scene", {}).get("description", "")
        except (OSError, tomllib.TOMLDecodeError):
            desc = ""
        out[p.stem] = " ".join(str(desc).split())
    return out


def builtin_scene_path(name: str) -> Path:
    """Path of the built-in scene ``name`` (``clothsim/scenes/<name>.toml``)."""
    return BUILTIN_DIR / f"{name}.toml"


def parse_toml(text: str, source: str) -> dict:
    """Parse TOML text; a syntax error becomes ``"<source>: line N: invalid TOML: …"``."""
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        msg = str(exc)
        m = re.search(r"\(at line (\d+), column (\d+)\)", msg)
        where = f"line {m.group(1)}" if m else ""
        raise SceneError(source, where, f"invalid TOML: {msg}") from None


def load_scene(path_or_name) -> Scene:
    """Load and validate a scene file (``.toml``), an assignment ``.json``, or a built-in.

    Parameters
    ----------
    path_or_name : str or Path
        A file path, or the name of a built-in scene (see :func:`list_builtin_scenes`).

    Raises
    ------
    SceneError
        One line, ``"<file>: <key.path>: <what is wrong>"``.
    """
    p = Path(path_or_name).expanduser()
    if not p.is_file():
        name = str(path_or_name)
        builtin = builtin_scene_path(name)
        if "/" not in name and "\\" not in name and builtin.is_file():
            p = builtin
        elif p.suffix in (".toml", ".json") or os.sep in name:
            raise SceneError(name, "", "file not found")
        else:
            names = list(list_builtin_scenes())
            raise SceneError(name, "", "no such scene file or built-in scene"
                             + _suggest(name, names).replace("expected one of",
                                                             "built-in scenes:"))
    source = str(p)
    if p.suffix.lower() == ".json":
        try:
            doc = scene_dict(p)
        except AssignmentError as exc:
            raise SceneError(exc.source, exc.path, exc.detail) from None
        return Scene.from_dict(doc, source=source, base_dir=p.parent)
    try:
        text = p.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise SceneError(source, "", f"cannot read: {exc}") from None
    return Scene.from_dict(parse_toml(text, source), source=source, base_dir=p.parent)


__all__ = ["Scene", "SceneError", "load_scene", "list_builtin_scenes", "builtin_scene_path",
           "parse_toml", "data_dir", "DEFAULT_SCENE", "SHAPES"]
