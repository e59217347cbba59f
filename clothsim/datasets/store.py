"""Unpacking a bundled data set, and checking files against their pinned SHA-256."""

from __future__ import annotations

import hashlib
import logging
import os
import shutil
import tarfile
import tempfile
from importlib import resources
from io import BytesIO
from pathlib import Path

from ..errors import ClothsimError
from .registry import Dataset

log = logging.getLogger("clothsim.datasets")

#: File in an unpacked bundled data set: the SHA-256 of the archive it came from.
STAMP = ".clothsim-archive"


class DataUnavailableError(ClothsimError):
    """A data set is missing and could not be got; the message (one line) says how to get it."""


def missing_count(ds: Dataset, folder: Path) -> int:
    """How many files of a data set a folder lacks.

    Parameters
    ----------
    ds : Dataset
    folder : Path

    Returns
    -------
    int
        Files of ``ds`` not in ``folder`` (contents not checked).
    """
    return sum(not (folder / f).is_file() for f in ds.files)


def changed(ds: Dataset, folder: Path) -> list[str]:
    """The files of a data set a folder lacks, or holds with other contents.

    Parameters
    ----------
    ds : Dataset
    folder : Path

    Returns
    -------
    list of str
        Files of ``ds`` missing from ``folder`` or not matching their pinned SHA-256.
    """
    return [f for f, h in ds.files.items()
            if not (folder / f).is_file() or file_sha256(folder / f) != h]


def file_sha256(path) -> str:
    """The SHA-256 of a file.

    Parameters
    ----------
    path : path-like

    Returns
    -------
    str
        Its bytes' SHA-256, 64 hex digits.
    """
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def _archive_bytes(ds: Dataset) -> bytes:
    return resources.files(__package__).joinpath(ds.archive).read_bytes()


def archive_digest(ds: Dataset) -> str:
    """The SHA-256 of a bundled data set's archive in the package.

    Parameters
    ----------
    ds : Dataset
        A bundled data set.

    Returns
    -------
    str
        64 hex digits (what an unpacking's :data:`STAMP` file holds).
    """
    return hashlib.sha256(_archive_bytes(ds)).hexdigest()


def stamp(folder: Path) -> str | None:
    """The archive digest an unpacked folder was made from.

    Parameters
    ----------
    folder : Path

    Returns
    -------
    str or None
        The content of its :data:`STAMP` file; None when missing or unreadable.
    """
    try:
        return (folder / STAMP).read_text(encoding="ascii").strip()
    except (OSError, UnicodeDecodeError):
        return None


def _kept(ds: Dataset, folder: Path, digest: str, verify: bool) -> bool:
    """``folder`` is a complete unpacking of the archive ``digest`` (``verify``: every file
    still matching its SHA-256)."""
    return (stamp(folder) == digest and missing_count(ds, folder) == 0
            and not (verify and changed(ds, folder)))


def unpack(ds: Dataset, folder: Path, verify: bool = False) -> Path:
    """Unpack a bundled data set into ``folder``, whole or not at all.

    The archive is unpacked into a temporary folder beside ``folder``, every file checked
    against its SHA-256, then renamed onto ``folder``: a reader never sees half of it, and
    two processes unpacking at once both end with the same complete folder.

    Parameters
    ----------
    ds : Dataset
        A bundled data set.
    folder : Path
        Where it goes.
    verify : bool
        Keep an existing unpacking of the same archive only if every file still matches
        its SHA-256 (otherwise: if every file is there).

    Returns
    -------
    Path
        ``folder``.

    Raises
    ------
    DataUnavailableError
        The package's archive is damaged (reinstall clothsim).
    OSError
        The folder cannot be written (nothing is left behind).
    """
    data = _archive_bytes(ds)
    digest = hashlib.sha256(data).hexdigest()
    if _kept(ds, folder, digest, verify):
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
        bad = changed(ds, tmp)
        if bad:
            raise DataUnavailableError(f"{ds.archive} in the clothsim package is damaged "
                                       f"({bad[0]} fails its SHA-256); reinstall clothsim")
        if ds.readme:
            (tmp / "README.md").write_bytes(
                resources.files(__package__).joinpath(ds.readme).read_bytes())
        (tmp / STAMP).write_text(digest + "\n", encoding="ascii")
        tmp.chmod(0o755)
        if _kept(ds, folder, digest, verify):
            return folder  # another process unpacked it meanwhile
        if folder.exists():  # an older or damaged unpacking: move it aside, then replace it
            old = Path(tempfile.mkdtemp(prefix=f".{folder.name}.", suffix=".old",
                                        dir=folder.parent))
            os.replace(folder, old / "x")
            shutil.rmtree(old, ignore_errors=True)
        try:
            os.rename(tmp, folder)
        except OSError:
            if stamp(folder) != digest:  # not another process's identical unpacking
                raise
        log.info("unpacked %s into %s", ds.name, folder)
        return folder
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
