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


@pytest.mark.parametrize("n", [9, 73])  # 73²: decimated (10 368 triangles)
def test_run_pictures_are_those_of_its_trajectory(tmp_path, n):
    scene = hanging(n)
    out = tmp_path / "run"
    result = run_scene(scene, out, frames=3)
    assert [p.name for p in result.files[-2:]] == ["preview.gif", "final.png"]
    want = pictures_of_trajectory(scene, out, tmp_path / "after")
    for name, data in want.items():
        assert (out / name).read_bytes() == data, name


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
