"""Forces too large for float64 (issue 34, item 4): never a silently frozen cloth.

Gravity, an impulse, a force (per vertex or from a file), a wind or a pin's velocity of 1e160 …
1e300 made the step's gradient overflow: the run finished with exit 0, status completed,
0 iterations, residual inf, and the cloth never moved. A scene is now refused when it is
built, naming the key (clothsim.magnitudes.force_problem: h²|f|·√n ≤ 1e150 kg·m and
h²|f|/m ≤ 1e100 m per step, h|v| ≤ 1e100 m for a pin); a step whose gradient overflows
anyway (the Python API, a cloth that travelled too far) raises NonFiniteStateError naming
the magnitude, and `run` stops with exit 1 and status failed.
"""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

import clothsim as cs
from clothsim.cli import main
from clothsim.errors import InputError, NonFiniteStateError
from clothsim.scene import Scene, SceneError, load_scene

BASE = {"scene": {"frames": 2}, "cloth": {"resolution": [4, 4], "plane": "xy"},
        "springs": {"structural": 100.0}}


def _scene(effects, tmp_path=None):
    return Scene.from_dict({**BASE, "effects": effects},
                           base_dir=tmp_path if tmp_path is not None else None)


PIN = {"kind": "pin", "vertices": [12, 15]}


@pytest.mark.parametrize("size", [1e160, 1e200, 1e300])
@pytest.mark.parametrize("effect, key", [
    ({"kind": "gravity", "acceleration": [0.0, "-S", 0.0]}, "effects[0].acceleration"),
    ({"kind": "force", "per_vertex": [0.0, "-S", 0.0]}, "effects[0].per_vertex"),
    ({"kind": "impulse", "center": [0.0, 0.0, 0.0], "radius": 2.0, "force": [0.0, "S", 0.0]},
     "effects[0].force"),
    ({"kind": "pin", "vertices": [0], "velocity": [0.0, "S", 0.0]}, "effects[0].velocity"),
    ({"kind": "wind", "velocity": [0.0, 0.0, "S"]}, "effects[0].velocity"),
], ids=["gravity", "force", "impulse", "pin-velocity", "wind"])
def test_a_huge_force_is_refused_naming_its_key(effect, key, size):
    e = {k: ([size if x == "S" else -size if x == "-S" else x for x in v]
             if isinstance(v, list) else v) for k, v in effect.items()}
    with pytest.raises(SceneError) as info:
        _scene([e]).build_simulation()
    text = str(info.value)
    assert text.startswith(f"<dict>: {key}: ") and "overflow float64" in text, text
    assert "\n" not in text


def test_a_force_file_of_huge_forces_is_refused_naming_the_file_key(tmp_path):
    (tmp_path / "f.txt").write_text("0 -1e200 0\n" * 16)
    with pytest.raises(SceneError, match=r"effects\[0\]\.file: a force of 1e\+200 N"):
        _scene([{"kind": "force", "file": "f.txt"}], tmp_path).build_simulation()


def test_large_but_representable_forces_run_and_move():
    """Below the bounds the cloth moves: 1e90 m/s² falls h²g ≈ 1.1e87 m in the first step."""
    sim = _scene([{"kind": "gravity", "acceleration": [0.0, -1e90, 0.0]}]).build_simulation()
    x0 = sim.state.positions.copy()
    record = sim.step()
    assert record.iterations > 0 and np.isfinite(record.residual)
    drop = x0[:, 1] - sim.state.positions[:, 1]
    np.testing.assert_allclose(drop, 1e90 / 900, rtol=1e-6)


def test_ordinary_scenes_are_far_from_the_bounds():
    from clothsim.scene import list_builtin_scenes

    for name in ("hanging", "flag", "impulse", "drop-on-square"):
        assert name in list_builtin_scenes()
        load_scene(name).build_simulation()  # no refusal


def test_the_python_api_fails_the_step_loudly_instead_of_freezing(monkeypatch):
    """Simulation refuses the forces as the scene does (clothsim.magnitudes.check_step);
    with that bound off (a cloth that travelled beyond it), the step's backstop raises."""
    import clothsim.simulation

    mesh = cs.grid(4, 4, plane="xy")
    model = cs.Model.build(mesh, cs.grid_springs(mesh, structural=100.0), total_mass=1.0)
    cases = (([cs.Gravity((0.0, -1e300, 0.0))], "effects[0].acceleration"),
             ([cs.Force((0.0, 1e200, 0.0))], "effects[0].per_vertex"),
             ([cs.Pin([0], velocity=(0.0, 1e300, 0.0), method="penalty")],
              "effects[0].velocity"))
    for effects, key in cases:
        with pytest.raises(InputError, match=re.escape(key) + ": .*float64") as info:
            cs.Simulation(model, h=1 / 30, effects=[type(effects[0])(**_args(effects[0]))])
        assert info.value.field == key
    monkeypatch.setattr(clothsim.simulation, "check_step", lambda *a: None)
    for effects, _key in cases:
        for method in ("local-global", "newton", "chebyshev"):
            sim = cs.Simulation(model, h=1 / 30, effects=effects if method == "local-global"
                                else [type(effects[0])(**_args(effects[0]))], solver=method)
            x0 = sim.state.positions.copy()
            with pytest.raises(NonFiniteStateError, match="overflows float64 from its start"):
                sim.step()
            np.testing.assert_array_equal(sim.state.positions, x0)  # the last finite state


def _args(e):
    if isinstance(e, cs.Gravity):
        return {"acceleration": e.acceleration}
    if isinstance(e, cs.Force):
        return {"per_vertex": e.per_vertex}
    return {"vertices": e.vertices, "velocity": e.velocity, "method": e.method}


def test_run_refuses_a_huge_gravity_by_its_set_with_exit_2(tmp_path, capsys):
    code = main(["run", "hanging", "--set", "effects[0].acceleration=[0, -1e200, 0]",
                 "--out", str(tmp_path / "o"), "--no-preview"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1, err
    assert "--set effects[0].acceleration=[0, -1e200, 0]: effects[0].acceleration: " in err
    assert not (tmp_path / "o").exists()


def test_a_run_whose_step_overflows_anyway_fails_with_exit_1(tmp_path, capsys, monkeypatch):
    """The bounds off (as if a cloth travelled beyond them): the step backstop."""
    import clothsim.simulation

    monkeypatch.setattr(clothsim.simulation, "check_step", lambda *a: None)
    code = main(["run", "hanging", "--set", "effects[0].acceleration=[0, -1e300, 0]",
                 "--set", "scene.frames=3", "--out", str(tmp_path / "o"), "--no-preview"])
    err = capsys.readouterr().err
    assert code == 1 and "frame 1: " in err and "overflows float64" in err, err
    record = json.loads((tmp_path / "o" / "run.json").read_text())
    assert record["status"] == "failed"
