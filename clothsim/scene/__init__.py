"""Scene files: parse, validate, then build a model, its effects and a simulation.

A scene is a TOML file (read with :mod:`tomllib`) with the tables ``[scene]``, ``[cloth]``,
``[springs]``, ``[solver]`` and an array ``[[effects]]``; every key is documented in
``docs/scenes.md`` (generated from :func:`schema_markdown`). The whole file is validated
before anything is built; every problem is a :class:`SceneError`, whose message is one
line::

    <file>: <key.path>: <what is wrong>

The package, along the way a scene file goes:

- :mod:`.schema`: every key, its type, default, unit and meaning, as data;
- :mod:`.checks`, :mod:`.validate`, :mod:`.effects`: validation, in one place;
- :mod:`.files`: the data root (``data:`` paths), built-in scenes, TOML parsing;
- :mod:`.tables`: plain-text model files (vertices, triangles, spring tables, masses);
- :mod:`.build`: the :class:`Scene` and what it builds.

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
import dataclasses
import re

from ..errors import SceneError
from ..io.assignment import scene_dict
from .build import Scene
from .checks import shorten
from .files import (
    BUILTIN_DIR,
    DATA_PREFIX,
    DEFAULT_SCENE,
    builtin_scene_path,
    builtin_scene_text,
    data_dir,
    data_root,
    find_scene,
    list_builtin_scenes,
    parse_toml,
)
from .overrides import apply_overrides, blame, moved_indices
from .schema import SHAPES, schema_markdown


def load_scene(path_or_name, overrides=()) -> Scene:
    """Load and validate a scene file (``.toml``), an assignment ``.json``, or a built-in.

    Parameters
    ----------
    path_or_name : str or Path
        A file path, or the name of a built-in scene (see :func:`list_builtin_scenes`).
    overrides : sequence of str, optional
        ``KEY=VALUE`` changes applied before validation (``--set``;
        :mod:`clothsim.scene.overrides`), e.g. ``["springs.structural=50"]``.

    Returns
    -------
    Scene

    Raises
    ------
    SceneError
        One line, ``"<file>: <key.path>: <what is wrong>"``.
    """
    p = find_scene(path_or_name)
    source = str(p)
    if p.suffix.lower() == ".json":
        d = scene_dict(p)
        # the scene name comes from the file name, which the user may have spelled freely
        name = re.sub(r"[^\w.-]+", "-", d["scene"]["name"], flags=re.ASCII)
        d["scene"]["name"] = name.lstrip(".")[:100] or "scene"
        return _validated(d, source, p.parent, overrides)
    try:
        text = p.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise SceneError(source, "", f"cannot read: not UTF-8 text (byte {exc.start})") from None
    except OSError as exc:
        raise SceneError(source, "", f"cannot read: {shorten(str(exc), 200)}") from None
    return _validated(parse_toml(text, source), source, p.parent, overrides)


def _validated(doc: dict, source: str, base_dir, overrides) -> Scene:
    before = copy.deepcopy(doc) if overrides else None
    done = apply_overrides(doc, overrides)
    base = None
    if done:  # the file as it is: to tell the errors its --set changes cause
        try:
            base = Scene.from_dict(copy.deepcopy(before), source=source, base_dir=base_dir)
        except SceneError:
            base = None
    try:
        scene = Scene.from_dict(doc, source=source, base_dir=base_dir)
    except SceneError as exc:
        raise blame(exc, done, lambda: base is not None) from None
    if not done:
        return scene
    if (moved := moved_indices(before, scene.data, done)) is not None:
        raise moved
    return dataclasses.replace(scene, overrides=tuple(done), base=base)


__all__ = ["Scene", "SceneError", "load_scene", "list_builtin_scenes", "builtin_scene_path",
           "builtin_scene_text", "parse_toml", "data_dir", "data_root", "schema_markdown",
           "DEFAULT_SCENE", "SHAPES", "DATA_PREFIX", "BUILTIN_DIR"]
