"""Validation of a whole scene document, in one place, before anything is built.

:func:`validate` checks every key (known keys and defaults from :mod:`.schema`, values with
:mod:`.checks`) and returns the resolved document: defaults filled in, file paths
absolute. Effects' parameters are type-checked here and then given to the effect's own
constructor, whose complaints are mapped to the effect's key path.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from ..effects.holding import CONTACT_MODES
from ..effects.pins import PIN_METHODS
from ..factorization import BACKENDS, CHOLMOD_MODES
from ..io.frames import FRAME_COMPRESSIONS
from ..mesh import PLANES
from ..model import MASS_LUMPINGS
from ..problem import INITIAL_GUESSES
from ..solvers import SOLVERS
from ..springs import BENDING_PATTERNS
from . import schema
from .checks import (
    Invalid,
    check_finite_everywhere,
    check_keys,
    integer,
    number,
    safe_name,
    show,
    string,
    table,
    type_name,
    vector,
)
from .effects import grid_vertices, validate_effect
from .files import resolve_path
from .schema import (
    MAX_FRAMES,
    MAX_H,
    MAX_ITERATIONS,
    MAX_SUBSTEPS,
    MAX_VERTICES,
    MIN_H,
    SHAPES,
    TOP_KEYS,
    sci,
)

MAX_LENGTH = 1e100  # coordinates and lengths [m]: squares and sums stay finite


def _scene_table(raw: dict, default_name: str) -> dict:
    s = table(raw.get("scene", {}), "scene")
    check_keys(s, "scene", schema.keys("scene"))
    d = schema.default
    out = {
        "name": safe_name(s.get("name", default_name)),
        "description": string(s.get("description", d("scene", "description")),
                              "scene.description"),
        "frames": integer(s.get("frames", d("scene", "frames")), "scene.frames", minimum=0,
                          maximum=MAX_FRAMES),
    }
    if "h" in s:
        for key in ("fps", "substeps"):
            if key in s:
                raise Invalid(f"scene.{key}", "give either 'h' or 'fps'/'substeps', not both")
        h = number(s["h"], "scene.h", positive=True)
        if not MIN_H <= h <= MAX_H:
            raise Invalid("scene.h", f"must be between {MIN_H:g} s and {MAX_H:g} s, got {h!r}")
        out.update(h=h, fps=1.0 / h, substeps=1)
        return out
    out["fps"] = number(s.get("fps", d("scene", "fps")), "scene.fps", positive=True)
    out["substeps"] = integer(s.get("substeps", d("scene", "substeps")), "scene.substeps",
                              minimum=1, maximum=MAX_SUBSTEPS)
    rate = out["fps"] * out["substeps"]
    if not math.isfinite(rate) or 1.0 / rate == 0.0:
        raise Invalid("scene.fps", f"fps · substeps = {out['fps']!r} · {out['substeps']} "
                                   f"overflows: the time step h = 1 / (fps · substeps) would "
                                   f"be 0")
    if not MIN_H <= 1.0 / rate <= MAX_H:
        raise Invalid("scene.fps", f"the time step h = 1 / (fps · substeps) = {1.0 / rate:.3g} s"
                                   f" must be between {MIN_H:g} s and {MAX_H:g} s")
    return out


def _grid(c: dict, cloth: dict) -> int:
    d = schema.default
    cloth["size"] = vector(c.get("size", d("cloth", "size")), "cloth.size", 2, positive=True)
    for i, v in enumerate(cloth["size"]):
        if v > MAX_LENGTH:
            raise Invalid(f"cloth.size[{i}]", f"must be at most {MAX_LENGTH:g} m, got {v!r}")
    res = c.get("resolution", d("cloth", "resolution"))
    if not isinstance(res, (list, tuple)) or len(res) != 2:
        raise Invalid("cloth.resolution", f"expected an array of 2 integers, got "
                                          f"{type_name(res)}")
    cloth["resolution"] = [integer(r, f"cloth.resolution[{i}]", minimum=2, maximum=100_000)
                           for i, r in enumerate(res)]
    if cloth["resolution"][0] * cloth["resolution"][1] > MAX_VERTICES:
        raise Invalid("cloth.resolution", f"{cloth['resolution'][0]} × "
                                          f"{cloth['resolution'][1]} vertices is more than "
                                          f"{sci(MAX_VERTICES)}")
    cloth["center"] = _point(c.get("center", d("cloth", "center")), "cloth.center")
    cloth["plane"] = string(c.get("plane", d("cloth", "plane")), "cloth.plane", choices=PLANES)
    # the spacing must be resolvable at the grid's coordinates (else every vertex collapses)
    spacing = min(s / (r - 1) for s, r in zip(cloth["size"], cloth["resolution"]))
    reach = max(abs(x) for x in cloth["center"]) + max(cloth["size"])
    if spacing <= 1e3 * 2.220446049250313e-16 * reach:
        raise Invalid("cloth.center", f"the grid spacing {spacing:.3g} m is below the rounding "
                                      f"of coordinates near {reach:.3g} m; move the cloth "
                                      f"nearer the origin")
    return cloth["resolution"][0] * cloth["resolution"][1]


def _point(v, path) -> list[float]:
    p = vector(v, path, 3)
    for i, x in enumerate(p):
        if abs(x) > MAX_LENGTH:
            raise Invalid(f"{path}[{i}]", f"must be within ±{MAX_LENGTH:g} m, got {x!r}")
    return p


_FILE_KEYS = {"mesh": "mesh", "jacobson": "file", "files": "vertices"}
"""The key naming the file a cloth of each shape is read from."""


def _cloth(raw: dict, base_dir: Path) -> tuple[dict, int | None]:
    c = table(raw.get("cloth", {}), "cloth")
    check_keys(c, "cloth", schema.keys("cloth"))
    shape = string(c.get("shape", "grid"), "cloth.shape", choices=SHAPES)
    allowed = schema.keys("cloth", shape)
    for key in c:
        if key not in allowed:
            users = schema.spec("cloth", key).shapes
            own = _FILE_KEYS.get(shape)  # cloth.file on a mesh: say which key reads its file
            hint = (f"; a {shape} cloth reads its file from cloth.{own}"
                    if own and key in _FILE_KEYS.values() and own in allowed else "")
            raise Invalid(f"cloth.{key}", f"not used with cloth.shape = '{shape}' (only with "
                                          f"{' or '.join(repr(u) for u in users)}){hint}")
    cloth: dict[str, Any] = {"shape": shape}
    cloth["pin_method"] = string(c.get("pin_method", "penalty"), "cloth.pin_method",
                                 choices=PIN_METHODS)
    if "pin_stiffness" in c:
        cloth["pin_stiffness"] = number(c["pin_stiffness"], "cloth.pin_stiffness",
                                        positive=True)
    vertex_count = None
    if shape == "grid":
        vertex_count = _grid(c, cloth)
    elif shape == "mesh":
        if "mesh" not in c:
            raise Invalid("cloth.mesh", "missing: give the mesh file (relative to the scene)")
        cloth["mesh"] = str(resolve_path(string(c["mesh"], "cloth.mesh"), base_dir,
                                         "cloth.mesh"))
    elif shape == "polygon":
        if "outline" not in c:
            raise Invalid("cloth.outline", "missing: give at least 3 [x, y] points")
        outline = c["outline"]
        if not isinstance(outline, (list, tuple)) or len(outline) < 3:
            raise Invalid("cloth.outline", f"expected an array of at least 3 [x, y] points, "
                                           f"got {type_name(outline)}")
        cloth["outline"] = [vector(p, f"cloth.outline[{i}]", 2) for i, p in enumerate(outline)]
        for i, p in enumerate(cloth["outline"]):
            _point(p + [0.0], f"cloth.outline[{i}]")
        cloth["spacing"] = number(c.get("spacing", schema.default("cloth", "spacing")),
                                  "cloth.spacing", positive=True)
        cloth["center"] = _point(c.get("center", schema.default("cloth", "center")),
                                 "cloth.center")
        xs, ys = zip(*cloth["outline"])
        cells = ((max(xs) - min(xs)) / cloth["spacing"]) * ((max(ys) - min(ys))
                                                            / cloth["spacing"])
        if cells > MAX_VERTICES:
            raise Invalid("cloth.spacing", f"{cloth['spacing']!r} m gives about {cells:.3g} "
                                           f"vertices, more than {sci(MAX_VERTICES)}")
        cloth["plane"] = string(c.get("plane", "xz"), "cloth.plane", choices=PLANES)
    elif shape == "files":
        if "vertices" not in c:
            raise Invalid("cloth.vertices", "missing: give the file of initial positions")
        cloth["vertices"] = str(resolve_path(string(c["vertices"], "cloth.vertices"),
                                             base_dir, "cloth.vertices"))
        if "triangles" in c:
            cloth["triangles"] = str(resolve_path(string(c["triangles"], "cloth.triangles"),
                                                  base_dir, "cloth.triangles"))
        cloth["index_base"] = integer(c.get("index_base", 0), "cloth.index_base", minimum=0,
                                      maximum=1)
    else:  # jacobson
        if "file" not in c:
            raise Invalid("cloth.file", "missing: give the assignment .json file")
        cloth["file"] = str(resolve_path(string(c["file"], "cloth.file"), base_dir,
                                         "cloth.file"))
    if shape != "jacobson":
        if "mass" in c and "vertex_mass" in c:
            raise Invalid("cloth.vertex_mass", "give either 'mass' or 'vertex_mass', not both")
        if "vertex_mass" in c:
            vm = c["vertex_mass"]
            if isinstance(vm, (list, tuple)):
                vm = [number(m, f"cloth.vertex_mass[{i}]", nonnegative=True)
                      for i, m in enumerate(vm)]
                if vertex_count is not None and len(vm) != vertex_count:
                    raise Invalid("cloth.vertex_mass", f"expected {vertex_count} values (one "
                                                       f"per vertex), got {len(vm)}")
            elif isinstance(vm, str):
                vm = str(resolve_path(vm, base_dir, "cloth.vertex_mass"))
            else:
                vm = number(vm, "cloth.vertex_mass", positive=True)
            cloth["vertex_mass"] = vm
        else:
            cloth["mass"] = number(c.get("mass", 1.0), "cloth.mass", positive=True)
        cloth["mass_lumping"] = string(c.get("mass_lumping", "uniform"), "cloth.mass_lumping",
                                       choices=MASS_LUMPINGS)
    return cloth, vertex_count


def _springs(raw: dict, shape: str, base_dir: Path) -> dict:
    sp = table(raw.get("springs", {}), "springs")
    check_keys(sp, "springs", schema.keys("springs"))
    allowed = schema.keys("springs", shape)
    for key in sp:
        if key not in allowed:
            if shape == "jacobson":
                raise Invalid(f"springs.{key}", "not used with cloth.shape = 'jacobson' (the "
                                                "JSON's k sets every spring)")
            raise Invalid(f"springs.{key}", f"only grid cloths have it; a '{shape}' cloth "
                                            f"gets structural (edges) and bending springs")
    springs: dict[str, Any] = {}
    for fam in ("structural", "shear", "bending"):
        if fam in sp:
            springs[fam] = number(sp[fam], f"springs.{fam}", nonnegative=True)
    if shape == "grid":
        springs["bending_pattern"] = string(sp.get("bending_pattern", "every"),
                                            "springs.bending_pattern",
                                            choices=BENDING_PATTERNS)
    if "table" in sp:
        springs["table"] = str(resolve_path(string(sp["table"], "springs.table"), base_dir,
                                            "springs.table"))
        cols = sp.get("columns", schema.default("springs", "columns"))
        if not isinstance(cols, list) or not cols:
            raise Invalid("springs.columns", f"expected an array of column names, got "
                                             f"{type_name(cols)}")
        cols = [string(v, f"springs.columns[{i}]") for i, v in enumerate(cols)]
        for need in ("a", "b", "stiffness"):
            if need not in cols:
                raise Invalid("springs.columns", f"needs a column '{need}', got {show(cols)}")
        for i, v in enumerate(cols):
            if v in cols[:i] and v in ("a", "b", "stiffness", "rest", "damping"):
                raise Invalid(f"springs.columns[{i}]", f"column '{v}' is named twice")
        springs["columns"] = cols
        springs["index_base"] = integer(sp.get("index_base", 0), "springs.index_base",
                                        minimum=0, maximum=1)
    else:
        for key in ("columns", "index_base"):
            if key in sp:
                raise Invalid(f"springs.{key}", "only used with springs.table")
    return springs


def validate_solver(method, iterations, tolerance, backend, initial_guess="y",
                    cholmod_mode="auto") -> dict:
    """Check the ``[solver]`` values (also used for overrides).

    Parameters
    ----------
    method : str
        A solver name of :data:`clothsim.solvers.SOLVERS`, e.g. ``"local-global"``.
    iterations : int
        Maximum iterations per step, 1 to 100 000.
    tolerance : float or None
        Relative residual to stop at, > 0 (dimensionless); None: run all iterations.
    backend : str
        The factorization backend, one of the scene's backend names.
    initial_guess : str, default "y"
        ``"y"`` or ``"x_n"``: where each step's iteration starts.
    cholmod_mode : str, default "auto"
        ``"auto"``, ``"simplicial"`` or ``"supernodal"``.

    Returns
    -------
    dict
        ``method``, ``iterations``, ``tolerance``, ``backend``, ``initial_guess``,
        ``cholmod_mode``, checked.

    Raises
    ------
    Invalid
        At ``solver.<key>`` for the first bad value.
    """
    return {
        "method": string(method, "solver.method", choices=tuple(SOLVERS)),
        "iterations": integer(iterations, "solver.iterations", minimum=1,
                              maximum=MAX_ITERATIONS),
        "tolerance": None if tolerance is None else number(tolerance, "solver.tolerance",
                                                           positive=True),
        "backend": string(backend, "solver.backend", choices=BACKENDS),
        "initial_guess": string(initial_guess, "solver.initial_guess",
                                choices=INITIAL_GUESSES),
        "cholmod_mode": string(cholmod_mode, "solver.cholmod_mode", choices=CHOLMOD_MODES),
    }


def validate(raw: dict, base_dir: Path, default_name: str) -> dict:
    """Check every key of a scene document; return it resolved (defaults, absolute paths).

    Parameters
    ----------
    raw : dict
        The document as parsed from TOML or JSON.
    base_dir : Path
        The scene file's folder; relative file names are resolved against it.
    default_name : str
        ``scene.name`` when the document gives none (e.g. the file's stem).

    Returns
    -------
    dict
        The ``scene``, ``cloth``, ``springs``, ``solver``, ``contact``, ``output`` and
        ``effects`` tables,
        checked, with defaults filled in (lengths [m], masses [kg], times [s], stiffnesses [N/m]).

    Raises
    ------
    Invalid
        The first problem, with its key path.
    """
    table(raw, "")
    check_finite_everywhere(raw, "")
    check_keys(raw, "", TOP_KEYS)
    out: dict[str, Any] = {"scene": _scene_table(raw, default_name)}
    out["cloth"], vertex_count = _cloth(raw, base_dir)
    out["springs"] = _springs(raw, out["cloth"]["shape"], base_dir)
    so = table(raw.get("solver", {}), "solver")
    check_keys(so, "solver", schema.keys("solver"))
    d = schema.default
    out["solver"] = validate_solver(so.get("method", d("solver", "method")),
                                    so.get("iterations", d("solver", "iterations")),
                                    so.get("tolerance"),
                                    so.get("backend", d("solver", "backend")),
                                    so.get("initial_guess", d("solver", "initial_guess")),
                                    so.get("cholmod_mode", d("solver", "cholmod_mode")))
    co = table(raw.get("contact", {}), "contact")
    check_keys(co, "contact", schema.keys("contact"))
    out["contact"] = {"mode": string(co.get("mode", d("contact", "mode")), "contact.mode",
                                     choices=CONTACT_MODES)}
    ou = table(raw.get("output", {}), "output")
    check_keys(ou, "output", schema.keys("output"))
    out["output"] = {"frame_compression": string(
        ou.get("frame_compression", d("output", "frame_compression")),
        "output.frame_compression", choices=FRAME_COMPRESSIONS)}
    effects = raw.get("effects", [])
    if not isinstance(effects, list):
        raise Invalid("effects", f"expected an array of tables ([[effects]]), got "
                                 f"{type_name(effects)}")
    out["effects"] = [validate_effect(e, f"effects[{i}]", vertex_count, base_dir)
                      for i, e in enumerate(effects)]
    for i, e in enumerate(out["effects"]):
        if "grid" in e:  # [row, column] pairs stay the same vertices at any resolution
            if out["cloth"]["shape"] != "grid":
                raise Invalid(f"effects[{i}].grid", f"only a grid cloth has rows and columns "
                                                    f"(cloth.shape = '{out['cloth']['shape']}')")
            e["vertices"] = grid_vertices(e["grid"], out["cloth"]["resolution"],
                                          f"effects[{i}].grid")
    pinned: dict[int, int] = {}
    for i, e in enumerate(out["effects"]):
        if e["kind"] == "pin" and isinstance(e.get("vertices"), list):
            for v in e["vertices"]:
                if v in pinned:
                    raise Invalid(f"effects[{i}].vertices", f"vertex {v} is already pinned by "
                                                            f"effects[{pinned[v]}]")
                pinned[v] = i
    return out


__all__ = ["validate", "validate_solver"]
