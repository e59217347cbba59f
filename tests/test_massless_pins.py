"""A vertex of mass 0 is pinned exactly at its initial position (engines' inverse mass 0)."""

import logging

import numpy as np
import pytest

import clothsim as cs
from clothsim.errors import InputError
from clothsim.gallery import GRAVITY, grid_cloth
from clothsim.scene import Scene, SceneError


def hanging_by_mass(n=5, **kw):
    base = grid_cloth(n, k=400.0, plane="xy")
    m = base.vertex_mass.copy()
    top = [n * (n - 1), n * n - 1]
    m[top] = 0.0
    return cs.Model(base.mesh, base.springs, m), top


def test_massless_vertices_hang_a_cloth_like_exact_pins(caplog):
    model, top = hanging_by_mass()
    assert model.massless_vertices.tolist() == top
    with caplog.at_level(logging.INFO, logger="clothsim.simulation"):
        a = cs.Simulation(model, h=1 / 30, effects=[cs.Gravity(GRAVITY)], iterations=20)
    assert "2 vertices of mass 0 are pinned" in caplog.text
    assert a.effects_built == ["pin", "gravity"]
    assert a.problem().fixed_vertices.tolist() == top
    # the same cloth with the masses of the pinned pair restored and an explicit Pin: the
    # same motion (a pinned vertex's mass never enters the step)
    full = grid_cloth(5, k=400.0, plane="xy")
    b = cs.Simulation(full, h=1 / 30, effects=[cs.Gravity(GRAVITY), cs.Pin(top)],
                      iterations=20)
    a.run(20), b.run(20)
    np.testing.assert_array_equal(a.state.positions[top], model.mesh.vertices[top])
    np.testing.assert_allclose(a.state.positions, b.state.positions, rtol=0, atol=1e-12)
    assert a.state.positions[:, 1].min() < model.mesh.vertices[:, 1].min() - 0.005  # it sags


def test_a_massless_vertex_already_pinned_is_not_pinned_twice():
    model, top = hanging_by_mass()
    sim = cs.Simulation(model, h=1 / 30, effects=[cs.Pin(top, method="penalty",
                                                         stiffness=1e6)])
    assert sim.effects_built == ["pin"]
    assert sim.problem().anchor_vertices.tolist() == top
    # one of them pinned by the user, the other by its mass
    sim = cs.Simulation(model, h=1 / 30, effects=[cs.Gravity(GRAVITY), cs.Pin(top[:1])])
    assert sim.effects_built == ["pin", "gravity", "pin"]
    assert sorted(sim.pinned_vertices(1 / 30).tolist()) == top


def test_massless_vertex_in_contact_and_free_fall():
    # a falling cloth whose one massless vertex stays put: the rest fall, a plane stops them
    base = grid_cloth(5, k=400.0, center=(0.0, 0.2, 0.0))
    m = base.vertex_mass.copy()
    m[12] = 0.0
    model = cs.Model(base.mesh, base.springs, m)
    sim = cs.Simulation(model, h=1 / 60, effects=[cs.Gravity(GRAVITY),
                                                  cs.Plane([0, 0, 0], [0, 1, 0])],
                        iterations=10)
    sim.run(60)
    x = sim.state.positions
    assert x[12].tolist() == model.mesh.vertices[12].tolist()
    assert x[:, 1].min() >= -1e-12 and x[0, 1] < 0.1


def test_negative_mass_and_a_scene_with_massless_vertices(tmp_path):
    base = grid_cloth(3)
    with pytest.raises(InputError, match="vertex_mass"):
        cs.Model(base.mesh, base.springs, -np.ones(9))
    (tmp_path / "m.txt").write_text("0 1 1 1 1 1 1 1 0\n")
    scene = {"cloth": {"shape": "grid", "resolution": [3, 3], "plane": "xy",
                       "vertex_mass": "m.txt"},
             "springs": {"structural": 100.0}, "effects": [{"kind": "gravity"}]}
    sim = Scene.from_dict(scene, base_dir=tmp_path).build_simulation()
    assert sim.problem().fixed_vertices.tolist() == [0, 8]
    scene["cloth"]["vertex_mass"] = [0.0] + [1.0] * 8
    sim = Scene.from_dict(scene, base_dir=tmp_path).build_simulation()
    assert sim.problem().fixed_vertices.tolist() == [0]
    scene["cloth"]["vertex_mass"] = [-1.0] + [1.0] * 8
    with pytest.raises(SceneError, match=r"cloth.vertex_mass\[0\]"):
        Scene.from_dict(scene, base_dir=tmp_path)
    scene["cloth"]["vertex_mass"] = 0.0
    with pytest.raises(SceneError, match="cloth.vertex_mass"):
        Scene.from_dict(scene, base_dir=tmp_path)
