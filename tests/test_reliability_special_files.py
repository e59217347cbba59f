"""A FIFO (or another special file) given to compare, check or diff-model is refused at
once with one line naming it: no read that waits forever."""

import os
import subprocess
import sys
import threading

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


def _in_process(argv, cwd, monkeypatch, capsys) -> tuple[int | None, str]:
    """clothsim's main() on ``argv`` in a thread of this process: (exit status, stderr), or
    (None, ...) when it is still waiting after 60 s (a read that blocks on the FIFO)."""
    from clothsim.cli import main

    monkeypatch.chdir(cwd)
    status = []
    worker = threading.Thread(target=lambda: status.append(main(argv)), daemon=True)
    worker.start()
    worker.join(60)
    return (status[0] if status else None), capsys.readouterr().err


# one real process per command (compare, check, diff-model: the process boundary and its
# timeout); the other arguments in this process (its imports cost about 1 s a process)
@pytest.mark.parametrize("argv, process", [
    (["compare", "pipe.npy", "ref.npy"], True),
    (["compare", "ref.npy", "pipe.npy"], False),
    (["compare", "pipe.mtx", "ref.mtx"], False),
    (["check", "hanging", "pipe.npy"], True),
    (["check", "hanging", "folder"], False),
    (["diff-model", "folder", "hanging"], True),
])
def test_cli_refuses_a_fifo_at_once(argv, process, fifo, tmp_path, monkeypatch, capsys):
    os.mkfifo(tmp_path / "pipe.mtx")
    (tmp_path / "folder").mkdir()
    os.mkfifo(tmp_path / "folder" / "positions.txt")
    if process:
        r = _cli(*argv, cwd=tmp_path)  # the timeout fails the test if it hangs
        status, stderr = r.returncode, r.stderr
    else:
        status, stderr = _in_process(argv, tmp_path, monkeypatch, capsys)
    assert status == 2, stderr   # None: still waiting on the FIFO after 60 s
    assert len(stderr.strip().splitlines()) == 1 and "FIFO" in stderr
    assert "Traceback" not in stderr


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
