"""Output folders: which ones clothsim may write into, and the lock on them.

clothsim writes only into a folder it owns (:func:`claim_folder`): a missing or empty one, or
one whose own record marks it as clothsim's output of the same kind: ``run.json`` with
``clothsim_run`` for a run (``clothsim run``), ``manifest.json`` with clothsim's ``layout``
for an export (``clothsim export``), ``accuracy.json`` with ``clothsim`` and ``scene`` for an
accuracy study (``clothsim accuracy``), ``paper.json`` with ``clothsim`` and ``paper`` for
its paper report (``clothsim accuracy --paper --out``), a ``README.md`` headed as a
conformance set's or a coursework profile's for those (``clothsim conformance``,
``--profile coursework``): one folder, one profile. Anything else is refused with an
:class:`~clothsim.errors.InputError` naming the folder and its first foreign file, unless
``force`` is given. :class:`FolderLock` is an exclusive :func:`fcntl.flock` on
``<folder>/.clothsim.lock``, taken by every kind alike.
"""

from __future__ import annotations

import fcntl
import json
import os
from pathlib import Path

from ..errors import InputError

LOCK_NAME = ".clothsim.lock"
RUN_RECORD = "run.json"
EXPORT_RECORD = "manifest.json"
ACCURACY_RECORD = "accuracy.json"
PAPER_RECORD = "paper.json"
CONFORMANCE_RECORD = "README.md"
#: first line of the README.md of each profile of ``clothsim conformance`` (the writers in
#: clothsim.ports begin their README with it, so ownership follows the heading they write)
CONFORMANCE_HEADING = "# clothsim conformance set"
COURSEWORK_HEADING = "# clothsim coursework profile"
CONFORMANCE_HEADINGS = {CONFORMANCE_HEADING: "conformance", COURSEWORK_HEADING: "coursework"}
KINDS = {"run": "a clothsim run", "export": "a clothsim export",
         "accuracy": "a clothsim accuracy study",
         "paper": "a clothsim accuracy --paper report", "conformance": "a clothsim conformance set",
         "coursework": "a clothsim coursework profile"}


def _record(path: Path) -> dict | None:
    """A JSON object read from ``path`` (None when missing, unreadable or not an object)."""
    try:
        if not path.is_file() or path.stat().st_size > 1 << 28:
            return None
        data = json.loads(path.read_bytes())
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) else None


def folder_kind(folder) -> str | None:
    """What clothsim's own record in ``folder`` says the folder is.

    Parameters
    ----------
    folder : str or Path

    Returns
    -------
    {"run", "export", "accuracy", "paper", "conformance", "coursework"} or None
        ``"run"`` when ``run.json`` is a clothsim run record, ``"export"`` when
        ``manifest.json`` is a clothsim export manifest, ``"accuracy"`` when
        ``accuracy.json`` is an accuracy study's record, ``"paper"`` when ``paper.json`` is
        a paper report's, ``"conformance"`` or
        ``"coursework"`` when ``README.md`` is that profile's, else None.
    """
    p = Path(folder)
    run = _record(p / RUN_RECORD)
    if run is not None and "clothsim_run" in run:
        return "run"
    manifest = _record(p / EXPORT_RECORD)
    if manifest is not None and str(manifest.get("layout", "")).startswith("x in R^{3n}"):
        return "export"
    study = _record(p / ACCURACY_RECORD)
    if study is not None and "clothsim" in study and "scene" in study:
        return "accuracy"
    paper = _record(p / PAPER_RECORD)
    if paper is not None and "clothsim" in paper and "paper" in paper:
        return "paper"
    return CONFORMANCE_HEADINGS.get(_first_line(p / CONFORMANCE_RECORD))


def _first_line(path: Path) -> str | None:
    """The first line of a small text file (None when missing or unreadable)."""
    try:
        if not path.is_file():
            return None
        with open(path, "rb") as fh:
            return fh.readline(200).decode("utf-8", "replace").rstrip("\r\n")
    except OSError:
        return None


def _foreign_entries(p: Path) -> list[str]:
    """Names in ``p`` clothsim did not write: all but the lock file and owned subfolders."""
    names = []
    for entry in sorted(p.iterdir(), key=lambda e: e.name):
        if entry.name == LOCK_NAME:
            continue
        if entry.is_dir() and not entry.is_symlink() and folder_kind(entry) is not None:
            continue  # e.g. out/<scene>/export beside a run
        names.append(entry.name)
    return names


def claim_folder(folder, kind: str, *, force: bool = False) -> Path:
    """Check that clothsim may write its ``kind`` of output into ``folder``.

    Parameters
    ----------
    folder : str or Path
        The output folder (need not exist).
    kind : {"run", "export", "accuracy", "paper", "conformance", "coursework"}
        What will be written.
    force : bool
        Write into a folder clothsim does not own anyway (``--force``).

    Returns
    -------
    Path
        ``folder``.

    Raises
    ------
    InputError
        ``folder`` is a file, or holds files and no clothsim record of the same kind: the
        message names the folder and the first foreign file.
    """
    if kind not in KINDS:
        raise ValueError(f"kind: must be one of {', '.join(KINDS)}, got {kind!r}")
    p = Path(folder)
    if str(folder) == "":
        raise InputError("--out: empty; name a folder")
    if p.exists() and not p.is_dir():
        raise InputError(f"{p}: is not a folder (--out names a folder)")
    if force or not p.exists():
        return p
    try:
        found = folder_kind(p)
        if found == kind:
            return p
        foreign = _foreign_entries(p)
    except OSError as exc:
        raise InputError(f"{p}: cannot read the folder ({exc.strerror or exc})") from None
    if not foreign:
        return p
    what = (f"holds {KINDS[found]}, not {KINDS[kind]}" if found
            else f"is not {KINDS[kind]}'s folder: it holds {foreign[0]!r}"
            + (f" and {len(foreign) - 1} more" if len(foreign) > 1 else ""))
    raise InputError(f"{p}: {what}; clothsim writes only into an empty folder or its own "
                     f"{kind} folder (choose another --out, or --force to write into it)")


class FolderLock:
    """Exclusive lock on an output folder, held from :meth:`acquire` to :meth:`release`.

    Parameters
    ----------
    folder : Path
        The output folder (exists).
    kind : {"run", "export", "accuracy", "paper", "conformance", "coursework"}, default "run"
        What this process writes there (written into the lock file beside its id, so that
        a process refused the lock is told what holds it).

    Raises
    ------
    InputError
        From :meth:`acquire`, when another process holds the lock: names the folder, what
        that process writes and its id.
    """

    def __init__(self, folder, kind: str = "run"):
        if kind not in KINDS:
            raise ValueError(f"kind: must be one of {', '.join(KINDS)}, got {kind!r}")
        self.path = Path(folder) / LOCK_NAME
        self.kind = kind
        self._fd: int | None = None

    def acquire(self) -> FolderLock:
        """Take the lock (without waiting) and write this process's id and kind into the
        lock file.

        Returns
        -------
        FolderLock
            ``self``.
        """
        fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            words = os.pread(fd, 64, 0).decode("ascii", "replace").split()
            os.close(fd)
            holder = words[0] if words else "unknown"
            what = KINDS.get(words[1], "a clothsim run") if len(words) > 1 else "a clothsim run"
            raise InputError(f"{self.path.parent}: another {what.split(' ', 1)[1]} (pid "
                             f"{holder}) is writing into this folder; wait for it or choose "
                             "another --out") from None
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()} {self.kind}\n".encode("ascii"), 0)
        self._fd = fd
        return self

    def release(self) -> None:
        """Release the lock (no-op when not held); the lock file stays."""
        if self._fd is not None:
            os.close(self._fd)  # closing the descriptor releases the flock
            self._fd = None

    def __enter__(self) -> FolderLock:
        return self.acquire()

    def __exit__(self, *exc) -> None:
        self.release()


__all__ = ["FolderLock", "LOCK_NAME", "claim_folder", "folder_kind"]
