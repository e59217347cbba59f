"""The clothsim command: subcommands, exit statuses, one-line errors, and the built-in
demos run end to end (--frames 2)."""

import json
import subprocess
import sys

import numpy as np
import pytest

from clothsim import cli, io
from clothsim.scene import list_builtin_scenes
from clothsim.simulation import Simulation

from .data_sets import assignment_dir, write_assignment_scene

RESULTS = ("trajectory.pvd", "trajectory.npz", "preview.gif", "final.png", "run.json")


def check_results(out, frames, vertex_count=None):
    for name in RESULTS:
        assert (out / name).stat().st_size > 0, name
    z = np.load(out / "trajectory.npz")
    assert z["positions"].shape[0] == frames + 1
    if vertex_count is not None:
        assert z["positions"].shape[1] == vertex_count
    assert np.all(np.isfinite(z["positions"]))
    x, _ = io.read_frame(out / f"frame_{frames:06d}.vtu")
    assert np.array_equal(x, z["positions"][-1])
    run = json.loads((out / "run.json").read_text())
    assert run["status"] == "completed" and run["last_frame"] == frames
    return z, run


def test_scenes_lists_builtins(capsys):
    assert cli.main(["scenes"]) == 0
    lines = capsys.readouterr().out.splitlines()
    names = list_builtin_scenes()
    assert len(lines) == len(names)
    for line, (name, desc) in zip(lines, names.items()):
        assert line.split()[0] == name and desc in line


def test_validate_ok(capsys):
    assert cli.main(["validate", "hanging"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("ok: ") and "441 vertices" in out and "gravity, pin" in out


@pytest.mark.parametrize("scene, vertices", [("drop-on-square", 625), ("impulse", 625)])
def test_seed_demos_run(tmp_path, capsys, scene, vertices):
    out = tmp_path / scene
    assert cli.main(["run", scene, "--out", str(out), "--frames", "2"]) == 0
    z, run = check_results(out, 2, vertices)
    assert run["effects_built"][0] == "gravity"
    # after 2 frames (1/15 s) of free fall the cloth is still above its obstacle, and
    # it fell by about g t^2 / 2 (implicit Euler with v0 = 0: g h^2 (1 + 2) = 0.0327 m)
    drop = z["positions"][0, :, 1].mean() - z["positions"][2, :, 1].mean()
    assert drop == pytest.approx(9.81 * 3 / 900, rel=0.05)


def test_default_scene_and_out_dir(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert cli.main(["run", "--frames", "1", "--no-preview"]) == 0
    out = tmp_path / "out" / "drop-on-square"
    assert (out / "frame_000001.vtu").is_file() and (out / "run.json").is_file()
    assert not (out / "preview.gif").exists()
    assert "drop-on-square: 1 frames written" in capsys.readouterr().out


@pytest.mark.slow
@pytest.mark.parametrize("scene, vertices", [("jacobson-flag", 3200),
                                             ("jacobson-skirt", 9840)])
def test_jacobson_cloths_run(tmp_path, scene, vertices):
    data = assignment_dir()  # third party: skipped when absent
    out = tmp_path / scene
    assert cli.main(["run", scene, "--out", str(out), "--frames", "2"]) == 0
    z, run = check_results(out, 2, vertices)
    assert run["effects_built"] == ["pin", "force"]  # the assignment: −9.8 N per vertex
    pins = np.asarray(json.loads((data / f"{scene[9:]}.json").read_text())["b"]) - 1
    # the assignment's penalty pins (w = 1e10 N/m) hold within load / w, far below 1e-6 m
    moved = np.abs(z["positions"][2][pins] - z["positions"][0][pins]).max()
    assert 0 < moved < 1e-6
    free = np.setdiff1d(np.arange(vertices), pins)
    assert z["positions"][2][free, 1].mean() < z["positions"][0][free, 1].mean()


def test_jacobson_json_runs_directly(tmp_path):
    path = write_assignment_scene(tmp_path, "chain")  # as the assignment's horizontal chain
    out = tmp_path / "chain"
    assert cli.main(["run", str(path), "--out", str(out), "--frames", "3"]) == 0
    z, run = check_results(out, 3, 10)
    # both ends pinned (by the assignment's w = 1e10 N/m penalty: they give by load / w,
    # about 1e-9 m), the middle sags; the chain stays symmetric about its middle
    y = z["positions"][3][:, 1]
    assert abs(y[0]) < 1e-8 and abs(y[9]) < 1e-8 and y[4] < -0.01
    np.testing.assert_allclose(y, y[::-1], atol=1e-12)


def test_usage_error_exit_2(capsys):
    assert cli.main(["run", "--frames", "many"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("clothsim: error: argument --frames")
    assert cli.main([]) == 2
    assert cli.main(["run", "--frames", "-1"]) == 2
    assert capsys.readouterr().err.count("\n") == 2


def test_interrupt_exit_130_and_error_exit_1(tmp_path, monkeypatch, capsys):
    def boom(self):
        raise KeyboardInterrupt

    monkeypatch.setattr(Simulation, "step", boom)
    assert cli.main(["run", "hanging", "--out", str(tmp_path / "a"), "--frames", "3"]) == 130
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "interrupted" in err
    run = json.loads((tmp_path / "a" / "run.json").read_text())
    assert run["status"] == "interrupted" and run["last_frame"] == 0

    def fail(self):
        raise FloatingPointError("overflow\nin solve")

    monkeypatch.setattr(Simulation, "step", fail)
    assert cli.main(["run", "hanging", "--out", str(tmp_path / "b"), "--frames", "3"]) == 1
    err = capsys.readouterr().err
    assert err == "clothsim: error: FloatingPointError: overflow in solve\n"


def test_resume_from_cli(tmp_path, monkeypatch, capsys):
    out = tmp_path / "r"
    real, calls = Simulation.step, {"n": 0}

    def step(self):
        calls["n"] += 1
        if calls["n"] == 3:
            raise KeyboardInterrupt
        return real(self)

    with monkeypatch.context() as m:
        m.setattr(Simulation, "step", step)
        assert cli.main(["run", "hanging", "--out", str(out), "--frames", "4",
                         "--no-preview"]) == 130
    assert cli.main(["run", "hanging", "--out", str(out), "--frames", "4", "--resume",
                     "--no-preview"]) == 0
    run = json.loads((out / "run.json").read_text())
    assert run["status"] == "completed" and run["resumed_from"] == 2


def test_accuracy_subcommand_is_registered(capsys):
    assert cli.main(["accuracy", "--help"]) == 0
    assert "--quick" in capsys.readouterr().out


def test_python_dash_m(tmp_path):
    r = subprocess.run([sys.executable, "-m", "clothsim", "validate", "nope.toml"],
                       capture_output=True, text=True, cwd=tmp_path, timeout=60)
    assert r.returncode == 2 and r.stdout == ""
    assert r.stderr == "clothsim: error: nope.toml: file not found\n"


def test_without_out_the_run_stays_in_out_and_never_touches_the_current_folder(
        tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "frame_000000.vtu").write_text("a file of the user")
    (tmp_path / "run.json").write_text("{}")
    assert cli.main(["run", "hanging", "--frames", "1", "--no-preview"]) == 0
    assert (tmp_path / "frame_000000.vtu").read_text() == "a file of the user"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["frame_000000.vtu", "out",
                                                          "run.json"]
    assert (tmp_path / "out" / "hanging" / "frame_000001.vtu").is_file()
    capsys.readouterr()
    scene = tmp_path / "dots.toml"
    scene.write_text('[scene]\nname = ".."\n[[effects]]\nkind = "gravity"\n')
    assert cli.main(["run", str(scene), "--frames", "1"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "scene.name" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dots.toml", "frame_000000.vtu",
                                                          "out", "run.json"]
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["hanging"]


def test_a_blowup_exits_1_with_one_line(tmp_path, capsys):
    scene = tmp_path / "blow.toml"
    scene.write_text('[scene]\nname = "blow"\nframes = 60\n[cloth]\nplane = "xy"\n'
                     'resolution = [5, 5]\n[springs]\nstructural = 1e9\nshear = 1e9\n'
                     '[solver]\nmethod = "symplectic-euler"\n[[effects]]\nkind = "gravity"\n')
    code = cli.main(["run", str(scene), "--out", str(tmp_path / "o"), "--no-preview"])
    assert code == 1
    err = capsys.readouterr().err   # the error, then one summary line per warning kind
    errors = [line for line in err.splitlines() if line.startswith("clothsim: error:")]
    assert len(errors) == 1 and errors[0].startswith("clothsim: error: frame ")
    assert "Traceback" not in err and all(line.startswith("clothsim: ")
                                          for line in err.splitlines())
    assert "the state became non-finite (" in err
    assert json.loads((tmp_path / "o" / "run.json").read_text())["status"] == "failed"
