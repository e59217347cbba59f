"""--set KEY=VALUE on the commands that load a scene: applied, validated, recorded."""

import json

import numpy as np
import pytest

import clothsim as cs
from clothsim.cli import main
from clothsim.scene.overrides import apply_overrides


def test_run_records_the_override(tmp_path):
    out = tmp_path / "d"
    code = main(["run", "hanging", "--set", "springs.structural=50", "--frames", "2",
                 "--out", str(out), "--no-preview"])
    assert code == 0
    info = json.loads((out / "run.json").read_text())
    assert info["scene"]["springs"]["structural"] == 50
    assert info["overrides"] == ["springs.structural=50"]


def test_a_misspelt_key_is_one_line_with_a_suggestion(tmp_path, capsys):
    code = main(["run", "hanging", "--set", "springs.structral=50", "--frames", "1",
                 "--out", str(tmp_path / "d")])
    err = capsys.readouterr().err.strip()
    assert code != 0 and len(err.splitlines()) == 1
    assert "--set springs.structral=50" in err and "did you mean 'structural'" in err
    assert not (tmp_path / "d" / "run.json").exists()


def test_values_are_toml_and_effects_are_indexed():
    scene = cs.load_scene("hanging", ["effects[0].acceleration=[0.0, -1.0, 0.0]",
                                      "solver.method=newton", "solver.iterations=20"])
    assert scene.data["effects"][0]["acceleration"] == [0.0, -1.0, 0.0]
    assert scene.data["solver"]["method"] == "newton"
    assert scene.data["solver"]["iterations"] == 20
    assert scene.overrides[0] == "effects[0].acceleration=[0.0, -1.0, 0.0]"
    for bad, text in ((["effects[7].kind=pin"], "the scene has 2 effects"),
                      (["solver.iterations=1 2"], "not a TOML value"),
                      (["solver.iterations=0"], "solver.iterations"),
                      (["sprngs.bending=1"], "did you mean 'springs'"),
                      (["springs"], "expected KEY=VALUE"),
                      (["springs.structural.x=1"], "is a value, not a table")):
        with pytest.raises(cs.InputError, match=text):
            cs.load_scene("hanging", bad)


def test_a_new_table_key_and_a_later_override_wins():
    doc = {"springs": {"structural": 1.0}}
    assert apply_overrides(doc, ["springs.structural=2", "springs.structural=3",
                                 "solver.tolerance=1e-6"])
    assert doc == {"springs": {"structural": 3}, "solver": {"tolerance": 1e-6}}


def test_validate_export_and_check_take_it(tmp_path, capsys):
    assert main(["validate", "hanging", "--set", "solver.iterations=3"]) == 0
    assert "ok:" in capsys.readouterr().out
    out = tmp_path / "e"
    assert main(["export", "hanging", "--set", "solver.iterations=3", "--frames", "2",
                 "--iterate-steps", "0", "--out", str(out)]) == 0
    assert "iterations 3" in (out / "settings.txt").read_text()
    capsys.readouterr()
    # the export holds 2 of the scene's 90 frames: --steps 2 checks those (a short output fails)
    assert main(["check", "hanging", str(out), "--set", "solver.iterations=3"]) == 1
    assert "the scene asks for" in capsys.readouterr().out
    assert main(["check", "hanging", str(out), "--set", "solver.iterations=3",
                 "--steps", "2"]) == 0
    assert capsys.readouterr().out.startswith("PASS")
    # without the override the 3-iteration answers are another setting's
    assert main(["check", "hanging", str(out), "--steps", "2"]) == 1
    assert np.isfinite(np.loadtxt(out / "positions.txt")).all()
