"""Every option of every command has help, and help never breaks inside a solver name."""

import argparse

from clothsim.cli import build_parser


def subcommands():
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return sub.choices


def test_every_option_has_help():
    missing = [f"{name} {'/'.join(a.option_strings) or a.dest}"
               for name, p in subcommands().items() for a in p._actions
               if not isinstance(a, argparse._HelpAction) and not (a.help or "").strip()]
    assert not missing, missing


def test_help_does_not_break_hyphenated_names():
    for name, p in subcommands().items():
        text = p.format_help()
        assert "local-\n" not in text and "float-\n" not in text, name
