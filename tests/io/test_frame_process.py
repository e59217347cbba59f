"""Frame files written by a second process (clothsim.io.frameproc): the same bytes as the
run writes itself, a dead process leaving the frames to the run, the process's errors raised
in the run naming the file, a resumed run bit for bit, and no file the run did not claim."""

from __future__ import annotations

import json
import os
import pickle
import random
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

import clothsim as cs
from clothsim.io import frameproc
from clothsim.io.frames import FrameWriter, read_frame, read_pvd
from clothsim.runner import run_scene
from tests import test_interrupts as interrupts

SETS = ["cloth.resolution=[13, 9]"]


@pytest.fixture
def spy(monkeypatch):
    """Frames of any size go through a process (two cores assumed); the answers it gave."""
    monkeypatch.setattr(frameproc, "PROCESS_FROM", 0)
    monkeypatch.setattr(frameproc, "cores", lambda: 2)
    answers = []
    write = frameproc.FrameProcess.write

    def spying(self, *args):
        answers.append(write(self, *args))
        return answers[-1]

    monkeypatch.setattr(frameproc.FrameProcess, "write", spying)
    return answers


def frame_bytes(folder, frames):
    return [(folder / f"frame_{k:06d}.vtu").read_bytes() for k in range(frames + 1)]


def run_here(monkeypatch, name, sets, out, frames):
    """The run written without a process."""
    with monkeypatch.context() as m:
        m.setattr(frameproc, "PROCESS_FROM", 10 ** 9)
        return run_scene(cs.load_scene(name, sets), out, frames=frames, preview=False)


@pytest.mark.parametrize("name, sets", [("hanging", SETS),
                                        ("drop-on-square", ["cloth.resolution=[9, 9]"])])
def test_the_process_writes_the_bytes_the_run_would_write(tmp_path, monkeypatch, spy, name,
                                                          sets):
    here = run_here(monkeypatch, name, sets, tmp_path / "here", 3)
    assert spy == []
    there = run_scene(cs.load_scene(name, sets), tmp_path / "there", frames=3, preview=False)
    assert spy == [True] * 4                          # every frame went through the process
    assert frame_bytes(here.out_dir, 3) == frame_bytes(there.out_dir, 3)
    assert sorted(p.name for p in there.out_dir.iterdir()) == sorted(
        p.name for p in here.out_dir.iterdir())      # no temporary file left behind
    assert [p.name for _, p in read_pvd(there.out_dir / "trajectory.pvd")] == [
        f"frame_{k:06d}.vtu" for k in range(4)]


def test_a_process_that_cannot_start_leaves_the_frames_to_the_run(tmp_path, monkeypatch, spy):
    here = run_here(monkeypatch, "hanging", SETS, tmp_path / "here", 2)
    monkeypatch.setattr(sys, "executable", "/bin/false")   # the process dies at once
    there = run_scene(cs.load_scene("hanging", SETS), tmp_path / "there", frames=2,
                      preview=False)
    assert spy and not any(spy)                            # asked once, then never again
    assert frame_bytes(here.out_dir, 2) == frame_bytes(there.out_dir, 2)
    assert json.loads((there.out_dir / "run.json").read_text())["status"] == "completed"


def test_a_process_dying_between_frames_leaves_the_rest_to_the_run(tmp_path, spy):
    mesh = cs.grid(5, 4)
    writer = FrameWriter(tmp_path, mesh)
    writer.process = frameproc.FrameProcess(writer)
    x, v = mesh.vertices, np.ones((mesh.vertex_count, 3))
    writer.write(0, 0.0, x, v)
    writer.process._proc.kill()
    writer.process._proc.wait()
    writer.write(1, 0.1, x + 1.0, v)                       # written here
    assert spy == [True, False] and writer.process.running is False
    got = read_frame(tmp_path / "frame_000001.vtu")
    np.testing.assert_array_equal(got[0], x + 1.0)
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "frame_000000.vtu", "frame_000001.vtu", "trajectory.pvd"]


def test_an_error_in_the_process_is_raised_naming_the_frame(tmp_path, spy):
    mesh = cs.grid(4, 4)
    writer = FrameWriter(tmp_path / "out", mesh)
    writer.process = frameproc.FrameProcess(writer)
    writer.write(0, 0.0, mesh.vertices, np.zeros((16, 3)))
    (tmp_path / "out" / "frame_000000.vtu").unlink()
    (tmp_path / "out" / "trajectory.pvd").unlink()
    (tmp_path / "out").rmdir()                             # the folder is gone
    with pytest.raises(OSError) as info:
        writer.write(1, 0.1, mesh.vertices, np.zeros((16, 3)))
    assert info.value.filename == str(tmp_path / "out" / "frame_000001.vtu")
    assert writer.process.running                          # an answer, not a failure
    writer.process.close()
    assert spy == [True]


def test_a_resumed_run_repeats_the_frames_bit_for_bit(tmp_path, spy):
    scene = cs.load_scene("hanging", SETS)
    whole = run_scene(scene, tmp_path / "whole", frames=4, preview=False)
    run_scene(cs.load_scene("hanging", SETS), tmp_path / "parts", frames=2, preview=False)
    parts = run_scene(cs.load_scene("hanging", SETS), tmp_path / "parts", frames=4,
                      resume=True, preview=False)
    assert all(spy)
    assert frame_bytes(whole.out_dir, 4) == frame_bytes(parts.out_dir, 4)


def test_small_cloths_and_one_core_write_in_the_run(monkeypatch):
    monkeypatch.setattr(frameproc, "cores", lambda: 2)
    assert not frameproc.wanted(frameproc.PROCESS_FROM)
    assert frameproc.wanted(frameproc.PROCESS_FROM + 1)
    monkeypatch.setattr(frameproc, "cores", lambda: 1)
    assert not frameproc.wanted(10 ** 6)


# a real `python -m clothsim run` of a 4 x 4 cloth with its frames written by the process
CHILD = ("import sys\nfrom clothsim.io import frameproc\nframeproc.PROCESS_FROM = 0\n"
         "frameproc.cores = lambda: 2\nfrom clothsim.cli import main\nsys.exit(main())\n")


def start_run_with_process(scene, out):
    env = {**os.environ, "PYTHONPATH": str(interrupts.REPO)}
    return subprocess.Popen([sys.executable, "-c", CHILD, "run", str(scene), "--out", str(out),
                             "--no-preview"], env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True,
                            preexec_fn=interrupts._default_signals)


@pytest.mark.parametrize("signame", [   # SIGTERM takes SIGINT's path: a variant (-m slow)
    "SIGINT", pytest.param("SIGTERM", marks=pytest.mark.slow), "SIGKILL"])
def test_a_signal_leaves_a_true_folder_and_resume_finishes_bit_for_bit(tmp_path, signame):
    frame = random.Random(signame).randint(1, interrupts.FRAMES - 4)
    out = tmp_path / "run"
    proc = start_run_with_process(interrupts.write_scene(tmp_path, "local-global"), out)
    interrupts.wait_for_frame(out, frame, proc)
    proc.send_signal(getattr(signal, signame))
    _, err = proc.communicate(timeout=60)
    if signame == "SIGKILL":   # nothing marks it; the process removes its half file
        end = time.monotonic() + 10
        while list(out.glob(".frame_*.tmp*")) and time.monotonic() < end:
            time.sleep(0.05)
        assert not list(out.glob(".frame_*.tmp*"))
    else:
        assert f"interrupted ({signame})" in err
        assert interrupts.assert_truthful(out) >= frame
    short = interrupts.write_scene(tmp_path, "local-global", frames=interrupts.FRAMES)
    result = run_scene(cs.load_scene(short), out, resume=True, preview=False)
    assert result.status == "completed"
    reference = run_scene(cs.load_scene(short), tmp_path / "reference", preview=False)
    a, b = np.load(reference.out_dir / "trajectory.npz"), np.load(out / "trajectory.npz")
    for key in a.files:
        assert np.array_equal(a[key], b[key]), key


def test_no_room_for_the_shared_frame_leaves_the_frames_to_the_run(tmp_path, monkeypatch, spy):
    def full(fd, offset, size):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(frameproc.os, "posix_fallocate", full)   # never SIGBUS later
    result = run_scene(cs.load_scene("hanging", SETS), tmp_path / "run", frames=2,
                       preview=False)
    assert spy and not any(spy) and result.status == "completed"
    x, _ = read_frame(tmp_path / "run" / "frame_000002.vtu")
    np.testing.assert_array_equal(x, np.load(tmp_path / "run" / "trajectory.npz")["positions"][2])


def test_the_writers_description_crosses_in_a_file_not_the_pipe():
    """pack/unpack: the mesh and springs out of band in a file (the pipe carries a few KB
    where it carried about 60 MB at 513²); the arrays come back equal, copies."""
    mesh = cs.grid(65, 65)
    model = cs.load_scene("hanging", ["cloth.resolution=[65, 65]"]).build_model()
    strided = np.arange(30.0).reshape(5, 6)[:, ::2]          # not contiguous: in band
    obj = {"mesh": mesh, "springs": model.springs, "strided": strided, "name": "x"}
    message, file = frameproc.pack(obj)
    assert len(pickle.dumps(message)) < 20_000 < mesh.vertices.nbytes
    message["fd"] = os.dup(file.fileno())    # unpack closes its descriptor, as the process's
    got = frameproc.unpack(message)
    file.close()
    np.testing.assert_array_equal(got["mesh"].vertices, mesh.vertices)
    np.testing.assert_array_equal(got["mesh"].triangles, mesh.triangles)
    np.testing.assert_array_equal(got["springs"].spring_vertices, model.springs.spring_vertices)
    np.testing.assert_array_equal(got["strided"], strided)
    inband = pickle.loads(pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL))
    assert got["name"] == "x"    # and the arrays' flags are those the pipe's pickle gave
    assert got["mesh"].vertices.flags.writeable == inband["mesh"].vertices.flags.writeable
    assert (got["springs"].spring_rest_length.flags.writeable
            == inband["springs"].spring_rest_length.flags.writeable)
    message, file = frameproc.pack(obj)
    file.truncate(10)                        # a file cut short is an error, not a mesh
    message["fd"] = os.dup(file.fileno())
    with pytest.raises(EOFError):
        frameproc.unpack(message)
    file.close()
