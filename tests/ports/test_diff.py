"""The model diff names what differs: springs, duplicates, stiffness, rest, mass, pins."""

import numpy as np

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
