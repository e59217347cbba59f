"""The files a scene reads besides itself, and their content hashes.

A resolved scene (:meth:`clothsim.scene.Scene.to_dict`) names every file it reads by its
absolute path: meshes, vertex and triangle files, vertex masses, spring tables, pin and
force files. :func:`input_hashes` finds them all, and an assignment ``.json`` scene's own
file, and hashes their contents: ``run.json`` records them at the start of a run and
``--resume`` refuses when one changed (:func:`changed_input`).
"""

from __future__ import annotations

import hashlib
from pathlib import Path

from ..errors import InputError
from ..io.resume import changed_input  # noqa: F401 - re-exported (its old home)


def _paths(value, out: set) -> None:
    if isinstance(value, dict):
        for v in value.values():
            _paths(v, out)
    elif isinstance(value, (list, tuple)):
        for v in value:
            _paths(v, out)
    elif isinstance(value, str) and value.startswith("/") and "\n" not in value:
        try:
            p = Path(value)
            if p.is_file():
                out.add(str(p))
        except (OSError, ValueError):
            pass


def input_files(scene) -> list[str]:
    """Every file ``scene`` reads, sorted.

    Parameters
    ----------
    scene : Scene
        A resolved scene (file names in it are absolute).

    Returns
    -------
    list of str
        Absolute paths: the files its keys name, and the scene file itself when it is an
        assignment ``.json`` (a TOML scene's content is in :meth:`Scene.to_dict` already).
    """
    found: set[str] = set()
    _paths(scene.to_dict(), found)
    source = Path(str(scene.source))
    if source.suffix.lower() == ".json" and source.is_file():
        found.add(str(source.resolve()))
    return sorted(found)


def file_sha256(path) -> str:
    """SHA-256 of a file's content (hex).

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    str
        64 hexadecimal digits.

    Raises
    ------
    InputError
        The file cannot be read: names it and the cause.
    """
    digest = hashlib.sha256()
    try:
        with open(path, "rb") as f:
            for chunk in iter(lambda: f.read(1 << 20), b""):
                digest.update(chunk)
    except OSError as exc:
        raise InputError(f"{path}: cannot read ({exc.strerror or exc})") from None
    return digest.hexdigest()


def input_hashes(scene) -> dict[str, str]:
    """``{path: sha256}`` of every file of :func:`input_files`.

    Parameters
    ----------
    scene : Scene

    Returns
    -------
    dict of str to str
    """
    return {p: file_sha256(p) for p in input_files(scene)}


__all__ = ["input_files", "input_hashes", "changed_input", "file_sha256"]
