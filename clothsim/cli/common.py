"""What every command shares: the program name, one-line errors, the parser class."""

from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path

PROG = "clothsim"
log = logging.getLogger("clothsim.cli")


class _Formatter(argparse.HelpFormatter):
    """Help lines that never break inside a hyphenated name ("local-global")."""

    def _split_lines(self, text, width):
        import textwrap

        return textwrap.wrap(" ".join(text.split()), width, break_on_hyphens=False)


class _Parser(argparse.ArgumentParser):
    """argparse, but a usage error is one line and exit status 2 (no usage dump)."""

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("formatter_class", _Formatter)
        super().__init__(*args, **kwargs)

    def error(self, message):
        raise _UsageError(message)


class _UsageError(Exception):
    pass


def _one_line(text: str) -> str:
    return " ".join(str(text).split())


def _fail(message: str, code: int) -> int:
    print(f"{PROG}: error: {_one_line(message)}", file=sys.stderr)
    return code


def add_set_option(parser) -> None:
    """``--set KEY=VALUE`` (repeatable): change a scene key before validation.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        A command that loads a scene.
    """
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="change a scene key, e.g. springs.structural=50, "
                        "solver.iterations=20, 'effects[0].acceleration=[0, -1.62, 0]' (a TOML "
                        "value; repeatable; validated like the file)")


def count(low: int, high: int):
    """An argparse ``type``: an integer flag within ``[low, high]`` (the scene schema's limits).

    Parameters
    ----------
    low, high : int
        Inclusive bounds.

    Returns
    -------
    callable
        ``str -> int``; raises :class:`argparse.ArgumentTypeError` with ``must be an integer
        between low and high, got …`` (argparse names the flag).
    """
    from ..scene.schema import sci

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            value = None
        if value is None or not low <= value <= high:
            raise argparse.ArgumentTypeError(
                f"must be an integer between {low} and {sci(high)}, got {text[:40]!r}")
        return value

    parse.__name__ = "count"
    return parse


def os_error_line(exc: OSError, where=None) -> str:
    """One line for an I/O error: the path and the cause, no Python type name.

    Parameters
    ----------
    exc : OSError
    where : path, optional
        The folder or file the command was writing (named first, e.g. the run folder).

    Returns
    -------
    str
        E.g. ``"out/run: cannot write: No space left on device (out/run/frame_000003.vtu)"``.
    """
    cause = exc.strerror or " ".join(str(exc).split()) or type(exc).__name__
    name = exc.filename if exc.filename is not None else None
    if where is None:
        return f"{name}: {cause}" if name is not None else cause
    detail = f" ({name})" if name is not None and str(name) != str(where) else ""
    return f"{where}: {cause}{detail}"


def interrupted(exc: BaseException, detail: str | None = None, out=None) -> int:
    """Say that a command was interrupted, in one line; exit 128 + the signal's number.

    Parameters
    ----------
    exc : KeyboardInterrupt
        Ctrl-C, or a :class:`clothsim.interrupts.SignalInterrupt` (SIGTERM, SIGHUP).
    detail : str, optional
        What was left, e.g. where the complete frames are.
    out : path, optional
        The output folder: its status is reported (:func:`folder_note`).

    Returns
    -------
    int
        130 for SIGINT, 143 for SIGTERM, 129 for SIGHUP.
    """
    import signal

    signum = getattr(exc, "signum", signal.SIGINT)
    if detail is None and out is not None:
        detail = folder_note(out)
    line = f"interrupted ({signal.Signals(signum).name})" + (f"; {detail}" if detail else "")
    return _fail(line, 128 + signum)


def folder_note(out) -> str | None:
    """What an output folder holds after its writer stopped, and how to complete it.

    Parameters
    ----------
    out : path
        The folder.

    Returns
    -------
    str or None
        E.g. ``"DIR is marked interrupted (its manifest.json says so): write it again with
        clothsim export"``; None when it is not clothsim's.
    """
    from ..io.folders import REMEDY, folder_state

    try:
        state = folder_state(out)
    except OSError:
        return None
    if state.kind is None:
        return None
    if state.status == "complete":
        return f"{out} still holds the earlier complete output, unchanged"
    return (f"{out} is marked {state.status} (its {state.record} says {state.word!r}): "
            f"{REMEDY[state.kind]}")


def stopped(exc: BaseException, out) -> int:
    """One line for a writing command stopped by a signal or an I/O error: the cause, the
    file and what the folder holds now.

    Parameters
    ----------
    exc : KeyboardInterrupt or OSError
    out : path
        The command's output folder.

    Returns
    -------
    int
        The exit status: 128 + the signal's number, or 1.
    """
    if isinstance(exc, KeyboardInterrupt):
        return interrupted(exc, out=out)
    log.debug("I/O error", exc_info=True)
    note = folder_note(out)
    return _fail(os_error_line(exc, out) + (f"; {note}" if note else ""), 1)


def _where(source) -> str:
    """A scene source as an absolute path where it names a file (run.json keeps it as given)."""
    p = Path(str(source))
    return str(p.resolve()) if p.is_file() else str(source)


def other_output(out: Path, scene, record: str = "run.json") -> str | None:
    """Why ``out`` (a default folder, out/<name>) holds another scene's output, if it does.

    Parameters
    ----------
    out : Path
        The default output folder.
    scene : Scene
        The scene about to write there.
    record : {"run.json", "manifest.json"}
        The output's own record (a run's, an export's); both keep the scene's ``source``
        and resolved ``scene``.

    Returns
    -------
    str or None
        The one-line refusal naming both sources and the ways on, or None when ``out``
        holds nothing of another scene.
    """
    import json

    from ..io.folders import folder_record

    previous = folder_record(out, "run" if record == "run.json" else "export")
    if previous is None or not previous.get("source"):
        return None
    mine = json.loads(json.dumps(scene.to_dict(), default=str))
    theirs = previous.get("scene")
    same_source = _where(previous.get("source")) == _where(scene.source)
    if same_source and theirs == mine:
        return None
    what = "another version of this scene" if same_source else "another scene"
    kind = "a run" if record == "run.json" else "an export"
    return (f"{out} holds {kind} of {what}: {previous.get('source')} there, {scene.source} now "
            f"(same scene.name); run with --out DIR to keep both, --force to replace it"
            + (", or --resume to continue it" if what.startswith("another version")
               and record == "run.json" else ""))
