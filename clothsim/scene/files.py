"""Where scene files and the data they name are found.

The data root
    A path ``data:<name>/<file>`` in a scene names a file of a data set
    (:mod:`clothsim.datasets`): ``data:liu13-port/default-scene/x0.txt`` (shipped with
    clothsim) or ``data:jacobson-a8/flag.json`` (the assignment's files, downloaded on
    first use). ``$CLOTHSIM_DATA``, when set, is looked in first, and may hold other
    folders of the user's own (``data:my-meshes/sheet.obj``). The old form
    ``data:flag.json`` (relative to the ``jacobson-a8`` folder) is still accepted.
Built-in scenes
    ``clothsim/scenes/<name>.toml``, loaded by name.
"""

from __future__ import annotations

import os
import re
import tomllib
from importlib import resources
from pathlib import Path

from .. import datasets
from ..errors import InputError, SceneError
from ..io.common import special_file
from .checks import Invalid, shorten, suggest

DEFAULT_SCENE = "drop-on-square"
DATA_PREFIX = "data:"
BUILTIN_DIR = Path(str(resources.files("clothsim").joinpath("scenes")))  # package data
ASSIGNMENT_FOLDER = "jacobson-a8"


def data_root() -> Path:
    """The folder ``data:`` paths are looked up in first.

    Returns
    -------
    Path
        ``$CLOTHSIM_DATA`` when set, else the cache folder the data sets are unpacked and
        downloaded into (:func:`clothsim.datasets.cache_dir`). It may not exist.
    """
    env = os.environ.get("CLOTHSIM_DATA")
    if env:
        return Path(env).expanduser()
    return datasets.cache_dir()


def data_dir() -> Path:
    """The folder of A. Jacobson's assignment data, where it is or would be downloaded to.

    Nothing is downloaded: see :func:`clothsim.datasets.locate` for that.

    Returns
    -------
    Path
        ``$CLOTHSIM_DATA/jacobson-a8`` (or ``$CLOTHSIM_DATA`` itself when it is the
        assignment's folder, the older convention), else the cache's ``jacobson-a8``
        (it may not exist, or not hold every file yet).
    """
    return datasets.status(ASSIGNMENT_FOLDER).folder


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


def _data_set_of(rel: str) -> tuple[str, str] | None:
    """(data set, path inside it) a ``data:`` path names, or None."""
    first, _, rest = rel.partition("/")
    if first in datasets.DATASETS:
        return first, rest
    if rel in datasets.DATASETS[ASSIGNMENT_FOLDER].files:  # the old form data:flag.json
        return ASSIGNMENT_FOLDER, rel
    return None


def _data_path(value: str, path: str) -> Path:
    """The file a ``data:`` path names: under ``$CLOTHSIM_DATA`` first, else in its data
    set (unpacked or downloaded on first use)."""
    rel = value[len(DATA_PREFIX):]
    env = os.environ.get("CLOTHSIM_DATA")
    named = _data_set_of(rel)
    if env:
        root = data_root()
        if not root.is_dir():
            raise Invalid(path, f"data directory {root} not found (CLOTHSIM_DATA names it); "
                                f"set CLOTHSIM_DATA to an existing folder, or unset it")
        candidates = _data_candidates(rel)
        p = next((c for c in candidates if c.exists()), None)
        if p is not None or named is None:
            p = candidates[0] if p is None else p
            if not _inside_data_root(p, root):
                raise Invalid(path, f"a data: path must stay inside the data root {root}, "
                                    f"got {shorten(value)}")
            return p
    if named is None:
        raise Invalid(path, f"{shorten(value)} names no data set (known: "
                            f"{', '.join(datasets.DATASETS)}); set CLOTHSIM_DATA to the "
                            f"folder holding it")
    name, inner = named
    try:
        folder = datasets.locate(name)
    except datasets.DataUnavailableError as exc:
        raise Invalid(path, str(exc)) from None
    p = folder / inner
    try:
        inside = p.resolve().is_relative_to(folder.resolve())
    except (OSError, RuntimeError):
        inside = False
    if not inside:
        raise Invalid(path, f"a data: path must stay inside the data set's folder {folder}, "
                            f"got {shorten(value)}")
    return p


def resolve_data_path(value: str, what: str = "path") -> Path:
    """The existing file or folder a ``data:<name>/...`` path names (a command-line
    argument, e.g. ``data:liu13-port/default-scene``), got first when missing.

    Parameters
    ----------
    value : str
        ``data:`` followed by a data set's name and a path inside it (or a path under
        ``$CLOTHSIM_DATA``).
    what : str
        What the value is, for the error message (e.g. ``"PORT"``).

    Returns
    -------
    Path
        The file or folder.

    Raises
    ------
    InputError
        One line: the data set cannot be got (and how to get it), or nothing is there.
    """
    try:
        p = _data_path(value, what)
    except Invalid as exc:
        raise InputError(f"{what}: {exc.detail}", field=what) from None
    if not p.exists():
        raise InputError(f"{what}: {shorten(value)}: no such file or folder ({p})", field=what)
    return p


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
        At ``path``: ``$CLOTHSIM_DATA`` names no folder, a data set is missing and cannot
        be got (one line saying how to get it), the file is missing, or it is a directory.
    """
    if "\x00" in value:
        raise Invalid(path, "a file name cannot contain a NUL character")
    if value.startswith(DATA_PREFIX):
        p = _data_path(value, path)
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
        A directory, a FIFO or device, a missing file, or an unknown name (with the
        closest built-in names).
    """
    name = str(path_or_name)
    try:
        p = Path(path_or_name).expanduser()
        is_file, is_dir = p.is_file(), p.is_dir()
    except (OSError, ValueError) as exc:
        raise SceneError(shorten(name), "", f"cannot use this path: {exc}") from None
    if is_dir:
        raise SceneError(shorten(name, 200), "", "is a directory, not a scene file")
    if is_file:
        return p
    what = special_file(p)  # /dev/null, a FIFO: there, but not a file a scene is read from
    if what:
        raise SceneError(shorten(name, 200), "", f"is {what}, not a scene file")
    builtin = builtin_scene_path(name)
    if "/" not in name and "\\" not in name and builtin.is_file():
        return builtin
    if p.suffix in (".toml", ".json") or os.sep in name:
        raise SceneError(shorten(name, 200), "", "file not found")
    names = list(list_builtin_scenes())
    raise SceneError(shorten(name), "", "no such scene file or built-in scene"
                     + suggest(name, names).replace("expected one of", "built-in scenes:"))


__all__ = ["data_root", "data_dir", "resolve_path", "resolve_data_path", "list_builtin_scenes",
           "builtin_scene_path", "builtin_scene_text", "parse_toml", "find_scene",
           "DEFAULT_SCENE", "DATA_PREFIX", "BUILTIN_DIR"]
