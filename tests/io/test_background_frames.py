"""Frames written on a background thread (RunFolder.write_frame(wait=False)): one at a time,
every file true at every instant, errors raised in the caller's thread, the frame in flight
finished before the run is marked."""

from __future__ import annotations

import json
import threading

import numpy as np
import pytest

import clothsim as cs
from clothsim.io.background import BackgroundJob
from clothsim.io.frames import read_frame
from clothsim.io.runfolder import RunFolder
from clothsim.runner import run_scene


def test_a_background_job_runs_one_call_at_a_time_and_hands_its_error_over():
    job, order, gate = BackgroundJob(), [], threading.Event()

    def slow(tag):
        gate.wait(5)
        order.append(tag)

    job.start(slow, "first")
    assert order == []                   # it runs in the background ...
    gate.set()
    job.start(slow, "second")            # ... and the next call waits for it
    assert order[0] == "first"
    job.wait()
    assert order == ["first", "second"]

    def boom():
        raise OSError(28, "No space left on device")

    job.start(boom)
    with pytest.raises(OSError, match="No space"):
        job.wait()
    job.wait()                           # handed over once
    job.start(boom)
    assert isinstance(job.join(), OSError) and job.join() is None
    with pytest.raises(OSError):         # start() raises the error of the call before
        job.start(boom)
        job.start(lambda: None)


def folder_with_frames(path, model, frames: int, **kw) -> RunFolder:
    folder = RunFolder(path)
    folder.__enter__()
    folder.begin({"scene": "test"}, model, 10.0)
    x = model.mesh.vertices
    for k in range(frames + 1):
        folder.write_frame(k, x + 0.01 * k, np.zeros_like(x), None if k == 0 else {"frame": k},
                           **kw)
    return folder


def test_background_frames_equal_waited_ones_and_run_json_follows_them(tmp_path):
    model = cs.load_scene("hanging").build_model()
    a = folder_with_frames(tmp_path / "a", model, 3, wait=False)
    b = folder_with_frames(tmp_path / "b", model, 3)
    for folder in (a, b):
        folder.end("complete", None)
        folder.__exit__(None, None, None)
    for k in range(4):
        xa, _ = read_frame(tmp_path / "a" / a.writer.filename(k))
        xb, _ = read_frame(tmp_path / "b" / b.writer.filename(k))
        np.testing.assert_array_equal(xa, xb)
    ra, rb = (json.loads((tmp_path / d / "run.json").read_text()) for d in "ab")
    assert ra["last_frame"] == rb["last_frame"] == 3 and ra["status"] == "completed"
    assert ra["trajectory_frames"] == 4 and [r["frame"] for r in ra["frames"]] == [1, 2, 3]


def test_run_json_records_the_information_of_the_hand_over(tmp_path):
    """The caller changes its information right after handing a frame over: run.json for
    that frame still says what it was (the solver state of that frame, not of the next)."""
    model = cs.load_scene("hanging").build_model()
    folder = RunFolder(tmp_path / "r")
    folder.__enter__()
    folder.begin({"state": 0}, model, 10.0)
    x = model.mesh.vertices
    folder.write_frame(0, x, 0 * x)
    gate = threading.Event()
    write = folder.writer.write
    folder.writer.write = lambda *a: (gate.wait(5), write(*a))[1]   # hold the frame
    folder.write_frame(1, x, 0 * x, {"frame": 1}, wait=False)
    folder.info["state"] = 1             # the next frame's, while frame 1 is in flight
    run = json.loads((tmp_path / "r" / "run.json").read_text())
    assert run["last_frame"] == 0        # frame 1 is not claimed before it is on disk
    gate.set()
    folder.wait()
    run = json.loads((tmp_path / "r" / "run.json").read_text())
    assert (run["last_frame"], run["state"]) == (1, 0)
    folder.end("complete", None)
    folder.__exit__(None, None, None)


def test_a_failed_background_write_fails_the_run_and_claims_only_whole_frames(tmp_path,
                                                                             monkeypatch):
    from clothsim.io import frames as frames_module

    real = frames_module.FrameWriter.write

    def full_disk(self, index, *args):
        if index == 2:
            raise OSError(28, "No space left on device")
        return real(self, index, *args)

    monkeypatch.setattr(frames_module.FrameWriter, "write", full_disk)
    out = tmp_path / "out"
    with pytest.raises(OSError, match="No space"):
        run_scene(cs.load_scene("hanging"), out, frames=4, preview=False)
    run = json.loads((out / "run.json").read_text())
    assert run["status"] == "failed" and run["last_frame"] == 1 and "No space" in run["error"]
    assert run["trajectory_frames"] == 2 and not (out / "frame_000002.vtu").exists()


def test_an_interruption_waits_for_the_frame_in_flight(tmp_path):
    seen = []

    def progress(k, total):
        seen.append(k)
        if k == 2:
            raise KeyboardInterrupt

    out = tmp_path / "out"
    with pytest.raises(KeyboardInterrupt):
        run_scene(cs.load_scene("hanging"), out, frames=5, preview=False, progress=progress)
    run = json.loads((out / "run.json").read_text())
    # progress(2) comes once frame 2 is on disk, while frame 3 is being handed over: the run
    # stops there, with frames 0-2 (frame 3 was never handed over)
    assert seen == [1, 2] and run["status"] == "interrupted" and run["last_frame"] == 2
    assert run["trajectory_frames"] == 3 and (out / "frame_000002.vtu").exists()
    assert not (out / "frame_000003.vtu").exists()


def test_the_end_rebuilds_trajectory_npz_only_when_it_lacks_frames(tmp_path, monkeypatch):
    model = cs.load_scene("hanging").build_model()
    folder = folder_with_frames(tmp_path / "r", model, 2, wait=False)
    folder.save_npz()                            # frames 0..2: all of them
    rebuilt = []
    real = folder.store.write_npz
    monkeypatch.setattr(folder.store, "write_npz", lambda *a: (rebuilt.append(a[1]), real(*a)))
    folder.end("complete", None)
    assert rebuilt == []                         # it held every frame already
    folder.write_frame(3, model.mesh.vertices, 0 * model.mesh.vertices, {"frame": 3})
    folder.end("complete", None)
    assert rebuilt == [4]                        # frame 3 was missing: rebuilt once
    folder.__exit__(None, None, None)
    with np.load(tmp_path / "r" / "trajectory.npz") as z:
        assert z["positions"].shape[0] == 4
    assert json.loads((tmp_path / "r" / "run.json").read_text())["trajectory_frames"] == 4
