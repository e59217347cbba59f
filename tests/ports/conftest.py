"""Fixtures of the port-checking tests: the paper authors' default scene, from its own files.

``liu13_simulation()`` is THE one place that rebuilds the port's model in Python; it is to be
replaced by ``load_scene("examples/ports/liu13-default.toml")`` once scenes can take a model
from files.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

import clothsim as cs
from clothsim.springs import Springs

REPO = Path(__file__).resolve().parents[2]
H = 0.0333


def data_root() -> Path | None:
    """The shared data folder ($CLOTHSIM_DATA, ../shared/data, /work/shared/data), or None."""
    for root in (os.environ.get("CLOTHSIM_DATA"), REPO.parent / "shared" / "data",
                 "/work/shared/data"):
        if root and (Path(root) / "liu13-port" / "default-scene" / "x0.txt").is_file():
            return Path(root)
    return None


def port_dir() -> Path:
    root = data_root()
    if root is None:
        pytest.skip("the liu13-port data is absent (set CLOTHSIM_DATA or provide ../shared/data)")
    return root / "liu13-port" / "default-scene"


def liu13_simulation(*, attachments: bool = True, iterations: int = 10) -> cs.Simulation:
    """The port's default scene as a clothsim Simulation (replaced by the scene file at merge)."""
    d = port_dir()
    x0 = np.loadtxt(d / "x0.txt").reshape(-1, 3)
    tri = np.loadtxt(d / "triangles.txt", dtype=np.int64)
    rows = np.loadtxt(d / "springs.txt", comments="#")
    springs = rows[rows[:, 0] == 1]
    attach = rows[rows[:, 0] == 0]
    mesh = cs.mesh.from_cells(x0, [("triangle", tri)])
    sp = Springs(springs[:, 1:3].astype(np.int64), springs[:, 3], springs[:, 4],
                 np.zeros(len(springs), np.int8))
    model = cs.Model.build(mesh, sp, total_mass=1.0)
    effects = [cs.Gravity((0.0, -100.0, 0.0)), cs.Damping("rigid", 0.001)]
    if attachments:
        effects.insert(0, cs.Pin(attach[:, 1].astype(np.int64), method="penalty",
                                 stiffness=float(attach[0, 3])))
    return cs.Simulation(model, h=H, effects=effects, iterations=iterations)


def liu13_trajectory() -> tuple[np.ndarray, np.ndarray]:
    """The port's positions and velocities, shape (61, 441, 3) each."""
    d = port_dir()
    x = np.loadtxt(d / "positions.txt")
    v = np.loadtxt(d / "velocities.txt")
    return x.reshape(len(x), -1, 3), v.reshape(len(v), -1, 3)
