"""Helper processes of a large run: started from the very clothsim package this process
imported, talking pickles over their standard input and output.

A run hands work that holds the GIL for long (drawing its pictures,
:mod:`clothsim.pictures`; writing its frame files, :mod:`clothsim.io.frameproc`) to a
second process on a machine with two cores or more, so that it runs beside the solves
(which hold the GIL, one core) instead of between them. Each process runs in a session of
its own, so Ctrl-C at the terminal reaches the run alone (which then ends it), and ends by
itself when its input closes, which the end of the run, or of the run's process, does.
"""

from __future__ import annotations

import os
import pickle
import subprocess
import sys
from pathlib import Path

#: The program of a helper process: the clothsim package at argv[1] (whatever the other
#: process's sys.path would find first), then ``serve()`` of the module named by argv[2];
#: with argv[3] "light", the package's ``__init__`` is not run (nor its imports: only
#: those of the module served).
_BOOT = (
    "import importlib, importlib.util, os, sys\n"
    "pkg = sys.argv[1]\n"
    "spec = importlib.util.spec_from_file_location("
    "'clothsim', os.path.join(pkg, '__init__.py'), submodule_search_locations=[pkg])\n"
    "module = sys.modules['clothsim'] = importlib.util.module_from_spec(spec)\n"
    "if sys.argv[3] != 'light':\n"
    "    spec.loader.exec_module(module)\n"
    "importlib.import_module(sys.argv[2]).serve()\n")


def cores() -> int:
    """CPUs this process may run on.

    Returns
    -------
    int
    """
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not on Linux
        return os.cpu_count() or 1


def start_child(module: str, pass_fds: tuple[int, ...] = (), *,
                light: bool = False) -> subprocess.Popen:
    """Start ``module.serve()`` (e.g. ``"clothsim.pictures"``) in a new process of this
    Python and this clothsim, in a session of its own, its input and output piped.

    Parameters
    ----------
    module : str
        The module whose ``serve()`` runs.
    pass_fds : tuple of int
        File descriptors the process inherits (with the same numbers).
    light : bool
        Import only what ``module`` imports, not the whole package (``import clothsim``:
        0.7 s of CPU; the frame process's imports take 0.2 s).

    Returns
    -------
    subprocess.Popen

    Raises
    ------
    OSError
        When the process cannot start.
    """
    package = str(Path(__file__).resolve().parents[1])
    return subprocess.Popen([sys.executable, "-c", _BOOT, package, module,
                             "light" if light else "full"],
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                            start_new_session=True, pass_fds=pass_fds)


def answer_stream():
    """In a helper process: the binary stream of its answers (the original standard
    output), with anything printed from now on sent to standard error instead.

    Returns
    -------
    io.BufferedWriter
    """
    out = os.fdopen(os.dup(1), "wb")
    os.dup2(2, 1)
    return out


def send_answer(out, answer) -> None:
    """In a helper process: send ``answer`` (a result, or the error raised) as a pickle;
    an error that does not pickle is sent as a RuntimeError with its text.

    Parameters
    ----------
    out : binary stream
        :func:`answer_stream`.
    answer : object
    """
    try:
        data = pickle.dumps(answer, protocol=pickle.HIGHEST_PROTOCOL)
    except Exception:  # noqa: BLE001 - an error that does not pickle: its text
        data = pickle.dumps(RuntimeError(f"{type(answer).__name__}: {answer}"))
    out.write(data)
    out.flush()


def end_child(proc: subprocess.Popen | None) -> None:
    """Close a helper process's pipes (it ends) and wait for it (killed after 5 s).

    Parameters
    ----------
    proc : subprocess.Popen or None

    Returns
    -------
    None
    """
    if proc is None:
        return
    for stream in (proc.stdin, proc.stdout):
        try:
            stream.close()
        except OSError:   # pragma: no cover - a broken pipe on close
            pass
    try:
        proc.wait(timeout=5)
    except subprocess.TimeoutExpired:  # pragma: no cover - a hung process
        proc.kill()
        proc.wait()


__all__ = ["cores", "start_child", "answer_stream", "send_answer", "end_child"]
