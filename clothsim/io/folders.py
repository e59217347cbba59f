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
``force`` is given. :class:`FolderLock` (:mod:`clothsim.io.lock`) is an exclusive
:func:`fcntl.flock` on ``<folder>/.clothsim.lock``, taken by every kind alike.

Each record also holds the folder's status (:data:`STATUSES`), written by
:meth:`clothsim.io.outfolder.OutputFolder.mark` and read by :func:`folder_state`;
:func:`require_complete` is what readers call before they read a folder.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path

from ..errors import InputError
from .lock import LOCK_NAME, FolderLock

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
         "paper": "a clothsim accuracy --paper report",
         "conformance": "a clothsim conformance set",
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
    return _line(path, 0)


def _line(path: Path, index: int) -> str | None:
    """Line ``index`` (0-based, at most 200 bytes) of a text file (None when missing,
    unreadable or shorter)."""
    try:
        if not path.is_file():
            return None
        with open(path, "rb") as fh:
            for _ in range(index):
                fh.readline(200)
            line = fh.readline(200)
    except OSError:
        return None
    return line.decode("utf-8", "replace").rstrip("\r\n") if line else None


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


def _linked_folder(p: Path) -> Path | None:
    """The first symbolic link to a folder inside ``p`` (its real subfolders searched too).

    A link to a file is harmless (clothsim replaces a file by renaming a new one onto its
    name, which replaces the link, never its target); a linked folder (a run's ``state``, a
    conformance case, an export's ``iterates``) would take clothsim's files into its target.
    """
    for top, folders, _files in os.walk(p):
        for name in sorted(folders):
            if os.path.islink(os.path.join(top, name)):
                return Path(top) / name
    return None


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
        ``folder`` (or the nearest existing path above it) is a file, or it holds files
        and no clothsim record of the same kind: the message names the folder and the first
        foreign file.
    """
    if kind not in KINDS:
        raise ValueError(f"kind: must be one of {', '.join(KINDS)}, got {kind!r}")
    p = Path(folder)
    if str(folder) == "":
        raise InputError("--out: empty; name a folder")
    if p.exists() and not p.is_dir():
        raise InputError(f"{p}: is not a folder (--out names a folder)")
    for link in (a for a in (p, *p.parents) if a.is_symlink() and not a.exists()):
        raise InputError(f"{p}: {'' if link == p else f'{link} '}is a symbolic link to "
                         f"{os.readlink(link)}, which does not exist; clothsim makes no folder "
                         f"through a dangling link (create its target, or choose another "
                         f"--out)")
    above = next((a for a in p.parents if a.exists()), None)
    if above is not None and not above.is_dir():  # --out file.txt/sub
        raise InputError(f"{p}: cannot be a folder: {above} is a file, not a folder")
    if not p.exists():
        return p
    try:
        if (link := _linked_folder(p)) is not None:  # its files would land in the target
            raise InputError(f"{link}: is a symbolic link to a folder ({os.readlink(link)}); "
                             f"clothsim never writes through one (remove it, or choose "
                             f"another --out)")
        found = None if force else folder_kind(p)
        if force or found == kind:
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


STATUSES = ("writing", "complete", "interrupted", "failed")
"""A folder's status, kept in its record: ``writing`` from before its first file until its
writer ends, then ``complete``, ``interrupted`` (a signal) or ``failed`` (an error)."""
RECORDS = {"run": RUN_RECORD, "export": EXPORT_RECORD, "accuracy": ACCURACY_RECORD,
           "paper": PAPER_RECORD, "conformance": CONFORMANCE_RECORD,
           "coursework": CONFORMANCE_RECORD}
#: the word a kind's record stores for a status where it is not the status itself:
#: run.json and accuracy.json said "running" and "completed" before the statuses were one
#: set, and scripts read them
WORDS = {"run": {"writing": "running", "complete": "completed"},
         "accuracy": {"writing": "running"}}
#: the line a conformance README carries below its heading while it is not complete
STATUS_PREFIX = "status: "
#: how to complete a folder of each kind that is not complete
REMEDY = {"run": "finish it with clothsim run --resume, or run it again",
           "export": "write it again with clothsim export",
           "accuracy": "run the study again with clothsim accuracy",
           "paper": "run it again with clothsim accuracy --paper --out",
           "conformance": "write the set again with clothsim conformance",
           "coursework": "write the set again with clothsim conformance --profile coursework"}
_MEANING = {"writing": "still being written, or its writer was killed",
            "interrupted": "its writer was interrupted", "failed": "its writer failed"}


def folder_record(folder, kind: str) -> dict | None:
    """The JSON record of ``kind`` in ``folder`` (``run.json``, ``manifest.json``,
    ``accuracy.json``), whatever it says.

    Parameters
    ----------
    folder : str or Path
    kind : {"run", "export", "accuracy"}

    Returns
    -------
    dict or None
        None when it is missing, unreadable or not a JSON object.
    """
    return _record(Path(folder) / RECORDS[kind])


def status_word(kind: str, status: str) -> str:
    """The word ``kind``'s record stores for ``status`` (e.g. run.json's ``"completed"``).

    Parameters
    ----------
    kind : {"run", "export", "accuracy", "conformance", "coursework"}
    status : {"writing", "complete", "interrupted", "failed"}

    Returns
    -------
    str
    """
    if status not in STATUSES:
        raise ValueError(f"status: must be one of {', '.join(STATUSES)}, got {status!r}")
    return WORDS.get(kind, {}).get(status, status)


@dataclass(frozen=True)
class FolderState:
    """What an output folder's record says about it (:func:`folder_state`).

    Attributes
    ----------
    kind : str or None
        As :func:`folder_kind`; None for a folder clothsim did not write.
    status : {"writing", "complete", "interrupted", "failed"} or None
        None when ``kind`` is None.
    word : str or None
        The record's own word for it (``"running"`` in run.json for ``"writing"``).
    error : str or None
        The one-line error an interrupted or failed writer recorded.
    """

    kind: str | None
    status: str | None = None
    word: str | None = None
    error: str | None = None

    @property
    def record(self) -> str | None:
        """The record's file name, e.g. ``manifest.json`` (None for a foreign folder)."""
        return RECORDS.get(self.kind)


def folder_state(folder) -> FolderState:
    """The kind and status of an output folder, read from its record.

    An export manifest without a status (written before statuses) is complete when it lists
    its files; a conformance README without a ``status:`` line below its heading is
    complete.

    Parameters
    ----------
    folder : str or Path

    Returns
    -------
    FolderState
    """
    p = Path(folder)
    kind = folder_kind(p)
    if kind is None:
        return FolderState(None)
    if kind in ("conformance", "coursework"):
        line = _line(p / CONFORMANCE_RECORD, 2) or ""
        word, _, error = line.removeprefix(STATUS_PREFIX).partition(" ")
        word = word if line.startswith(STATUS_PREFIX) else "complete"
        error = error.strip("() ") or None
    else:
        record = _record(p / RECORDS[kind]) or {}
        legacy = "complete" if kind == "export" and "files" in record else "writing"
        word = str(record.get("status", legacy))
        error = record.get("error") if isinstance(record.get("error"), str) else None
    words = {status_word(kind, s): s for s in STATUSES}
    return FolderState(kind, words.get(word, "writing"), word, error)


def require_complete(path) -> None:
    """Refuse to read an output folder of clothsim (or a file directly in one) whose status
    is not ``complete``: what it holds may be half of one output and half of an earlier.

    Parameters
    ----------
    path : str or Path
        A folder, or a file in a folder, about to be read (a folder clothsim did not write
        passes).

    Returns
    -------
    None

    Raises
    ------
    InputError
        Naming the folder, its record's status and how to complete it, in one line.
    """
    p = Path(path)
    folder = p if p.is_dir() else p.parent
    try:
        state = folder_state(folder)
    except OSError:
        return  # the reader names the unreadable file itself
    if state.kind is None or state.status == "complete":
        return
    why = _MEANING[state.status] + (f": {state.error}" if state.error else "")
    raise InputError(f"{folder}: {KINDS[state.kind]} whose {state.record} says "
                     f"{state.word!r}, not complete ({why}); refusing to read it: "
                     f"{REMEDY[state.kind]}")


__all__ = ["FolderLock", "FolderState", "LOCK_NAME", "STATUSES", "claim_folder",
           "folder_kind", "folder_record", "folder_state", "require_complete", "status_word"]
