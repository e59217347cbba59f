"""I/O errors (full disk, file too large, a file as --out, an unwritable plot path) exit 1
with one line naming the path and the cause; run.json then says "failed" with the error,
and --resume completes the run with one record per frame."""

import errno
import json

import numpy as np
import pytest

from clothsim.cli import main
from clothsim.io.frames import FrameWriter

TINY = """
[scene]
name = "tiny"
frames = 4
fps = 30
[cloth]
resolution = [3, 3]
plane = "xy"
[springs]
structural = 200.0
[[effects]]
kind = "gravity"
"""


@pytest.fixture
def tiny(tmp_path):
    p = tmp_path / "tiny.toml"
    p.write_text(TINY)
    return str(p)


def _fail_frame(monkeypatch, k, err):
    real = FrameWriter.write

    def write(self, index, *a, **kw):
        if index == k:
            raise OSError(err, "simulated " + errno.errorcode[err],
                          str(self.folder / f"frame_{k:06d}.vtu")
                          if hasattr(self, "folder") else "frame")
        return real(self, index, *a, **kw)

    monkeypatch.setattr(FrameWriter, "write", write)


@pytest.mark.parametrize("err", [errno.ENOSPC, errno.EFBIG, errno.EROFS])
def test_io_error_in_a_run_is_one_line_and_recorded_failed(tiny, tmp_path, capsys,
                                                          monkeypatch, err):
    out = tmp_path / "out"
    with monkeypatch.context() as m:
        _fail_frame(m, 2, err)
        assert main(["run", tiny, "--out", str(out), "--no-preview"]) == 1
    line = capsys.readouterr().err.strip()
    assert len(line.splitlines()) == 1 and str(out) in line
    assert "simulated" in line and "OSError" not in line and "Errno" not in line
    run = json.loads((out / "run.json").read_text())
    assert run["status"] == "failed" and run["last_frame"] == 1 and "simulated" in run["error"]
    assert main(["run", tiny, "--out", str(out), "--no-preview", "--resume"]) == 0
    run = json.loads((out / "run.json").read_text())
    assert run["status"] == "completed"
    assert [r["frame"] for r in run["frames"]] == [1, 2, 3, 4]


def test_resume_frames_down_then_up_keeps_one_record_per_frame(tiny, tmp_path):
    out = tmp_path / "out"
    assert main(["run", tiny, "--out", str(out), "--no-preview"]) == 0
    full = np.load(out / "trajectory.npz")["positions"]
    assert main(["run", tiny, "--out", str(out), "--no-preview", "--resume",
                 "--frames", "2"]) == 0
    assert main(["run", tiny, "--out", str(out), "--no-preview", "--resume",
                 "--frames", "4"]) == 0
    run = json.loads((out / "run.json").read_text())
    assert [r["frame"] for r in run["frames"]] == [1, 2, 3, 4]
    assert np.array_equal(np.load(out / "trajectory.npz")["positions"], full)


def test_resume_after_a_lost_record_recomputes_that_frame(tiny, tmp_path):
    """As after SIGKILL between a frame file and its record."""
    out = tmp_path / "out"
    assert main(["run", tiny, "--out", str(out), "--no-preview"]) == 0
    full = np.load(out / "trajectory.npz")["positions"]
    run = json.loads((out / "run.json").read_text())
    run["frames"] = run["frames"][:2]
    run["status"], run["last_frame"] = "running", 2
    (out / "run.json").write_text(json.dumps(run))
    assert main(["run", tiny, "--out", str(out), "--no-preview", "--resume"]) == 0
    run = json.loads((out / "run.json").read_text())
    assert [r["frame"] for r in run["frames"]] == [1, 2, 3, 4] and run["resumed_from"] == 2
    assert np.array_equal(np.load(out / "trajectory.npz")["positions"], full)


def test_plot_into_a_missing_folder_is_one_line(tmp_path, capsys):
    np.save(tmp_path / "a.npy", np.zeros((2, 3, 3)))
    target = tmp_path / "no" / "such" / "p.png"
    assert main(["compare", str(tmp_path / "a.npy"), str(tmp_path / "a.npy"),
                 "--plot", str(target), "--no-table"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(target) in err[0] and "No such file" in err[0]
    assert "FileNotFoundError" not in err[0]


def test_export_into_a_file_path_is_one_line(tiny, tmp_path, capsys):
    f = tmp_path / "f"
    f.write_text("x")
    assert main(["export", tiny, "--out", str(f / "sub")]) in (1, 2)
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(f) in err[0] and "Error" not in err[0]


def test_a_folder_that_cannot_take_the_lock_says_nothing_was_written(tiny, tmp_path, capsys):
    """An --out under a file (and, for a user who is not root, a read-only folder) fails
    before anything is written: the line must not promise frames or a --resume. Under a
    file it is bad input, refused by name (exit 2: tests/test_reliability_hostile2.py)."""
    (tmp_path / "a-file").write_text("")
    out = tmp_path / "a-file" / "out"
    assert main(["run", tiny, "--out", str(out), "--no-preview"]) == 2
    line = capsys.readouterr().err.strip()
    assert len(line.splitlines()) == 1 and str(out) in line, line
    assert line.endswith("a-file is a file, not a folder") and "--resume" not in line, line
