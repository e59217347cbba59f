"""The data the tests read, wherever the checkout is: nothing outside the repository.

* ``liu13-port`` ships with clothsim: :func:`liu13_dir` unpacks it on first use.
* ``jacobson-a8`` is third party and never downloaded by the suite (``CLOTHSIM_OFFLINE``
  is set in conftest.py): :func:`assignment_dir` skips with one line when it is absent.
  Tests that only need *an* assignment-format scene write their own with
  :func:`write_assignment_scene` (the same reader, the same machinery).
"""

from __future__ import annotations

import os
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest

from clothsim import datasets
from clothsim.io.assignment import write_assignment

SKIP_ASSIGNMENT = ("the assignment's data (jacobson-a8, third party) is absent: "
                   "`clothsim data fetch jacobson-a8` or set CLOTHSIM_DATA")


def liu13_dir() -> Path:
    """The shipped ``liu13-port/default-scene`` folder (unpacked on first use)."""
    return datasets.locate("liu13-port") / "default-scene"


def have_assignment() -> bool:
    """Are the assignment's files here (``$CLOTHSIM_DATA`` or the cache)? Never downloads."""
    return datasets.status("jacobson-a8").present


def assignment_dir() -> Path:
    """The assignment's data folder, or skip the test with one line saying how to get it."""
    if not have_assignment():
        pytest.skip(SKIP_ASSIGNMENT)
    return datasets.locate("jacobson-a8", download=False)


@contextmanager
def assignment_stand_in(root: Path):
    """While in the block, without the assignment's own files, ``CLOTHSIM_DATA`` names
    ``root``, where stand-ins of their format are written as ``jacobson-a8/{net, flag,
    horizontal-chain, single-spring-horizontal}.json`` (:func:`write_assignment_scene`), so
    tests of the built-in ``jacobson-*`` scenes that need *an* assignment scene, not the
    assignment's own numbers, still run. With the files present, nothing changes.

    Yields
    ------
    bool
        True when the stand-ins are in use.
    """
    if have_assignment():
        yield False
        return
    folder = root / "jacobson-a8"
    for kind, name in (("net", "net"), ("flag", "flag"), ("chain", "horizontal-chain"),
                       ("spring", "single-spring-horizontal")):
        write_assignment_scene(folder, kind, name)
    old = os.environ.get("CLOTHSIM_DATA")
    os.environ["CLOTHSIM_DATA"] = str(root)
    try:
        yield True
    finally:
        if old is None:
            os.environ.pop("CLOTHSIM_DATA", None)
        else:
            os.environ["CLOTHSIM_DATA"] = old


def write_assignment_scene(folder: Path, kind: str = "net", name: str | None = None) -> Path:
    """A small scene in the assignment's format (JSON + OBJ), like its own files; the JSON.

    ``kind``: ``"spring"`` (one spring, one end pinned: single-spring-horizontal),
    ``"chain"`` (10 unit masses pinned at both ends: horizontal-chain), ``"net"`` (a
    5 × 5 net of strands with ``m`` and 1-based pins, like net) or ``"sheet"`` (a 5 × 4
    quad sheet without ``m``: libigl Voronoi masses, like flag and skirt) or ``"flag"`` (a
    12 × 24 quad sheet of 1.1 × 0.53 m held along its 12-vertex pole edge, k = 1e5 N/m on
    Voronoi masses of about 2e-3 kg: stiff like the assignment's flag, so that 50
    iterations do not converge a step). ``name``: the file name (default ``kind``).
    """
    stem = name or kind
    folder.mkdir(parents=True, exist_ok=True)
    if kind == "spring":
        x = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
        return write_assignment(folder / f"{stem}.json", x, [[0, 1]], k=500.0, m=1.0, b=[0])
    if kind == "chain":
        x = np.column_stack([np.linspace(0.0, 1.0, 10), np.zeros(10), np.zeros(10)])
        return write_assignment(folder / f"{stem}.json", x, [[a, a + 1] for a in range(9)],
                                k=500.0, m=1.0, b=[0, 9])
    if kind == "flag":
        i, j = np.meshgrid(np.arange(12), np.arange(24), indexing="ij")
        i, j = i.ravel(), j.ravel()
        x = np.column_stack([0.048 * j, -0.048 * i, np.zeros(len(i))])
        v = 24 * i + j
        faces = [[a, a + 24, a + 25, a + 1] for a in v[(i < 11) & (j < 23)]]
        return write_assignment(folder / f"{stem}.json", x, faces, k=1e5,
                                b=list(v[j == 0]))
    i, j = np.meshgrid(np.arange(5), np.arange(5 if kind == "net" else 4))
    i, j = i.ravel(), j.ravel()
    x = np.column_stack([0.25 * i, np.zeros(len(i)), 0.25 * j])
    v = 5 * j + i
    if kind == "net":
        faces = [[a, a + 1] for a in v[i < 4]] + [[a, a + 5] for a in v[j < 4]]
        return write_assignment(folder / f"{stem}.json", x, faces, k=300.0, m=1.0, b=[0, 4, 24])
    if kind == "sheet":
        faces = [[a, a + 5, a + 6, a + 1] for a in v[(i < 4) & (j < 3)]]
        return write_assignment(folder / f"{stem}.json", x, faces, k=1000.0, b=[0, 4])
    raise ValueError(f"kind: {kind!r}")
