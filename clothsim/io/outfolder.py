"""One output folder from claiming it to its final status: :class:`OutputFolder`.

Every command that writes a folder (``run``, ``export``, ``accuracy``, ``conformance``) goes
through one :class:`OutputFolder` (a run through its subclass
:class:`clothsim.io.runfolder.RunFolder`):

1. it claims the folder (:func:`clothsim.io.folders.claim_folder`: missing, empty, or its
   own kind), creates it, locks it (:class:`clothsim.io.lock.FolderLock`) and claims it again
   now that no other clothsim process can write there;
2. :meth:`OutputFolder.mark` is the one way a folder's status is written: ``writing``
   before the first file, then ``complete``; leaving the ``with`` block by an exception
   marks it ``interrupted`` (a signal: :class:`KeyboardInterrupt`) or ``failed`` (any other
   error) with the error in one line;
3. :meth:`OutputFolder.file` writes a file atomically under its final name, and an I/O
   error names that file;
4. the lock file is removed when the block ends.

Readers (``compare``, ``check``, ``diff-model``, ``--resume``) honour the status through
:func:`clothsim.io.folders.require_complete` and :func:`clothsim.io.folders.folder_state`.
"""

from __future__ import annotations

import logging
from contextlib import contextmanager, nullcontext
from pathlib import Path

from .common import atomic_path
from .folders import (
    CONFORMANCE_HEADINGS,
    RECORDS,
    STATUS_PREFIX,
    claim_folder,
    folder_state,
    status_word,
)
from .lock import FolderLock
from .runfiles import read_json, write_json

log = logging.getLogger(__name__)
_HEADINGS = {kind: heading for heading, kind in CONFORMANCE_HEADINGS.items()}


def error_line(exc: BaseException) -> str:
    """An exception as the one line a record keeps: ``"Type: message"``.

    Parameters
    ----------
    exc : BaseException

    Returns
    -------
    str
        E.g. ``"SignalInterrupt: SIGTERM"``, ``"OSError: [Errno 28] No space left on
        device: 'out/frame_000003.vtu'"``.
    """
    return f"{type(exc).__name__}: {' '.join(str(exc).split())}".rstrip(": ")


class OutputFolder:
    """An output folder of ``kind``, claimed, locked and marked (see the module docstring).

    Parameters
    ----------
    path : str or Path
        The folder (created when missing).
    kind : {"run", "export", "accuracy", "conformance", "coursework"}
        What is written there.
    force : bool
        Write into a folder clothsim does not own (``--force``).
    guard : callable, optional
        A context-manager factory held around each status write (the runner passes
        :func:`clothsim.interrupts.signals_deferred`, so that a signal never cuts one).

    Attributes
    ----------
    path : Path
    kind : str
    status : str or None
        The last status marked (None before the first).
    earlier : FolderState
        What the folder held before this writer took it.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     with OutputFolder(tmp, "accuracy") as out:
    ...         out.mark("writing", {"clothsim": "x", "scene": "hanging"})
    ...         out.mark("complete")
    ...     folder_state(tmp).status
    'complete'
    """

    def __init__(self, path, kind: str, *, force: bool = False, guard=None):
        if kind not in RECORDS:
            raise ValueError(f"kind: must be one of {', '.join(RECORDS)}, got {kind!r}")
        self.path = Path(path)
        self.kind = kind
        self.force = force
        self.status: str | None = None
        self.guard = guard or nullcontext
        self._lock: FolderLock | None = None
        self._record: dict | None = None
        self._made: list[Path] = []

    def __enter__(self) -> OutputFolder:
        claim_folder(self.path, self.kind, force=self.force)  # before anything is written
        self._made = [p for p in (self.path, *self.path.parents) if not p.exists()]
        self.path.mkdir(parents=True, exist_ok=True)
        try:
            self._lock = FolderLock(self.path, self.kind).acquire()
            # again, now that no other clothsim process can write here
            claim_folder(self.path, self.kind, force=self.force)
            self.earlier = folder_state(self.path)
        except BaseException:
            if self._lock is not None:
                self._lock.release()
                self._lock = None
            self._remove_made()
            raise
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        try:
            if exc is not None and self.status == "writing":
                status = "interrupted" if isinstance(exc, KeyboardInterrupt) else "failed"
                log.info("%s in %s stopped: %s", self.kind, self.path, error_line(exc))
                try:
                    with self.guard():
                        self.end(status, error_line(exc))
                except OSError as again:  # e.g. still no space: the first error is the news
                    log.info("could not mark %s %s: %s", self.path, status,  # (and the CLI
                             again.strerror or again)                        # names the status)
        finally:
            if self._lock is not None:
                self._lock.release()
                self._lock = None
            if exc is not None and self.status is None:  # refused before its first file
                self._remove_made()

    def _remove_made(self) -> None:
        """Remove the folders :meth:`__enter__` created when they are still empty (a refused
        writer leaves the disk as it found it)."""
        for p in self._made:
            try:
                p.rmdir()
            except OSError:  # not empty (someone else's file), or gone: leave it
                return

    def end(self, status: str, error: str | None) -> None:
        """Mark the folder's final status (:meth:`mark`); a subclass first completes what
        its record describes (a run's trajectory.npz).

        Parameters
        ----------
        status : {"complete", "interrupted", "failed"}
        error : str or None
            One line, for interrupted and failed.
        """
        self.mark(status, error=error)

    def mark(self, status: str, record=None, *, error: str | None = None) -> None:
        """Write the folder's record with ``status``: the one way a status is written.

        Parameters
        ----------
        status : {"writing", "complete", "interrupted", "failed"}
        record : dict or str, optional
            The record's content: a dict for ``run.json``, ``manifest.json`` and
            ``accuracy.json`` (its ``status`` and ``error`` are set here), the README's text
            for a conformance set (written as is when complete; otherwise its heading and a
            ``status:`` line are written). Default: the record as last marked (or as on
            disk), with the new status.
        error : str, optional
            One line, recorded for ``interrupted`` and ``failed``.
        """
        word = status_word(self.kind, status)
        target = self.path / RECORDS[self.kind]
        if self.kind in _HEADINGS:
            text = record if status == "complete" and isinstance(record, str) else (
                f"{_HEADINGS[self.kind]}\n\n{STATUS_PREFIX}{word}"
                + (f" ({error})" if error else "") + "\n\nThis set is not complete: write "
                "it again (clothsim conformance) before checking a port against it.\n")
            with self.file(target.name) as tmp:
                tmp.write_text(text, encoding="utf-8")
        else:
            if record is not None:
                self._record = dict(record)
            elif self._record is None:
                self._record = read_json(target) or {}
            self._record["status"] = word
            if error is not None or status != "writing":
                self._record["error"] = error
            write_json(target, self._record)
        self.status = status

    @contextmanager
    def file(self, name: str):
        """Write ``name`` in the folder atomically: yields a temporary path, moved onto the
        name when the block succeeds (:func:`clothsim.io.common.atomic_path`); an I/O error
        names the file.

        Parameters
        ----------
        name : str
            File name (or a path relative to the folder).

        Yields
        ------
        Path
            The temporary file to write.
        """
        with atomic_path(self.path / name) as tmp:
            yield tmp


__all__ = ["OutputFolder", "error_line"]
