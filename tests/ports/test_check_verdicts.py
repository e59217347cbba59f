"""Verdicts on ports that are wrong, or right under other settings (issue 19's cases).

The ports here are clothsim itself run under another model or other settings: a missing
pin, a pin of another stiffness, another start point, float32 data. The compiled port of
examples/ports/cpp checks the same verdicts end to end (tests/ports/test_cpp_port.py).
"""

import copy
import json
import shutil
from importlib import resources

import numpy as np
import pytest

import clothsim as cs
from clothsim.ports.check import check_steps
from clothsim.scene import Scene
from clothsim.scene.files import data_root


def trajectory(sim, steps):
    xs, vs = [sim.state.positions.copy()], [sim.state.velocities.copy()]
    for _ in range(steps):
        sim.step()
        xs.append(sim.state.positions.copy())
        vs.append(sim.state.velocities.copy())
    return np.stack(xs), np.stack(vs)


def scene_variant(tmp_path, name, **replace):
    """A built-in scene's TOML with lines replaced (old line -> new line), as a file."""
    text = resources.files("clothsim.scenes").joinpath(f"{name}.toml").read_text()
    for old, new in replace.values():
        assert old in text, old
        text = text.replace(old, new)
    path = tmp_path / f"{name}-{len(list(tmp_path.iterdir()))}.toml"
    path.write_text(text)
    return cs.load_scene(path)


def unpinned(scene, tmp_path):
    """The scene without its pins (a port that lost them): pin effects and the JSON's b."""
    data = copy.deepcopy(scene.data)
    data["effects"] = [e for e in data["effects"] if e["kind"] != "pin"]
    cloth = data["cloth"]
    if cloth["shape"] == "jacobson":
        path = scene.base_dir / cloth["file"] if not str(cloth["file"]).startswith("data:") \
            else data_root() / str(cloth["file"])[5:]
        spec = json.loads(path.read_text())
        spec["b"] = []
        shutil.copy(path.with_name(spec["obj"]), tmp_path / spec["obj"])
        (tmp_path / "free.json").write_text(json.dumps(spec))
        cloth["file"] = str(tmp_path / "free.json")
    return Scene.from_dict(data, source="unpinned", base_dir=tmp_path)


@pytest.fixture
def net():
    if not (data_root() / "jacobson-a8" / "net.json").is_file():
        pytest.skip("the assignment's files (jacobson-a8) are absent: clothsim data fetch")
    return cs.load_scene("jacobson-net")


def test_exact_pins_missing_fail_at_the_first_step_naming_the_pinned_vertex(tmp_path):
    scene = cs.load_scene("hanging")
    free = unpinned(scene, tmp_path)
    xs, vs = trajectory(free.build_simulation(free.build_model()), 3)
    report = check_steps(scene, xs, vs)
    first = report.first_failure
    assert first.k == 0 and first.status == "pinned vertex moved", report.summary()
    assert first.role == "pinned exactly" and "pinned" in first.line()
    assert report.summary().startswith("FAIL at step 0 -> 1")
    # float32 data of the same unpinned run fail as float32 too
    x32, v32 = (a.astype(np.float32).astype(np.float64) for a in (xs, vs))
    assert check_steps(scene, x32, v32, precision="float32").first_failure.k == 0


def test_penalty_pins_of_another_stiffness_fail_naming_a_pinned_vertex(net, tmp_path):
    soft = scene_variant(tmp_path, "jacobson-net",
                         pins=("file = \"data:jacobson-a8/net.json\"",
                               "file = \"data:jacobson-a8/net.json\"\npin_stiffness = 1e7"))
    xs, vs = trajectory(soft.build_simulation(soft.build_model()), 4)
    report = check_steps(net, xs, vs)
    first = report.first_failure
    assert first is not None and first.k == 0, report.summary()
    assert "pinned by a 1e+10 N/m penalty" in first.line(), first.line()
    # a float64 port: its 1e-6 m are not float32 rounding, however small
    assert first.status != "float32 rounding" and "precision float32" not in first.note
    assert check_steps(soft, xs, vs).passed


def test_missing_penalty_pins_fail_at_step_0(net, tmp_path):
    free = unpinned(net, tmp_path)
    xs, vs = trajectory(free.build_simulation(free.build_model()), 2)
    first = check_steps(net, xs, vs).first_failure
    assert first is not None and first.k == 0 and "pinned" in first.line(), first.line()


def test_another_start_point_is_start_dependent_with_the_settings(net, tmp_path):
    short = scene_variant(tmp_path, "jacobson-net", count=("iterations = 50 ", "iterations = 5 "))
    xs, vs = trajectory(short.build_simulation(short.build_model()), 3)  # x_n, 5 iterations
    assert check_steps(short, xs, vs).passed
    from_y = scene_variant(tmp_path, "jacobson-net",
                           start=('initial_guess = "x_n"', 'initial_guess = "y"'),
                           count=("iterations = 50 ", "iterations = 5 "))
    report = check_steps(from_y, xs, vs)
    first = report.first_failure
    assert report.summary().startswith("UNDECIDED"), report.summary()
    assert first.status == "start-dependent"
    assert first.settings == '[solver] initial_guess = "x_n" and iterations = 5', first.line()


def test_float32_data_pass_float32_and_get_the_rounding_status_at_float64():
    scene = cs.load_scene("hanging")
    xs, vs = trajectory(scene.build_simulation(scene.build_model()), 4)
    x32, v32 = (a.astype(np.float32).astype(np.float64) for a in (xs, vs))
    assert check_steps(scene, x32, v32, precision="float32").passed
    report = check_steps(scene, x32, v32)
    assert {s.status for s in report.steps} == {"float32 rounding"}, report.summary()


def test_too_few_frames_for_the_steps_asked_is_an_error():
    scene = cs.load_scene("hanging")
    xs, vs = trajectory(scene.build_simulation(scene.build_model()), 2)
    with pytest.raises(cs.InputError, match="steps: 5 steps asked for, but the port has only 3"):
        check_steps(scene, xs, vs, steps=5)
