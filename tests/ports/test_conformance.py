"""The conformance set: every case is exported and passes the checker against itself."""

import json

import numpy as np
import pytest

from clothsim.cli import main
from clothsim.ports.conformance import CASES, write_conformance
from clothsim.scene import load_scene


@pytest.fixture(scope="module")
def conformance(tmp_path_factory):
    out = tmp_path_factory.mktemp("conformance")
    assert main(["conformance", "--out", str(out)]) == 0
    return out


def test_every_case_is_written_and_documented(conformance):
    readme = (conformance / "README.md").read_text()
    for name in CASES:
        d = conformance / name
        assert f"`{name}`" in readme
        manifest = json.loads((d / "manifest.json").read_text())
        assert manifest["frames"] == 21 and manifest["iterate_steps"] == 2
        assert (d / "iterates" / "step_0001.npz").is_file()
        load_scene(d / "scene.toml")  # every scene file loads
    kinds = {e["kind"] for name in CASES for e in CASES[name]["effects"]}
    assert kinds >= {"gravity", "pin", "plane", "sphere", "box", "impulse", "damping",
                     "strain-limit", "wind"}
    pins = json.loads((conformance / "penalty-pins" / "manifest.json").read_text())["pins"]
    assert {p["method"] for p in pins} == {"penalty"} and pins[0]["stiffness"] == 1000.0
    stretch = np.loadtxt(conformance / "springs-stretch" / "initial-state.txt")
    rest = np.loadtxt(conformance / "springs-stretch" / "vertices.txt")
    assert np.ptp(stretch[:, 0]) == pytest.approx(1.2 * np.ptp(rest[:, 0]))


@pytest.mark.parametrize("name", list(CASES))
def test_each_case_passes_the_checker_against_itself(conformance, name, capsys):
    d = conformance / name
    assert main(["check", str(d / "scene.toml"), str(d)]) == 0, capsys.readouterr()
    assert main(["compare", str(d / "positions.txt"), str(d)]) == 0


def test_a_wrong_port_fails_its_case(conformance, tmp_path, capsys):
    d = conformance / "damping-rigid"
    x = np.loadtxt(d / "positions.txt")
    v = np.loadtxt(d / "velocities.txt") * 1.01  # damping off by 1 %
    np.savetxt(tmp_path / "positions.txt", x)
    np.savetxt(tmp_path / "velocities.txt", v)
    assert main(["check", str(d / "scene.toml"), str(tmp_path)]) == 1
    assert "FAIL at step" in capsys.readouterr().out


def test_subset(tmp_path):
    assert write_conformance(tmp_path, cases=["wind"], frames=2) == ["wind"]
    assert not (tmp_path / "plane").exists()


def test_a_folder_of_other_files_is_refused_unless_forced(tmp_path):
    from clothsim.errors import InputError
    from clothsim.ports.coursework import write_coursework

    out = tmp_path / "set"
    out.mkdir()
    (out / "README.md").write_text("my notes\n")
    with pytest.raises(InputError, match="is not a clothsim conformance set's folder: it "
                                         "holds 'README.md'"):
        write_conformance(out, cases=["wind"], frames=2)
    assert (out / "README.md").read_text() == "my notes\n" and len(list(out.iterdir())) == 1
    assert write_conformance(out, cases=["wind"], frames=2, force=True) == ["wind"]
    # now a conformance set: written into again without --force; one folder, one profile
    assert write_conformance(out, cases=["plane"], frames=2) == ["plane"]
    with pytest.raises(InputError, match="holds a clothsim conformance set, not a clothsim "
                                         "coursework profile"):
        write_coursework(out, cases=["spring"], frames=2)
    assert not (out / "spring").exists()
    assert write_coursework(tmp_path / "cw", cases=["spring"], frames=2) == ["spring"]
    assert write_coursework(tmp_path / "cw", cases=["chain"], frames=2) == ["chain"]
    with pytest.raises(InputError, match="holds a clothsim coursework profile"):
        write_conformance(tmp_path / "cw", cases=["wind"], frames=2)


def test_contact_case_failure_names_the_projection(conformance):
    from clothsim.ports.check import check_steps

    d = conformance / "plane"
    x = np.loadtxt(d / "positions.txt").reshape(21, -1, 3)
    v = np.loadtxt(d / "velocities.txt").reshape(21, -1, 3)
    x[10:, 12, 0] += 1e-3
    report = check_steps(load_scene(d / "scene.toml"), x, v)
    first = report.first_failure
    assert (first.k, first.vertex) == (9, 12), first.line()
    assert "corrected after the solve by plane" in first.note
