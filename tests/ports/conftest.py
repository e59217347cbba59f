"""Fixtures of the port-checking tests: the paper authors' default scene, from its own files.

The model comes from ``examples/ports/liu13-default.toml``, a scene built only from the
port's own files (no Python glue); the data is the data set liu13-port, shipped with
clothsim.
"""

from __future__ import annotations

import tempfile
import tomllib
from pathlib import Path

import numpy as np
import pytest

import clothsim as cs
from clothsim.scene import Scene

from ..data_sets import assignment_stand_in, liu13_dir

REPO = Path(__file__).resolve().parents[2]
SCENE = REPO / "examples" / "ports" / "liu13-default.toml"
H = 0.0333


@pytest.fixture(scope="module", autouse=True)
def _assignment_scenes(tmp_path_factory):
    """The port tests run the built-in jacobson-net and jacobson-flag scenes: without the
    assignment's own files (third party; the suite never downloads them), on stand-ins of
    their format (tests/data_sets.py), for each module of this folder."""
    with assignment_stand_in(tmp_path_factory.mktemp("assignment")):
        yield


def port_dir() -> Path:
    """The port's folder (the data set liu13-port, shipped with clothsim)."""
    return liu13_dir()


def liu13_simulation(*, attachments: bool = True, iterations: int = 10,
                     tmp_dir: Path | None = None) -> cs.Simulation:
    """The port's default scene as a clothsim Simulation, from the scene file.

    ``attachments=False`` leaves the two attachment rows out of the spring table (a model
    that differs from the port's: the model diff must name them).
    """
    d = port_dir()
    scene = cs.load_scene(SCENE)
    if not attachments:
        rows = [r for r in (d / "springs.txt").read_text().splitlines()
                if not r.startswith("0 ")]
        folder = Path(tempfile.mkdtemp()) if tmp_dir is None else tmp_dir
        (folder / "springs.txt").write_text("\n".join(rows) + "\n")
        data = tomllib.loads(SCENE.read_text(encoding="utf-8"))
        data["springs"]["table"] = str(folder / "springs.txt")
        scene = Scene.from_dict(data, source=str(SCENE), base_dir=SCENE.parent)
    return scene.build_simulation(iterations=iterations)


def liu13_trajectory() -> tuple[np.ndarray, np.ndarray]:
    """The port's positions and velocities, shape (61, 441, 3) each."""
    d = port_dir()
    x = np.loadtxt(d / "positions.txt")
    v = np.loadtxt(d / "velocities.txt")
    return x.reshape(len(x), -1, 3), v.reshape(len(v), -1, 3)
