"""The data clothsim's scenes, tests and lessons read: what it is, where it is, how to get it.

Two data sets (:mod:`clothsim.datasets.registry`; README.md beside this file says where
each comes from):

``liu13-port``
    The paper authors' own C++ code run on its default scene: the port checker's reference.
    It ships inside the package (``liu13-port.tar.xz``, 1 MB, the exact text files) and is
    unpacked on first use, each file checked against its SHA-256.
``jacobson-a8``
    A. Jacobson's mass-spring assignment scenes (third party, not redistributed). They are
    downloaded on first use with pooch from the assignment's public repository at a pinned
    commit, each file checked against its SHA-256, or read from a folder the user names.

Where a data set is found, first match first:

1. ``$CLOTHSIM_DATA``, a folder the user names: ``$CLOTHSIM_DATA/<name>/``, or for
   ``jacobson-a8`` the folder itself when it holds the assignment's files (a checkout's
   ``data/`` folder). Files there are used as they are (a student's edits included).
2. The cache folder ``$CLOTHSIM_CACHE``, else the user's cache folder
   (``pooch.os_cache("clothsim")``: ``~/.cache/clothsim`` on Linux): ``<cache>/<name>/``.

:func:`locate` finds a data set, unpacking or downloading it when it is missing (no
download when ``$CLOTHSIM_OFFLINE`` is set to anything but ``0``: the error then says how to
get it); :func:`fetch` gets it on purpose; :func:`status` reports without changing anything.
The command line is ``clothsim data list | fetch | path``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from ..errors import InputError
from .download import fetch_files
from .registry import DATASETS, JACOBSON_COMMIT, Dataset
from .store import (
    STAMP,
    DataUnavailableError,
    archive_digest,
    changed,
    file_sha256,
    missing_count,
    stamp,
    unpack,
)


@dataclass(frozen=True)
class Status:
    """Where a data set is and whether it is ready, without changing anything.

    Attributes
    ----------
    name : str
    folder : Path
        Where it is, or where :func:`locate` would put it.
    present : bool
        Every file is there (a user's folder: the folder is).
    origin : str
        ``"CLOTHSIM_DATA"`` (a folder the user named), ``"cache"``, or ``"package"`` (bundled,
        not unpacked yet: unpacked on first use, no download).
    missing : int
        Files of the registry not in ``folder`` (0 for a user's folder).
    """

    name: str
    folder: Path
    present: bool
    origin: str
    missing: int


def dataset(name: str) -> Dataset:
    """The data set ``name``.

    Parameters
    ----------
    name : str
        A key of :data:`~clothsim.datasets.registry.DATASETS`.

    Returns
    -------
    Dataset

    Raises
    ------
    InputError
        An unknown name (the message lists the known ones).
    """
    if name not in DATASETS:
        raise InputError(f"data set {name!r} is unknown; known: {', '.join(DATASETS)}",
                         field="name")
    return DATASETS[name]


def cache_dir() -> Path:
    """The cache folder the data sets are unpacked and downloaded into.

    Returns
    -------
    Path
        ``$CLOTHSIM_CACHE``, else ``pooch.os_cache("clothsim")`` (``~/.cache/clothsim`` on
        Linux). It may not exist yet.
    """
    env = os.environ.get("CLOTHSIM_CACHE")
    if env:
        return Path(env).expanduser()
    import pooch

    return Path(pooch.os_cache("clothsim"))


def offline() -> bool:
    """Is downloading on first use forbidden?

    Returns
    -------
    bool
        ``$CLOTHSIM_OFFLINE`` is set to anything but empty or ``0``.
    """
    return os.environ.get("CLOTHSIM_OFFLINE", "0") not in ("", "0")


def user_folder(name: str) -> Path | None:
    """The data set's folder under ``$CLOTHSIM_DATA``, if the user named one.

    Parameters
    ----------
    name : str
        A key of :data:`~clothsim.datasets.registry.DATASETS`.

    Returns
    -------
    Path or None
        ``$CLOTHSIM_DATA/<name>/`` when it is a folder; for ``jacobson-a8`` also
        ``$CLOTHSIM_DATA`` itself when it holds one of the assignment's files or any scene
        of its format (a ``.json`` file: a student's own checkout may have others). None
        when unset or not there.
    """
    env = os.environ.get("CLOTHSIM_DATA")
    if not env:
        return None
    root = Path(env).expanduser()
    ds = dataset(name)
    if (root / name).is_dir():
        return root / name
    if ds.loose_folder and root.is_dir() and (any((root / f).is_file() for f in ds.files)
                                              or any(root.glob("*.json"))):
        return root
    return None


def status(name: str) -> Status:
    """Where the data set ``name`` is and whether it is ready (nothing is changed).

    Parameters
    ----------
    name : str
        A key of :data:`~clothsim.datasets.registry.DATASETS`.

    Returns
    -------
    Status
    """
    ds = dataset(name)
    user = user_folder(name)
    if user is not None:
        return Status(name, user, True, "CLOTHSIM_DATA", 0)
    folder = cache_dir() / name
    missing = missing_count(ds, folder)
    if ds.bundled and (missing or stamp(folder) != archive_digest(ds)):
        return Status(name, folder, True, "package", missing)
    return Status(name, folder, missing == 0, "cache", missing)


def how_to_get(name: str) -> str:
    """How to get the data set ``name``, for error messages.

    Parameters
    ----------
    name : str
        A key of :data:`~clothsim.datasets.registry.DATASETS`.

    Returns
    -------
    str
        One line: the ``clothsim data fetch`` command, and ``CLOTHSIM_DATA`` for a copy.
    """
    ds = dataset(name)
    if ds.bundled:
        return f"it ships with clothsim: `clothsim data fetch {name}` unpacks it"
    return (f"run `clothsim data fetch {name}` with a network connection, or set "
            f"CLOTHSIM_DATA to a folder holding a copy (a checkout's data/ folder)")


def locate(name: str, *, download: bool | None = None) -> Path:
    """The folder of the data set ``name``, unpacked or downloaded first when missing.

    Parameters
    ----------
    name : str
        A key of :data:`~clothsim.datasets.registry.DATASETS`.
    download : bool, optional
        Download a missing third-party data set (default: unless :func:`offline`).

    Returns
    -------
    Path
        The folder (``$CLOTHSIM_DATA``'s, else the cache's).

    Raises
    ------
    DataUnavailableError
        Missing and not got (offline, no network, a file that fails its SHA-256); the
        message is one line saying how to get it.
    """
    ds = dataset(name)
    user = user_folder(name)
    if user is not None:
        return user
    folder = cache_dir() / name
    if ds.bundled:
        return _unpack(ds, folder, False)
    if missing_count(ds, folder) == 0:
        return folder
    if download is False or (download is None and offline()):
        note = " (CLOTHSIM_OFFLINE is set)" if download is None else ""
        raise DataUnavailableError(f"data set {name} is not downloaded{note}; "
                                   + how_to_get(name))
    return fetch_files(ds, folder, None, how_to_get(name))


def fetch(name: str, *, into=None, base_url: str | None = None) -> Path:
    """Get the data set ``name`` now: unpack it, or download and check every file.

    Files already there and matching their SHA-256 are kept; a file that does not match
    is downloaded again.

    Parameters
    ----------
    name : str
        A key of :data:`~clothsim.datasets.registry.DATASETS`.
    into : path, optional
        Put it in ``<into>/<name>/`` (then ``CLOTHSIM_DATA=<into>`` finds it) instead of the
        cache folder.
    base_url : str, optional
        Download from this mirror (``<base_url>/<file>``) instead of the data set's own URL;
        the files are still checked against their SHA-256.

    Returns
    -------
    Path
        The folder.

    Raises
    ------
    DataUnavailableError
        A download failed or a file failed its SHA-256 (nothing partial is left).
    """
    ds = dataset(name)
    folder = (Path(into).expanduser() if into is not None else cache_dir()) / name
    if ds.bundled:
        return _unpack(ds, folder, True)
    return fetch_files(ds, folder, base_url, how_to_get(name))


def _unpack(ds: Dataset, folder: Path, verify: bool) -> Path:
    try:
        return unpack(ds, folder, verify=verify)
    except OSError as exc:  # a read-only or full cache folder: say where and what to do
        raise DataUnavailableError(
            f"data set {ds.name}: cannot unpack it into {folder} "
            f"({exc.strerror or exc}); set CLOTHSIM_CACHE to a writable folder") from None


def changed_files(name: str, folder) -> list[str]:
    """Files of the data set ``name`` missing from ``folder`` or not matching their SHA-256.

    Parameters
    ----------
    name : str
        A key of :data:`~clothsim.datasets.registry.DATASETS`.
    folder : path
        Where the data set is (e.g. :attr:`Status.folder`).

    Returns
    -------
    list of str
        Their names, in the registry's order (empty: all there and unchanged).
    """
    return changed(dataset(name), Path(folder))


__all__ = ["DATASETS", "Dataset", "DataUnavailableError", "Status", "JACOBSON_COMMIT",
           "STAMP", "cache_dir", "changed_files", "dataset", "fetch", "file_sha256",
           "how_to_get", "locate", "offline", "status", "user_folder"]
