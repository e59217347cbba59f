"""The lock on an output folder: ``<folder>/.clothsim.lock``, never followed, removed at the end.

:class:`FolderLock` takes an exclusive :func:`fcntl.flock` on the lock file, which every kind
of output (run, export, accuracy study, conformance set) takes alike, and writes its holder's
id and kind into it. The lock file is opened without following a symbolic link
(``O_NOFOLLOW``) and must be a regular file with one name: a ``.clothsim.lock`` that is a
link, a folder, a FIFO or a hard link to another file is refused by name and nothing is
written through it (else a planted link would make clothsim write its pid into the file it
points to). The holder removes the file when it releases the lock, so a finished folder
holds no lock file; a process that opened the old file before the removal sees that the
name now points elsewhere and opens it again.
"""

from __future__ import annotations

import errno
import fcntl
import os
import stat
from pathlib import Path

from ..errors import InputError

LOCK_NAME = ".clothsim.lock"
#: what each kind of output is called in a refusal ("another clothsim run (pid …)")
HOLDERS = {"run": "clothsim run", "export": "clothsim export",
           "accuracy": "clothsim accuracy study",
           "paper": "clothsim accuracy --paper report", "conformance": "clothsim conformance set",
           "coursework": "clothsim coursework profile"}
_ATTEMPTS = 5  # opens of a lock file removed by its holder meanwhile, before giving up


class FolderLock:
    """Exclusive lock on an output folder, held from :meth:`acquire` to :meth:`release`.

    Parameters
    ----------
    folder : Path
        The output folder (exists).
    kind : {"run", "export", "accuracy", "conformance", "coursework"}, default "run"
        What this process writes there (written into the lock file beside its id, so that
        a process refused the lock is told what holds it).

    Raises
    ------
    InputError
        From :meth:`acquire`, when another process holds the lock (names the folder, what
        that process writes and its id), or when ``.clothsim.lock`` is not a regular file
        of its own (a symbolic or hard link, a folder, a FIFO: named, nothing written).
    """

    def __init__(self, folder, kind: str = "run"):
        if kind not in HOLDERS:
            raise ValueError(f"kind: must be one of {', '.join(HOLDERS)}, got {kind!r}")
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
        for _ in range(_ATTEMPTS):
            fd = self._open()
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                words = os.pread(fd, 64, 0).decode("ascii", "replace").split()
                os.close(fd)
                holder = words[0] if words else "unknown"
                what = HOLDERS.get(words[1] if len(words) > 1 else "run", HOLDERS["run"])
                raise InputError(f"{self.path.parent}: another {what} (pid {holder}) is "
                                 "writing into this folder; wait for it or choose another "
                                 "--out") from None
            if self._still_named(fd):
                self._fd = fd
                try:
                    os.ftruncate(fd, 0)
                    os.pwrite(fd, f"{os.getpid()} {self.kind}\n".encode("ascii"), 0)
                except OSError:  # a full disk: the lock file goes with the error
                    self.release()
                    raise
                return self
            os.close(fd)  # its holder removed it after we opened it: open the new one
        raise InputError(f"{self.path}: removed and created again {_ATTEMPTS} times while "
                         "locking; another clothsim process is busy with this folder")

    def _open(self) -> int:
        """The lock file opened read-write (created if missing), never through a link."""
        try:
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_NONBLOCK,
                         0o644)
        except OSError as exc:
            if exc.errno in (errno.ELOOP, errno.EMLINK):
                raise InputError(f"{self.path}: is a symbolic link; clothsim never writes "
                                 "through one (remove it, or choose another --out)") from None
            if exc.errno == errno.EISDIR:
                raise InputError(f"{self.path}: is a folder, not clothsim's lock file "
                                 "(remove it, or choose another --out)") from None
            raise
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode) or st.st_nlink != 1:
            os.close(fd)
            what = ("another name of a file (a hard link)" if stat.S_ISREG(st.st_mode)
                    else "not a regular file")
            raise InputError(f"{self.path}: is {what}; clothsim never writes into it "
                             "(remove it, or choose another --out)")
        return fd

    def _still_named(self, fd: int) -> bool:
        """Whether the lock file's name still points at the file ``fd`` has open."""
        try:
            st = os.lstat(self.path)
        except FileNotFoundError:
            return False
        mine = os.fstat(fd)
        return (st.st_dev, st.st_ino) == (mine.st_dev, mine.st_ino)

    def release(self) -> None:
        """Remove the lock file and release the lock (no-op when not held)."""
        if self._fd is not None:
            try:
                if self._still_named(self._fd):
                    self.path.unlink()  # removed while held: nobody takes a stale one
            except OSError:
                pass  # a read-only or vanished folder: the lock file stays, harmless
            os.close(self._fd)  # closing the descriptor releases the flock
            self._fd = None

    def __enter__(self) -> FolderLock:
        return self.acquire()

    def __exit__(self, *exc) -> None:
        self.release()


__all__ = ["FolderLock", "LOCK_NAME", "HOLDERS"]
