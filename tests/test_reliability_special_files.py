"""A FIFO (or another special file) given to compare, check or diff-model is refused at
once with one line naming it: no read that waits forever."""

import os
import subprocess
import sys

import numpy as np
import pytest

from clothsim.errors import InputError
from clothsim.io import read_matrix, read_vector
from clothsim.ports.formats import read_trajectory

pytestmark = pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs mkfifo (POSIX)")
REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def _cli(*args, cwd):
    env = {**os.environ, "PYTHONPATH": REPO}
    return subprocess.run([sys.executable, "-m", "clothsim", *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=60)


@pytest.fixture
def fifo(tmp_path):
    p = tmp_path / "pipe.npy"
    os.mkfifo(p)
    np.save(tmp_path / "ref.npy", np.zeros((2, 3, 3)))
    return p


@pytest.mark.parametrize("argv", [
    ["compare", "pipe.npy", "ref.npy"],
    ["compare", "ref.npy", "pipe.npy"],
    ["compare", "pipe.mtx", "ref.mtx"],
    ["check", "hanging", "pipe.npy"],
    ["check", "hanging", "folder"],
    ["diff-model", "folder", "hanging"],
])
def test_cli_refuses_a_fifo_at_once(argv, fifo, tmp_path):
    os.mkfifo(tmp_path / "pipe.mtx")
    (tmp_path / "folder").mkdir()
    os.mkfifo(tmp_path / "folder" / "positions.txt")
    r = _cli(*argv, cwd=tmp_path)  # the timeout fails the test if it hangs
    assert r.returncode == 2, r.stderr
    assert len(r.stderr.strip().splitlines()) == 1 and "FIFO" in r.stderr
    assert "Traceback" not in r.stderr


def test_readers_refuse_a_fifo(fifo, tmp_path):
    for read in (read_trajectory, read_matrix, read_vector):
        with pytest.raises(InputError, match="is a FIFO"):
            read(fifo)
    d = tmp_path / "frames"
    d.mkdir()
    np.savetxt(d / "f_0.txt", np.zeros((3, 3)))
    os.mkfifo(d / "f_1.txt")
    with pytest.raises(InputError, match="f_1.txt: is a FIFO"):
        read_trajectory(d)
