"""Validation of one ``[[effects]]`` table: kind, keys, and the type of every parameter.

The types of the parameters a scene file may give (:data:`PARAMETERS`) are checked here,
with the key path, before the effect's own constructor sees them; the constructor's checks
(ranges, shapes) then run, and their complaints are reported at the effect's key path.
"""

from __future__ import annotations

from pathlib import Path

from ..effects import EFFECTS
from ..errors import InputError
from ..magnitudes import MAX_LENGTH  # [m]: coordinates and radii whose squares stay finite
from .checks import (
    Invalid,
    check_keys,
    constructor_keys,
    integer,
    locate,
    number,
    show,
    string,
    suggest,
    table,
    type_name,
)
from .files import resolve_path
from .schema import EFFECT_KEYS, MAX_ITERATIONS

PARAMETERS = {kind: {key: t for key, (t, _unit) in keys.items()}
              for kind, keys in EFFECT_KEYS.items()}  # kind -> key -> type word
_SCENE_ONLY = {"pin": ("index_base", "grid"), "force": ("index_base",)}  # read by the scene
_PYTHON_ONLY_KEYS = {"pin": ("motion",),     # callables: Python API only, not in scene files
                     # an obstacle's contact mode: the scene's [contact] mode sets it
                     "plane": ("contact",), "sphere": ("contact",), "box": ("contact",)}


def _vec3(v, path: str, *, point=False) -> list[float]:
    if isinstance(v, (list, tuple)) and len(v) != 3:
        raise Invalid(path, f"expected 3 numbers, got {show(v)}")
    if not isinstance(v, (list, tuple)) or all(isinstance(x, bool) for x in v):
        raise Invalid(path, f"must be a list of 3 numbers, got {show(v)}")
    out = [number(x, f"{path}[{i}]") for i, x in enumerate(v)]
    if point:
        for i, x in enumerate(out):
            if abs(x) > MAX_LENGTH:
                raise Invalid(f"{path}[{i}]", f"must be within ±{MAX_LENGTH:g} m, got {x!r}")
    return out


def _region(v, path: str) -> dict:
    r = table(v, path)
    check_keys(r, path, ("min", "max"))
    for corner in ("min", "max"):
        if corner not in r:
            raise Invalid(f"{path}.{corner}", "missing: a region needs 'min' and 'max'")
    return {c: _vec3(r[c], f"{path}.{c}", point=True) for c in ("min", "max")}


def check_parameter(kind: str, key: str, v, path: str, base_dir: Path):
    """The value of ``effects[i].key`` checked for its type; returns it (paths resolved).

    Parameters
    ----------
    kind : str
        The effect kind, e.g. ``"gravity"``.
    key : str
        The parameter's key; its type word comes from :data:`PARAMETERS` (keys without one
        are passed through unchecked).
    v : object
        The value, in the unit the scene reference gives (e.g. [m], [m/s²], [s]).
    path : str
        Its key path, e.g. ``"effects[0].acceleration"``.
    base_dir : Path
        The scene file's folder, for file names.

    Returns
    -------
    object
        The checked value: a float, an int, a list of 3 floats, a string or a resolved path.

    Raises
    ------
    Invalid
        At ``path`` on a wrong type or value.
    """
    t = PARAMETERS.get(kind, {}).get(key)
    if t is None:
        return v
    if t in ("vec3", "point"):
        return _vec3(v, path, point=t == "point")
    if t == "number":
        return number(v, path)
    if t == "nonneg":
        return number(v, path, nonnegative=True)
    if t == "margin":
        return "auto" if v == "auto" else number(v, path, nonnegative=True)
    if t in ("positive", "time"):
        if t == "time":
            return number(v, path, nonnegative=True)
        return number(v, path, positive=True)
    if t == "length":
        return number(v, path, positive=True, maximum=MAX_LENGTH)
    if t == "string":
        return string(v, path)
    if t == "count":
        return integer(v, path, minimum=1, maximum=MAX_ITERATIONS)
    if t == "base":
        return integer(v, path, minimum=0, maximum=1)
    if t == "strings":
        if not isinstance(v, list):
            raise Invalid(path, f"expected an array of strings, got {type_name(v)}")
        return [string(x, f"{path}[{i}]") for i, x in enumerate(v)]
    if t == "region":
        if isinstance(v, list):  # several boxes: [{min, max}, ...]
            if not v:
                raise Invalid(path, "an empty array of boxes pins nothing")
            return [_region(b, f"{path}[{i}]") for i, b in enumerate(v)]
        return _region(v, path)
    if t == "file":
        return str(resolve_path(string(v, path), base_dir, path))
    if t == "cells":
        if not isinstance(v, list) or not v:
            raise Invalid(path, f"expected an array of [row, column] pairs, got {type_name(v)}")
        for i, rc in enumerate(v):
            if not isinstance(rc, list) or len(rc) != 2:
                raise Invalid(f"{path}[{i}]", f"expected [row, column], got {type_name(rc)}")
        return [[integer(x, f"{path}[{i}][{j}]") for j, x in enumerate(rc)]
                for i, rc in enumerate(v)]
    if t == "vertices":
        if isinstance(v, str):
            return str(resolve_path(v, base_dir, path))
        if not isinstance(v, (list, tuple)):
            raise Invalid(path, f"expected an array of vertex indices or a file, got "
                                f"{type_name(v)}")
        return [integer(x, f"{path}[{i}]", minimum=0) for i, x in enumerate(v)]
    raise AssertionError(t)  # pragma: no cover


def validate_effect(e, path: str, vertex_count: int | None, base_dir: Path) -> dict:
    """Check one effect table; return ``{"kind": ..., **parameters}`` (paths resolved).

    The parameters' types are checked here, then the effect's constructor is tried (not
    bound to a model) and its complaints reported at ``path``.

    Parameters
    ----------
    e : object
        The ``[[effects]]`` table.
    path : str
        Its key path, e.g. ``"effects[2]"``.
    vertex_count : int or None
        n, to range-check a pin's vertex list (None: not checked here).
    base_dir : Path
        The scene file's folder, for file names.

    Returns
    -------
    dict
        ``kind`` and the checked parameters.

    Raises
    ------
    Invalid
        On a missing or unknown kind, an unknown key or a bad value.
    """
    e = table(e, path)
    if "kind" not in e:
        raise Invalid(f"{path}.kind", f"missing: every effect needs a kind ({', '.join(EFFECTS)})")
    kind = string(e["kind"], f"{path}.kind")
    if kind not in EFFECTS:
        raise Invalid(f"{path}.kind", f"unknown effect kind {show(kind)}" + suggest(kind, EFFECTS))
    names, any_key = constructor_keys(EFFECTS[kind])
    names = [k for k in names if k not in _PYTHON_ONLY_KEYS.get(kind, ())]
    names += list(_SCENE_ONLY.get(kind, ()))
    if not any_key:
        check_keys(e, path, ["kind"] + names)
    params = {k: check_parameter(kind, k, v, f"{path}.{k}", base_dir)
              for k, v in e.items() if k != "kind"}
    if kind == "plane" and "normal" in params:
        big = max(abs(x) for x in params["normal"])
        if big == 0:
            raise Invalid(f"{path}.normal", "must not be the zero vector")
        if big > 1e150 or big < 1e-150:  # rescaled so that its length neither over- nor
            params["normal"] = [x / big for x in params["normal"]]  # underflows
    if kind in ("pin", "force"):
        if "index_base" in params and not isinstance(params.get("vertices"), str):
            raise Invalid(f"{path}.index_base", "only used when 'vertices' is a file")
        vs = params.get("vertices")
        if isinstance(vs, list):
            seen = set()
            for i, v in enumerate(vs):
                if vertex_count is not None and v >= vertex_count:
                    raise Invalid(f"{path}.vertices[{i}]", f"vertex {v} out of range "
                                                           f"0..{vertex_count - 1}")
                if v in seen:
                    raise Invalid(f"{path}.vertices[{i}]", f"vertex {v} is listed twice")
                seen.add(v)
    if "grid" in params:  # [row, column] pairs: made vertex indices by validate()
        others = [k for k in ("vertices", "region") if k in params]
        if others:
            raise Invalid(f"{path}.grid", f"give one of 'vertices', 'region' or 'grid', not "
                                          f"both 'grid' and '{others[0]}'")
        params_for_check = {**params, "vertices": []}
    else:
        params_for_check = params
    if not isinstance(params.get("vertices"), str):  # a file of indices: read on build
        try:  # the constructor checks its own parameters; nothing is bound to a model here
            EFFECTS[kind](**constructor_params(kind, params_for_check))
        except (InputError, TypeError, ValueError) as exc:
            raise Invalid(*locate(exc, path, kind, path)) from None
    return {"kind": kind, **params}


def grid_vertices(cells: list, resolution: list, path: str) -> list[int]:
    """Vertex indices of ``[row, column]`` pairs of a grid cloth (negative: from the end).

    Parameters
    ----------
    cells : list of [int, int]
        Rows and columns; row −1 is the last (the top of an ``"xy"`` cloth), column −1 the
        last, as Python indexes.
    resolution : [nx, ny]
        The grid's vertices along its two axes; vertex (row i, column j) is ``i * nx + j``.
    path : str
        The key path of ``cells`` (e.g. ``"effects[1].grid"``), for errors.

    Returns
    -------
    list of int

    Raises
    ------
    Invalid
        At ``path[i]`` for a row or column out of range, or a vertex named twice.
    """
    nx, ny = resolution
    out = []
    for i, (r, c) in enumerate(cells):
        if not (-ny <= r < ny and -nx <= c < nx):
            raise Invalid(f"{path}[{i}]", f"[{r}, {c}] is outside the {nx} × {ny} grid (rows "
                                          f"{-ny}..{ny - 1}, columns {-nx}..{nx - 1})")
        v = (r % ny) * nx + c % nx
        if v in out:
            j = out.index(v)
            raise Invalid(f"{path}[{i}]", f"[{r}, {c}] is vertex {v}, as {path}[{j}] "
                                          f"{cells[j]} is")
        out.append(v)
    return out


def constructor_params(kind: str, params: dict) -> dict:
    """The parameters the effect's constructor takes (scene-only keys removed).

    Parameters
    ----------
    kind : str
        The effect kind.
    params : dict
        A checked effect table (``kind`` may be in it).

    Returns
    -------
    dict
        ``params`` without ``kind`` and the keys only the scene reads (``index_base``).
    """
    return {k: v for k, v in params.items() if k != "kind"
            and k not in _SCENE_ONLY.get(kind, ())}


__all__ = ["validate_effect", "check_parameter", "constructor_params", "grid_vertices",
           "PARAMETERS"]
