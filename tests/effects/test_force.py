"""The Force effect: newtons per vertex, constant, on all, on listed vertices or from a file."""

import numpy as np
import pytest

import clothsim as cs
from clothsim.errors import InputError
from clothsim.gallery import GRAVITY, grid_cloth, top_corners
from clothsim.scene import Scene, SceneError


def springless(n=3, mass=4.0):
    mesh = cs.grid(n, n, center=(0.0, 1.0, 0.0))
    return cs.Model.build(mesh, cs.mesh_springs(mesh), total_mass=mass,
                          mass_lumping="area")


def test_force_is_newtons_whatever_the_mass_and_gravity_is_m_g():
    model = springless()
    m = model.vertex_mass
    assert np.ptp(m) > 0  # area lumping: unequal masses
    f = cs.Simulation(model, h=0.1, effects=[cs.Force([0.0, -9.8, 0.0])]).problem().f_ext
    np.testing.assert_array_equal(f, np.tile([0.0, -9.8, 0.0], (9, 1)))
    g = cs.Simulation(model, h=0.1, effects=[cs.Gravity([0.0, -9.8, 0.0])]).problem().f_ext
    np.testing.assert_allclose(g[:, 1], -9.8 * m, rtol=1e-15)


def test_free_fall_under_a_force_is_f_over_m():
    # no springs: x_{k} = x_0 + h² (f/m) k(k+1)/2 (implicit Euler), per vertex mass
    model = springless()
    h = 0.05
    sim = cs.Simulation(model, h=h, effects=[cs.Force([0.0, -1.0, 0.5])], iterations=1)
    sim.run(4)
    a = np.array([0.0, -1.0, 0.5])[None, :] / model.vertex_mass[:, None]
    np.testing.assert_allclose(sim.state.positions - model.mesh.vertices, a * h * h * 10,
                               rtol=1e-13, atol=1e-15)


def test_listed_vertices_rows_and_a_file(tmp_path):
    model = springless()
    f = cs.Simulation(model, h=0.1, effects=[cs.Force([1.0, 2.0, 3.0], vertices=[0, 8])]
                      ).problem().f_ext
    assert f[0].tolist() == f[8].tolist() == [1.0, 2.0, 3.0] and not f[1:8].any()
    rows = np.arange(27.0).reshape(9, 3)
    (tmp_path / "f.txt").write_text("# fx fy fz\n" + "\n".join(" ".join(map(str, r))
                                                                for r in rows) + "\n")
    for e in (cs.Force(rows), cs.Force(file=tmp_path / "f.txt")):
        p = cs.Simulation(model, h=0.1, effects=[e]).problem()
        np.testing.assert_array_equal(p.f_ext, rows)
    e = cs.Force(file=tmp_path / "f.txt")
    assert e.describe() == {"kind": "force", "unit": "N", "file": str(tmp_path / "f.txt")}
    assert cs.Force([0, -9.8, 0]).describe() == {"kind": "force", "unit": "N",
                                                 "per_vertex": [0.0, -9.8, 0.0]}


def test_force_and_gravity_add_and_a_pin_holds_against_them():
    n = 5
    model = grid_cloth(n, k=400.0, plane="xy")
    pins = top_corners(n)
    sim = cs.Simulation(model, h=1 / 30, effects=[cs.Gravity(GRAVITY), cs.Pin(pins),
                                                  cs.Force([0.0, 0.0, 0.2])])
    f = sim.problem().f_ext
    np.testing.assert_allclose(f, model.vertex_mass[:, None] * GRAVITY + [0.0, 0.0, 0.2])
    sim.run(30)
    np.testing.assert_array_equal(sim.state.positions[pins], model.mesh.vertices[pins])
    assert sim.state.positions[:, 2].mean() > 0.01  # the +z force pushed the cloth


def test_a_force_pressing_a_cloth_into_a_plane_is_stopped():
    model = grid_cloth(5, k=400.0, center=(0.0, 0.01, 0.0))
    sim = cs.Simulation(model, h=1 / 60, effects=[cs.Force([0.0, -5.0, 0.0]),
                                                  cs.Plane([0, 0, 0], [0, 1, 0])])
    sim.run(40)
    assert sim.state.positions[:, 1].min() >= -1e-12


@pytest.mark.parametrize("kwargs, match", [
    ({}, "exactly one"),
    ({"per_vertex": [0, 1, 0], "file": "f.txt"}, "exactly one"),
    ({"per_vertex": [0, 1]}, "per_vertex"),
    ({"per_vertex": [0, np.nan, 0]}, "per_vertex"),
    ({"per_vertex": np.zeros((2, 3)), "vertices": [1, 2, 3]}, "2 rows for 3"),
    ({"per_vertex": [0, 1, 0], "vertices": [0.5]}, "integer"),
])
def test_bad_force_is_one_line_error(kwargs, match):
    with pytest.raises(InputError, match=match):
        cs.Force(**kwargs)


def test_bad_force_at_bind_and_in_a_file(tmp_path):
    model = springless()
    with pytest.raises(InputError, match="force.vertices.*out of range"):
        cs.Simulation(model, h=0.1, effects=[cs.Force([0, 1, 0], vertices=[9])])
    with pytest.raises(InputError, match="force.per_vertex: 2 forces for 9"):
        cs.Simulation(model, h=0.1, effects=[cs.Force(np.zeros((2, 3)))])
    (tmp_path / "f.txt").write_text("1 2 3\n4 5\n")
    with pytest.raises(InputError, match="f.txt, line 2"):
        cs.Force(file=tmp_path / "f.txt")


SCENE = {"cloth": {"shape": "grid", "resolution": [3, 3]}, "springs": {"structural": 50.0}}


def test_scene_force_kinds_of_input(tmp_path):
    (tmp_path / "f.txt").write_text("\n".join(["0 -1 0"] * 9))
    (tmp_path / "v.txt").write_text("1 9\n")
    for eff, total in [({"per_vertex": [0, -2, 0]}, -18.0),
                       ({"per_vertex": [0, -2, 0], "vertices": [0, 8]}, -4.0),
                       ({"per_vertex": [0, -2, 0], "vertices": "v.txt", "index_base": 1},
                        -4.0),
                       ({"file": "f.txt"}, -9.0)]:
        scene = Scene.from_dict({**SCENE, "effects": [{"kind": "force", **eff}]},
                                base_dir=tmp_path)
        sim = scene.build_simulation()
        assert sim.problem().f_ext[:, 1].sum() == total
        assert sim.effects[0].describe()["unit"] == "N"


@pytest.mark.parametrize("eff, key", [
    ({"per_vertex": [0, 1]}, "effects[0].per_vertex"),
    ({"per_vertex": [0, "a", 0]}, "effects[0].per_vertex[1]"),
    ({"file": "missing.txt"}, "effects[0].file"),
    ({"per_vertex": [0, 1, 0], "vertices": [9]}, "effects[0].vertices[0]"),
    ({"per_vertex": [0, 1, 0], "index_base": 1}, "effects[0].index_base"),
    ({"per_vertex": [0, 1, 0], "speed": 1}, "effects[0].speed"),
    ({}, "effects[0]"),
])
def test_scene_force_errors_name_the_key(tmp_path, eff, key):
    with pytest.raises(SceneError) as info:
        Scene.from_dict({**SCENE, "effects": [{"kind": "force", **eff}]}, base_dir=tmp_path)
    assert f"{key}:" in str(info.value) and "\n" not in str(info.value)


def test_scene_force_file_of_wrong_length(tmp_path):
    (tmp_path / "f.txt").write_text("0 -1 0\n0 -1 0\n")
    scene = Scene.from_dict({**SCENE, "effects": [{"kind": "force", "file": "f.txt"}]},
                            base_dir=tmp_path)
    with pytest.raises(SceneError, match=r"effects\[0\].file: 2 forces for 9 vertices"):
        scene.build_simulation()
