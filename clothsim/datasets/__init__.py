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

import hashlib
import logging
import os
import shutil
import tarfile
import tempfile
from contextlib import contextmanager
from dataclasses import dataclass
from importlib import resources
from io import BytesIO
from pathlib import Path

from ..errors import ClothsimError, InputError
from .registry import DATASETS, JACOBSON_COMMIT, Dataset

log = logging.getLogger(__name__)

#: File in an unpacked bundled data set: the SHA-256 of the archive it came from.
STAMP = ".clothsim-archive"
TIMEOUT = 30.0  # seconds without an answer before a download gives up


class DataUnavailableError(ClothsimError):
    """A data set is missing and could not be got; the message (one line) says how to get it."""


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
    """The data set ``name``; an unknown name is an :class:`InputError` listing the known."""
    if name not in DATASETS:
        raise InputError(f"data set {name!r} is unknown; known: {', '.join(DATASETS)}",
                         field="name")
    return DATASETS[name]


def cache_dir() -> Path:
    """The cache folder: ``$CLOTHSIM_CACHE``, else ``pooch.os_cache("clothsim")``."""
    env = os.environ.get("CLOTHSIM_CACHE")
    if env:
        return Path(env).expanduser()
    import pooch

    return Path(pooch.os_cache("clothsim"))


def offline() -> bool:
    """``$CLOTHSIM_OFFLINE`` is set (and not ``0``): never download on first use."""
    return os.environ.get("CLOTHSIM_OFFLINE", "0") not in ("", "0")


def user_folder(name: str) -> Path | None:
    """The data set's folder under ``$CLOTHSIM_DATA``, or None (unset, or not there).

    ``$CLOTHSIM_DATA/<name>/`` when it is a folder; for ``jacobson-a8`` also
    ``$CLOTHSIM_DATA`` itself when it holds one of the assignment's files or any scene of
    its format (a ``.json`` file: a student's own checkout may have others).
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


def _missing(ds: Dataset, folder: Path) -> int:
    return sum(not (folder / f).is_file() for f in ds.files)


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
    missing = _missing(ds, folder)
    if ds.bundled and (missing or _stamp(folder) != _archive_digest(ds)):
        return Status(name, folder, True, "package", missing)
    return Status(name, folder, missing == 0, "cache", missing)


def how_to_get(name: str) -> str:
    """One line saying how to get the data set ``name``."""
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
        return _unpack(ds, folder)
    if _missing(ds, folder) == 0:
        return folder
    if download is False or (download is None and offline()):
        note = " (CLOTHSIM_OFFLINE is set)" if download is None else ""
        raise DataUnavailableError(f"data set {name} is not downloaded{note}; "
                                   + how_to_get(name))
    return _download(ds, folder, None)


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
    return _unpack(ds, folder) if ds.bundled else _download(ds, folder, base_url)


def file_sha256(path) -> str:
    """SHA-256 (hex) of a file's bytes."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


# ------------------------------------------------------------------ bundled: unpack
def _archive_bytes(ds: Dataset) -> bytes:
    return resources.files(__name__).joinpath(ds.archive).read_bytes()


def _archive_digest(ds: Dataset) -> str:
    return hashlib.sha256(_archive_bytes(ds)).hexdigest()


def _stamp(folder: Path) -> str | None:
    try:
        return (folder / STAMP).read_text(encoding="ascii").strip()
    except (OSError, UnicodeDecodeError):
        return None


def _unpack(ds: Dataset, folder: Path) -> Path:
    """Unpack a bundled data set into ``folder`` (whole or not at all); a folder already
    unpacked from the same archive is kept."""
    data = _archive_bytes(ds)
    digest = hashlib.sha256(data).hexdigest()
    if _stamp(folder) == digest and _missing(ds, folder) == 0:
        return folder
    folder.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{folder.name}.", suffix=".tmp", dir=folder.parent))
    try:
        with tarfile.open(fileobj=BytesIO(data), mode="r:xz") as tar:
            names = {m.name for m in tar.getmembers() if m.isfile()}
            if names != set(ds.files):
                raise DataUnavailableError(f"{ds.archive} in the clothsim package does not "
                                           f"hold the files of {ds.name}; reinstall clothsim")
            if hasattr(tarfile, "data_filter"):
                tar.extractall(tmp, filter="data")
            else:  # pragma: no cover - Python < 3.11.4; the names were checked above
                tar.extractall(tmp)  # noqa: S202
        bad = [f for f, h in ds.files.items() if file_sha256(tmp / f) != h]
        if bad:
            raise DataUnavailableError(f"{ds.archive} in the clothsim package is damaged "
                                       f"({bad[0]} fails its SHA-256); reinstall clothsim")
        if ds.readme:
            (tmp / "README.md").write_bytes(
                resources.files(__name__).joinpath(ds.readme).read_bytes())
        (tmp / STAMP).write_text(digest + "\n", encoding="ascii")
        tmp.chmod(0o755)
        if folder.exists():  # an older unpacking: move it aside, then replace it
            old = Path(tempfile.mkdtemp(prefix=f".{folder.name}.", suffix=".old",
                                        dir=folder.parent))
            os.replace(folder, old / "x")
            shutil.rmtree(old, ignore_errors=True)
        try:
            os.rename(tmp, folder)
        except OSError:
            if _stamp(folder) != digest:  # not another process's identical unpacking
                raise
        log.info("unpacked %s into %s", ds.name, folder)
        return folder
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


# ------------------------------------------------------------------ third party: download
@contextmanager
def _quiet_pooch():
    """pooch logs every download on stderr by itself; clothsim logs its own lines."""
    import pooch

    logger = pooch.get_logger()
    level = logger.level
    logger.setLevel(logging.WARNING)
    try:
        yield pooch
    finally:
        logger.setLevel(level)


def _reason(exc: BaseException) -> str:
    """A short cause of a failed download (requests' own messages run to several lines)."""
    import requests

    if isinstance(exc, requests.HTTPError) and exc.response is not None:
        return f"HTTP {exc.response.status_code}"
    if isinstance(exc, requests.Timeout):
        return f"no answer within {TIMEOUT:g} s"
    if isinstance(exc, requests.ConnectionError):
        return "no connection"
    if isinstance(exc, ValueError) and "hash" in str(exc).lower():
        return "the file does not match its pinned SHA-256"
    return " ".join(str(exc).split())[:200] or type(exc).__name__


def _remove_if_empty(folder: Path) -> None:
    try:
        folder.rmdir()
    except OSError:
        pass


def _download(ds: Dataset, folder: Path, base_url: str | None) -> Path:
    url = base_url or ds.url
    url = url if url.endswith("/") else url + "/"
    with _quiet_pooch() as pooch:
        repo = pooch.create(path=folder, base_url=url, retry_if_failed=1,
                            registry={f: f"sha256:{h}" for f, h in ds.files.items()})
        downloader = pooch.HTTPDownloader(progressbar=False, timeout=TIMEOUT)
        for f in ds.files:
            try:
                repo.fetch(f, downloader=downloader)
            except (OSError, ValueError) as exc:  # requests' errors are OSErrors
                log.debug("download of %s failed", f, exc_info=True)
                _remove_if_empty(folder)
                raise DataUnavailableError(
                    f"data set {ds.name}: could not download {f} from {url} "
                    f"({_reason(exc)}); {how_to_get(ds.name)}") from None
    log.info("%s: %d files in %s", ds.name, len(ds.files), folder)
    return folder


__all__ = ["DATASETS", "Dataset", "DataUnavailableError", "Status", "JACOBSON_COMMIT",
           "cache_dir", "dataset", "fetch", "file_sha256", "how_to_get", "locate", "offline",
           "status", "user_folder", "STAMP"]
