"""``--set KEY=VALUE``: change one key of a scene document before it is validated.

A key is a dotted path into the document, with ``[i]`` for an entry of the effects array:
``springs.structural=50``, ``solver.iterations=20``, ``effects[1].strength=2``. The value
is parsed as a TOML value (``50``, ``1e-3``, ``[0.0, -9.81, 0.0]``, ``"newton"``); a bare
word that is not TOML (``newton``, ``x_n``) is taken as a string. The changed document is
validated like a file, and an error about a changed key names the ``--set`` it came from.

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
from .schema import TOP_KEYS

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
