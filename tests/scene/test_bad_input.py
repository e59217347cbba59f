"""Bad scene files: every bad input is one line naming the file, the key and the index.

The same bad numbers the core API rejects (NaN, inf, negative stiffness, ...) arriving
through a scene file (TOML allows nan and inf literals) or a mesh file, and the inputs a
hostile user tried: wrong types, huge numbers, deep nesting, long strings, odd paths.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from benchmarks import fuzz_scenes

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
    ("mesh file nan", '[cloth]\nshape = "mesh"\nmesh = "nan.obj"\n', "cloth.mesh",
     "vertices[2, 1]: must be a finite number, got nan"),  # the key the user wrote
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
    from clothsim.scene import SceneError, load_scene
    scene = load_scene("hanging")
    with pytest.raises(SceneError, match=r": scene\.substeps: must be an integer >= 1, got 0$"):
        scene.build_simulation(substeps=0)
    with pytest.raises(SceneError, match=r": solver\.iterations: must be an integer >= 1, got -1$"):
        scene.build_simulation(iterations=-1)
    (tmp_path / "s.obj").write_text("v 0 0 0\nv 1 0 0\nf 1 2\n")  # the assignment's spring
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


# ---------------------------------------------------------------------------- hostile input
# Each input a hostile user tried that did not name its key: now exit 2, one line, the key.
GRAVITY_TOML = GRID_TOML + '[[effects]]\nkind = "gravity"\n'
BIG_INT = "1" + "0" * 400
HOSTILE = [
    # (label, scene text, key path, message fragment)
    ("integer beyond float range", GRID_TOML + f"[scene]\nfps = {BIG_INT}\n", "scene.fps",
     "an integer of 401 digits is beyond the floating-point range"),
    ("integer beyond float range in an effect",
     GRAVITY_TOML + f"acceleration = [0, {BIG_INT}, 0]\n",
     "effects[0].acceleration[1]", "beyond the floating-point range"),
    ("integer beyond int64 in a count", f"[solver]\niterations = {2 ** 70}\n",
     "solver.iterations", f"must be an integer <= 1e5 (larger is almost surely a mistake and "
                          f"would run for ages), got {2 ** 70}"),
    ("radius 1e200", GRID_TOML + '[[effects]]\nkind = "sphere"\ncenter = [0, 0, 0]\n'
     'radius = 1e200\n', "effects[0].radius", "must be at most 1e+100, got 1e+200"),
    ("stiffness 1e17", '[springs]\nstructural = 1e17\n', "springs.structural",
     "is too large for h = 0.0333 s"),
    ("huge substeps", "[scene]\nsubsteps = 100000000\n", "scene.substeps",
     "must be an integer <= 1e4"),
    ("huge iterations", "[solver]\niterations = 1000000000\n", "solver.iterations",
     "must be an integer <= 1e5"),
    ("huge frames", "[scene]\nframes = 100000000000\n", "scene.frames",
     "must be an integer <= 1e7"),
    ("huge grid", "[cloth]\nresolution = [100000, 100000]\n", "cloth.resolution",
     "100000 × 100000 vertices is more than 1e7"),
    ("tiny polygon spacing", '[cloth]\nshape = "polygon"\noutline = [[0, 0], [1, 0], [0, 1]]\n'
     'spacing = 1e-200\n', "cloth.spacing", "more than 1e7"),
    ("h beyond float rounding", "[scene]\nfps = 1e300\n", "scene.fps",
     "must be between 1e-09 s and 1e+06 s"),
    ("word for a vector", GRAVITY_TOML + 'acceleration = "down"\n', "effects[0].acceleration",
     "must be a list of 3 numbers, got 'down'"),
    ("booleans for a vector", GRAVITY_TOML + "acceleration = [true, false, true]\n",
     "effects[0].acceleration", "must be a list of 3 numbers, got [True, False, True]"),
    ("numeric string", GRID_TOML + '[[effects]]\nkind = "plane"\npoint = [0, 0, 0]\n'
     'normal = [0, 1, 0]\nfriction = "0.5"\n', "effects[0].friction",
     "expected a number, got string '0.5'"),
    ("boolean for a number", "[scene]\nfps = true\n", "scene.fps",
     "expected a number, got boolean True"),
    ("numeric string for an integer", '[scene]\nframes = "10"\n', "scene.frames",
     "expected an integer, got string '10'"),
    ("wrong type in strain-limit", GRID_TOML + '[[effects]]\nkind = "strain-limit"\n'
     'families = "structural"\n', "effects[0].families", "expected an array of strings"),
    ("grid centred at 1e17", "[cloth]\ncenter = [1e17, 0, 0]\n", "cloth.center",
     "below the rounding of coordinates near 1e+17 m"),
    ("negative pin release", GRID_TOML + PIN_0 + "release = -1.0\n", "effects[0].release",
     "must be non-negative, got -1.0"),
    ("name ..", '[scene]\nname = ".."\n', "scene.name", "use letters, digits"),
    ("name with a slash", '[scene]\nname = "a/b"\n', "scene.name", "use letters, digits"),
    ("name with a leading dot", '[scene]\nname = ".hidden"\n', "scene.name", "not starting"),
    ("name too long", f'[scene]\nname = "{"a" * 101}"\n', "scene.name", "at most 100"),
    ("directory as mesh", '[cloth]\nshape = "mesh"\nmesh = "folder"\n', "cloth.mesh",
     "is a directory"),
    ("OBJ index beyond int64", '[cloth]\nshape = "mesh"\nmesh = "big.obj"\n', "cloth.mesh",
     "out of range"),
    ("unknown effect key", GRAVITY_TOML + "strength = 1\n", "effects[0].strength",
     "unknown key 'strength'"),
    ("nested value", GRAVITY_TOML + "acceleration = [[0, 1, 0]]\n", "effects[0].acceleration",
     "expected 3 numbers"),
]


@pytest.mark.parametrize("label, text, path, message", HOSTILE, ids=[c[0] for c in HOSTILE])
def test_hostile_input_names_the_key(tmp_path, capsys, label, text, path, message):
    from clothsim import cli
    (tmp_path / "folder").mkdir()
    (tmp_path / "big.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 " + "9" * 30 + "\n")
    p = tmp_path / "scene.toml"
    p.write_text(text)
    for argv in (["validate", str(p)], ["run", str(p), "--out", str(tmp_path / "o"),
                                        "--no-preview"]):
        assert cli.main(argv) == 2
        out, err = capsys.readouterr()
        assert err.count("\n") == 1, err
        assert err.startswith(f"clothsim: error: {p}: {path}: "), err
        assert message in err, err
        assert "np.float64" not in err and "Traceback" not in err
    assert not list(tmp_path.glob("o/*"))     # nothing written for a bad scene


def test_huge_value_is_echoed_truncated(tmp_path):
    from clothsim.scene import SceneError, load_scene
    p = tmp_path / "s.toml"
    p.write_text(f'[scene]\nname = "{"x" * 100_000}"\n')
    with pytest.raises(SceneError) as info:
        load_scene(p)
    assert len(str(info.value)) < 400 and "…" in str(info.value)
    p.write_text(f'[[effects]]\nkind = "{"y" * 100_000}"\n')
    with pytest.raises(SceneError) as info:
        load_scene(p)
    assert len(str(info.value)) < 400 and str(info.value).startswith(f"{p}: effects[0].kind: ")


def test_deep_nesting_is_one_line(tmp_path, capsys):
    from clothsim import cli
    for i, text in enumerate(["a = " + "[" * 900 + "]" * 900,
                              '[scene]\nname = ' + "{a = " * 900 + "1" + "}" * 900]):
        p = tmp_path / f"deep{i}.toml"
        p.write_text(text + "\n")
        assert cli.main(["validate", str(p)]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "nested too deeply" in err, err


def test_byte_order_mark_is_accepted(tmp_path):
    from clothsim.scene import load_scene
    p = tmp_path / "bom.toml"
    p.write_bytes(b"\xef\xbb\xbf[scene]\nframes = 3\n")
    assert load_scene(p).frames == 3


def test_plane_normal_of_huge_numbers_is_not_ignored():
    from clothsim.scene import Scene
    s = Scene.from_dict({"cloth": {"resolution": [3, 3]}, "effects": [
        {"kind": "plane", "point": [0, 0, 0], "normal": [1e300, 1e300, 0]}]})
    plane = s.build_effects()[0]
    np.testing.assert_allclose(plane.normal, [2 ** -0.5, 2 ** -0.5, 0.0], rtol=1e-15)


def test_assignment_file_name_with_a_space_is_not_a_scene_name_error(tmp_path):
    from clothsim.scene import load_scene

    from ..data_sets import write_assignment_scene
    src = write_assignment_scene(tmp_path, "spring")  # spring.json + spring.obj
    p = tmp_path / "my spring (copy).json"
    p.write_bytes(src.read_bytes())
    scene = load_scene(p)
    assert scene.name == "jacobson-my-spring-copy-"
    assert scene.build_model().vertex_count == 2


def test_core_error_field_is_used_before_the_message():
    """The scene layer takes the key from InputError.field, not from parsing the message."""
    from clothsim.errors import InputError
    from clothsim.scene.checks import locate
    assert locate(InputError("anything at all", field="vertex_mass[3]"), "cloth") == \
        ("cloth.vertex_mass[3]", "anything at all")
    assert locate(InputError("vertex_mass[3]: must be positive"), "cloth") == \
        ("cloth.vertex_mass[3]", "must be positive")
    assert locate(InputError("sphere.radius: bad", field="sphere.radius"), "effects[2]",
                  "sphere", "effects[2]") == ("effects[2].radius", "bad")
    assert locate(InputError("no field here"), "cloth") == ("cloth", "no field here")


# ---------------------------------------------------------------------------- mutations
# The generators are benchmarks/fuzz_scenes.py's, whose counts docs/reliability.md shows.
@settings(max_examples=150, deadline=None)
@given(doc=fuzz_scenes.mutated_scene())
def test_mutated_scenes_exit_2_naming_a_key_never_a_traceback(tmp_path_factory, doc):
    """Mutate a valid scene (a value's type or magnitude, a key's name, extra nesting): the
    command either accepts it or exits 2 with one line naming a key; never exit 1; `run`
    refuses it the same way, before writing anything."""
    p = tmp_path_factory.mktemp("mut") / "scene.toml"
    p.write_text(fuzz_scenes.to_toml(doc))
    kind, line = fuzz_scenes.outcome(p)
    assert kind in ("accepted", "refused"), line


def test_errors_carry_their_field():
    import pickle

    from clothsim.errors import InputError, SceneError
    e = InputError("vertex_mass[2]: must be positive", field="vertex_mass[2]")
    assert e.field == "vertex_mass[2]" and str(e) == "vertex_mass[2]: must be positive"
    assert InputError("plain").field is None
    s = SceneError("a.toml", "effects[1].radius", "must be\npositive")
    assert s.field == "effects[1].radius"
    assert str(s) == "a.toml: effects[1].radius: must be positive"
    assert isinstance(s, InputError) and SceneError("a.toml", "", "x").field is None
    e2 = pickle.loads(pickle.dumps(e))
    assert str(e2) == str(e) and e2.field == "vertex_mass[2]"
    s2 = pickle.loads(pickle.dumps(s))
    assert str(s2) == str(s) and s2.field == s.field
