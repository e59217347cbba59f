"""Helpers shared by clothsim's file readers and writers: meshio loaded on demand and kept
quiet, one-line messages, and atomic writes (temporary file, then :func:`os.replace`)."""

from __future__ import annotations

import os
import stat
from contextlib import contextmanager, redirect_stderr, redirect_stdout
from io import StringIO
from pathlib import Path

_SPECIAL = ((stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISCHR, "a character device"),
            (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))


def special_file(path) -> str | None:
    """What kind of special file ``path`` is, without opening it (opening a FIFO blocks).

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    str or None
        E.g. ``"a FIFO (named pipe)"``; None for a regular file, a folder, or a path that
        does not exist or cannot be examined.
    """
    try:
        mode = os.stat(path).st_mode
    except (OSError, ValueError):
        return None
    return next((what for test, what in _SPECIAL if test(mode)), None)


def refuse_special(path, *, inside: bool = False) -> None:
    """Raise when ``path`` (or, with ``inside``, an entry of the folder ``path``) is a
    FIFO, device or socket: clothsim reads only regular files and folders, and would wait
    forever on a FIFO.

    Parameters
    ----------
    path : str or path-like
    inside : bool
        Also examine the entries of ``path`` when it is a folder (not recursively).

    Returns
    -------
    None

    Raises
    ------
    InputError
        Naming the file and its kind, in one line.
    """
    from ..errors import InputError

    what = special_file(path)
    if what:
        raise InputError(f"{path}: is {what}, not a regular file; give a file or a folder")
    if inside and os.path.isdir(path):
        try:
            entries = sorted(os.scandir(path), key=lambda e: e.name)
        except OSError as exc:
            raise InputError(f"{path}: cannot list the folder ({exc.strerror})") from None
        for entry in entries:
            refuse_special(entry.path)


def file_stamp(path) -> tuple | None:
    """What changes whenever a file's content may have: a cache key for what was read from it.

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    tuple or None
        ``(st_mtime_ns, st_size, st_ctime_ns, st_ino, st_dev)`` (a rewrite in the same
        nanosecond, even one that keeps the size and restores the modification time, changes
        ``st_ctime_ns``; a file replaced by another changes the inode), or None when ``path``
        cannot be examined.
    """
    try:
        st = os.stat(path)
    except (OSError, ValueError):
        return None
    return st.st_mtime_ns, st.st_size, st.st_ctime_ns, st.st_ino, st.st_dev


def load_meshio():
    """The meshio module (imported here, so ``import clothsim`` stays light).

    Returns
    -------
    module
        The imported :mod:`meshio`.

    Raises
    ------
    ImportError
        When meshio is not installed.
    """
    try:
        import meshio
    except ImportError as exc:  # pragma: no cover - meshio is a declared dependency
        raise ImportError("clothsim needs meshio for mesh files: pip install meshio") from exc
    return meshio


def one_line(exc: BaseException) -> str:
    """An exception as one line of at most 200 characters.

    Parameters
    ----------
    exc : BaseException
        The exception to describe.

    Returns
    -------
    str
        Its message with whitespace collapsed (its type name when empty), cut to 200
        characters with a trailing ``...``.
    """
    text = " ".join(str(exc).split()) or type(exc).__name__
    return text if len(text) < 200 else text[:197] + "..."


class MeshioFailure(Exception):
    """meshio failed; the message is one line."""


def quietly(call, *args, **kwargs):
    """Run a meshio function without letting it print or exit.

    On a file it cannot parse, meshio 5.3.5 prints the reason and calls ``sys.exit(1)``;
    here the output is captured and any failure becomes :class:`MeshioFailure`.

    Parameters
    ----------
    call : callable
        The meshio function, e.g. ``meshio.read``.
    *args, **kwargs
        Passed to ``call``.

    Returns
    -------
    object
        What ``call`` returns.

    Raises
    ------
    MeshioFailure
        On any exception or ``SystemExit`` of ``call``; the message is one line holding
        what meshio printed and the exception text.
    """
    buffer = StringIO()
    try:
        with redirect_stdout(buffer), redirect_stderr(buffer):
            return call(*args, **kwargs)
    except (Exception, SystemExit) as exc:
        said = " ".join(buffer.getvalue().split())
        text = one_line(exc) if not isinstance(exc, SystemExit) else ""
        text = "; ".join(t for t in (said, text) if t) or type(exc).__name__
        raise MeshioFailure(text if len(text) < 300 else text[:297] + "...") from exc


@contextmanager
def atomic_path(path):
    """Yield a temporary name beside ``path``; on success move it onto ``path``
    (:func:`os.replace`, atomic), otherwise delete it. Readers never see a partial file, an
    :class:`OSError` names ``path`` (a full disk's names no file), and a link at the
    temporary name is removed first, never written through.

    Parameters
    ----------
    path : str or path-like
        The file to write in the end.

    Yields
    ------
    pathlib.Path
        The temporary file ``.<name>.<pid>.tmp<suffix>`` in the same folder (it keeps the
        suffix, so writers that choose a format by it choose the right one); write to it
        inside the ``with`` block.
    """
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp{path.suffix}")
    try:
        tmp.unlink(missing_ok=True)  # a link planted there is removed, never written through
        yield tmp
        os.replace(tmp, path)
    except OSError as exc:   # the error names the file the caller asked for (a full disk's
        if exc.filename is None or Path(os.fsdecode(exc.filename)) == tmp:  # has no name)
            exc.filename = str(path)
        raise
    finally:
        if tmp.exists():
            tmp.unlink()


def write_text(path, text: str) -> Path:
    """Write ``text`` to ``path`` atomically (:func:`atomic_path`): a crash leaves the
    previous complete file, never half of one.

    Parameters
    ----------
    path : str or path-like
        The file (overwritten).
    text : str
        Its content (UTF-8).

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    path = Path(path)
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return path


def is_number(token: str) -> bool:
    """Whether ``token`` parses as a float (the readers name the first token that does not).

    Parameters
    ----------
    token : str

    Returns
    -------
    bool
    """
    try:
        float(token)
    except ValueError:
        return False
    return True
