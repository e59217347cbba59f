"""No silent numerical freeze: magnitudes that overflow a step's residual or energy (a rest
length of 1e300, vertices near 1e200, stiffness x length² beyond 1e300) are refused when
the scene is built, naming the key; nothing is written."""

import numpy as np
import pytest

from clothsim.cli import main
from clothsim.scene import SceneError, load_scene
from clothsim.scene.scale import overflow_problem


def _scene(tmp_path, x, table, extra="vertex_mass = 1e100\n"):
    (tmp_path / "x.txt").write_text("\n".join(" ".join(map(repr, r)) for r in x) + "\n")
    (tmp_path / "t.txt").write_text("0 1 2\n0 2 3\n")
    (tmp_path / "s.txt").write_text(table)
    p = tmp_path / "s.toml"
    p.write_text('[scene]\nframes = 2\n[cloth]\nshape = "files"\nvertices = "x.txt"\n'
                 f'triangles = "t.txt"\n{extra}[springs]\ntable = "s.txt"\n'
                 '[[effects]]\nkind = "gravity"\n')
    return p


SQUARE = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 0.0, 1.0], [0.0, 0.0, 1.0]]


@pytest.mark.parametrize("x, table, key, word", [
    (SQUARE, "0 1 10 1e300\n1 2 10 1\n", "springs.table", "rest length"),
    ([[c * 1e200 for c in r] for r in SQUARE], "0 1 10 1e200\n", "cloth.vertices",
     "coordinates"),
    ([[c * 1e99 for c in r] for r in SQUARE], "0 1 1e110 1e99\n", "springs.table",
     "energy overflow"),
])
def test_overflowing_magnitudes_are_refused_naming_the_key(tmp_path, capsys, x, table, key,
                                                           word):
    p = _scene(tmp_path, x, table)
    with pytest.raises(SceneError, match=f"{key}: .*{word}"):
        load_scene(p).build_simulation()
    assert main(["run", str(p), "--out", str(tmp_path / "out"), "--no-preview"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and key in err
    assert not (tmp_path / "out").exists()  # no frame written as if it had moved


def test_large_but_safe_cloth_still_runs_and_moves(tmp_path):
    p = _scene(tmp_path, [[c * 1e3 for c in r] for r in SQUARE], "0 1 10 1e3\n1 2 10 1e3\n")
    sim = load_scene(p).build_simulation()
    assert overflow_problem(sim.model, sim.h) is None
    x0 = sim.state.positions.copy()
    sim.step()
    assert np.all(np.isfinite(sim.state.positions)) and not np.array_equal(sim.state.positions,
                                                                           x0)
