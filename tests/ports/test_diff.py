"""The model diff names what differs: springs, duplicates, stiffness, rest, mass, pins."""

import numpy as np
import pytest

import clothsim as cs
from clothsim.cli import main
from clothsim.gallery import grid_cloth
from clothsim.ports.diff import ModelTables, diff_models, model_tables
from clothsim.ports.export import export_port


def tables(model=None, pins=None):
    model = model or grid_cloth(4)
    s = model.springs
    return ModelTables(model.mesh.vertices, s.spring_vertices, s.spring_stiffness,
                       s.spring_rest_length, model.vertex_mass, pins or {})


def test_identical_and_renumbered():
    a = tables()
    perm = np.random.default_rng(0).permutation(16)
    inv = np.argsort(perm)
    b = ModelTables(a.x0[perm], inv[a.springs], a.stiffness, a.rest, a.masses[perm], {})
    assert diff_models(a, a).identical
    d = diff_models(a, b)
    assert d.identical and "numbering" in d.lines[0]


def test_each_kind_of_difference_is_named():
    a = tables()
    dup = ModelTables(a.x0, np.vstack([a.springs, a.springs[:1]]),
                      np.append(a.stiffness, a.stiffness[0]), np.append(a.rest, a.rest[0]),
                      a.masses, {})
    d = diff_models(a, dup)
    assert not d.identical and "1 duplicated springs in B" in d.cause
    fewer = ModelTables(a.x0, a.springs[1:], a.stiffness[1:], a.rest[1:], a.masses, {})
    a0, b0 = sorted(a.springs[0])
    d = diff_models(a, fewer)
    assert d.cause == "1 springs only in A" and f"{a0}-{b0}" in d.lines[0]
    k = a.stiffness.copy()
    k[3] *= 2
    assert "1 stiffnesses differ" in diff_models(a, ModelTables(a.x0, a.springs, k, a.rest,
                                                               a.masses, {})).cause
    r = a.rest * 1.01
    assert "rest lengths differ" in diff_models(a, ModelTables(a.x0, a.springs, a.stiffness, r,
                                                              a.masses, {})).cause
    m = a.masses.copy()
    m[5] *= 3
    d = diff_models(a, ModelTables(a.x0, a.springs, a.stiffness, a.rest, m, {}))
    assert "1 masses differ" in d.cause and "vertex 5" in d.lines[0]
    d = diff_models(tables(pins={0: ("constraint", None)}), tables(pins={0: ("penalty", 1e3)}))
    assert "pins differ" in d.cause
    d = diff_models(a, ModelTables(a.x0 + 1.0, a.springs, a.stiffness, a.rest, a.masses, {}))
    assert not d.identical and "initial shapes differ" in d.cause


def test_scene_against_its_export_and_cli(tmp_path, capsys):
    scene = cs.load_scene("hanging")
    export_port(scene, tmp_path / "e", frames=1, iterate_steps=0)
    assert diff_models(scene, tmp_path / "e").identical
    t = model_tables(tmp_path / "e")
    assert set(t.pins) == {420, 440} and t.pins[420] == ("constraint", None)
    assert main(["diff-model", "hanging", str(tmp_path / "e")]) == 0
    assert main(["diff-model", "drop-on-square", str(tmp_path / "e")]) == 1
    assert "DIFFERENT" in capsys.readouterr().out


def _flag_scene(tmp_path, effects):
    """The assignment's flag (libigl Voronoi masses: not uniform) with the given effects."""
    from clothsim.scene.files import data_root

    if not (data_root() / "jacobson-a8" / "flag.json").is_file():
        pytest.skip("the assignment's files (jacobson-a8) are absent: clothsim data fetch")
    path = tmp_path / "flag.toml"
    path.write_text(f'[scene]\nname = "flag"\nframes = 2\nfps = 30\nsubsteps = 1\n'
                    f'[cloth]\nshape = "jacobson"\nfile = "data:jacobson-a8/flag.json"\n'
                    f'[solver]\nmethod = "local-global"\ninitial_guess = "x_n"\n'
                    f'iterations = 50\n{effects}')
    return path


def test_gravity_convention_is_named_as_a_force(tmp_path, capsys):
    port = _flag_scene(tmp_path, '[[effects]]\nkind = "force"\nper_vertex = [0.0, -9.8, 0.0]\n')
    export_port(cs.load_scene(port), tmp_path / "port", frames=1, iterate_steps=0)
    (tmp_path / "s").mkdir()
    scene = _flag_scene(tmp_path / "s", '[[effects]]\nkind = "gravity"\n'
                       'acceleration = [0.0, -9.8, 0.0]\n')
    d = diff_models(scene, tmp_path / "port")
    assert not d.identical and d.cause.startswith("force: gravity convention"), d.report()
    assert "B applies (0, -9.8, 0) N on every vertex, A m·g with g = (0, -9.8, 0)" in d.cause
    assert main(["diff-model", str(scene), str(tmp_path / "port")]) == 1
    assert "force" in capsys.readouterr().out


def test_forces_and_settings_differences_each_get_a_line(tmp_path):
    scene = cs.load_scene("hanging")
    export_port(scene, tmp_path / "e", frames=1, iterate_steps=0)
    f = np.loadtxt(tmp_path / "e" / "forces.txt")
    f[7] += [0.0, 0.0, 1.0]
    np.savetxt(tmp_path / "e" / "forces.txt", f)
    text = (tmp_path / "e" / "settings.txt").read_text()
    text = text.replace("initial_guess y", "initial_guess x_n").replace("precision float64",
                                                                        "precision float32")
    (tmp_path / "e" / "settings.txt").write_text(text)
    d = diff_models(scene, tmp_path / "e")
    report = d.report()
    assert not d.identical
    assert "force: 1 vertices feel another external force, e.g. vertex 7" in report
    assert "setting initial_guess: y vs x_n" in report
    assert "setting precision: float64 vs float32" in report


def test_malformed_folder_files_name_file_and_line(tmp_path):
    scene = cs.load_scene("hanging")
    export_port(scene, tmp_path / "e", frames=1, iterate_steps=0)
    pins = tmp_path / "e" / "pins.txt"
    lines = pins.read_text().splitlines()
    lines[1] = lines[1] + " 4"
    pins.write_text("\n".join(lines) + "\n")
    with pytest.raises(cs.InputError, match=r"pins.txt: line 2: 7 numbers, expected 6"):
        diff_models(scene, tmp_path / "e")
    pins.write_text("# vertex method stiffness x y z\n0 0 0 a b c\n")
    with pytest.raises(cs.InputError, match=r"pins.txt: line 2: not a number: .a."):
        model_tables(tmp_path / "e")
    (tmp_path / "e" / "masses.txt").write_text("1\n2\n")
    pins.unlink()
    with pytest.raises(cs.InputError, match=r"masses.txt: 2 rows for 441 vertices"):
        model_tables(tmp_path / "e")


def test_nan_masses_are_a_difference():
    a = model_tables(cs.load_scene("hanging"))
    b = ModelTables(a.x0, a.springs, a.stiffness, a.rest, np.full(len(a.x0), np.nan), a.pins)
    d = diff_models(a, b)
    assert not d.identical and "masses of B: 441 not finite" in d.cause


def test_negative_masses_in_a_folder_are_an_error(tmp_path):
    export_port(cs.load_scene("hanging"), tmp_path / "e", frames=1, iterate_steps=0)
    m = np.loadtxt(tmp_path / "e" / "masses.txt")
    m[5] = -1.0
    np.savetxt(tmp_path / "e" / "masses.txt", m)
    with pytest.raises(cs.InputError, match="masses.txt: vertex 5: mass -1 kg is negative"):
        model_tables(tmp_path / "e")
