"""Where scene files and the data they name are found.

The data root
    A path ``data:<relative>`` in a scene names a file under the data root: the folder in
    ``$CLOTHSIM_DATA``, else ``<repository>/../shared/data``. For example
    ``data:liu13-port/default-scene/x0.txt`` or ``data:jacobson-a8/flag.json``. The old
    form ``data:flag.json`` (relative to the ``jacobson-a8`` folder) is still accepted.
Built-in scenes
    ``clothsim/scenes/<name>.toml``, loaded by name.
"""

from __future__ import annotations

import os
import re
import tomllib
from pathlib import Path

from ..errors import SceneError
from ..io.common import special_file
from .checks import Invalid, shorten, suggest

DEFAULT_SCENE = "drop-on-square"
DATA_PREFIX = "data:"
BUILTIN_DIR = Path(__file__).resolve().parent.parent / "scenes"
ASSIGNMENT_FOLDER = "jacobson-a8"


def data_root() -> Path:
    """The folder ``data:`` paths are relative to.

    Returns
    -------
    Path
        ``$CLOTHSIM_DATA`` when set, else ``<repository>/../shared/data`` (the repository
        being the folder holding the ``clothsim`` package). It may not exist.
    """
    env = os.environ.get("CLOTHSIM_DATA")
    if env:
        return Path(env).expanduser()
    return Path(__file__).resolve().parents[3] / "shared" / "data"


def data_dir() -> Path:
    """The folder of A. Jacobson's assignment data (``<data root>/jacobson-a8``).

    ``$CLOTHSIM_DATA`` may also name that folder itself (the older convention).

    Returns
    -------
    Path
        The folder (it may not exist).
    """
    root = data_root()
    if (root / ASSIGNMENT_FOLDER).is_dir():
        return root / ASSIGNMENT_FOLDER
    if os.environ.get("CLOTHSIM_DATA") and root.is_dir():
        return root  # $CLOTHSIM_DATA is the assignment folder itself
    return root / ASSIGNMENT_FOLDER


def _data_candidates(rel: str) -> list[Path]:
    root = data_root()
    out = [root / rel, root / ASSIGNMENT_FOLDER / rel]  # the second: the old form
    if root.name == ASSIGNMENT_FOLDER:
        out.append(root.parent / rel)
    return out


def _inside_data_root(p: Path, root: Path) -> bool:
    """``p`` (links followed) lies inside the data root (or, when the root is the old
    ``jacobson-a8`` folder itself, inside its parent)."""
    try:
        real = p.resolve()
        roots = [root.resolve()]
        if root.name == ASSIGNMENT_FOLDER:
            roots.append(root.parent.resolve())
    except (OSError, RuntimeError):
        return False
    return any(real == r or real.is_relative_to(r) for r in roots)


def resolve_path(value: str, base_dir: Path, path: str) -> Path:
    """An existing file named in a scene: ``data:...``, absolute, or relative to the scene.

    Parameters
    ----------
    value : str
        The file name as the scene writes it.
    base_dir : Path
        The scene file's folder (relative names are resolved against it).
    path : str
        The scene key holding ``value``, for error messages (e.g. ``"cloth.mesh"``).

    Returns
    -------
    Path
        The existing file.

    Raises
    ------
    Invalid
        At ``path``: the data root is missing, the file is missing, or it is a directory.
    """
    if "\x00" in value:
        raise Invalid(path, "a file name cannot contain a NUL character")
    if value.startswith(DATA_PREFIX):
        rel = value[len(DATA_PREFIX):]
        root = data_root()
        if not root.is_dir():
            raise Invalid(path, f"data directory {root} not found; set CLOTHSIM_DATA to the "
                                f"folder holding the shared data (jacobson-a8, liu13-port)")
        candidates = _data_candidates(rel)
        p = next((c for c in candidates if c.exists()), candidates[0])
        if not _inside_data_root(p, root):
            raise Invalid(path, f"a data: path must stay inside the data root {root}, got "
                                f"{shorten(value)}")
    else:
        p = Path(value).expanduser()
        p = p if p.is_absolute() else base_dir / p
    try:
        if p.is_dir():
            raise Invalid(path, f"is a directory, not a file: {shorten(str(p), 200)}")
        if not p.is_file():
            what = special_file(p)  # a FIFO would block the reader; /dev/zero never ends
            raise Invalid(path, f"is {what}, not a regular file: {shorten(str(p), 200)}" if what
                          else f"file not found: {shorten(str(p), 200)}")
    except OSError as exc:  # e.g. a name too long for the file system
        raise Invalid(path, f"cannot use {shorten(value)}: {exc.strerror}") from None
    return p.resolve()


def list_builtin_scenes() -> dict[str, str]:
    """Built-in scene names and their one-line descriptions.

    Returns
    -------
    dict of str to str
        Scene name (file stem in ``clothsim/scenes``, sorted) to its ``scene.description``
        on one line (empty when the file has none or cannot be read).
    """
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
    """Path of the built-in scene ``name`` (``clothsim/scenes/<name>.toml``).

    Parameters
    ----------
    name : str
        Scene name, e.g. ``"hanging"``.

    Returns
    -------
    Path
        The TOML file's path (not checked to exist).
    """
    return BUILTIN_DIR / f"{name}.toml"


def builtin_scene_text(name: str) -> str:
    """The TOML text of a built-in scene (a template to start a scene file from).

    Parameters
    ----------
    name : str
        A name of :func:`list_builtin_scenes`.

    Returns
    -------
    str
        The file's text.

    Raises
    ------
    SceneError
        ``name`` is not a built-in scene.
    """
    names = list(list_builtin_scenes())
    if name not in names:
        raise SceneError(shorten(name), "", "no such built-in scene"
                         + suggest(name, names).replace("expected one of", "built-in scenes:"))
    return builtin_scene_path(name).read_text(encoding="utf-8")


MAX_DEPTH = 100


def parse_toml(text: str, source: str) -> dict:
    """Parse TOML text; a syntax error becomes ``"<source>: line N: invalid TOML: …"``.

    A leading UTF-8 byte-order mark is accepted (and ignored); nesting deeper than
    100 levels is an error.

    Parameters
    ----------
    text : str
        The TOML document.
    source : str
        Where it came from (file name), for error messages.

    Returns
    -------
    dict
        The parsed document.

    Raises
    ------
    SceneError
        On a syntax error (naming the line) or nesting deeper than 100 levels.
    """
    if text.startswith("\ufeff"):
        text = text[1:]
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        msg = str(exc)
        m = re.search(r"\(at line (\d+), column (\d+)\)", msg)
        where = f"line {m.group(1)}" if m else ""
        raise SceneError(source, where, f"invalid TOML: {shorten(msg, 200)}") from None
    except RecursionError:
        raise SceneError(source, "", f"invalid TOML: nested too deeply (more than "
                                     f"{MAX_DEPTH} levels)") from None
    _check_depth(doc, source)
    return doc


def _check_depth(doc, source: str) -> None:
    stack = [(doc, 0, "")]
    while stack:
        v, depth, path = stack.pop()
        if depth > MAX_DEPTH:
            raise SceneError(source, shorten(path, 80), f"nested too deeply (more than "
                                                        f"{MAX_DEPTH} levels)")
        if isinstance(v, dict):
            stack.extend((x, depth + 1, f"{path}.{k}" if path else str(k)) for k, x in v.items())
        elif isinstance(v, list):
            stack.extend((x, depth + 1, f"{path}[{i}]") for i, x in enumerate(v))


def find_scene(path_or_name) -> Path:
    """The scene file a command-line argument names: a file, or a built-in scene name.

    Parameters
    ----------
    path_or_name : str or Path
        An existing file, or the name of a built-in scene.

    Returns
    -------
    Path
        The scene file.

    Raises
    ------
    SceneError
        A directory, a missing file, or an unknown name (with the closest built-in names).
    """
    name = str(path_or_name)
    try:
        p = Path(path_or_name).expanduser()
        is_file = p.is_file()
        if p.is_dir():
            raise SceneError(shorten(name, 200), "", "is a directory, not a scene file")
    except (OSError, ValueError) as exc:
        raise SceneError(shorten(name), "", f"cannot use this path: {exc}") from None
    if is_file:
        return p
    builtin = builtin_scene_path(name)
    if "/" not in name and "\\" not in name and builtin.is_file():
        return builtin
    if p.suffix in (".toml", ".json") or os.sep in name:
        raise SceneError(shorten(name, 200), "", "file not found")
    names = list(list_builtin_scenes())
    raise SceneError(shorten(name), "", "no such scene file or built-in scene"
                     + suggest(name, names).replace("expected one of", "built-in scenes:"))


__all__ = ["data_root", "data_dir", "resolve_path", "list_builtin_scenes", "builtin_scene_path",
           "builtin_scene_text", "parse_toml", "find_scene", "DEFAULT_SCENE", "DATA_PREFIX",
           "BUILTIN_DIR"]
