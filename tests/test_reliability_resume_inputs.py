"""--resume checks every input file by content: a changed pin file (or any other file the
scene reads) is refused, naming the file; run.json records the hashes at the start."""

import json

import pytest

from clothsim.cli import main
from clothsim.errors import InputError
from clothsim.runner import run_scene
from clothsim.scene import load_scene
from clothsim.scene.inputs import changed_input, input_files, input_hashes

SCENE = """
[scene]
name = "pinned"
frames = 2
fps = 30
[cloth]
resolution = [3, 3]
plane = "xy"
[springs]
structural = 200.0
[[effects]]
kind = "gravity"
[[effects]]
kind = "pin"
vertices = "pins.txt"
index_base = 0
"""


@pytest.fixture
def scene(tmp_path):
    (tmp_path / "pins.txt").write_text("6 8\n")
    p = tmp_path / "s.toml"
    p.write_text(SCENE)
    return p


def test_run_json_records_every_input_file(scene, tmp_path):
    out = tmp_path / "out"
    run_scene(str(scene), out, preview=False)
    inputs = json.loads((out / "run.json").read_text())["inputs"]
    pins = str((tmp_path / "pins.txt").resolve())
    assert list(inputs) == [pins] and len(inputs[pins]) == 64


def test_resume_after_editing_the_pin_file_is_refused(scene, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["run", str(scene), "--out", str(out), "--frames", "1", "--no-preview"]) == 0
    record = (out / "run.json").read_bytes()
    (tmp_path / "pins.txt").write_text("0 2\n")
    assert main(["run", str(scene), "--out", str(out), "--frames", "2", "--resume",
                 "--no-preview"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "pins.txt" in err and "changed" in err
    assert (out / "run.json").read_bytes() == record and not (out / "frame_000002.vtu").exists()
    (tmp_path / "pins.txt").write_text("6 8\n")  # back as it was: resumes
    assert main(["run", str(scene), "--out", str(out), "--frames", "2", "--resume",
                 "--no-preview"]) == 0


def test_resume_with_a_missing_input_names_it(scene, tmp_path):
    out = tmp_path / "out"
    run_scene(str(scene), out, frames=1, preview=False)
    (tmp_path / "pins.txt").rename(tmp_path / "pins2.txt")
    (tmp_path / "s.toml").write_text(SCENE.replace("pins.txt", "pins2.txt"))
    with pytest.raises(InputError, match="pins.txt: is missing now"):
        run_scene(str(scene), out, frames=2, resume=True, preview=False)


def test_assignment_json_is_an_input(tmp_path):
    p = tmp_path / "a.json"
    p.write_text("{}")

    class Fake:
        source = str(p)

        def to_dict(self):
            return {"cloth": {"file": str(tmp_path / "nope.obj")}}

    assert input_files(Fake()) == [str(p.resolve())]


def test_changed_input_names_the_first_change(scene):
    now = input_hashes(load_scene(str(scene)))
    assert changed_input(now, now) is None
    (path,) = now
    assert changed_input({path: "0" * 64}, now).startswith(path)
    assert "was not" in changed_input({}, now)
