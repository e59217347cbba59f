"""A model from files in a scene: vertices, triangles, spring tables with attachments,
masses and pins from plain text; the paper authors' default scene rebuilt from its own
files (the data set liu13-port, shipped with clothsim)."""

from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from clothsim import cli
from clothsim import matrices as mx
from clothsim.scene import Scene, SceneError, load_scene

from ..data_sets import liu13_dir

REPO = Path(__file__).resolve().parents[2]
PORT_SCENE = REPO / "examples" / "ports" / "liu13-default.toml"


def port_dir() -> Path:
    return liu13_dir()  # ships with clothsim


def square(tmp_path, *, one_line=False, base=0, table=None, extra_cloth="", effects=""):
    """A unit square of 4 vertices, 2 triangles, written as files; returns the scene path."""
    x = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 0.0, 1.0], [0.0, 0.0, 1.0]]
    (tmp_path / "x.txt").write_text(" ".join(repr(v) for r in x for v in r) + "\n" if one_line
                                    else "# x y z\n" + "\n".join(" ".join(map(repr, r))
                                                                 for r in x) + "\n")
    (tmp_path / "t.txt").write_text(f"{0 + base} {1 + base} {2 + base}\n"
                                    f"{0 + base} {2 + base} {3 + base}\n")
    springs = ""
    if table is not None:
        (tmp_path / "s.txt").write_text(table)
        springs = f'[springs]\ntable = "s.txt"\nindex_base = {base}\n'
    text = (f'[scene]\nframes = 2\n[cloth]\nshape = "files"\nvertices = "x.txt"\n'
            f'triangles = "t.txt"\nindex_base = {base}\n{extra_cloth}{springs}{effects}')
    p = tmp_path / "files.toml"
    p.write_text(text)
    return p


@pytest.mark.parametrize("one_line", [False, True])
@pytest.mark.parametrize("base", [0, 1])
def test_vertices_and_triangles_from_files(tmp_path, one_line, base):
    p = square(tmp_path, one_line=one_line, base=base, table="0 1 10 1\n1 2 10 1\n",
               extra_cloth="")
    if base:
        (tmp_path / "s.txt").write_text("1 2 10 1\n2 3 10 1\n")
    m = load_scene(p).build_model()
    assert m.vertex_count == 4 and m.mesh.triangle_count == 2
    assert m.mesh.triangles.tolist() == [[0, 1, 2], [0, 2, 3]]
    assert m.springs.spring_vertices.tolist() == [[0, 1], [1, 2]]
    np.testing.assert_array_equal(m.vertex_mass, 0.25)


def test_table_adds_to_generated_families_and_rest_defaults_to_initial_length(tmp_path):
    p = square(tmp_path, table="# a b k\n0 2 7\n")
    text = p.read_text().replace('table = "s.txt"', 'table = "s.txt"\nstructural = 3.0\n'
                                 'columns = ["a", "b", "stiffness"]')
    p.write_text(text)
    m = load_scene(p).build_model()
    assert m.spring_count == 5 + 1                       # 5 edges, then the table's row
    assert m.springs.spring_stiffness[-1] == 7.0
    assert m.springs.spring_rest_length[-1] == pytest.approx(np.sqrt(2.0), abs=1e-15)


def test_attachments_become_penalty_pins(tmp_path):
    p = square(tmp_path, table="0 1 10 1\n3 -1 50 0\n", effects='[[effects]]\n'
               'kind = "gravity"\n')
    s = load_scene(p)
    m = s.build_model()
    assert m.spring_count == 1
    sim = s.build_simulation(m)
    assert sim.effects_built == ["pin", "gravity"]
    pin = sim.effects[0]
    assert pin.method == "penalty" and pin.stiffness == 50.0 and pin.vertices.tolist() == [3]
    sim.run(20)       # vertex 3 hangs on its 50 N/m spring: below, but near, where it was
    assert 0 < m.mesh.vertices[3, 1] - sim.state.positions[3, 1] < 0.5


@pytest.mark.parametrize("table, message", [
    ("0 1 10\n", "line 1 of s.txt: expected 4 numbers (a b stiffness rest), got 3"),
    ("0 9 10 1\n", "line 1 of s.txt: vertex 9 out of range 0..3"),
    ("0 1.5 10 1\n", "vertex indices must be integers, got 1.5"),
    ("0 1 x 1\n", "line 1 of s.txt: not a number: 'x'"),
    ("0 -1 10 0.5\n", "an attachment (b = -1) must have rest length 0, got 0.5"),
    ("-1 2 10 0\n", "a = -1; only b may mark an attachment"),
    ("0 1 -3 1\n", "stiffness must be non-negative, got -3.0"),
    ("0 1 nan 1\n", "must be a finite number, got nan"),
    ("# only a comment\n", "s.txt holds no numbers"),
])
def test_bad_spring_table_names_key_and_line(tmp_path, capsys, table, message):
    p = square(tmp_path, table=table)
    assert cli.main(["validate", str(p)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"{p}: springs.table: " in err and message in err, err


def test_masses_and_pins_from_files(tmp_path):
    (tmp_path / "m.txt").write_text("0.1\n0.2\n0.3\n0.4\n")
    (tmp_path / "pins.txt").write_text("# 1-based\n1 2\n")
    p = square(tmp_path, table="0 1 10 1\n", extra_cloth='vertex_mass = "m.txt"\n',
               effects='[[effects]]\nkind = "pin"\nvertices = "pins.txt"\nindex_base = 1\n')
    s = load_scene(p)
    m = s.build_model()
    np.testing.assert_array_equal(m.vertex_mass, [0.1, 0.2, 0.3, 0.4])
    assert s.build_effects(m)[0].vertices.tolist() == [0, 1]
    (tmp_path / "m.txt").write_text("0.1 0.2\n")
    with pytest.raises(SceneError, match=r"cloth.vertex_mass: expected 4 values"):
        s.build_model()


def test_vertex_file_layout_errors(tmp_path):
    p = square(tmp_path)
    (tmp_path / "x.txt").write_text("0 0 0 1 0\n")
    with pytest.raises(SceneError, match=r"cloth.vertices: line 1 of x.txt: one line must "
                                         r"hold 3n numbers"):
        load_scene(p).build_model()
    (tmp_path / "x.txt").write_text("0 0 0\n1 0\n")
    with pytest.raises(SceneError, match=r"cloth.vertices: line 2 of x.txt: expected 3"):
        load_scene(p).build_model()


def test_exact_time_step():
    s = Scene.from_dict({"scene": {"h": 0.0333}})
    assert s.h == 0.0333 and s.substeps == 1
    assert s.build_simulation(s.build_model()).h == 0.0333
    with pytest.raises(SceneError, match=r"scene.fps: give either 'h' or 'fps'"):
        Scene.from_dict({"scene": {"h": 0.0333, "fps": 30}})
    with pytest.raises(SceneError, match=r"scene.h: must be positive"):
        Scene.from_dict({"scene": {"h": -1.0}})


# ---------------------------------------------------------------------------- the real port
def test_port_scene_model_matches_the_ports_matrices():
    import scipy.io
    d = port_dir()
    scene = load_scene(PORT_SCENE)
    model = scene.build_model()
    assert scene.h == 0.0333
    assert model.vertex_count == 441 and model.spring_count == 2038
    pins = [e for e in scene.build_effects(model) if e.kind == "pin"]
    assert len(pins) == 1 and pins[0].method == "penalty"
    assert pins[0].vertices.tolist() == [0, 420] and pins[0].stiffness == 120.0
    M = scipy.io.mmread(d / "M.mtx").tocsr()
    assert abs(mx.mass_matrix(model) - M).max() == 0.0
    n = model.vertex_count
    anchors = sp.coo_matrix((np.full(2, 120.0), ([0, 420], [0, 420])), shape=(n, n))
    L = sp.kron(mx.stiffness_matrix(model, expand=False) + anchors, sp.eye(3)).tocsr()
    L_port = scipy.io.mmread(d / "L.mtx").tocsr()
    assert abs(L - L_port).max() <= 1e-12 * abs(L_port).max()
    A = mx.system_matrix(model, scene.h, expand=True, anchor_vertices=[0, 420],
                         anchor_stiffness=120.0)
    A_port = scipy.io.mmread(d / "A.mtx").tocsr()
    assert abs(A - A_port).max() <= 1e-12 * abs(A_port).max()


def test_port_scene_run_matches_the_ports_positions(tmp_path):
    d = port_dir()
    out = tmp_path / "liu13"
    assert cli.main(["run", str(PORT_SCENE), "--out", str(out), "--frames", "5",
                     "--no-preview"]) == 0
    with np.load(out / "trajectory.npz") as z:
        x = z["positions"]
    port = np.loadtxt(d / "positions.txt", max_rows=6)
    assert x.shape == (6, 441, 3)
    np.testing.assert_array_equal(x[0].reshape(-1), port[0])
    err = np.abs(x[1:].reshape(5, -1) - port[1:6]).max()
    assert err <= 1e-9, err
