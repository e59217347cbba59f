"""The command line's polish: --version, -v after the command, warnings aggregated into one
line per kind, no progress bars when stderr is not a terminal."""

import os
import tomllib
import warnings
from pathlib import Path

import clothsim
from clothsim import cli
from clothsim.errors import ConvergenceWarning

ROOT = Path(__file__).resolve().parents[1]


def test_version_prints_the_package_version(capsys):
    assert cli.main(["--version"]) == 0
    assert capsys.readouterr().out.strip() == f"clothsim {clothsim.__version__}"


def test_version_comes_from_one_place():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert "version" not in project and "version" in project["dynamic"]


def test_verbose_is_accepted_after_the_command(monkeypatch, capsys):
    args = cli.build_parser().parse_args(["-v", "validate", "hanging", "-v"])
    assert args.verbose + args.verbose_after == 2
    assert cli.main(["validate", "hanging", "-vv"]) == 0

    def chatty(args):
        cli.log.info("some detail")
        return 0

    monkeypatch.setitem(cli.COMMANDS, "scenes", chatty)
    capsys.readouterr()
    assert cli.main(["scenes"]) == 0
    assert "some detail" not in capsys.readouterr().err
    assert cli.main(["scenes", "-v"]) == 0
    assert "INFO: some detail" in capsys.readouterr().err


def test_warnings_are_counted_one_line_per_kind(monkeypatch, capsys):
    def noisy(args):
        for k in range(40):
            warnings.warn(f"local-global: relative residual {k}.5e-3 after {k} iterations",
                          ConvergenceWarning, stacklevel=1)
        warnings.warn("something else", UserWarning, stacklevel=1)
        print("done")
        return 0

    monkeypatch.setitem(cli.COMMANDS, "scenes", noisy)
    assert cli.main(["scenes"]) == 0
    out, err = capsys.readouterr()
    assert out == "done\n"
    lines = err.strip().splitlines()
    assert len(lines) == 2, err
    assert "ConvergenceWarning (40 times): local-global: relative residual 0.5e-3" in lines[0]
    assert "UserWarning (once): something else" in lines[1]
    assert ".py:" not in err  # no file paths


def test_a_file_left_to_the_collector_adds_no_line(monkeypatch, capsys):
    # a SIGTERM that lands inside an import leaves the module's open .pyc to the collector:
    # its ResourceWarning once made an interrupted command print a second line (CI, stop 38)
    def leaky(args):
        warnings.warn("unclosed file <_io.BufferedReader name='gui.pyc'>", ResourceWarning,
                      stacklevel=1)
        warnings.warn("something else", UserWarning, stacklevel=1)
        return 0

    monkeypatch.setitem(cli.COMMANDS, "scenes", leaky)
    assert cli.main(["scenes"]) == 0
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and "UserWarning (once): something else" in lines[0], lines


def test_progress_bars_are_off_when_stderr_is_not_a_terminal(monkeypatch, capsys):
    monkeypatch.delenv("TQDM_DISABLE", raising=False)
    seen = {}

    def look(args):
        seen["env"] = os.environ.get("TQDM_DISABLE")
        return 0

    monkeypatch.setitem(cli.COMMANDS, "scenes", look)
    assert cli.main(["scenes"]) == 0  # capsys: stderr is not a terminal
    assert seen["env"] == "1"
    assert "TQDM_DISABLE" not in os.environ  # restored


def test_citation_cites_the_paper_and_the_software():
    text = (ROOT / "CITATION.cff").read_text()
    assert "10.1145/2508363.2508406" in text and "Fast Simulation of Mass-Spring Systems" in text
    assert f"version: {clothsim.__version__}" in text
