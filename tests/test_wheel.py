"""A wheel works: clothsim built as a wheel (not editable), installed into a fresh
environment and run from an unrelated folder, finds its built-in scenes and its shipped data
as package data, with nothing beside it.

Offline and quick: the wheel is built without build isolation from a copy of the source
tree, the fresh environment has no pip and borrows the dependencies of the environment
running the tests (a ``.pth`` file naming its site-packages, after its own), and the wheel
is installed there with ``--no-deps``. Slow (about half a minute of CPU): CI runs it,
``make test`` does not.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import sysconfig
import zipfile
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
IGNORE = shutil.ignore_patterns(".venv", ".git", "_build", "auto_examples", "out", "build",
                                "*.egg-info", "__pycache__", ".pytest_cache", ".hypothesis",
                                "accuracy-out", "conformance", "coursework")


def run(cmd, cwd, env, ok=True) -> subprocess.CompletedProcess:
    done = subprocess.run([str(c) for c in cmd], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=900)
    if ok:
        assert done.returncode == 0, f"{cmd}: exit {done.returncode}\n{done.stderr[-3000:]}"
    return done


@pytest.fixture(scope="module")
def installed(tmp_path_factory) -> dict:
    tmp = tmp_path_factory.mktemp("wheel")
    src = tmp / "src"
    shutil.copytree(REPO, src, ignore=IGNORE, symlinks=True)
    env = {k: v for k, v in os.environ.items()
           if not k.startswith(("PYTHON", "CLOTHSIM", "VIRTUAL_ENV", "PIP_"))}
    run([sys.executable, "-m", "pip", "wheel", "--no-build-isolation", "--no-deps",
         "--no-index", "-q", "-w", tmp / "dist", src], tmp, env)
    wheel = next((tmp / "dist").glob("clothsim-*.whl"))
    venv = tmp / "venv"
    run([sys.executable, "-m", "venv", "--without-pip", venv], tmp, env)
    python = venv / "bin" / "python"
    site = Path(run([python, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                    tmp, env).stdout.strip())
    here = {sysconfig.get_paths()["purelib"], sysconfig.get_paths()["platlib"]}
    (site / "zz-borrowed-dependencies.pth").write_text("\n".join(sorted(here)) + "\n")
    run([sys.executable, "-m", "pip", "--python", python, "install", "--no-deps",
         "--no-index", "-q", wheel], tmp, env)
    elsewhere = tmp / "elsewhere"  # an unrelated folder: no repository, nothing beside it
    elsewhere.mkdir()
    env.update(PATH=f"{venv / 'bin'}{os.pathsep}{env.get('PATH', '')}", MPLBACKEND="Agg",
               CLOTHSIM_CACHE=str(tmp / "cache"), CLOTHSIM_OFFLINE="1")
    return {"wheel": wheel, "venv": venv, "cwd": elsewhere, "env": env}


def clothsim(installed, *args, ok=True) -> subprocess.CompletedProcess:
    return run([installed["venv"] / "bin" / "clothsim", *args], installed["cwd"],
               installed["env"], ok)


@pytest.mark.slow
def test_the_wheel_holds_the_scenes_and_the_shipped_data(installed):
    names = set(zipfile.ZipFile(installed["wheel"]).namelist())
    assert {"clothsim/scenes/drop-on-square.toml", "clothsim/scenes/jacobson-net.toml",
            "clothsim/datasets/liu13-port.tar.xz", "clothsim/datasets/liu13-port.md",
            "clothsim/datasets/README.md"} <= names
    assert not any(n.startswith(("tests/", "examples/", "docs/")) for n in names)
    where = run([installed["venv"] / "bin" / "python", "-c",
                 "import clothsim; print(clothsim.__file__)"],
                installed["cwd"], installed["env"]).stdout.strip()
    assert Path(where).is_relative_to(installed["venv"])  # the wheel's copy, not the source


@pytest.mark.slow
def test_the_installed_command_runs_from_an_unrelated_folder(installed):
    listed = clothsim(installed, "scenes").stdout
    assert "drop-on-square" in listed and "jacobson-net" in listed
    out = clothsim(installed, "run", "drop-on-square").stdout
    assert out.startswith("drop-on-square: ") and "frames written to out/drop-on-square" in out
    run_json = json.loads((installed["cwd"] / "out" / "drop-on-square" / "run.json").read_text())
    assert run_json["status"] == "completed"
    clothsim(installed, "conformance", "--profile", "coursework")
    readme = (installed["cwd"] / "coursework" / "README.md").read_text()
    assert "clothsim check CASE/scene.toml OUT/" in readme
    case = installed["cwd"] / "coursework" / "net"
    assert "PASS" in clothsim(installed, "check", case / "scene.toml", case).stdout
    # the port reference shipped in the package, checked with the repository's scene file
    shutil.copy(REPO / "examples" / "ports" / "liu13-default.toml", installed["cwd"])
    checked = clothsim(installed, "check", "liu13-default.toml",
                       "data:liu13-port/default-scene").stdout
    assert checked.startswith("PASS: 60 steps agree")
    folder = Path(clothsim(installed, "data", "path", "liu13-port").stdout.strip())
    assert folder.is_relative_to(installed["env"]["CLOTHSIM_CACHE"])
    # the third-party files, offline: one line on how to get them
    failed = clothsim(installed, "validate", "jacobson-net", ok=False)
    assert failed.returncode == 2 and failed.stderr.count("\n") == 1
    assert "`clothsim data fetch jacobson-a8`" in failed.stderr
