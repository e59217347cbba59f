"""docs/ports.md's worked example runs as written (its data: arguments name the shipped
data set liu13-port)."""

import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from clothsim.cli import main

from .conftest import REPO

SCENE = REPO / "examples" / "ports" / "liu13-default.toml"


def commands(programs=(".venv/bin/clothsim ",)) -> list[list[str]]:
    """The page's command lines of ``programs``, in order, without the program (the
    ``.venv/bin/python`` lines keep their script's path) and without a trailing comment."""
    return [argv for argv, _ in _lines(programs)]


def exits(programs) -> list[int]:
    """The exit status the page says each of those commands ends with: 0, or N where its
    line ends with the comment ``# exits with N`` (an UNDECIDED or FAIL check shown on
    purpose)."""
    return [code for _, code in _lines(programs)]


def _lines(programs):
    lines = (REPO / "docs" / "ports.md").read_text().splitlines()
    return [(shlex.split(t, comments=True)[1:],
             int(m.group(1)) if (m := re.search(r"# exits with (\d+)", t)) else 0)
            for t in lines if t.startswith(programs)]


def run(argv: list[str]) -> int:
    """One command of the page: clothsim in this process, an example script in another
    (``.venv/bin/python examples/...``, run from the repository's copy)."""
    if argv[0].startswith("examples/"):
        return subprocess.run([sys.executable, str(REPO / argv[0]), *argv[1:]]).returncode
    return main(argv)


def test_the_docs_show_every_step():
    names = [c[0] for c in commands()]
    for cmd in ("diff-model", "export", "compare", "check"):
        assert cmd in names


def test_worked_example_runs(tmp_path, monkeypatch, capsys):
    if not SCENE.is_file():
        pytest.skip(f"{SCENE.relative_to(REPO)} is not in this checkout (it builds the port's "
                    f"model from its files)")
    monkeypatch.chdir(tmp_path)
    programs = (".venv/bin/clothsim ", ".venv/bin/python examples/")
    assert 1 in exits(programs)   # the sphere's %g port: UNDECIDED at its landing
    for argv, code in zip(commands(programs), exits(programs), strict=True):
        argv = [str(SCENE) if a == "examples/ports/liu13-default.toml" else a for a in argv]
        assert run(argv) == code, (argv, capsys.readouterr())
    out = capsys.readouterr().out
    assert "IDENTICAL" in out and "PASS: 60 steps agree" in out
    assert Path(tmp_path / "out" / "liu13" / "deviation.png").is_file()


class _HelperScene:
    """Stands in for examples/ports/liu13-default.toml until scenes take models from files."""

    name = "liu13-default"
    frames = 60
    source = "liu13-default.toml"

    def build_model(self):
        return None

    def build_simulation(self, model):
        from .conftest import liu13_simulation

        return liu13_simulation()


@pytest.mark.slow   # a variant; the suite's fast run keeps the main case
def test_worked_example_runs_with_the_helper_model(tmp_path, monkeypatch, capsys):
    import clothsim.scene

    real = clothsim.scene.load_scene
    monkeypatch.setattr(clothsim.scene, "load_scene", lambda s, overrides=(): _HelperScene()
                        if str(s).endswith("liu13-default.toml") else real(s, overrides))
    monkeypatch.chdir(tmp_path)
    programs = (".venv/bin/clothsim ", ".venv/bin/python examples/")
    for argv, code in zip(commands(programs), exits(programs), strict=True):
        assert run(argv) == code, (argv, capsys.readouterr())
    out = capsys.readouterr().out
    assert "IDENTICAL" in out and "PASS: 60 steps agree" in out
    assert "after dropping 6 attachment columns" in out
    assert (tmp_path / "out" / "liu13" / "deviation.png").is_file()
