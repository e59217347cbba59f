"""Large runs a user can plan: the disk a run will use is estimated before anything is
written (within 15 % of what it writes), announced above a threshold and refused when the
disk cannot hold it, naming --frames; off a terminal the run reports its progress."""

import io
import json
import re

import pytest

from clothsim.cli import logs, main
from clothsim.io import diskspace
from clothsim.io.runfolder import RunFolder
from clothsim.runner import run_scene
from clothsim.scene import load_scene
from tests.test_reliability_folders import TINY


@pytest.fixture
def scene(tmp_path):
    p = tmp_path / "s.toml"
    p.write_text(TINY.replace("[3, 3]", "[21, 21]").replace("frames = 2", "frames = 6"))
    return str(p)


@pytest.mark.parametrize("compression", ["zlib", "none"])
def test_the_estimate_is_what_the_run_writes(scene, tmp_path, compression):
    out = tmp_path / "out"
    run_scene(load_scene(scene, [f"output.frame_compression='{compression}'"]), out,
              preview=False)
    plan = json.loads((out / "run.json").read_text())["disk_estimate"]
    frames = sum(p.stat().st_size for p in out.glob("frame_*.vtu"))
    npz = (out / "trajectory.npz").stat().st_size
    if compression == "none":
        assert 0.85 < plan["frames"] / frames < 1.15, (plan, frames)
    else:  # an upper bound: a smooth cloth's frames compress far better than random data
        assert frames <= plan["frames"] < 8 * frames, (plan, frames)
    assert 0.85 < plan["trajectory"] / npz < 1.15, (plan, npz)
    assert plan["peak"] > plan["end"] > plan["frames"]


def test_a_run_the_disk_cannot_hold_is_refused_before_writing(scene, tmp_path, capsys,
                                                              monkeypatch):
    out = tmp_path / "out"
    raw = ["--no-preview", "--set", "output.frame_compression='none'"]
    monkeypatch.setattr(diskspace, "free_bytes", lambda path: 480_000)
    assert main(["run", scene, "--out", str(out), *raw]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and str(out) in err and "are free" in err
    assert "frame_compression" in err
    fits = re.search(r"--frames (\d+) fits", err)
    assert fits and 0 < int(fits.group(1)) < 6, err
    assert not out.exists()  # nothing written, not even the lock file or the folder
    assert main(["run", scene, "--out", str(out), *raw, "--frames", fits.group(1)]) == 0
    assert main(["run", scene, "--out", str(tmp_path / "new"), *raw, "--frames",
                 str(int(fits.group(1)) + 1)]) == 2  # the number that fits is the largest


def test_an_earlier_run_being_replaced_counts_as_free(scene, tmp_path, monkeypatch):
    out = tmp_path / "out"
    run_scene(scene, out, preview=False)
    peak = json.loads((out / "run.json").read_text())["disk_estimate"]["peak"]
    earlier = sum(p.stat().st_size for p in out.iterdir() if p.is_file())
    monkeypatch.setattr(diskspace, "free_bytes", lambda path: peak - earlier // 2)
    run_scene(scene, out, preview=False)  # fits once the earlier run is removed


def test_a_large_run_is_announced(scene, tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(diskspace, "DISK_WARNING", 1000)
    assert main(["run", scene, "--out", str(tmp_path / "o"), "--no-preview",
                 "--set", "output.frame_compression='none'"]) == 0
    err = capsys.readouterr().err
    warning = [line for line in err.splitlines() if "will write about" in line]
    assert len(warning) == 1 and "7 frames of" in warning[0] and "kB" in warning[0]
    assert "frame_compression" in warning[0]


def test_the_plan_of_a_513_cloth(tmp_path):
    """The issue's numbers: a 513² frame is about 49 MB raw; 90 frames about 4.4 GB."""
    import clothsim as cs
    from clothsim.io.frames import FrameWriter

    mesh = cs.grid(513, 513)
    writer = FrameWriter(tmp_path, mesh, springs=cs.grid_springs(mesh, structural=1.0),
                         pinned=lambda t: None, compression="none")
    plan = diskspace.run_plan(writer.estimated_bytes(), mesh.vertex_count, 90)
    assert 47e6 < plan["frame"] < 52e6 and 4.3e9 < plan["frames"] < 4.7e9


def test_progress_lines_off_a_terminal(scene, tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(logs, "PROGRESS_SECONDS", 0.0)
    assert main(["run", scene, "--out", str(tmp_path / "o"), "--no-preview"]) == 0
    lines = [line for line in capsys.readouterr().err.splitlines() if "frame" in line]
    assert lines[0].startswith("clothsim: tiny: frame 1 of 6 (16 %), ")
    assert len(lines) == 5 and " left" in lines[-1]  # frames 1..5: the last one is the end


def test_progress_lines_every_few_seconds(monkeypatch):
    clock = iter([0.0, 1.0, 4.0, 5.5, 6.0, 11.0, 11.5]).__next__
    out = io.StringIO()
    lines = logs.ProgressLines("s", stream=out, clock=clock)
    for k in range(1, 7):
        lines(k, 100)
    printed = out.getvalue().splitlines()
    assert [line.split(": ")[2].split(" (")[0] for line in printed] == ["frame 3 of 100",
                                                                       "frame 5 of 100"]
    assert "1.8 s a frame" in printed[0] and "about 2 min 58 s left" in printed[0]


def test_no_progress_lines_on_a_terminal(scene, tmp_path, capsys, monkeypatch):
    import clothsim.cli as cli

    monkeypatch.setattr(logs, "PROGRESS_SECONDS", 0.0)
    monkeypatch.setattr(cli, "_isatty", lambda stream: True)
    monkeypatch.setenv("TQDM_DISABLE", "1")  # the bar itself is tqdm's
    assert main(["run", scene, "--out", str(tmp_path / "o"), "--no-preview"]) == 0
    assert "frame 1 of" not in capsys.readouterr().err


def test_a_resumed_run_is_planned_for_its_new_frames(scene, tmp_path):
    out = tmp_path / "out"
    run_scene(scene, out, frames=3, preview=False)
    with RunFolder(out) as folder:
        folder.writer = type("W", (), {"estimated_bytes": lambda self: 1000})()
        folder._model = load_scene(scene).build_model()
        assert folder.plan(6, start=3)["frames"] == 3000
        assert folder.plan(6)["frames"] == 7000
