"""Bad scene files: every bad input is one line naming the file, the key and the index.

The same bad numbers the core API rejects (NaN, inf, negative stiffness, ...) arriving
through a scene file (TOML allows nan and inf literals) or a mesh file, and the inputs a
hostile user tried: wrong types, huge numbers, deep nesting, long strings, odd paths.
"""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

# ---------------------------------------------------------------------------- scene files
# The same bad numbers arriving through a scene file (TOML allows nan and inf literals) or a
# mesh file: one line "<file>: <key.path>: <what>", naming the key and the index.
GRID_TOML = '[cloth]\nresolution = [3, 3]\n[springs]\nstructural = 10.0\n'
PIN_0 = '[[effects]]\nkind = "pin"\nvertices = [0]\n'
SCENE_CASES = [
    # (label, scene text, key path, message)
    ("gravity nan", GRID_TOML + '[[effects]]\nkind = "gravity"\nacceleration = [0.0, nan, 0.0]\n',
     "effects[0].acceleration[1]", "must be a finite number, got nan"),
    ("stiffness -inf", GRID_TOML.replace("10.0", "-inf"), "springs.structural",
     "must be a finite number, got -inf"),
    ("stiffness +nan", GRID_TOML.replace("10.0", "+nan"), "springs.structural",
     "must be a finite number, got nan"),
    ("vertex mass nan", '[cloth]\nresolution = [2, 2]\nvertex_mass = [1.0, 1.0, nan, 1.0]\n',
     "cloth.vertex_mass[2]", "must be a finite number, got nan"),
    ("pin region nan", GRID_TOML + '[[effects]]\nkind = "pin"\n'
     'region = { min = [nan, 0, 0], max = [1, 1, 1] }\n', "effects[0].region.min[0]",
     "must be a finite number, got nan"),
    ("pin release nan", GRID_TOML + PIN_0 + 'release = nan\n', "effects[0].release",
     "must be a finite number, got nan"),
    ("tolerance inf", '[solver]\ntolerance = inf\n', "solver.tolerance",
     "must be a finite number, got inf"),
    ("h <= 0: fps negative", '[scene]\nfps = -30\n', "scene.fps", "must be positive, got -30.0"),
    ("h <= 0: fps inf", '[scene]\nfps = inf\n', "scene.fps", "must be a finite number, got inf"),
    ("h <= 0: fps · substeps overflows", GRID_TOML + '[scene]\nfps = 1e308\nsubsteps = 10\n',
     "scene.fps", "fps · substeps = 1e+308 · 10 overflows: the time step h = 1 / (fps · "
                  "substeps) would be 0"),
    ("pin in two pins", GRID_TOML + PIN_0 + '[[effects]]\nkind = "pin"\n'
     'region = { min = [-1, -1, -1], max = [1, 1, 1] }\n', "effects",
     "vertex 0 is pinned by more than one pin"),
    ("mesh file nan", '[cloth]\nshape = "mesh"\nmesh = "nan.obj"\n', "cloth.vertices[2, 1]",
     "must be a finite number, got nan"),
    ("mesh file unreadable", '[cloth]\nshape = "mesh"\nmesh = "broken.ply"\n', "cloth.mesh",
     "cannot read "),
    ("mesh file unknown format", '[cloth]\nshape = "mesh"\nmesh = "cloth.xyz"\n', "cloth.mesh",
     "unknown mesh format '.xyz'"),
]


@pytest.mark.parametrize("label, text, path, message", SCENE_CASES,
                         ids=[c[0] for c in SCENE_CASES])
def test_bad_scene_numbers_name_key_and_index(tmp_path, label, text, path, message):
    from clothsim.scene import SceneError, load_scene
    (tmp_path / "nan.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n")
    (tmp_path / "broken.ply").write_bytes(b"ply\nformat nonsense\n\x00\x01")
    (tmp_path / "cloth.xyz").write_text("1 2 3\n")
    scene_file = tmp_path / "scene.toml"
    scene_file.write_text(text)
    with pytest.raises(SceneError) as info:
        load_scene(scene_file).build_simulation()
    line = str(info.value)
    assert "\n" not in line
    assert line.startswith(f"{scene_file}: {path}: {message}"), line
    if "mesh file un" in label:       # an unreadable mesh names the formats that are read
        formats = line.split("supported formats:")[1].split()
        assert {".obj", ".ply", ".stl", ".vtu", ".msh"} <= set(formats)


def test_bad_scene_overrides_and_assignment_json(tmp_path):
    """h ≤ 0 and iterations < 1 through overrides; NaN/inf in an assignment's JSON."""
    from clothsim.scene import SceneError, data_dir, load_scene
    scene = load_scene("hanging")
    with pytest.raises(SceneError, match=r": scene\.substeps: must be an integer >= 1, got 0$"):
        scene.build_simulation(substeps=0)
    with pytest.raises(SceneError, match=r": solver\.iterations: must be an integer >= 1, got -1$"):
        scene.build_simulation(iterations=-1)
    obj = data_dir() / "single-spring-horizontal.obj"
    if not obj.is_file():
        pytest.skip("assignment data not found")
    (tmp_path / "s.obj").write_bytes(obj.read_bytes())
    for key, text in (("k", "NaN"), ("m", "Infinity"), ("m", "-Infinity")):
        p = tmp_path / "s.json"
        values = {"k": "1.0", "m": "1.0", key: text}
        p.write_text(f'{{"obj": "s.obj", "b": [1], "k": {values["k"]}, "m": {values["m"]}}}')
        with pytest.raises(SceneError) as info:
            load_scene(p).build_simulation()
        got = {"NaN": "nan", "Infinity": "inf", "-Infinity": "-inf"}[text]
        assert str(info.value) == f"{p}: {key}: expected a finite number, got {got}"


@settings(max_examples=20, deadline=None)
@given(data=st.data(), value=st.sampled_from(["nan", "inf", "-inf", "+inf"]))
def test_toml_nan_at_random_index_is_named(data, value):
    """A nan/inf literal at a random index of a TOML vertex_mass array or pin-region corner."""
    from clothsim.scene import Scene, SceneError, parse_toml
    if data.draw(st.booleans(), label="vertex_mass"):
        i = data.draw(st.integers(0, 15), label="vertex")
        masses = ["0.1"] * 16
        masses[i] = value
        text = f'[cloth]\nresolution = [4, 4]\nvertex_mass = [{", ".join(masses)}]\n'
        path = f"cloth.vertex_mass[{i}]"
    else:
        corner = data.draw(st.sampled_from(["min", "max"]), label="corner")
        i = data.draw(st.integers(0, 2), label="axis")
        box = {"min": ["-1.0"] * 3, "max": ["1.0"] * 3}
        box[corner][i] = value
        text = (f'[[effects]]\nkind = "pin"\nregion = {{ min = [{", ".join(box["min"])}], '
                f'max = [{", ".join(box["max"])}] }}\n')
        path = f"effects[0].region.{corner}[{i}]"
    with pytest.raises(SceneError) as info:
        Scene.from_dict(parse_toml(text, "s.toml"), source="s.toml")
    expected = repr(float(value))
    assert str(info.value) == f"s.toml: {path}: must be a finite number, got {expected}"
