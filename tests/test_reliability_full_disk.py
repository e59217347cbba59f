"""A full disk: run, export and conformance stop with one line naming the folder, the cause
and the file that could not be written; the folder says what it holds (failed, or still
writing when even that could not be written); the conformance set keeps its README."""

import errno
import subprocess

import numpy as np
import pytest

from clothsim.cli import main
from clothsim.io import diskspace
from clothsim.io.folders import folder_state
from tests.test_reliability_folders import TINY


@pytest.fixture
def tiny(tmp_path):
    p = tmp_path / "tiny.toml"
    p.write_text(TINY.replace("[3, 3]", "[12, 12]").replace("frames = 2", "frames = 30"))
    return str(p)


@pytest.fixture
def small_disk(tmp_path, monkeypatch):
    """A 160 kB tmpfs (needs root; skipped elsewhere). The free-space check before a run is
    off, so that the disk fills mid-way as an unforeseen one does."""
    disk = tmp_path / "disk"
    disk.mkdir()
    done = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=160k", "tmpfs", str(disk)],
                          capture_output=True)
    if done.returncode:
        pytest.skip("cannot mount a small tmpfs here (needs root)")
    monkeypatch.setattr(diskspace, "free_bytes", lambda path: None)
    try:
        yield disk
    finally:
        subprocess.run(["umount", "-l", str(disk)], check=False)


def _one_line_naming_a_file(err, out):
    lines = err.strip().splitlines()
    assert len(lines) == 1, lines
    line = lines[0]
    assert "No space left on device" in line and "Errno" not in line and "OSError" not in line
    assert f"({out}/" in line, line  # the file, inside the folder
    return line


@pytest.mark.parametrize("command", [["run", "--no-preview"],
                                     ["export", "--frames", "30", "--iterate-steps", "3"]])
def test_a_full_disk_names_the_file(tiny, small_disk, capsys, command):
    out = small_disk / "out"
    assert main([command[0], tiny, "--out", str(out), *command[1:]]) == 1
    _one_line_naming_a_file(capsys.readouterr().err, out)
    assert folder_state(out).status in ("failed", "writing")
    assert not list(out.glob(".*.tmp*"))


def test_a_full_disk_leaves_the_conformance_readme(small_disk, capsys):
    out = small_disk / "set"
    assert main(["conformance", "--out", str(out)]) == 1
    line = _one_line_naming_a_file(capsys.readouterr().err, out)
    readme = (out / "README.md").read_text().splitlines()
    assert readme[0] == "# clothsim conformance set" and readme[2].startswith("status: ")
    assert folder_state(out).status in ("failed", "writing") and "marked" in line


def test_an_error_without_a_file_name_is_given_the_file(tiny, tmp_path, capsys, monkeypatch):
    """What a full disk raises: ENOSPC from write(), with no file name."""
    real = np.savetxt

    def savetxt(fname, *args, **kwargs):
        if "springs" in str(fname):
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(fname, *args, **kwargs)

    monkeypatch.setattr(np, "savetxt", savetxt)
    out = tmp_path / "export"
    assert main(["export", tiny, "--out", str(out), "--frames", "2"]) == 1
    line = _one_line_naming_a_file(capsys.readouterr().err, out)
    assert f"({out / 'springs.txt'})" in line and "marked failed" in line
    assert folder_state(out).status == "failed"


def test_a_run_the_small_disk_cannot_hold_is_refused_up_front(tiny, small_disk, capsys,
                                                              monkeypatch):
    monkeypatch.undo()  # the real free space of the 160 kB disk
    out = small_disk / "out"
    assert main(["run", tiny, "--out", str(out), "--no-preview"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "are free on its disk" in err and "--frames" in err
    assert not out.exists()  # not even the folder the run made
