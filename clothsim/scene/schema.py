"""The scene schema as data: every key of a scene file, its type, default, unit and meaning.

The validator (:mod:`clothsim.scene.validate`) takes the known keys and the defaults from
:data:`KEYS`, and :func:`schema_markdown` renders the same entries as the key reference of
``docs/scenes.md``, so the documentation cannot drift from what is accepted.

Examples
--------
>>> from clothsim.scene.schema import default
>>> default("scene", "fps"), default("solver", "iterations")
(30.0, 10)
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

REQUIRED = object()   #: marker: the key has no default and must be given (when it applies)
NONE = object()       #: marker: absent means "not used" (no default value)

SHAPES = ("grid", "mesh", "polygon", "jacobson", "files")
TABLES = ("scene", "cloth", "springs", "solver", "contact", "output")
TOP_KEYS = TABLES + ("effects",)

# Upper bounds that keep a run finite (a larger value is almost surely a typo, and would
# otherwise hang without a word). Documented in docs/scenes.md through the schema.
MAX_FRAMES = 10_000_000
MAX_SUBSTEPS = 10_000
MAX_ITERATIONS = 100_000
MAX_NAME = 100
MAX_VERTICES = 10_000_000
MIN_H, MAX_H = 1e-9, 1e6  # [s]


def sci(n: float) -> str:
    """``1e7`` rather than ``1e+07``.

    Parameters
    ----------
    n : float
        A number, shown to one significant digit.

    Returns
    -------
    str
        E.g. ``"1e7"``, ``"2e-3"``.
    """
    return f"{n:.0e}".replace("e+0", "e").replace("e+", "e")


@dataclass(frozen=True)
class Key:
    """One key of a scene table.

    Attributes
    ----------
    table : str
        ``"scene"``, ``"cloth"``, ``"springs"``, ``"solver"``, ``"contact"`` or ``"output"``.
    name : str
        The key.
    type : str
        Its TOML type, in words (``"number"``, ``"[3] numbers"``, ``"string"``, ...).
    default : Any
        Default value, or :data:`REQUIRED` / :data:`NONE`.
    unit : str
        SI unit (empty when dimensionless).
    meaning : str
        One sentence or two: what it does and its range.
    shapes : tuple of str
        For ``[cloth]`` and ``[springs]``: the cloth shapes that use it (empty: all).
    """

    table: str
    name: str
    type: str
    default: Any
    unit: str
    meaning: str
    shapes: tuple[str, ...] = ()


_ALL_BUT_JACOBSON = ("grid", "mesh", "polygon", "files")

KEYS: tuple[Key, ...] = (
    # [scene]
    Key("scene", "name", "string", "file name", "",
        f"Scene name; names the default output folder `out/<name>`. Letters, digits, `_ . -`; "
        f"no leading `.`, at most {MAX_NAME} characters."),
    Key("scene", "description", "string", "", "", "One line, shown by `clothsim scenes`."),
    Key("scene", "frames", "integer", 60, "",
        f"Frames written after the initial one (frame 0 is the initial state); "
        f"0 ≤ frames ≤ {sci(MAX_FRAMES)}."),
    Key("scene", "fps", "number", 30.0, "1/s",
        "Frames per second, > 0. Frame k is at t = k / fps."),
    Key("scene", "substeps", "integer", 1, "",
        f"Implicit Euler steps per frame, 1 ≤ substeps ≤ {sci(MAX_SUBSTEPS)}. "
        f"The time step is h = 1 / (fps · substeps), between {MIN_H:g} s and {MAX_H:g} s."),
    Key("scene", "h", "number", NONE, "s",
        "The time step itself, used exactly as written (e.g. `h = 0.0333` for a port whose "
        "step is not 1/integer); one step per frame, frame k at t = k h. Give either `h` or "
        "`fps`/`substeps`, not both."),
    # [cloth]
    Key("cloth", "shape", "string", "grid", "",
        "How the cloth is made: `\"grid\"`, `\"mesh\"`, `\"polygon\"`, `\"jacobson\"` or "
        "`\"files\"`; each shape has its own keys below."),
    Key("cloth", "mass", "number", 1.0, "kg",
        "Total mass, > 0, spread over the vertices by `mass_lumping`.", _ALL_BUT_JACOBSON),
    Key("cloth", "vertex_mass", "number, array or file", NONE, "kg",
        "Mass of every vertex (one number > 0, or one per vertex, or a text file of n "
        "numbers, each ≥ 0). A vertex of mass 0 is pinned exactly at its initial position "
        "(as engines read an inverse mass of 0): a penalty pin on it, an obstacle it starts "
        "inside, or an impulse on massless vertices only is refused. Replaces `mass`; give "
        "one of the two.",
        _ALL_BUT_JACOBSON),
    Key("cloth", "mass_lumping", "string", "uniform", "",
        "`\"uniform\"`: every vertex the same. `\"area\"`: proportional to a third of the "
        "adjacent triangles' area.", _ALL_BUT_JACOBSON),
    Key("cloth", "size", "[2] numbers", [1.0, 1.0], "m",
        "Extent along the two grid axes, > 0.", ("grid",)),
    Key("cloth", "resolution", "[2] integers", [21, 21], "",
        f"Vertices `[nx, ny]` along the two axes, each ≥ 2, nx · ny ≤ {sci(MAX_VERTICES)}. "
        f"Vertex (row i, column j) has index `i * nx + j`.", ("grid",)),
    Key("cloth", "center", "[3] numbers", [0.0, 0.0, 0.0], "m",
        "Centre of the rectangle (grid) or offset of the outline's origin (polygon).",
        ("grid", "polygon")),
    Key("cloth", "plane", "string", "xz", "",
        "`\"xz\"`: lies flat, normal +y, rows run along −z. `\"xy\"`: hangs vertically, "
        "row `ny − 1` is the top.", ("grid", "polygon")),
    Key("cloth", "mesh", "string (file)", REQUIRED, "m",
        "Mesh file `clothsim.mesh.load` reads (OBJ, PLY, STL, MSH, VTU, …).", ("mesh",)),
    Key("cloth", "outline", "array of [2] numbers", REQUIRED, "m",
        "At least 3 corners of a closed outline in the cloth's plane.", ("polygon",)),
    Key("cloth", "spacing", "number", 0.05, "m",
        f"Target edge length, > 0 (at most about {sci(MAX_VERTICES)} vertices).", ("polygon",)),
    Key("cloth", "file", "string (file)", REQUIRED, "",
        "An assignment `.json` file; mesh, springs, masses and pins all come from it.",
        ("jacobson",)),
    Key("cloth", "pin_method", "string", "penalty", "",
        "How the pins a cloth's files declare (a `jacobson` JSON's `b`, a spring table's "
        "attachment rows) are held: `\"penalty\"`, a spring of rest length 0 to the pin's "
        "target (the assignment's `main.cpp`), or `\"constraint\"`, exactly. A pin "
        "effect keeps its own `method`."),
    Key("cloth", "pin_stiffness", "number", NONE, "N/m",
        "Stiffness of those penalty pins, > 0. Default: the assignment's w = 1e10 for a "
        "`jacobson` cloth, each attachment row's own stiffness for a spring table."),
    Key("cloth", "vertices", "string (file)", REQUIRED, "m",
        "Initial positions: a text file of n lines of 3 numbers, or one line of 3n numbers "
        "(x y z per vertex); `#` starts a comment.", ("files",)),
    Key("cloth", "triangles", "string (file)", NONE, "",
        "Triangles: a text file of lines of 3 vertex indices (base `index_base`). Without it "
        "the cloth has no triangles (springs only).", ("files",)),
    Key("cloth", "index_base", "integer", 0, "",
        "0 or 1: the number of the first vertex in `triangles`.", ("files",)),
    # [springs]
    Key("springs", "structural", "number", NONE, "N/m",
        "Grid: (i,j)–(i,j+1) and (i,j)–(i+1,j). Mesh, polygon, files: every edge. ≥ 0.",
        _ALL_BUT_JACOBSON),
    Key("springs", "shear", "number", NONE, "N/m",
        "Grid only: the two diagonals of each cell. ≥ 0.", ("grid",)),
    Key("springs", "bending", "number", NONE, "N/m",
        "Grid: (i,j)–(i,j+2) and (i,j)–(i+2,j). Mesh, polygon, files: the two vertices "
        "opposite each interior edge. ≥ 0.", _ALL_BUT_JACOBSON),
    Key("springs", "bending_pattern", "string", "every", "",
        "Grid only. `\"every\"`: a bending spring starts at every vertex. `\"alternate\"`: "
        "at every other vertex (the C++ ports).", ("grid",)),
    Key("springs", "table", "string (file)", NONE, "",
        "A spring table, one spring a line (columns in `columns`; `#` starts a comment), "
        "added to the generated families. A row whose `b` is −1 is an attachment: a "
        "penalty pin of the row's stiffness holding vertex `a` at its initial position "
        "(rest must be 0).", _ALL_BUT_JACOBSON),
    Key("springs", "columns", "array of strings", ["a", "b", "stiffness", "rest"], "",
        "Column names of `table`: `a`, `b` (vertex indices, required), `stiffness` [N/m] "
        "(required), `rest` [m] (default: the initial distance), `damping` [N·s/m] (≥ 0, "
        "default 0: damping along the spring as newton and warp define it, implicit in the "
        "step; docs/math.md); any other name (e.g. `type`) is read and ignored.",
        _ALL_BUT_JACOBSON),
    Key("springs", "index_base", "integer", 0, "",
        "0 or 1: the number of the first vertex in `table` (−1 in `b` always marks an "
        "attachment).", _ALL_BUT_JACOBSON),
    # [solver]
    Key("solver", "method", "string", "local-global", "",
        "A name in `clothsim.solvers.SOLVERS`: `\"local-global\"` (the paper), `\"newton\"` "
        "(exact reference), `\"chebyshev\"`, …"),
    Key("solver", "iterations", "integer", 10, "",
        f"Iterations per step; the maximum when `tolerance` is set. "
        f"1 ≤ iterations ≤ {sci(MAX_ITERATIONS)}."),
    Key("solver", "tolerance", "number", NONE, "",
        "Stop a step once ‖∇g(x_k)‖ / ‖∇g(x_0)‖ ≤ tolerance (> 0). Without it, exactly "
        "`iterations` are done."),
    Key("solver", "backend", "string", "auto", "",
        "Sparse factorization: `\"auto\"` (CHOLMOD if installed, else SuperLU), "
        "`\"cholmod\"`, `\"splu\"`."),
    Key("solver", "cholmod_mode", "string", "auto", "",
        "CHOLMOD's factorization of the global step (local/global family): `\"auto\"` by "
        "predicted cost, the factorization plus the run's frames × substeps × iterations "
        "solves (simplicial's solves are faster on small cloths, supernodal's factor on "
        "large ones; docs/performance.md), `\"simplicial\"`, `\"supernodal\"`. The "
        "run's `run.json` records the choice and why."),
    Key("solver", "initial_guess", "string", "y", "",
        "Where each step's iteration starts: `\"y\"`, the inertial target x_n + h v_n (the "
        "paper), or `\"x_n\"`, the previous positions (most ports, the assignment's "
        "`main.cpp`). With a fixed iteration count the answer depends on it."),
    # [contact]
    Key("contact", "mode", "string", "hold", "",
        "How the obstacles (`plane`, `sphere`, `box`) answer contact. `\"hold\"`: a vertex "
        "an obstacle pushes is held on its contact plane during the next step's solve and "
        "slides in it (sticks while static friction holds it), and leaves the surface when "
        "the cloth pulls it away; the cloth stays whole over edges (docs/effects.md). "
        "`\"post-solve\"`: the seed's and the paper's projection of each vertex after the "
        "solve, for reproducing the seed's demos and checking ports that do that."),
    # [output]
    Key("output", "frame_compression", "string", "auto", "",
        "How `clothsim run` writes the `frame_%06d.vtu` files: `\"zlib\"` (compressed, about "
        "a third of the size), `\"none\"` (raw binary, several times faster to write) or "
        "`\"auto\"`: zlib up to 100 000 vertices, none above (docs/performance.md). Both "
        "read in ParaView and meshio. The run's `run.json` records the choice and why; it "
        "is not part of the scene hash (a run may be resumed with another)."),
)


# [[effects]]: kind -> key -> (type, unit). The type words are checked by
# clothsim.scene.effects: "vec3"/"point" 3 numbers (a point within ±1e100 m), "number",
# "nonneg" (>= 0), "positive" (> 0), "time" (>= 0), "length" (> 0, <= 1e100), "string",
# "strings", "margin" (>= 0 or "auto"), "count" (an iteration count), "vertices" (indices
# or a file), "region", "base",
# "file" (a file name, resolved against the scene's folder), "cells" ([row, column] pairs of a
# grid cloth, negative from the end).
EFFECT_KEYS: dict[str, dict[str, tuple[str, str]]] = {
    "gravity": {"acceleration": ("vec3", "m/s²")},
    "force": {"per_vertex": ("vec3", "N"), "vertices": ("vertices", ""), "file": ("file", ""),
              "index_base": ("base", "")},
    "pin": {"vertices": ("vertices", ""), "region": ("region", "m"), "method": ("string", ""),
            "stiffness": ("positive", "N/m"), "release": ("time", "s"),
            "velocity": ("vec3", "m/s"), "index_base": ("base", ""), "grid": ("cells", "")},
    "plane": {"point": ("point", "m"), "normal": ("vec3", ""), "friction": ("nonneg", ""),
              "thickness": ("margin", "m")},
    "sphere": {"center": ("point", "m"), "radius": ("length", "m"), "friction": ("nonneg", ""),
               "thickness": ("margin", "m")},
    "box": {"min": ("point", "m"), "max": ("point", "m"), "friction": ("nonneg", ""),
            "thickness": ("margin", "m")},
    "impulse": {"center": ("point", "m"), "radius": ("length", "m"), "force": ("vec3", "N"),
                "start": ("number", "s"), "duration": ("positive", "s")},
    "wind": {"velocity": ("vec3", "m/s"), "drag": ("nonneg", ""),
             "density": ("nonneg", "kg/m³")},
    "damping": {"model": ("string", ""), "coefficient": ("number", "")},
    "strain-limit": {"max_strain": ("positive", ""), "iterations": ("count", ""),
                     "families": ("strings", "")},
}
_TYPE_WORDS = {"vec3": "[3] numbers", "point": "[3] numbers", "number": "number",
               "nonneg": "number ≥ 0", "margin": "number ≥ 0 or `\"auto\"`",
               "positive": "number > 0", "time": "number ≥ 0",
               "length": "number > 0", "string": "string", "strings": "array of strings",
               "count": "integer ≥ 1", "vertices": "array of integers, or a file",
               "region": "table `{min, max}`, or an array of them", "base": "0 or 1 (with a file)",
               "file": "string (file)",
               "cells": "array of `[row, column]` (grid cloths; −1 is the last)"}


def keys(table: str, shape: str | None = None) -> tuple[str, ...]:
    """Names of the keys of ``table`` (those a cloth ``shape`` uses, when given).

    Parameters
    ----------
    table : str
        ``"scene"``, ``"cloth"``, ``"springs"``, ``"solver"`` or ``"output"``.
    shape : str, optional
        A cloth shape (``"grid"``, ``"polygon"``, ...): only the keys it uses.

    Returns
    -------
    tuple of str
        Key names in schema order.
    """
    return tuple(k.name for k in KEYS
                 if k.table == table and (shape is None or not k.shapes or shape in k.shapes))


def spec(table: str, name: str) -> Key:
    """The :class:`Key` entry of ``table.name``.

    Parameters
    ----------
    table, name : str
        The table and the key.

    Returns
    -------
    Key
        Its type, default, unit and meaning.

    Raises
    ------
    KeyError
        When there is no such key.
    """
    for k in KEYS:
        if k.table == table and k.name == name:
            return k
    raise KeyError(f"{table}.{name}")


def default(table: str, name: str):
    """Default of ``table.name`` (a fresh copy for lists; None for REQUIRED/NONE).

    Parameters
    ----------
    table, name : str
        The table and the key.

    Returns
    -------
    object
        The default value, in the key's unit.
    """
    d = spec(table, name).default
    if d is REQUIRED or d is NONE:
        return None
    return list(d) if isinstance(d, list) else d


def _show_default(d) -> str:
    if d is REQUIRED:
        return "required"
    if d is NONE:
        return "—"
    if d == "file name":
        return "file name"
    if isinstance(d, str):
        return f'`"{d}"`'
    if isinstance(d, list):
        return "`[" + ", ".join(f'"{v}"' if isinstance(v, str) else repr(v) for v in d) + "]`"
    return f"`{d!r}`"


def schema_markdown() -> str:
    """The Markdown reference of every scene key, generated from :data:`KEYS`.

    Returns
    -------
    str
        One section per table (``[scene]``, ``[cloth]``, ``[springs]``, ``[solver]``,
        ``[output]``), each a
        table of key, type, default, unit, the cloth shapes that use it, and meaning.
    """
    out = []
    for table in TABLES:
        out.append(f"### `[{table}]`\n")
        shaped = table in ("cloth", "springs")
        head = "| key | type | default | unit |" + (" shapes |" if shaped else "") + " meaning |"
        out.append(head)
        out.append("|" + "---|" * (head.count("|") - 1))
        for k in KEYS:
            if k.table != table:
                continue
            row = (f"| `{k.name}` | {k.type} | {_show_default(k.default)} | "
                   f"{k.unit or '—'} |")
            if shaped:
                row += f" {', '.join(k.shapes) if k.shapes else 'all'} |"
            out.append(f"{row} {k.meaning} |")
        out.append("")
    out.append("### `[[effects]]`\n")
    out.append("Each table has `kind` and the keys of that kind (types checked before the "
               "effect is built; ranges by the effect).\n")
    out.append("| kind | key | type | unit |")
    out.append("|---|---|---|---|")
    for kind, params in EFFECT_KEYS.items():
        for name, (t, unit) in params.items():
            out.append(f"| `{kind}` | `{name}` | {_TYPE_WORDS[t]} | {unit or '—'} |")
    return "\n".join(out).rstrip() + "\n"


__all__ = ["KEYS", "Key", "SHAPES", "TABLES", "TOP_KEYS", "EFFECT_KEYS", "REQUIRED", "NONE",
           "keys", "spec",
           "default", "schema_markdown", "sci", "MAX_VERTICES", "MIN_H", "MAX_H", "MAX_FRAMES",
           "MAX_SUBSTEPS", "MAX_ITERATIONS", "MAX_NAME"]
