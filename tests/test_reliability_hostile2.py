"""Hostile users and fresh machines, round 2: what an outsider found with paths, folders and
resumes that the first rounds did not try.

Each case is a reproducer of a finding: one line naming the path or key, exit status 2 (bad
input) and nothing written, or a correct result.
"""

from __future__ import annotations

import errno
import os
import shutil

import numpy as np
import pytest

import clothsim as cs
from clothsim.cli import main
from clothsim.errors import InputError
from clothsim.scene import find_scene


def _one_line(capsys, code, expected_code=2) -> str:
    err = capsys.readouterr().err
    assert code == expected_code and err.count("\n") == 1, (code, err)
    assert "Error:" not in err and "Traceback" not in err, err
    return err.strip().removeprefix("clothsim: error: ")


# ------------------------------------------------------------------ the scene argument
def test_a_folder_as_the_scene_is_named_once(tmp_path, capsys):
    line = _one_line(capsys, main(["validate", str(tmp_path)]))
    assert line == f"{tmp_path}: is a directory, not a scene file"  # was: the path twice


@pytest.mark.skipif(not hasattr(os, "mkfifo") or not os.path.exists("/dev/null"),
                    reason="needs FIFOs and /dev/null")
def test_a_device_or_fifo_as_the_scene_is_named_as_such_not_missing(tmp_path, capsys):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    for target, what in (("/dev/null", "a character device"), (fifo, "a FIFO (named pipe)")):
        line = _one_line(capsys, main(["run", str(target), "--out", str(tmp_path / "o")]))
        assert line == f"{target}: is {what}, not a scene file", line  # was: file not found
        with pytest.raises(InputError, match="not a scene file"):
            find_scene(target)
    assert not (tmp_path / "o").exists()


# ------------------------------------------------------------------ --out inside a file
@pytest.mark.parametrize("command", [["run", "hanging", "--frames", "1", "--no-preview"],
                                     ["export", "hanging", "--frames", "1"],
                                     ["accuracy", "hanging", "--quick"],
                                     ["conformance"]])
def test_an_out_folder_below_a_file_is_bad_input_naming_the_file(tmp_path, capsys, command):
    afile = tmp_path / "notes.txt"
    afile.write_text("mine\n")
    out = afile / "sub" / "deeper"
    line = _one_line(capsys, main(command + ["--out", str(out)]))  # was: exit 1, Not a directory
    assert line == f"{out}: cannot be a folder: {afile} is a file, not a folder"
    assert afile.read_text() == "mine\n"


# ------------------------------------------------------------------ --resume of another scene
@pytest.fixture(scope="module")
def hanging_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("run") / "hanging"
    assert main(["run", "hanging", "--frames", "2", "--no-preview", "--out", str(out)]) == 0
    return out


@pytest.mark.parametrize("change, differs", [
    (["drop-on-square"], "scene.name: 'hanging' there, 'drop-on-square' now"),
    (["hanging", "--set", "cloth.mass=2"], "cloth.mass: 1.0 there, 2.0 now"),
    (["hanging", "--set", "solver.iterations=11"], "solver.iterations: 10 there, 11 now"),
    (["hanging", "--set", "effects[0].acceleration=[0, -9.8, 0]"],
     "effects[0].acceleration[1]: -9.81 there, -9.8 now"),
])
def test_resume_of_another_scene_names_the_key_that_differs(hanging_run, capsys, change,
                                                            differs):
    before = {p.name: p.stat().st_mtime_ns for p in hanging_run.iterdir()}
    code = main(["run", *change, "--frames", "4", "--no-preview", "--resume",
                 "--out", str(hanging_run)])
    line = _one_line(capsys, code)
    assert line == (f"{hanging_run}: cannot resume: it holds a run of a different scene "
                    f"({differs}); run without --resume to start afresh, or choose another "
                    "--out"), line  # was: two scene hashes, nothing a user can act on
    assert {p.name: p.stat().st_mtime_ns for p in hanging_run.iterdir()} == before
    # more frames and another output setting are the same scene: it resumes
    assert main(["run", "hanging", "--frames", "3", "--no-preview", "--resume",
                 "--set", "output.frame_compression=none", "--out", str(hanging_run)]) == 0


# ------------------------------------------------------------------ the Python API
def _api_cases():
    mesh = cs.grid(4, 4)
    model = cs.Model.build(mesh, cs.grid_springs(mesh, structural=100.0), total_mass=1.0)
    f64, i64 = np.float64, np.int64
    return {
        # numpy scalars (numpy >= 2 shows them as np.float64(…)) are shown as numbers
        "box": (lambda: cs.Box(min=(0, 0, 0), max=(f64(0), 1, 1)),
                "box.min[0]: must be less than box.max[0], got 0.0 >= 0.0"),
        "sphere": (lambda: cs.Sphere(center=(0, 0, 0), radius=f64(-1)),
                   "sphere.radius: must be one positive number, got -1.0"),
        "impulse radius": (lambda: cs.Impulse(force=(0, 1, 0), center=(0, 0, 0),
                                              radius=f64(-1)),
                           "impulse.radius: must be one positive number, got -1.0"),
        "impulse start": (lambda: cs.Impulse(force=(0, 1, 0), center=(0, 0, 0), radius=0.1,
                                             start=f64(-1)),
                          "impulse.start: must be one non-negative number, got -1.0"),
        "impulse duration": (lambda: cs.Impulse(force=(0, 1, 0), center=(0, 0, 0),
                                                radius=0.1, duration=f64(-1)),
                             "impulse.duration: must be positive (inf allowed), got -1.0"),
        "grid size": (lambda: cs.grid(3, 3, size=(f64(-1), 1)),
                      "size: both extents must be positive, got [-1.0, 1.0]"),
        "grid count": (lambda: cs.grid(i64(1), 3),
                       "resolution: nx must be an integer >= 2, got 1"),
        "iterations": (lambda: cs.Simulation(model, h=0.1, iterations=i64(0)),
                       "solver.iterations: must be an integer >= 1, got 0"),
        # values that raised ValueError, TypeError or OverflowError from inside numpy/Python
        "grid nan": (lambda: cs.grid(float("nan"), 3),
                     "resolution: nx must be an integer >= 2, got nan"),
        "grid inf": (lambda: cs.grid(3, float("inf")),
                     "resolution: ny must be an integer >= 2, got inf"),
        "grid text": (lambda: cs.grid("four", 3), "resolution: nx must be an integer >= 2, "
                                                  "got 'four'"),
        "grid None": (lambda: cs.grid(None, 3),
                      "resolution: nx must be an integer >= 2, got None"),
        "total_mass array": (lambda: cs.Model.build(mesh, cs.grid_springs(mesh),
                                                    total_mass=[1.0, 2.0]),
                             "total_mass: must be one number [kg], got shape (2,) "
                             "(vertex_mass= takes one mass per vertex)"),
        "pin text": (lambda: cs.Pin(["a"]), "pin.vertices: must be integer vertex indices"),
        "method=": (lambda: cs.Simulation(model, h=0.1, method="newton"),
                    "method: Simulation takes the method as solver=, e.g. solver='newton'"),
        "one effect": (lambda: cs.Simulation(model, h=0.1, effects=cs.Gravity((0, -9.81, 0))),
                       "effects: expected a list of effects, got Gravity "
                       "(write effects=[...])"),
    }


@pytest.mark.parametrize("case", list(_api_cases()))
def test_hostile_api_arguments_are_one_line_input_errors_with_plain_numbers(case):
    make, message = _api_cases()[case]
    with pytest.raises(InputError) as info:
        make()
    assert str(info.value) == message


def test_whole_numbers_of_any_type_still_make_grids():
    for nx in (3, 3.0, np.int32(3), np.float64(3.0), np.uint8(3)):
        assert len(cs.grid(nx, 2).vertices) == 6


# ------------------------------------------------------------------ a full disk at the start
def test_a_full_disk_at_the_lock_leaves_no_lock_file_and_no_new_folder(tmp_path, capsys,
                                                                        monkeypatch):
    """The disk filled before the run's first file: writing the holder's pid into the lock
    file failed, and the lock file (and the folder made for it) stayed behind."""
    import clothsim.io.lock as lock

    def full(fd, data, offset):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(lock.os, "pwrite", full)
    new = tmp_path / "new" / "run"
    mine = tmp_path / "mine"
    mine.mkdir()
    for out in (new, mine):
        code = main(["run", "hanging", "--frames", "2", "--no-preview", "--out", str(out)])
        assert _one_line(capsys, code, 1) == f"{out}: No space left on device; nothing was " \
                                              "written"
    assert not (tmp_path / "new").exists()             # made by the run: removed again
    assert mine.is_dir() and not any(mine.iterdir())   # the user's: kept, and empty
    monkeypatch.undo()
    assert main(["run", "hanging", "--frames", "2", "--no-preview", "--out", str(mine)]) == 0


def test_a_run_the_disk_cannot_hold_leaves_no_new_folder(tmp_path, capsys, monkeypatch):
    import clothsim.io.diskspace as diskspace

    monkeypatch.setattr(diskspace, "free_bytes", lambda path: 300_000)
    out = tmp_path / "a" / "b"
    code = main(["run", "hanging", "--frames", "30", "--no-preview", "--out", str(out)])
    line = _one_line(capsys, code)
    assert line.startswith(f"{out}: the run needs about ")
    assert line.endswith("are free on its disk; choose another --out on a larger disk"), line
    assert not (tmp_path / "a").exists()  # was: an empty folder a/b left behind


# ------------------------------------------------------------------ the folder vanishes
@pytest.mark.parametrize("how", ["removed", "moved"])
def test_a_run_folder_that_vanishes_mid_run_is_not_called_nothing_written(tmp_path, capsys,
                                                                          monkeypatch, how):
    """rm -rf or mv of the folder while the run writes: the line said 'nothing was written'
    (run.json was not where it looked), though frames had been written; a moved folder is
    resumable where it went."""
    import clothsim.cli as cli

    out, moved = tmp_path / "r", tmp_path / "moved"

    class Vanish:  # the CLI's progress lines (stderr is no terminal here), at frame 3
        def __init__(self, name):
            pass

        def __call__(self, k, total):
            if k == 3 and out.exists():
                shutil.rmtree(out) if how == "removed" else out.rename(moved)

    monkeypatch.setattr(cli, "ProgressLines", Vanish)
    code = main(["run", "hanging", "--frames", "8", "--no-preview", "--out", str(out)])
    line = _one_line(capsys, code, 1)
    assert line.startswith(f"{out}: No such file or directory"), line
    assert line.endswith("; the folder was removed or moved while the run wrote into it "
                         "(moved: --resume continues it where it went)"), line
    assert not out.exists()
    if how == "moved":
        monkeypatch.undo()
        assert main(["run", "hanging", "--frames", "8", "--no-preview", "--resume",
                     "--out", str(moved)]) == 0
        assert len(list(moved.glob("frame_*.vtu"))) == 9


# ------------------------------------------------------------------ colour fields overflow
def test_colour_fields_beyond_float32_are_inf_without_a_cryptic_warning(tmp_path, capsys):
    """A sphere of radius 1e30 around the cloth pushes it 1e30 m out: the frame's float32
    colour fields (area ratio ~1e60) overflowed and the run ended with 'WARNING:
    RuntimeWarning (3 times): overflow encountered in cast', naming nothing."""
    out = tmp_path / "r"
    assert main(["run", "drape-sphere", "--frames", "1", "--no-preview", "--out", str(out),
                 "--set", "effects[1].radius=1e30"]) == 0
    err = capsys.readouterr().err
    assert "overflow" not in err and "RuntimeWarning" not in err, err
    from clothsim.io.frames import read_frame

    x, v = read_frame(out / "frame_000001.vtu")  # the state itself is float64: finite
    assert np.isfinite(x).all() and np.isfinite(v).all() and np.abs(x).max() > 1e29


# ------------------------------------------------------------------ compare a blown-up port
def test_compare_names_where_a_trajectory_stops_being_finite(tmp_path, capsys):
    """A port that blew up writes NaN: compare said only 'max error inf m', which hides
    that the port's own numbers are NaN (not far off) and from where."""
    x = np.zeros((4, 9, 3)) + np.linspace(0, 1, 9)[None, :, None]
    np.savez(tmp_path / "ref.npz", positions=x)
    y = x.copy()
    y[2:, 7] = np.nan
    np.savez(tmp_path / "port.npz", positions=y)
    assert main(["compare", str(tmp_path / "port.npz"), str(tmp_path / "ref.npz")]) == 1
    out = capsys.readouterr().out
    assert ("note: the trajectory's positions are not finite (NaN or inf) at 2 of 36 "
            "(frame, vertex) pairs, first at frame 2 vertex 7; the error counts as inf there"
            ) in out, out
    assert "first failing frame 2 vertex 7" in out
    assert main(["compare", str(tmp_path / "ref.npz"), str(tmp_path / "port.npz")]) == 1
    assert "note: the reference's positions are not finite" in capsys.readouterr().out
    assert main(["compare", str(tmp_path / "ref.npz"), str(tmp_path / "ref.npz")]) == 0
    assert "not finite" not in capsys.readouterr().out


# ------------------------------------------------------------------ a cloth's file key
@pytest.mark.parametrize("shape, key, hint", [
    ("mesh", "file", "; a mesh cloth reads its file from cloth.mesh"),
    ("jacobson", "mesh", "; a jacobson cloth reads its file from cloth.file"),
    ("grid", "mesh", ""),  # a grid reads no file: nothing to point at
])
def test_the_file_key_of_another_shape_points_at_this_shapes_key(tmp_path, capsys, shape,
                                                                 key, hint):
    p = tmp_path / "s.toml"
    p.write_text(f'[cloth]\nshape = "{shape}"\n{key} = "cloth.obj"\n')
    line = _one_line(capsys, main(["validate", str(p)]))
    assert line.startswith(f"{p}: cloth.{key}: not used with cloth.shape = '{shape}'"), line
    assert line.endswith(")" + hint), line


def test_a_bad_vertex_in_a_mesh_file_names_the_key_the_user_wrote(tmp_path, capsys):
    (tmp_path / "m.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv nan 0 0\nf 1 2 3\n")
    p = tmp_path / "s.toml"
    p.write_text('[cloth]\nshape = "mesh"\nmesh = "m.obj"\n[springs]\nstructural = 10.0\n')
    line = _one_line(capsys, main(["validate", str(p)]))
    assert line == f"{p}: cloth.mesh: vertices[3, 0]: must be a finite number, got nan", line
