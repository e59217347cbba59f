"""The coursework profile: every case is the assignment's program, and its expected output
is what that program computes (an independent dense re-implementation of it, here)."""

import json

import numpy as np
import pytest

from clothsim.cli import main
from clothsim.io.assignment import read_pins
from clothsim.ports.coursework import CASES, write_coursework
from clothsim.ports.model_folder import read_table

FRAMES = 5


@pytest.fixture(scope="module")
def profile(tmp_path_factory):
    out = tmp_path_factory.mktemp("coursework")
    assert write_coursework(out, frames=FRAMES) == list(CASES)
    return out


def assignment_program(d, frames):
    """The assignment's main.cpp on the plain files, dense: one k, penalty w, Verlet y, x_n."""
    x = np.loadtxt(d / "vertices.txt")
    springs = np.loadtxt(d / "springs.txt", ndmin=2)
    E, r = springs[:, :2].astype(int), springs[:, 3]
    (k,) = set(springs[:, 2])
    m = np.loadtxt(d / "masses.txt", ndmin=1)
    pins = read_table(d / "pins.txt", 6, "pins", empty=True)
    b = pins[:, 0].astype(int)
    w = pins[0, 2] if len(pins) else 0.0
    f = np.loadtxt(d / "forces.txt")
    h = 1 / 30
    n = len(x)
    A = np.zeros((len(E), n))
    A[np.arange(len(E)), E[:, 0]], A[np.arange(len(E)), E[:, 1]] = 1.0, -1.0
    C = np.zeros((len(b), n))
    C[np.arange(len(b)), b] = 1.0
    Q = k * A.T @ A + np.diag(m) / h**2 + w * C.T @ C
    rest = x.copy()
    prev, cur, out = x.copy(), x.copy(), [x.copy()]
    for _ in range(frames):
        nxt = cur.copy()
        for _ in range(50):
            p = A @ nxt
            d_ = r[:, None] * p / np.linalg.norm(p, axis=1, keepdims=True)
            rhs = k * A.T @ d_ + (m[:, None] / h**2) * (2 * cur - prev) + f + w * C.T @ C @ rest
            nxt = np.linalg.solve(Q, rhs)
        prev, cur = cur, nxt
        out.append(cur.copy())
    return np.stack(out)


@pytest.mark.parametrize("name", CASES)
def test_each_case_is_the_assignments_program(profile, name):
    d = profile / name
    spec = json.loads((d / "case.json").read_text())
    assert set(spec) <= {"obj", "k", "m", "b"} and (d / spec["obj"]).is_file()
    springs = np.loadtxt(d / "springs.txt", ndmin=2)
    assert len(set(springs[:, 2])) == 1 and springs[0, 2] == spec["k"]      # one k
    pins = read_table(d / "pins.txt", 6, "pins", empty=True)
    assert sorted(pins[:, 0].astype(int)) == sorted(read_pins(d / "case.json").tolist())
    assert np.all(pins[:, 1] == 1) and np.all(pins[:, 2] == 1e10)           # penalty, one w
    f = np.loadtxt(d / "forces.txt")
    assert np.all(f == [0.0, -9.8, 0.0])                                     # -9.8 N a vertex
    settings = dict(line.split() for line in (d / "settings.txt").read_text().splitlines()
                    if not line.startswith("#"))
    assert settings["initial_guess"] == "x_n" and settings["iterations"] == "50"
    expected = np.loadtxt(d / "positions.txt").reshape(FRAMES + 1, -1, 3)
    ours = assignment_program(d, FRAMES)
    scale = np.abs(expected).max() + 1.0
    assert np.abs(ours - expected).max() < 1e-7 * scale, np.abs(ours - expected).max()
    assert main(["check", str(d / "scene.toml"), str(d)]) == 0
    assert main(["diff-model", str(d / "scene.toml"), str(d)]) == 0   # free-fall: no pins


def test_cli_writes_the_coursework_profile(tmp_path, capsys):
    assert main(["conformance", "--profile", "coursework", "--out", str(tmp_path / "c")]) == 0
    assert f"{len(CASES)} coursework conformance cases written" in capsys.readouterr().out
    assert "`sheet-voronoi`" in (tmp_path / "c" / "README.md").read_text()
