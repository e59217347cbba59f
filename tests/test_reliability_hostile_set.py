"""The last hostile scene inputs and ``--set`` changes of issue 34 (items 7, 11, 12, 13).

Each reproducer of the issue gives one line naming the key (and the ``--set`` that caused
it) or a correct result: never a Python exception text at exit 1, never a silent change.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings

import clothsim as cs
from benchmarks import fuzz_scenes
from clothsim.cli import main
from clothsim.errors import InputError
from clothsim.scene import Scene, SceneError, load_scene


def _one_line(capsys, code, expected_code=2) -> str:
    err = capsys.readouterr().err
    assert code == expected_code and err.count("\n") == 1, (code, err)
    assert "Error:" not in err and "Traceback" not in err, err
    return err.strip().removeprefix("clothsim: error: ")


# ---------------------------------------------------------------- item 7: pins that move
@pytest.mark.parametrize("resolution", [[21, 21], [31, 31], [11, 11], [2, 2], [101, 7]])
def test_hanging_hangs_from_its_two_top_corners_at_any_resolution(resolution):
    sim = load_scene("hanging", [f"cloth.resolution={resolution}"]).build_simulation()
    pinned = sim.problem().fixed_vertices
    nx, ny = resolution
    assert pinned.tolist() == [(ny - 1) * nx, ny * nx - 1]
    np.testing.assert_array_equal(sim.model.mesh.vertices[pinned],
                                  [[-0.5, 1.5, 0.0], [0.5, 1.5, 0.0]])


def test_hanging_keeps_its_corners_when_size_and_centre_change():
    sim = load_scene("hanging", ["cloth.size=[2, 1]", "cloth.center=[3, 0, 1]"]
                     ).build_simulation()
    np.testing.assert_array_equal(sim.model.mesh.vertices[sim.problem().fixed_vertices],
                                  [[2.0, 0.5, 1.0], [4.0, 0.5, 1.0]])


def test_index_pins_refuse_a_resolution_set_naming_it(tmp_path, capsys):
    p = tmp_path / "s.toml"
    p.write_text('[cloth]\nresolution = [21, 21]\nplane = "xy"\n[springs]\nstructural = 100.0\n'
                 '[[effects]]\nkind = "pin"\nvertices = [420, 440]\n')
    code = main(["validate", str(p), "--set", "cloth.resolution=[31, 31]"])
    line = _one_line(capsys, code)
    assert line.startswith("--set cloth.resolution=[31, 31]: effects[0].vertices: this pin "
                           "names vertices by index, which a new resolution moves (vertex 420 "
                           "is row 20, column 0 at 21 × 21 but row 13, column 17 at 31 × 31)")
    # the same resolution, or the vertices set along with it, is fine
    assert main(["validate", str(p), "--set", "cloth.resolution=[21, 21]"]) == 0
    assert main(["validate", str(p), "--set", "cloth.resolution=[31, 31]",
                 "--set", "effects[0].vertices=[930, 960]"]) == 0
    # an index beyond the new grid names the --set, not the file
    code = main(["validate", str(p), "--set", "cloth.resolution=[11, 11]"])
    assert _one_line(capsys, code).startswith("--set cloth.resolution=[11, 11]: effects[0]")


def test_grid_pins_are_checked_and_name_their_key():
    base = {"cloth": {"resolution": [4, 3]}, "springs": {"structural": 10.0}}
    for grid, message in (([[3, 0]], r"effects\[0\]\.grid\[0\]: \[3, 0\] is outside the 4 × 3 "
                                      r"grid \(rows -3\.\.2, columns -4\.\.3\)"),
                          ([[0]], r"effects\[0\]\.grid\[0\]: expected \[row, column\]"),
                          ("corners", r"effects\[0\]\.grid: expected an array"),
                          ([[0, 0.5]], r"effects\[0\]\.grid\[0\]\[1\]: expected an integer"),
                          ([[-1, 0], [2, -4]], r"effects\[0\]\.grid\[1\]: \[2, -4\] is vertex 8, "
                                               r"as effects\[0\]\.grid\[0\] \[-1, 0\] is")):
        with pytest.raises(SceneError, match=message):
            Scene.from_dict({**base, "effects": [{"kind": "pin", "grid": grid}]})
    with pytest.raises(SceneError, match=r"effects\[0\]\.grid: give one of 'vertices', "
                                         r"'region' or 'grid'"):
        Scene.from_dict({**base, "effects": [{"kind": "pin", "grid": [[0, 0]],
                                              "vertices": [0]}]})
    with pytest.raises(SceneError, match=r"effects\[0\]\.grid: only a grid cloth has rows"):
        Scene.from_dict({"cloth": {"shape": "polygon", "outline": [[0, 0], [1, 0], [0, 1]]},
                         "effects": [{"kind": "pin", "grid": [[0, 0]]}]})
    sim = Scene.from_dict({**base, "effects": [{"kind": "pin", "grid": [[-1, -1], [0, 1]]}]}
                          ).build_simulation()
    assert sorted(sim.problem().fixed_vertices.tolist()) == [1, 11]


def test_a_region_of_several_boxes_needs_a_vertex_in_each():
    mesh = cs.grid(5, 5, plane="xy")
    model = cs.Model.build(mesh, cs.grid_springs(mesh, structural=10.0), total_mass=1.0)
    x = mesh.vertices
    box = [{"min": x[i] - 1e-6, "max": x[i] + 1e-6} for i in (0, 24)]
    sim = cs.Simulation(model, h=1 / 30, effects=[cs.Pin(region=box)])
    assert sim.problem().fixed_vertices.tolist() == [0, 24]
    far = box + [{"min": [9, 9, 9], "max": [10, 10, 10]}]
    with pytest.raises(InputError, match=r"^pin\.region\[2\]: no vertex lies in the box"):
        cs.Simulation(model, h=1 / 30, effects=[cs.Pin(region=far)])


def test_an_error_a_set_causes_at_another_key_names_the_set(capsys):
    """flag's pin region is empty once --set moves the cloth: the --set is named, not
    the built-in file (the file itself is fine)."""
    code = main(["validate", "flag", "--set", "cloth.center=[5, 5, 5]"])
    line = _one_line(capsys, code)
    assert line.startswith("--set cloth.center=[5, 5, 5]: effects[1].region: no vertex lies")


# ---------------------------------------------------------------- item 11: exception text
def test_a_set_indexing_into_a_value_is_one_line(capsys):
    code = main(["validate", "hanging", "--set", "cloth.resolution[0].x=5"])
    assert _one_line(capsys, code) == ("--set cloth.resolution[0].x=5: cloth.resolution[0].x: "
                                       "resolution[0] is a value, not a table")


def test_spring_damping_beyond_the_factorization_is_refused_at_validate(tmp_path, capsys):
    (tmp_path / "t.txt").write_text("0 8 10 1.0 1e300\n")
    p = tmp_path / "s.toml"
    p.write_text('[cloth]\nresolution = [3, 3]\nplane = "xy"\n[springs]\nstructural = 10.0\n'
                 'table = "t.txt"\ncolumns = ["a", "b", "stiffness", "rest", "damping"]\n')
    line = _one_line(capsys, main(["validate", str(p)]))
    assert line.startswith(f"{p}: springs.table: stiffness + damping/h 3e+301 N/m is too "
                           f"large for h = 0.0333 s")


def test_symplectic_euler_with_massless_vertices_runs_and_keeps_them(tmp_path):
    doc = {"scene": {"frames": 2}, "cloth": {"resolution": [3, 3], "plane": "xy",
                                              "vertex_mass": [1.0] * 6 + [0.0, 1.0, 0.0]},
           "springs": {"structural": 10.0}, "solver": {"method": "symplectic-euler"},
           "effects": [{"kind": "gravity"}]}
    sim = Scene.from_dict(doc).build_simulation()
    x0 = sim.model.mesh.vertices.copy()
    sim.run(5)
    assert np.all(np.isfinite(sim.state.positions))
    assert sim.state.positions[[6, 8]].tolist() == x0[[6, 8]].tolist()
    assert sim.state.positions[0, 1] < x0[0, 1]
    assert np.isfinite(sim.solver.stable_h) and sim.solver.stable_h > 0


@pytest.mark.parametrize("content", [b"", b"not a zip", b"PK\x03\x04 truncated"],
                         ids=["empty", "text", "truncated-zip"])
def test_accuracy_steps_that_are_no_problem_set_are_one_line(tmp_path, capsys, content):
    steps = tmp_path / "steps.npz"
    steps.write_bytes(content)
    code = main(["accuracy", "hanging", "--quick", "--steps", str(steps),
                 "--out", str(tmp_path / "acc")])
    line = _one_line(capsys, code)
    assert line.startswith(f"accuracy.steps: '{steps}' is ")
    assert not (tmp_path / "acc").exists()  # refused before the study's folder is made


def test_compare_plot_to_a_folder_or_a_text_file_is_one_line_before_comparing(tmp_path,
                                                                             capsys):
    assert main(["run", "hanging", "--frames", "1", "--out", str(tmp_path / "r"),
                 "--no-preview"]) == 0
    capsys.readouterr()
    traj = str(tmp_path / "r" / "trajectory.npz")
    for plot, why in ((tmp_path, "is a folder; give an image file name"),
                      (tmp_path / "x.txt", "cannot tell the image format from '.txt'")):
        code = main(["compare", traj, traj, "--plot", str(plot)])
        out = capsys.readouterr()
        assert code == 2 and out.out == "", out  # refused before the comparison
        assert out.err.startswith("clothsim: error: --plot: ") and why in out.err
    assert main(["compare", traj, traj, "--plot", str(tmp_path / "d.png"), "--no-table"]) == 0
    assert (tmp_path / "d.png").stat().st_size > 0


# ---------------------------------------------------------------- item 12: misreported
def test_pin_stiffness_without_pins_to_hold_is_refused(capsys):
    code = main(["validate", "hanging", "--set", "cloth.pin_stiffness=1e5"])
    assert _one_line(capsys, code).startswith(
        "--set cloth.pin_stiffness=1e5: cloth.pin_stiffness: the cloth's files declare no pins")


def test_a_pin_stiffness_lost_in_rounding_is_refused(tmp_path, capsys):
    (tmp_path / "t.txt").write_text("0 -1 1e4 0\n")
    p = tmp_path / "s.toml"
    p.write_text('[cloth]\nresolution = [3, 3]\n[springs]\nstructural = 10.0\ntable = "t.txt"\n')
    code = main(["validate", str(p), "--set", "cloth.pin_stiffness=5e-324"])
    assert _one_line(capsys, code).startswith(
        "--set cloth.pin_stiffness=5e-324: cloth.pin_stiffness: 5e-324 N/m is lost in the "
        "rounding of vertex 0's mass")
    code = main(["validate", "hanging", "--set", 'effects[1].method="penalty"',
                 "--set", "effects[1].stiffness=5e-324"])
    assert "effects[1].stiffness: 5e-324 N/m is lost in the rounding" in _one_line(capsys, code)
    assert main(["validate", str(p), "--set", "cloth.pin_stiffness=1e-3"]) == 0  # weak, held


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs FIFOs")
@pytest.mark.parametrize("key", ["force", "table", "vertex_mass"])
def test_a_fifo_or_device_as_a_scene_file_is_named_as_such(tmp_path, capsys, key):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    for target, what in ((fifo, "a FIFO (named pipe)"), ("/dev/zero", "a character device")):
        text = {"force": f'[[effects]]\nkind = "force"\nfile = "{target}"\n',
                "table": f'[springs]\nstructural = 10.0\ntable = "{target}"\n',
                "vertex_mass": f'[cloth]\nvertex_mass = "{target}"\n'}[key]
        p = tmp_path / "s.toml"
        p.write_text(text)
        line = _one_line(capsys, main(["validate", str(p)]))
        assert re.search(rf": (effects\[0\]\.file|springs\.table|cloth\.vertex_mass): is "
                         rf"{re.escape(what)}, not a regular file", line), line
        assert "not found" not in line


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs FIFOs")
def test_a_fifo_or_device_as_steps_or_force_file_is_named_as_such(tmp_path, capsys):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    for target, what in ((fifo, "a FIFO (named pipe)"), ("/dev/zero", "a character device")):
        code = main(["accuracy", "hanging", "--quick", "--steps", str(target),
                     "--out", str(tmp_path / "acc")])
        assert _one_line(capsys, code) == (f"accuracy.steps: '{target}' is {what}, not a "
                                           f"regular file")
        with pytest.raises(InputError, match="is a FIFO or a device, not a regular file"):
            cs.Force(file=target)
    assert not (tmp_path / "acc").exists()


# ---------------------------------------------------------------- item 13: help example
def test_the_set_examples_of_the_help_work_on_the_default_scene(capsys):
    assert main(["run", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    sentence = re.search(r"--set KEY=VALUE change a scene key, e\.g\. (.*?) \(a TOML", text)[1]
    examples = [a or b for a, b in re.findall(r"'([^']+)'|([\w.\[\]]+=[^,\s]+)", sentence)]
    assert "effects[0].acceleration=[0, -1.62, 0]" in examples and len(examples) == 3, examples
    for example in examples:
        assert main(["validate", "drop-on-square", "--set", example]) == 0, example


# ---------------------------------------------------------------- the fuzz of --set
@settings(max_examples=150, deadline=None)
@given(item=fuzz_scenes.set_change())
def test_hostile_set_changes_exit_2_naming_the_set_or_a_key(tmp_path_factory, item):
    """One hostile --set on a valid scene (benchmarks/fuzz_scenes.py's generator): accepted,
    or one line naming the --set or the key; `run` refuses it identically, writing nothing."""
    p = tmp_path_factory.mktemp("set") / "scene.toml"
    p.write_text(fuzz_scenes.to_toml(fuzz_scenes.VALID))
    kind, line = fuzz_scenes.outcome(p, [item])
    assert kind in ("accepted", "refused"), line
    named = " ".join(f"--set {item}: ".split())  # (the message is one line, spaces collapsed)
    assert kind == "accepted" or line.startswith(named), line  # the file itself is fine


def test_the_documented_fuzz_counts_show_nothing_wrong():
    """docs/data/fuzz.md is written by `python -m benchmarks fuzz_scenes`, not by hand."""
    text = fuzz_scenes.OUT.read_text(encoding="utf-8")
    assert text.startswith("Printed by `.venv/bin/python -m benchmarks fuzz_scenes`")
    for name in ("scene files", "--set"):
        m = re.search(rf"^{re.escape(name)}: (\d+) cases; (\d+) accepted .*?; (\d+) refused "
                      rf".*?; (\d+) otherwise", text, re.M)
        assert m, name
        total, accepted, refused, wrong = map(int, m.groups())
        assert total == fuzz_scenes.EXAMPLES == accepted + refused + wrong and wrong == 0
    assert "fuzz.md" in (Path(__file__).parents[1] / "docs" / "reliability.md").read_text()
