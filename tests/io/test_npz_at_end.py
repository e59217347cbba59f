"""trajectory.npz is written once, at the end: built while the last frame's file is written
(RunFolder.wait_last, a temporary file), moved into place only once every frame it holds
is on disk; an interruption, a failed last frame or SIGKILL at that point leave a true folder,
no temporary file, and ``--resume`` finishes bit for bit."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys

import numpy as np
import pytest

import clothsim as cs
from clothsim.io import frames as frames_module
from clothsim.io.runfolder import RunFolder
from clothsim.runner import run_scene
from tests import test_interrupts as interrupts

FRAMES = 6


def tmp_files(out):
    return sorted(p.name for p in out.glob(".*.tmp*"))


def assert_same_run(a, b):
    with np.load(a / "trajectory.npz") as za, np.load(b / "trajectory.npz") as zb:
        assert za.files == zb.files
        for key in za.files:
            assert np.array_equal(za[key], zb[key]), key


@pytest.fixture
def scene(tmp_path):
    return interrupts.write_scene(tmp_path, "local-global", frames=FRAMES)


def test_the_npz_is_built_beside_the_last_frame_and_placed_once_it_is_on_disk(tmp_path,
                                                                            monkeypatch):
    seen = []
    real_write = frames_module.FrameWriter.write

    def write(self, index, *args):   # the last frame's file: is the npz there yet?
        if index == 3:
            seen.append((tmp_path / "r" / "trajectory.npz").exists())
        return real_write(self, index, *args)

    monkeypatch.setattr(frames_module.FrameWriter, "write", write)
    model = cs.load_scene("hanging").build_model()
    with RunFolder(tmp_path / "r") as folder:
        folder.begin({"clothsim_run": 1}, model, 30.0)
        for k in range(4):
            x = model.mesh.vertices + 0.01 * k
            folder.write_frame(k, x, 0 * x, {"frame": k} if k else None, wait=False)
        folder.wait_last()
        built = tmp_files(tmp_path / "r")
        assert built == [f".trajectory.npz.{os.getpid()}.tmp.npz"]    # complete, not placed
        assert not (tmp_path / "r" / "trajectory.npz").exists()
        assert json.loads((tmp_path / "r" / "run.json").read_text())["trajectory_frames"] is None
        folder.end("complete", None)
    assert seen == [False]               # never placed before its last frame is on disk
    assert tmp_files(tmp_path / "r") == []
    run = json.loads((tmp_path / "r" / "run.json").read_text())
    assert (run["status"], run["last_frame"], run["trajectory_frames"]) == ("completed", 3, 4)
    with np.load(tmp_path / "r" / "trajectory.npz") as z:
        assert z["positions"].shape[0] == 4 and np.array_equal(z["time"], np.arange(4) / 30.0)
        for k in range(4):
            x, v = cs.io.read_frame(tmp_path / "r" / f"frame_{k:06d}.vtu")
            assert np.array_equal(z["positions"][k], x) and np.array_equal(z["velocities"][k], v)


def test_an_interruption_after_the_npz_was_built_uses_it_and_resume_completes(tmp_path, scene):
    def progress(k, total):
        if k == total:   # after wait_last, before the run is marked complete
            assert tmp_files(out)    # the npz built beside the last frame
            raise KeyboardInterrupt

    out = tmp_path / "out"
    with pytest.raises(KeyboardInterrupt):
        run_scene(str(scene), out, preview=False, progress=progress)
    assert interrupts.assert_truthful(out) == FRAMES        # no temporary file either
    result = run_scene(str(scene), out, resume=True, preview=False)
    assert result.status == "completed"
    run_scene(str(scene), tmp_path / "full", preview=False)
    assert_same_run(out, tmp_path / "full")


def test_a_failed_last_frame_discards_the_npz_built_for_it(tmp_path, scene, monkeypatch):
    real_write = frames_module.FrameWriter.write

    def full_disk(self, index, *args):
        if index == FRAMES:
            raise OSError(28, "No space left on device")
        return real_write(self, index, *args)

    monkeypatch.setattr(frames_module.FrameWriter, "write", full_disk)
    out = tmp_path / "out"
    with pytest.raises(OSError, match="No space"):
        run_scene(str(scene), out, preview=False)
    run = json.loads((out / "run.json").read_text())
    assert (run["status"], run["last_frame"], run["trajectory_frames"]) == (
        "failed", FRAMES - 1, FRAMES)
    assert tmp_files(out) == [] and not (out / f"frame_{FRAMES:06d}.vtu").exists()
    with np.load(out / "trajectory.npz") as z:
        assert z["positions"].shape[0] == FRAMES       # frames 0..FRAMES-1, as on disk


KILL_AT_NPZ = r"""
import os, signal, sys
from clothsim.io import runfolder
real = runfolder.RunFolder.wait_last
def wait_last(self):
    real(self)     # the npz of every frame built beside them: killed before it is placed
    os.kill(os.getpid(), signal.SIGKILL)
runfolder.RunFolder.wait_last = wait_last
from clothsim.cli import main
sys.exit(main(sys.argv[1:]))
"""


def test_sigkill_before_the_npz_is_placed_leaves_a_resumable_folder(tmp_path, scene):
    out = tmp_path / "out"
    env = {**os.environ, "PYTHONPATH": str(interrupts.REPO)}
    proc = subprocess.run([sys.executable, "-c", KILL_AT_NPZ, "run", str(scene), "--out",
                           str(out), "--no-preview"], env=env, capture_output=True, text=True,
                          preexec_fn=interrupts._default_signals, timeout=120)
    assert proc.returncode == -signal.SIGKILL, proc.stderr
    run = json.loads((out / "run.json").read_text())
    # nothing marked it: "running", no trajectory.npz claimed and none there; the npz
    # built for the end is a temporary file, which the next run into the folder removes
    assert (run["status"], run["trajectory_frames"]) == ("running", None)
    assert not (out / "trajectory.npz").exists() and len(tmp_files(out)) == 1
    with pytest.raises(cs.errors.InputError, match="not complete"):
        cs.io.folders.require_complete(out / "trajectory.npz")
    result = run_scene(str(scene), out, resume=True, preview=False)
    assert result.status == "completed" and tmp_files(out) == []
    run_scene(str(scene), tmp_path / "full", preview=False)
    assert_same_run(out, tmp_path / "full")


def test_a_folder_an_earlier_version_left_mid_run_resumes_and_reads(tmp_path, scene):
    """Before this change a run rewrote trajectory.npz every few seconds: a killed run of
    that version left one lagging behind its frames, which run.json counted. Resume takes
    it over (rewritten from the frames at its start), and compare reads the result."""
    def progress(k, total):
        if k == 3:
            raise KeyboardInterrupt

    out = tmp_path / "out"
    with pytest.raises(KeyboardInterrupt):
        run_scene(str(scene), out, preview=False, progress=progress)
    run = json.loads((out / "run.json").read_text())
    with np.load(out / "trajectory.npz") as z:   # as the earlier version left it when killed
        np.savez(out / "trajectory.npz", **{k: z[k][:2] if z[k].ndim == 3 or k == "time"
                                            else z[k] for k in z.files})
    run.update(status="running", trajectory_frames=2, error=None)
    (out / "run.json").write_text(json.dumps(run))
    result = run_scene(str(scene), out, resume=True, preview=False)
    assert result.status == "completed"
    run_scene(str(scene), tmp_path / "full", preview=False)
    assert_same_run(out, tmp_path / "full")
    from clothsim.cli import main
    assert main(["compare", str(out / "trajectory.npz"), str(tmp_path / "full" / "trajectory.npz"),
                 "--no-table"]) == 0
