"""What every command shares: the program name, one-line errors, the parser class."""

from __future__ import annotations

import argparse
import logging
import sys

PROG = "clothsim"
log = logging.getLogger("clothsim.cli")


class _Parser(argparse.ArgumentParser):
    """argparse, but a usage error is one line and exit status 2 (no usage dump)."""

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
                        "solver.iterations=20, effects[1].strength=2 (a TOML value; "
                        "repeatable; validated like the file)")
