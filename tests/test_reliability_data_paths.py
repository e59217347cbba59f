"""data: paths stay inside the data root; a file that is no table is not echoed."""

import pytest

from clothsim.scene import SceneError, load_scene

SCENE = '[scene]\nframes = 1\n[cloth]\nshape = "files"\nvertices = "{v}"\n'


@pytest.fixture
def root(tmp_path, monkeypatch):
    r = tmp_path / "data"
    (r / "ok").mkdir(parents=True)
    (r / "ok" / "x.txt").write_text("0 0 0\n1 0 0\n1 0 1\n")
    (tmp_path / "secret.txt").write_text("0 0 0\n1 0 0\n1 0 1\n")
    (r / "link.txt").symlink_to(tmp_path / "secret.txt")
    monkeypatch.setenv("CLOTHSIM_DATA", str(r))
    return r


@pytest.mark.parametrize("v", ["data:../secret.txt", "data:ok/../../secret.txt",
                               "data:link.txt", "data:/etc/hostname"])
def test_data_paths_outside_the_root_are_refused(root, tmp_path, v):
    p = tmp_path / "s.toml"
    p.write_text(SCENE.format(v=v))
    with pytest.raises(SceneError, match="cloth.vertices: a data: path must stay inside"):
        load_scene(p)


def test_data_path_inside_the_root_is_read(root, tmp_path):
    p = tmp_path / "s.toml"
    p.write_text(SCENE.format(v="data:ok/x.txt"))
    assert load_scene(p).build_model().vertex_count == 3


def test_a_file_that_is_no_table_is_not_echoed(tmp_path):
    secret = "TOKEN=hunter2-very-secret-value-that-must-not-leak"
    (tmp_path / "env").write_bytes(secret.encode() + b"\x00HOME=/root\x00")
    p = tmp_path / "s.toml"
    p.write_text(SCENE.format(v="env"))
    with pytest.raises(SceneError) as info:
        load_scene(p).build_model()
    assert "hunter2" not in str(info.value) and "character word" in str(info.value)
