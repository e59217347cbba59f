"""A run never silently replaces another scene's run in the default folder out/<name>."""

from clothsim.cli import main
from clothsim.scene import builtin_scene_text


def test_a_copy_with_the_same_name_is_refused_naming_both(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["run", "hanging", "--frames", "3", "--no-preview"]) == 0
    before = sorted(p.name for p in (tmp_path / "out" / "hanging").iterdir())
    copy = tmp_path / "my-scene.toml"
    copy.write_text(builtin_scene_text("hanging").replace("frames = 90", "frames = 2"))
    capsys.readouterr()
    assert main(["run", str(copy), "--no-preview"]) == 2
    err = capsys.readouterr().err
    assert "another scene" in err and "my-scene.toml" in err and "hanging.toml" in err
    assert "--out DIR" in err and "--force" in err
    assert sorted(p.name for p in (tmp_path / "out" / "hanging").iterdir()) == before
    # the same scene again, or with --force / --out, is fine
    assert main(["run", "hanging", "--frames", "3", "--no-preview"]) == 0
    assert main(["run", str(copy), "--no-preview", "--out", "out/mine"]) == 0
    assert main(["run", str(copy), "--no-preview", "--force"]) == 0


def test_another_version_of_the_scene_suggests_resume(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["run", "hanging", "--frames", "2", "--no-preview"]) == 0
    capsys.readouterr()
    assert main(["run", "hanging", "--set", "solver.iterations=3", "--frames", "2",
                 "--no-preview"]) == 2
    err = capsys.readouterr().err
    assert "another version of this scene" in err and "--resume" in err


def test_an_export_of_another_scene_is_refused_too(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["export", "hanging", "--frames", "1", "--iterate-steps", "0"]) == 0
    copy = tmp_path / "other.toml"
    copy.write_text(builtin_scene_text("hanging").replace("mass = 1.0", "mass = 2.0"))
    capsys.readouterr()
    assert main(["export", str(copy), "--frames", "1", "--iterate-steps", "0"]) == 2
    assert "holds an export of another scene" in capsys.readouterr().err
    assert main(["export", "hanging", "--frames", "1", "--iterate-steps", "0"]) == 0


def test_the_default_accuracy_folder_keeps_another_scenes_study(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "accuracy-out").mkdir()
    (tmp_path / "accuracy-out" / "accuracy.json").write_text('{"scene": "drop-on-square"}')
    assert main(["accuracy", "hanging", "--quick"]) == 2
    err = capsys.readouterr().err
    assert "holds the accuracy study of 'drop-on-square', not of 'hanging'" in err
    assert (tmp_path / "accuracy-out" / "accuracy.json").read_text() == \
        '{"scene": "drop-on-square"}'
