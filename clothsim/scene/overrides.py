"""``--set KEY=VALUE``: change one key of a scene document before it is validated.

A key is a dotted path into the document, with ``[i]`` for an entry of the effects array:
``springs.structural=50``, ``solver.iterations=20``, ``effects[0].acceleration=[0, -1.62, 0]``.
The value is parsed as a TOML value (``50``, ``1e-3``, ``[0.0, -9.81, 0.0]``, ``"newton"``); a bare
word that is not TOML (``newton``, ``x_n``) is taken as a string. The changed document is
validated like a file, and an error about a changed key names the ``--set`` it came from,
as does any error the file without its ``--set`` changes does not have (:func:`blame`). A
``--set`` of a grid's resolution is refused when the scene pins or pushes vertices by index
(:func:`moved_indices`): the same indices would name other vertices.

Examples
--------
>>> doc = {"springs": {"structural": 800.0}, "effects": [{"kind": "gravity"}]}
>>> apply_overrides(doc, ["springs.structural=50", "effects[0].acceleration=[0, -1, 0]"])
['springs.structural=50', 'effects[0].acceleration=[0, -1, 0]']
>>> doc["springs"]["structural"], doc["effects"][0]["acceleration"]
(50, [0, -1, 0])
"""

from __future__ import annotations

import re
import tomllib

from ..errors import SceneError
from .checks import suggest
from .schema import TOP_KEYS, default

_PART = re.compile(r"^(?P<name>[A-Za-z_][\w-]*)(?:\[(?P<index>\d+)\])?$")
_BARE = re.compile(r"^[\w.:/+-]+$")
#: The scene document's tables; a --set outside them is an unknown key.
TABLES = TOP_KEYS


def parse_value(text: str, where: str):
    """A ``--set`` value: TOML, or a bare word as a string.

    Parameters
    ----------
    text : str
    where : str
        The ``--set`` argument, for the error message.

    Returns
    -------
    object
        int, float, bool, str, list or dict.

    Raises
    ------
    SceneError
        When the value is neither TOML nor a bare word.
    """
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        if _BARE.match(text):
            return text
        raise SceneError(f"--set {where}", "", f"value {text!r} is not a TOML value (quote "
                         f"text: KEY='\"text\"')") from None


def apply_overrides(doc: dict, overrides) -> list[str]:
    """Apply ``KEY=VALUE`` strings to a scene document in place.

    Parameters
    ----------
    doc : dict
        The parsed scene document (tables ``scene``, ``cloth``, ``springs``, ``solver`` and
        the ``effects`` array).
    overrides : sequence of str
        ``KEY=VALUE`` strings, applied in order.

    Returns
    -------
    list of str
        The overrides applied (to record with the run).

    Raises
    ------
    SceneError
        A malformed argument, an unknown table (with a suggestion), an effects index out of
        range, or a value that is not TOML.
    """
    done = []
    for item in overrides:
        key, sep, text = str(item).partition("=")
        key = key.strip()
        if not sep or not key:
            raise SceneError(f"--set {item}", "", "expected KEY=VALUE, e.g. "
                             "springs.structural=50")
        parts = key.split(".")
        node, path = doc, []
        for depth, part in enumerate(parts):
            m = _PART.match(part)
            if not m:
                raise SceneError(f"--set {item}", key, f"{part!r} is not a key (letters, "
                                 f"digits, _ and -, with [i] for an effect)")
            name, index = m.group("name"), m.group("index")
            if depth == 0 and name not in TABLES:
                raise SceneError(f"--set {item}", key, f"unknown table {name!r}"
                                 + suggest(name, TABLES))
            last = depth == len(parts) - 1
            path.append(name)
            if index is not None:
                seq = node.get(name)
                if not isinstance(seq, list) or int(index) >= len(seq):
                    count = len(seq) if isinstance(seq, list) else 0
                    raise SceneError(f"--set {item}", key, f"{name}[{index}]: the scene has "
                                     f"{count} {name}")
                if last:
                    seq[int(index)] = parse_value(text, item)
                    break
                node = seq[int(index)]
                if not isinstance(node, dict):
                    raise SceneError(f"--set {item}", key, f"{name}[{index}] is a value, not a "
                                     f"table")
                continue
            if last:
                node[name] = parse_value(text, item)
                break
            child = node.setdefault(name, {})
            if not isinstance(child, dict):
                raise SceneError(f"--set {item}", key, f"{'.'.join(path)} is a value, not a "
                                 f"table")
            node = child
        done.append(f"{key}={text}")
    return done


def rename_error(exc: SceneError, overrides) -> SceneError:
    """A validation error about a key that a ``--set`` changed, attributed to that ``--set``.

    Parameters
    ----------
    exc : SceneError
        The error of the validated document.
    overrides : sequence of str

    Returns
    -------
    SceneError
        ``exc`` itself, or one whose source is ``--set KEY=VALUE``.
    """
    for item in overrides:
        key = str(item).partition("=")[0].strip()
        if exc.path and (exc.path == key or exc.path.startswith(key + ".")
                         or key.startswith(exc.path + ".")
                         or exc.path.startswith(key + "[")):
            return SceneError(f"--set {item}", exc.path, exc.detail)
    return exc


def set_source(overrides) -> str:
    """The source an error caused by ``overrides`` names: ``"--set A"`` or ``"--set A, --set B"``.

    Parameters
    ----------
    overrides : sequence of str

    Returns
    -------
    str
    """
    return ", ".join(f"--set {item}" for item in overrides)


def builds(scene) -> bool:
    """Whether ``scene`` (a :class:`~clothsim.scene.Scene`, or None) builds a simulation.

    Parameters
    ----------
    scene : Scene or None

    Returns
    -------
    bool
        False for None or on any error (a probe: the error itself is reported elsewhere).
    """
    try:
        return scene is not None and scene.build_simulation() is not None
    except Exception:  # noqa: BLE001
        return False


def blame(exc: SceneError, overrides, base_is_fine) -> SceneError:
    """``exc`` attributed to the ``--set`` that caused it, if one did.

    First by key (:func:`rename_error`); else, when the document without its ``--set``
    changes has no error (``base_is_fine()``), to all of them: e.g. a resolution or a size
    that leaves a pin region empty.

    Parameters
    ----------
    exc : SceneError
    overrides : sequence of str
        The ``--set`` changes applied.
    base_is_fine : callable
        ``() -> bool``: whether the same step succeeds without the changes (called only
        when needed: it may build the scene).

    Returns
    -------
    SceneError
    """
    renamed = rename_error(exc, overrides)
    if renamed is not exc or not overrides or not base_is_fine():
        return renamed
    return SceneError(set_source(overrides), exc.path, exc.detail)


def moved_indices(before: dict, after: dict, overrides) -> SceneError | None:
    """A ``--set`` of a grid's resolution under effects that name vertices by index.

    Vertex (row i, column j) of an nx × ny grid is ``i * nx + j``: at another resolution
    the same index is another vertex (``hanging``'s corners 420 and 440 at 21 × 21 are in
    mid-cloth at 31 × 31). Pins given by ``grid`` ([row, column]) or ``region`` follow the
    cloth and are not affected.

    Parameters
    ----------
    before : dict
        The document as the file gives it.
    after : dict
        The validated document with the ``--set`` changes.
    overrides : sequence of str

    Returns
    -------
    SceneError or None
        The refusal, naming the ``--set`` and the effect's key; None when nothing moved.
    """
    cloth = after.get("cloth", {})
    file_cloth = before.get("cloth") if isinstance(before.get("cloth"), dict) else {}
    old = file_cloth.get("resolution", default("cloth", "resolution"))
    new = cloth.get("resolution")
    if (cloth.get("shape") != "grid" or new == old or not isinstance(old, list)
            or len(old) != 2 or not all(isinstance(r, int) and r > 0 for r in old)):
        return None  # (a file whose own resolution is invalid has no vertices to move)
    keys = [o.partition("=")[0].strip() for o in overrides]
    item = next((o for o, k in zip(overrides, keys) if "cloth.resolution".startswith(k)
                 or k.startswith("cloth.resolution")), overrides[0])
    for i, e in enumerate(after.get("effects", [])):
        if "vertices" not in e or "grid" in e or any(k.startswith(f"effects[{i}].vertices")
                                                      for k in keys):
            continue
        vs = e["vertices"]
        shown = (f"vertex {vs[0]} is row {vs[0] // old[0]}, column {vs[0] % old[0]} at "
                 f"{old[0]} × {old[1]} but row {vs[0] // new[0]}, column {vs[0] % new[0]} at "
                 f"{new[0]} × {new[1]}") if isinstance(vs, list) and vs and old[0] else \
            f"at {new[0]} × {new[1]} they name other vertices than at {old[0]} × {old[1]}"
        return SceneError(f"--set {item}", f"effects[{i}].vertices",
                          f"this {e['kind']} names vertices by index, which a new resolution "
                          f"moves ({shown}); name them by grid = [[row, column], …] (−1: the "
                          f"last) or by region, or --set the vertices too")
    return None

