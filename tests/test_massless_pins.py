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
    sim = cs.Simulation(model, h=1 / 30, effects=[cs.Pin(top)])
    assert sim.effects_built == ["pin"]
    assert sim.problem().fixed_vertices.tolist() == top
    # one of them pinned by the user, the other by its mass
    sim = cs.Simulation(model, h=1 / 30, effects=[cs.Gravity(GRAVITY), cs.Pin(top[:1])])
    assert sim.effects_built == ["pin", "gravity", "pin"]
    assert sorted(sim.pinned_vertices(1 / 30).tolist()) == top


def test_a_penalty_pin_on_a_massless_vertex_is_refused_by_name():
    """Mass 0 is documented as pinned exactly; a penalty pin let it move 2.5e-5 m."""
    model, top = hanging_by_mass()
    with pytest.raises(InputError, match=r"^pin\.method: vertex 20 has mass 0, which pins it "
                                         r"exactly .* use method 'constraint'"):
        cs.Simulation(model, h=1 / 30, effects=[cs.Gravity(GRAVITY),
                                                cs.Pin(top, method="penalty", stiffness=1e6)])


@pytest.mark.parametrize("obstacle", [
    lambda x: cs.Sphere(x, 0.1), lambda x: cs.Box(x - 0.05, x + 0.05),
    lambda x: cs.Plane(x + [0, 0.05, 0], [0, 1, 0]),
], ids=["sphere", "box", "plane"])
def test_a_massless_vertex_inside_an_obstacle_is_refused_by_name(obstacle):
    """A sphere at a massless vertex's position moved it 0.1 m."""
    model, top = hanging_by_mass()
    effect = obstacle(model.mesh.vertices[top[0]])
    with pytest.raises(InputError, match=rf"^{effect.kind}\.\w+: vertex {top[0]} has mass 0"):
        cs.Simulation(model, h=1 / 30, effects=[cs.Gravity(GRAVITY), effect])


def test_a_massless_vertex_stays_exactly_put_under_every_effect():
    """Gravity, wind, a force, damping, strain limiting, an impulse and an obstacle the
    massless vertex touches from outside: it never moves, to the bit."""
    model, top = hanging_by_mass()
    x = model.mesh.vertices
    effects = [cs.Gravity(GRAVITY), cs.Wind((3.0, 0.0, 1.0)), cs.Force((0.0, 0.0, 0.5)),
               cs.Damping(model="velocity", coefficient=0.1),
               cs.StrainLimit(max_strain=0.05),
               cs.Impulse(x[top[0]], 0.3, (0.0, 5.0, 1.0)),
               # touches vertex 20, no overlap (no contact thickness either)
               cs.Sphere(x[top[0]] + [0.0, 0.0, 0.2], 0.2, thickness=0.0)]
    sim = cs.Simulation(model, h=1 / 30, effects=effects, iterations=10)
    sim.run(30)
    assert sim.state.positions[top].tolist() == x[top].tolist()
    assert np.all(sim.state.velocities[top] == 0)
    assert np.abs(sim.state.positions - x).max() > 0.01  # the rest moved


def test_the_scene_names_the_key_of_a_penalty_pin_or_obstacle_on_a_massless_vertex(tmp_path):
    doc = {"cloth": {"resolution": [3, 3], "plane": "xy", "vertex_mass": [1.0] * 8 + [0.0]},
           "springs": {"structural": 100.0},
           "effects": [{"kind": "gravity"},
                       {"kind": "pin", "vertices": [8], "method": "penalty"}]}
    with pytest.raises(SceneError, match=r"^<dict>: effects\[1\]\.method: vertex 8 has mass 0"):
        Scene.from_dict(doc).build_simulation()
    doc["effects"][1] = {"kind": "sphere", "center": [0.5, 0.5, 0.0], "radius": 0.1}
    with pytest.raises(SceneError, match=r"^<dict>: effects\[1\]\.center: vertex 8 has mass 0"):
        Scene.from_dict(doc).build_simulation()
    (tmp_path / "t.txt").write_text("8 -1 1e4 0\n")  # a spring table's attachment: penalty
    doc["effects"] = [{"kind": "gravity"}]
    doc["springs"]["table"] = "t.txt"
    with pytest.raises(SceneError, match=r"^<dict>: springs\.table: attachments: .*vertex 8 "
                                         r"has mass 0.*cloth\.pin_method"):
        Scene.from_dict(doc, base_dir=tmp_path).build_simulation()
    doc["cloth"]["pin_method"] = "constraint"
    sim = Scene.from_dict(doc, base_dir=tmp_path).build_simulation()
    assert sim.problem().fixed_vertices.tolist() == [8]


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


def test_an_impulse_on_massless_vertices_only_is_refused_naming_its_radius():
    """Its force is shared in proportion to mass: 0/0 gave NaN and a message naming no key."""
    model, top = hanging_by_mass()
    x = model.mesh.vertices[top[0]]
    with pytest.raises(InputError, match=r"^impulse\.radius: every vertex within 0\.01 m .* has "
                                         r"mass 0"):
        cs.Simulation(model, h=1 / 30, effects=[cs.Impulse(x, 0.01, (0.0, 1.0, 0.0))])
    doc = {"cloth": {"resolution": [3, 3], "plane": "xy", "vertex_mass": [1.0] * 8 + [0.0]},
           "springs": {"structural": 100.0},
           "effects": [{"kind": "impulse", "center": [0.5, 0.5, 0.0], "radius": 0.01,
                        "force": [0.0, 1.0, 0.0]}]}
    with pytest.raises(SceneError, match=r"^<dict>: effects\[0\]\.radius: every vertex"):
        Scene.from_dict(doc).build_simulation()
