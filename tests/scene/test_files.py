"""Where scenes and their data are found: the data root behind ``data:``, the old
``data:<file>`` form of the assignment scenes, built-in scenes and ``scenes --show``."""

import shutil
import tomllib

import pytest

from clothsim import cli
from clothsim.scene import (
    SceneError,
    builtin_scene_path,
    data_dir,
    data_root,
    list_builtin_scenes,
    load_scene,
)


def test_scenes_show_prints_the_builtin_toml(capsys):
    assert cli.main(["scenes", "--show", "hanging"]) == 0
    out = capsys.readouterr().out
    assert out == builtin_scene_path("hanging").read_text(encoding="utf-8")
    assert tomllib.loads(out)["scene"]["name"] == "hanging"


def test_scenes_show_unknown_name_is_one_line(capsys):
    assert cli.main(["scenes", "--show", "hangin"]) == 2
    err = capsys.readouterr().err
    assert err == ("clothsim: error: hangin: no such built-in scene; did you mean "
                   "'hanging'?\n")


def test_every_builtin_scene_validates_or_needs_data():
    for name in list_builtin_scenes():
        try:
            load_scene(name)
        except SceneError as exc:  # only the third-party files may be missing (offline)
            assert name.startswith("jacobson-") and "\n" not in str(exc), exc
            assert "`clothsim data fetch jacobson-a8`" in str(exc)
            assert "or set CLOTHSIM_DATA" in str(exc)


def _fake_root(tmp_path):
    root = tmp_path / "data"
    (root / "jacobson-a8").mkdir(parents=True)
    (root / "jacobson-a8" / "s.obj").write_text("v 0 0 0\nv 1 0 0\nf 1 2\n")
    (root / "jacobson-a8" / "s.json").write_text('{"obj": "s.obj", "b": [1], "k": 10, "m": 1}')
    (root / "other").mkdir()
    (root / "other" / "x.txt").write_text("0 0 0 1 0 0 0 0 1\n")
    return root


@pytest.mark.parametrize("form", ["data:jacobson-a8/s.json", "data:s.json"])
def test_data_prefix_is_the_data_root_and_the_old_form_still_works(tmp_path, monkeypatch,
                                                                     form):
    root = _fake_root(tmp_path)
    monkeypatch.setenv("CLOTHSIM_DATA", str(root))
    assert data_root() == root and data_dir() == root / "jacobson-a8"
    p = tmp_path / "a.toml"
    p.write_text(f'[cloth]\nshape = "jacobson"\nfile = "{form}"\n')
    scene = load_scene(p)
    assert scene.data["cloth"]["file"] == str((root / "jacobson-a8" / "s.json").resolve())
    assert scene.build_model().vertex_count == 2
    p.write_text('[cloth]\nshape = "files"\nvertices = "data:other/x.txt"\n')
    assert load_scene(p).build_model().vertex_count == 3


def test_data_variable_may_name_the_assignment_folder_itself(tmp_path, monkeypatch):
    root = _fake_root(tmp_path)
    monkeypatch.setenv("CLOTHSIM_DATA", str(root / "jacobson-a8"))
    assert data_dir() == root / "jacobson-a8"
    for form in ("data:s.json", "data:jacobson-a8/s.json"):
        p = tmp_path / "a.toml"
        p.write_text(f'[cloth]\nshape = "jacobson"\nfile = "{form}"\n')
        assert load_scene(p).build_model().vertex_count == 2


def test_builtin_assignment_scenes_use_the_data_root():
    for name in list_builtin_scenes():
        if name.startswith("jacobson-"):
            text = builtin_scene_path(name).read_text()
            assert 'file = "data:jacobson-a8/' in text


def test_missing_file_and_directory_are_told_apart(tmp_path, monkeypatch):
    root = _fake_root(tmp_path)
    monkeypatch.setenv("CLOTHSIM_DATA", str(root))
    p = tmp_path / "a.toml"
    p.write_text('[cloth]\nshape = "jacobson"\nfile = "data:jacobson-a8"\n')
    with pytest.raises(SceneError, match=r": cloth.file: is a directory, not a file: "):
        load_scene(p)
    p.write_text('[cloth]\nshape = "jacobson"\nfile = "data:nothing.json"\n')
    with pytest.raises(SceneError, match=r": cloth.file: file not found: "):
        load_scene(p)
    shutil.rmtree(root)
    with pytest.raises(SceneError, match=r": cloth.file: data directory .* not found "
                                         r"\(CLOTHSIM_DATA names it\)"):
        load_scene(p)


def test_scene_path_that_is_a_directory(tmp_path, capsys):
    assert cli.main(["validate", str(tmp_path)]) == 2
    assert "is a directory, not a scene file" in capsys.readouterr().err
