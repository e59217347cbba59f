"""[cloth] pin_method / pin_stiffness: how the pins a cloth's files declare are held."""

import numpy as np
import pytest

from clothsim.scene import Scene, SceneError, data_dir, load_scene
from clothsim.scene.pins import ASSIGNMENT_PIN_STIFFNESS

G = 9.81


def two_masses(tmp_path, **cloth):
    """Two 0.5 kg vertices joined by a spring, each attached by a table row of 1000 N/m."""
    (tmp_path / "x.txt").write_text("0 0 0\n1 0 0\n")
    (tmp_path / "springs.txt").write_text("0 1 100\n0 -1 1000\n1 -1 1000\n")
    return Scene.from_dict({
        "cloth": {"shape": "files", "vertices": "x.txt", "mass": 1.0, **cloth},
        "springs": {"table": "springs.txt", "columns": ["a", "b", "stiffness"]},
        "solver": {"method": "newton", "iterations": 50, "tolerance": 1e-12},
        "effects": [{"kind": "gravity", "acceleration": [0.0, -G, 0.0]}]}, base_dir=tmp_path)


@pytest.mark.parametrize("cloth, sag", [({}, 0.5 * G / 1000),
                                        ({"pin_method": "penalty"}, 0.5 * G / 1000),
                                        ({"pin_stiffness": 4000.0}, 0.5 * G / 4000),
                                        ({"pin_method": "constraint"}, 0.0)])
def test_attachments_settle_at_m_g_over_k_or_stay_exactly(tmp_path, cloth, sag):
    sim = two_masses(tmp_path, **cloth).build_simulation()
    p = sim.problem()
    if sag:
        assert list(p.anchor_vertices) == [0, 1] and len(p.fixed_vertices) == 0
        np.testing.assert_array_equal(p.anchor_stiffness, 0.5 * G / sag)
    else:
        assert list(p.fixed_vertices) == [0, 1] and len(p.anchor_vertices) == 0
    sim.run(600)  # implicit Euler damps the bounce away: the static equilibrium
    y = sim.state.positions[:, 1]
    np.testing.assert_allclose(y, -sag, rtol=1e-6, atol=0.0)


def test_pin_keys_are_checked(tmp_path):
    with pytest.raises(SceneError, match="cloth.pin_method"):
        two_masses(tmp_path, pin_method="exact")
    for bad in (0.0, -1.0, "1e7"):
        with pytest.raises(SceneError, match="cloth.pin_stiffness"):
            two_masses(tmp_path, pin_stiffness=bad)


def test_a_pin_effect_keeps_its_own_method(tmp_path):
    (tmp_path / "x.txt").write_text("0 0 0\n1 0 0\n0 1 0\n")
    sim = Scene.from_dict({
        "cloth": {"shape": "files", "vertices": "x.txt", "pin_method": "constraint"},
        "springs": {"structural": 10.0},
        "effects": [{"kind": "pin", "vertices": [2], "method": "penalty", "stiffness": 77.0}]},
        base_dir=tmp_path).build_simulation()
    p = sim.problem()
    assert list(p.anchor_vertices) == [2] and p.anchor_stiffness.tolist() == [77.0]
    assert len(p.fixed_vertices) == 0


def jacobson(name, **cloth):
    if not (data_dir() / "net.json").is_file():
        pytest.skip("assignment data not found")
    scene = load_scene(name)
    d = scene.to_dict()
    d["cloth"] = {k: v for k, v in d["cloth"].items() if k in ("shape", "file")} | cloth
    return Scene.from_dict(d)


def test_assignment_pins_are_penalty_w_by_default_and_follow_the_keys():
    b = np.array([1, 5, 35, 61, 57, 27]) - 1  # net.json's b
    p = jacobson("jacobson-net").build_simulation().problem()
    assert sorted(p.anchor_vertices) == sorted(b) and len(p.fixed_vertices) == 0
    assert ASSIGNMENT_PIN_STIFFNESS == 1e10 and np.all(p.anchor_stiffness == 1e10)
    p = jacobson("jacobson-net", pin_stiffness=1e7).build_simulation().problem()
    assert np.all(p.anchor_stiffness == 1e7)
    sim = jacobson("jacobson-net", pin_method="constraint").build_simulation()
    p = sim.problem()
    assert sorted(p.fixed_vertices) == sorted(b) and len(p.anchor_vertices) == 0
    sim.run(5)
    np.testing.assert_array_equal(sim.state.positions[b], sim.model.mesh.vertices[b])


def test_softer_assignment_pins_sag_more():
    # the same net with w = 1e10 and w = 1e4: the pins move by about their load / w
    moved = {}
    for w in (1e10, 1e4):
        sim = jacobson("jacobson-net", pin_stiffness=w).build_simulation()
        sim.run(10)
        b = sim.problem().anchor_vertices
        moved[w] = np.abs(sim.state.positions[b] - sim.model.mesh.vertices[b]).max()
    # loads are O(100 N): 1e-8 m at w = 1e10, 1e-2 m at w = 1e4
    assert moved[1e10] < 1e-6 < 1e-3 < moved[1e4] < 1.0
