"""Reader for the scene format of A. Jacobson's mass-spring assignment (CSC317/CSC418, A8).

An assignment scene is a small JSON file next to an OBJ mesh::

    {"obj": "flag.obj", "b": [1, 2, 3], "k": 100000, "m": 1, "png": "flag.png"}

========  ==================================================================================
key       meaning, and how clothsim reads it
========  ==================================================================================
``obj``   Mesh file, relative to the JSON. Polygon faces (the flag and skirt are quads)
          are fan-triangulated for display and area; two-vertex faces ``f a b`` are
          strands (the chain, the net, the single spring).
``k``     One stiffness [N/m] for every spring. As in the assignment, springs lie on the
          sides of every face (each polygon's boundary, no quad diagonals), one per edge.
``m``     Mass of every vertex [kg]. Without it, each vertex gets its mixed Voronoi area
          at 1 kg/m², as the assignment's libigl mass matrix
          (``MASSMATRIX_TYPE_VORONOI``, Meyer et al. 2003; :mod:`clothsim.voronoi`).
``b``     Pinned vertices, **1-based**, held at their initial positions by the scene's
          ``[cloth] pin_method`` / ``pin_stiffness``: by default a penalty spring of
          w = 1e10 N/m, as the assignment (:mod:`clothsim.scene.pins`).
``png``   Texture; ignored.
========  ==================================================================================

:func:`scene_dict` (and the built-in ``jacobson-*`` scenes) run it as the assignment's
``main.cpp`` does: h = 1/30 s, gravity as a *force* of −9.8 N on every vertex (a
:class:`~clothsim.effects.Force`, not m g: the same where m = 1 kg, as in the chain, net
and spring, but about 5e4 g on the flag's 2e-4 kg vertices), each step's iteration
started from x_n, 50 local/global iterations. No mesh file passes through meshio here:
OBJ polygons and line faces are read directly.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from ..errors import InputError, SceneError
from ..mesh import Mesh, fan_triangles
from ..voronoi import voronoi_areas
from .common import file_stamp
from .obj import read_obj_cells


@dataclass(frozen=True, eq=False)
class Assignment:
    """One assignment scene, read and checked.

    Attributes
    ----------
    mesh : Mesh
        Vertices [m], fan-triangulated faces, and strands (two-vertex faces).
    spring_pairs : ndarray, shape (s, 2), int64
        Unique sides of every face (0-based vertex indices).
    stiffness : float
        k [N/m], the same for every spring.
    vertex_mass : ndarray, shape (n,)
        m_i [kg].
    pinned : ndarray, shape (p,), int64
        Pinned vertices, 0-based (the JSON's ``b`` minus one).
    source : Path
        The JSON file.
    """

    mesh: Mesh
    spring_pairs: np.ndarray
    stiffness: float
    vertex_mass: np.ndarray
    pinned: np.ndarray
    source: Path


#: Errors in an assignment file are scene errors: ``"<file>: <key>: <what is wrong>"``.
AssignmentError = SceneError


def _error(source, path: str, detail: str) -> AssignmentError:
    return AssignmentError(str(source), path, detail)


def _sides(faces: list[np.ndarray]) -> np.ndarray:
    """Undirected sides of polygon faces (each polygon's boundary cycle), shape (e, 2)."""
    parts = [np.stack([f, np.roll(f, -1, axis=1)], axis=2).reshape(-1, 2) for f in faces]
    return np.concatenate(parts) if parts else np.zeros((0, 2), np.int64)


def _load_json(path: Path) -> dict:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except json.JSONDecodeError as exc:
        raise _error(path, f"line {exc.lineno}", f"invalid JSON: {exc.msg}") from None
    except OSError as exc:
        raise _error(path, "", f"cannot read: {exc.strerror}") from None
    if not isinstance(data, dict):
        raise _error(path, "", "expected a JSON object")
    unknown = sorted(set(data) - {"obj", "b", "k", "m", "png", "bc"})
    if unknown:
        raise _error(path, unknown[0], "unknown key (expected obj, b, k, m, png)")
    if "bc" in data:
        raise _error(path, "bc", "not supported (pins stay at their initial positions)")
    for key in ("obj", "b", "k"):
        if key not in data:
            raise _error(path, key, "missing")
    return data


def _number(path, key, value) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value):
        raise _error(path, key, f"expected a finite number, got {value!r}")
    if value <= 0:
        raise _error(path, key, f"must be positive, got {value!r}")
    return float(value)


def read_pins(path) -> np.ndarray:
    """The JSON's ``b``, converted to 0-based vertex indices (range checked on build).

    Parameters
    ----------
    path : str or path-like
        The assignment's JSON file.

    Returns
    -------
    ndarray, shape (p,), int64
        Pinned vertices, 0-based, in the file's order.

    Raises
    ------
    SceneError
        On an unreadable file, a ``b`` that is not a list of integers >= 1, or a repeat.
    """
    path = Path(path)
    b = _load_json(path)["b"]
    if not isinstance(b, list) or not all(isinstance(i, int) and not isinstance(i, bool)
                                          for i in b):
        raise _error(path, "b", "expected an array of 1-based vertex indices")
    b = np.asarray(b, dtype=np.int64).reshape(-1)
    bad = np.flatnonzero(b < 1)
    if len(bad):
        raise _error(path, f"b[{bad[0]}]", f"vertex {b[bad[0]]} out of range (b is 1-based)")
    uniq, counts = np.unique(b, return_counts=True)
    if np.any(counts > 1):
        raise _error(path, "b", f"vertex {uniq[counts > 1][0]} is listed twice")
    return b - 1


def read_assignment(path) -> Assignment:
    """Read and check an assignment scene (JSON + OBJ); see the module docstring.

    Parameters
    ----------
    path : str or path-like
        The assignment's JSON file (its ``obj`` is relative to it).

    Returns
    -------
    Assignment
        Mesh [m], springs, stiffness [N/m], vertex masses [kg] and pins (read-only
        arrays; cached by the JSON's and the OBJ's path and :func:`~clothsim.io.common.file_stamp`:
        an edit of either is read again).

    Raises
    ------
    SceneError
        ``"<file>: <key>: <what is wrong>"`` for any problem in the JSON or the OBJ.
    """
    p = Path(path).resolve()
    files = [p]
    try:  # the key covers every file read: the JSON and the OBJ it names
        obj = json.loads(p.read_text(encoding="utf-8")).get("obj")
        if isinstance(obj, str):
            files.append(p.parent / obj)
    except (OSError, ValueError, AttributeError):
        pass  # reported, naming the key, by _read_cached
    return _read_cached(str(p), tuple((str(f), file_stamp(f)) for f in files))


@lru_cache(maxsize=4)
def _read_cached(path: str, stamps: tuple) -> Assignment:
    p = Path(path)
    data = _load_json(p)
    k = _number(p, "k", data["k"])
    if not isinstance(data["obj"], str):
        raise _error(p, "obj", f"expected a file name, got {data['obj']!r}")
    obj = p.parent / data["obj"]
    if not obj.is_file():
        raise _error(p, "obj", f"file not found: {obj}")
    try:  # the springs need the faces as written (quad sides, no diagonals)
        vertices, cells = read_obj_cells(obj, field="obj")
        faces = [c for kind, c in cells if kind != "line"]
        strands = np.concatenate([c for kind, c in cells if kind == "line"]
                                 or [np.zeros((0, 2), np.int64)])
        triangles = np.concatenate([fan_triangles(f) for f in faces]
                                   or [np.zeros((0, 3), np.int64)])
        mesh = Mesh(vertices, triangles, strands)
    except InputError as exc:
        raise _error(obj, "", str(exc)) from None
    n = len(vertices)
    pairs = np.sort(np.concatenate([_sides(faces), strands]), axis=1)
    pairs = np.unique(pairs[pairs[:, 0] != pairs[:, 1]], axis=0)
    if "m" in data:
        m = np.full(n, _number(p, "m", data["m"]))
    else:
        if mesh.triangle_count == 0:
            raise _error(p, "m", "missing: a mesh without polygons needs a per-vertex mass m")
        m = voronoi_areas(mesh.vertices, mesh.triangles)  # kg at 1 kg/m², as libigl
        if np.any(m <= 0):
            raise _error(p, "m", f"missing, and vertex {int(np.argmin(m)) + 1} touches no "
                                 f"polygon, so its Voronoi area, its mass, is 0")
    pinned = read_pins(p)
    if len(pinned) and pinned.max() >= n:
        i = int(np.argmax(pinned))
        raise _error(p, f"b[{i}]", f"vertex {pinned[i] + 1} out of range 1..{n}")
    for a in (pairs, m, pinned):
        a.flags.writeable = False
    return Assignment(mesh, pairs, k, m, pinned, p)


def scene_dict(path, *, frames: int = 60, iterations: int = 50) -> dict:
    """A scene document (as :class:`~clothsim.scene.Scene.from_dict` takes) for a JSON file.

    As the assignment's ``main.cpp``: h = 1/30 s, −9.8 N along y on every vertex (a
    ``force`` effect), penalty pins of w = 1e10 N/m from ``b`` (the ``jacobson`` shape's
    default), each step started from x_n, ``iterations`` local/global iterations.

    Parameters
    ----------
    path : str or path-like
        The assignment's JSON file.
    frames : int
        Frames to simulate (at 30 frames per second, one step per frame).
    iterations : int
        Local/global iterations per step.

    Returns
    -------
    dict
        The scene document: ``scene``, ``cloth`` (shape ``"jacobson"``), ``solver`` and
        ``effects`` (the force) tables.
    """
    p = Path(path).resolve()
    _load_json(p)  # fail early, naming the JSON file
    return {
        "scene": {"name": f"jacobson-{p.stem}", "frames": frames, "fps": 30, "substeps": 1,
                  "description": f"assignment scene {p.name}"},
        "cloth": {"shape": "jacobson", "file": str(p)},
        "solver": {"method": "local-global", "iterations": iterations, "initial_guess": "x_n"},
        "effects": [{"kind": "force", "per_vertex": [0.0, -9.8, 0.0]}],
    }


__all__ = ["Assignment", "AssignmentError", "read_assignment", "read_pins", "scene_dict"]
