"""A run's pictures are drawn while its last frame is written and written once it is
complete: they are those of its trajectory, byte for byte; an error drawing them is raised
after the run is marked complete; a resumed run with nothing left to compute draws them
from its files."""

import json

import numpy as np
import pytest

from clothsim.plotting import write_final_image, write_preview
from clothsim.runner import run_scene
from clothsim.scene import load_scene

pytest.importorskip("matplotlib")


def hanging(n: int):
    return load_scene("hanging", [f"cloth.resolution=[{n}, {n}]"])


def pictures_of_trajectory(scene, out, tmp):
    """preview.gif and final.png drawn afterwards from the run's trajectory.npz."""
    sim = scene.build_simulation()
    with np.load(out / "trajectory.npz") as z:
        positions, times = z["positions"], z["time"]
    tmp.mkdir()
    write_preview(tmp / "preview.gif", positions, sim.model.mesh, times=times,
                  effects=sim.effects)
    write_final_image(tmp / "final.png", positions[-1], sim.model.mesh,
                      title=f"{scene.name}, t = {times[-1]:.2f} s", effects=sim.effects,
                      t=float(times[-1]))
    return {name: (tmp / name).read_bytes() for name in ("preview.gif", "final.png")}


def assert_pictures_of_trajectory(scene, out, tmp):
    """The run's pictures in ``out`` are byte for byte those of its trajectory."""
    for name, data in pictures_of_trajectory(scene, out, tmp).items():
        assert (out / name).read_bytes() == data, name


@pytest.mark.parametrize("n", [9, 73])  # 73²: decimated (10 368 triangles)
def test_run_pictures_are_those_of_its_trajectory(tmp_path, n):
    scene = hanging(n)
    out = tmp_path / "run"
    result = run_scene(scene, out, frames=3)
    assert [p.name for p in result.files[-2:]] == ["preview.gif", "final.png"]
    assert_pictures_of_trajectory(scene, out, tmp_path / "after")


def test_a_picture_error_is_raised_once_the_run_is_complete(tmp_path, monkeypatch):
    import clothsim.runner as runner

    def broken(*args, **kw):
        raise RuntimeError("no pictures today")

    monkeypatch.setattr(runner, "draw_run_pictures", broken)
    out = tmp_path / "run"
    with pytest.raises(RuntimeError, match="no pictures today"):
        run_scene(hanging(9), out, frames=2)
    record = json.loads((out / "run.json").read_text())
    assert record["status"] == "completed" and record["last_frame"] == 2
    assert (out / "trajectory.npz").exists() and (out / "frame_000002.vtu").exists()
    assert not (out / "preview.gif").exists() and not (out / "final.png").exists()


def test_a_resumed_complete_run_draws_its_pictures_from_its_files(tmp_path):
    scene = hanging(9)
    fresh, resumed = tmp_path / "fresh", tmp_path / "resumed"
    run_scene(scene, fresh, frames=3)
    run_scene(scene, resumed, frames=3, preview=False)
    assert not (resumed / "final.png").exists()
    result = run_scene(scene, resumed, frames=3, resume=True)  # nothing left to compute
    assert result.last_frame == 3
    for name in ("preview.gif", "final.png"):
        assert (resumed / name).read_bytes() == (fresh / name).read_bytes(), name


@pytest.fixture
def picture_process(monkeypatch):
    """The picture process for any cloth (it starts above PROCESS_FROM vertices only); the
    processes started are recorded."""
    import clothsim.pictures as pictures

    started = []
    real_start = pictures.PictureProcess.start

    def start(self, *args, **kwargs):
        real_start(self, *args, **kwargs)
        started.append((self, self._proc))

    monkeypatch.setattr(pictures, "PROCESS_FROM", 0)
    monkeypatch.setattr(pictures, "_cores", lambda: 2)
    monkeypatch.setattr(pictures.PictureProcess, "start", start)
    return started


@pytest.mark.parametrize("name, sets", [
    ("hanging", ["cloth.resolution=[9, 9]"]),
    # decimated: a variant (-m slow); the fast run keeps the decimated pictures drawn in the
    # run's process (test_run_pictures_are_those_of_its_trajectory[73]) and the 9² here
    pytest.param("hanging", ["cloth.resolution=[73, 73]"], marks=pytest.mark.slow),
    ("hanging", ["cloth.resolution=[9, 9]", "effects[1].release=0.05"]),  # pins let go
    ("drape-sphere", ["cloth.resolution=[9, 9]"]),            # sphere and floor
    ("drop-on-square", ["cloth.resolution=[9, 9]"]),          # box and floor
])
def test_pictures_drawn_by_the_second_process_are_those_of_its_trajectory(
        tmp_path, monkeypatch, picture_process, name, sets):
    import clothsim.runner as runner

    def not_here(*args, **kw):
        raise AssertionError("drawn in the run's process")

    monkeypatch.setattr(runner, "draw_run_pictures", not_here)
    scene = load_scene(name, sets)
    out = tmp_path / "run"
    run_scene(scene, out, frames=3)
    [(worker, proc)] = picture_process
    assert proc is not None and proc.returncode == 0 and not worker.running
    assert_pictures_of_trajectory(scene, out, tmp_path / "after")


def test_a_failed_picture_process_leaves_the_pictures_to_the_run(tmp_path, monkeypatch,
                                                                picture_process):
    """A process that dies at once: the run draws the pictures itself, the same bytes."""
    import sys

    monkeypatch.setattr(sys, "executable", "/bin/false")   # the process dies at once
    scene = hanging(9)
    out = tmp_path / "run"
    result = run_scene(scene, out, frames=2)
    assert [p.name for p in result.files[-2:]] == ["preview.gif", "final.png"]
    assert_pictures_of_trajectory(scene, out, tmp_path / "after")


def test_the_picture_process_hands_its_error_over(tmp_path, monkeypatch):
    from clothsim.pictures import PictureProcess

    monkeypatch.setattr("clothsim.pictures._cores", lambda: 2)
    sim = hanging(9).build_simulation()
    x = sim.model.mesh.vertices
    with PictureProcess(10 ** 9) as worker:
        assert not worker.running      # started by the runner once the first frame is done
        worker.start()
        assert worker.running
        # one frame but no time for it: draw_run_pictures raises IndexError over there
        assert worker.request(tmp_path / "none", 0, x, sim.model.mesh, times=np.zeros(0),
                              effects=sim.effects, title="t")
        assert isinstance(worker.answer(), IndexError) and not worker.running
    for vertices, cores in ((10, 2), (10 ** 9, 1)):  # a small cloth, or one core: none
        monkeypatch.setattr("clothsim.pictures._cores", lambda c=cores: c)
        worker = PictureProcess(vertices)
        worker.start()
        assert not worker.running and not worker.request(tmp_path / "none", 0, x, None,
                                                         times=[0.0], effects=(), title="")


def test_the_mesh_goes_to_the_picture_process_at_its_start(tmp_path, monkeypatch,
                                                           picture_process):
    """The runner sends the mesh when it starts the process (a file without a name): the
    request after the last step carries neither it nor the last frame (every frame is in the
    store); without that file (/dev/shm full) the mesh goes with the request. The same
    pictures either way."""
    import pickle

    import clothsim.pictures as pictures

    sent = []
    real_dump = pickle.dump

    def dump(obj, file, *args, **kwargs):
        sent.append(obj)
        return real_dump(obj, file, *args, **kwargs)

    monkeypatch.setattr(pictures.pickle, "dump", dump)
    scene = hanging(9)
    run_scene(scene, tmp_path / "run", frames=2)
    init, request = sent
    assert set(init["mesh"]) == {"pickle", "sizes", "fd"}        # frameproc.pack's message
    assert request["mesh"] is None and request["last"] is None and request["stored"] == 3
    assert_pictures_of_trajectory(scene, tmp_path / "run", tmp_path / "after")

    def no_file(obj):
        raise OSError("No space left on device")

    monkeypatch.setattr(pictures, "pack", no_file)
    sent.clear()
    run_scene(scene, tmp_path / "run2", frames=2)
    init, request = sent
    assert init["mesh"] is None and request["mesh"].vertex_count == 81
    assert_pictures_of_trajectory(scene, tmp_path / "run2", tmp_path / "after2")
    assert [worker.running for worker, _ in picture_process] == [False, False]


def test_an_interrupted_run_ends_its_picture_process(tmp_path, picture_process):
    """Started after frame 1, ended (its input closed) when frame 2 is interrupted."""
    def progress(k, total):
        if k == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_scene(hanging(9), tmp_path / "run", frames=4, progress=progress)
    [(worker, proc)] = picture_process
    assert not worker.running and proc.returncode == 0   # its input closed: it ended
    assert not (tmp_path / "run" / "preview.gif").exists()


def test_a_run_of_one_frame_draws_its_pictures_itself(tmp_path, picture_process):
    """The process starts once the first frame is computed and more follow: a run with
    one frame to compute would wait for its imports, so it draws the pictures itself."""
    result = run_scene(hanging(9), tmp_path / "run", frames=1)
    assert picture_process == [] and result.files[-1].name == "final.png"
