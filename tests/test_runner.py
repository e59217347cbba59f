"""The run pipeline: every result file, interruption, bitwise resume, and that an effect a
scene does not declare costs nothing and changes nothing."""

import json
import textwrap

import numpy as np
import pytest

from clothsim import io
from clothsim.runner import completed_frames, run_scene
from clothsim.scene import Scene, load_scene
from clothsim.simulation import Simulation

# 5 x 5 cloth hanging from its two top corners (vertices 20 and 24 in plane "xy")
TINY = """
[scene]
name = "tiny"
frames = 4
fps = 30
[cloth]
resolution = [5, 5]
center = [0.0, 1.0, 0.0]
plane = "xy"
[springs]
structural = 200.0
shear = 200.0
bending = 20.0
[[effects]]
kind = "gravity"
[[effects]]
kind = "pin"
vertices = [20, 24]
"""


@pytest.fixture
def tiny(tmp_path):
    p = tmp_path / "tiny.toml"
    p.write_text(textwrap.dedent(TINY))
    return load_scene(p)


def test_run_writes_every_file(tiny, tmp_path):
    out = tmp_path / "out"
    seen = []
    result = run_scene(tiny, out, progress=lambda k, total: seen.append((k, total)))
    assert result.status == "completed" and result.last_frame == 4
    assert seen == [(1, 4), (2, 4), (3, 4), (4, 4)]
    for name in ("trajectory.pvd", "trajectory.npz", "preview.gif", "final.png", "run.json"):
        assert (out / name).stat().st_size > 0, name
    z = np.load(out / "trajectory.npz")
    assert z["positions"].shape == z["velocities"].shape == (5, 25, 3)
    assert z["positions"].dtype == np.float64
    np.testing.assert_allclose(z["time"], np.arange(5) / 30, rtol=0, atol=0)
    assert z["triangles"].shape == (32, 3) and z["springs"].shape == (40 + 32 + 30, 2)
    assert [p.name for _, p in io.read_pvd(out / "trajectory.pvd")] == \
        [f"frame_{k:06d}.vtu" for k in range(5)]
    for k in range(5):  # meshio reads every frame back, bit for bit
        x, v = io.read_frame(out / f"frame_{k:06d}.vtu")
        assert np.array_equal(x, z["positions"][k]) and np.array_equal(v, z["velocities"][k])
    # physics: pins stay exactly put, the free bottom row falls, v = (x1 - x0) / h
    x0, x4 = z["positions"][0], z["positions"][4]
    assert np.array_equal(x4[[20, 24]], x0[[20, 24]])
    assert np.all(x4[:5, 1] < x0[:5, 1] - 0.01)
    np.testing.assert_allclose(z["velocities"][1], (z["positions"][1] - x0) * 30, atol=1e-12)
    run = json.loads((out / "run.json").read_text())
    assert run["status"] == "completed" and run["last_frame"] == 4 and run["error"] is None
    assert run["effects_built"] == ["gravity", "pin"]
    assert run["effects"][1]["vertex_count"] == 2
    assert run["solver"]["method"] == "local-global"
    assert run["solver"]["backend"] in ("cholmod", "splu")
    assert {"python", "numpy", "scipy", "meshio", "matplotlib"} <= set(run["versions"])
    assert [f["frame"] for f in run["frames"]] == [1, 2, 3, 4]
    assert all(f["iterations"] == 10 and f["seconds"] > 0 and f["residual"] < 1
               for f in run["frames"])
    assert run["scene"]["cloth"]["resolution"] == [5, 5]
    from PIL import Image
    with Image.open(out / "preview.gif") as gif:
        assert gif.n_frames == 5


def _step_failing_at(monkeypatch, call, exc):
    real = Simulation.step
    count = {"n": 0}

    def step(self):
        count["n"] += 1
        if count["n"] == call:
            raise exc
        return real(self)

    monkeypatch.setattr(Simulation, "step", step)


@pytest.mark.parametrize("exc", [KeyboardInterrupt(), RuntimeError("solver exploded")])
def test_interrupt_at_frame_k_leaves_frames_before(tiny, tmp_path, monkeypatch, exc):
    k = 3
    _step_failing_at(monkeypatch, k, exc)
    out = tmp_path / "out"
    with pytest.raises(type(exc)):
        run_scene(tiny, out, preview=False)
    assert completed_frames(out) == k - 1
    assert not (out / f"frame_{k:06d}.vtu").exists()
    for j in range(k):
        x, _ = io.read_frame(out / f"frame_{j:06d}.vtu")
        assert x.shape == (25, 3)
    run = json.loads((out / "run.json").read_text())
    assert run["status"] == "interrupted" and run["last_frame"] == k - 1
    assert run["error"].startswith(type(exc).__name__)
    assert len(run["frames"]) == k - 1
    z = np.load(out / "trajectory.npz")
    assert z["positions"].shape == (k, 25, 3) and z["time"].shape == (k,)
    assert not list(out.glob(".*.tmp"))  # no temporary files left behind


def test_resume_equals_uninterrupted_bitwise(tmp_path, monkeypatch):
    # time-dependent forcing (switches on at t = 0.1 s = frame 3) and two substeps per frame:
    # resuming must restart each frame at exactly the same time as the full run
    scene = Scene.from_dict({
        "scene": {"name": "resume", "frames": 6, "fps": 30, "substeps": 2},
        "cloth": {"resolution": [5, 5], "center": [0, 1, 0]},
        "springs": {"structural": 100.0, "shear": 100.0},
        "effects": [{"kind": "gravity"},
                    {"kind": "impulse", "center": [0, 1, 0], "radius": 0.3,
                     "force": [0, 20, 0], "start": 0.1, "duration": 0.05}],
    })
    full = tmp_path / "full"
    run_scene(scene, full, preview=False)
    part = tmp_path / "part"
    with monkeypatch.context() as m:
        _step_failing_at(m, 2 * 3 + 1, KeyboardInterrupt())   # during frame 4
        with pytest.raises(KeyboardInterrupt):
            run_scene(scene, part, preview=False)
    assert completed_frames(part) == 3
    result = run_scene(scene, part, resume=True, preview=False)
    assert result.status == "completed" and result.last_frame == 6
    a, b = np.load(full / "trajectory.npz"), np.load(part / "trajectory.npz")
    for key in ("positions", "velocities", "time"):
        assert np.array_equal(a[key], b[key]), key
    assert not np.array_equal(a["positions"][6], a["positions"][0])
    for k in range(7):
        xa, va = io.read_frame(full / f"frame_{k:06d}.vtu")
        xb, vb = io.read_frame(part / f"frame_{k:06d}.vtu")
        assert np.array_equal(xa, xb) and np.array_equal(va, vb)
    run = json.loads((part / "run.json").read_text())
    assert run["status"] == "completed" and run["resumed_from"] == 3
    assert [f["frame"] for f in run["frames"]] == [1, 2, 3, 4, 5, 6]
    assert [p.name for _, p in io.read_pvd(part / "trajectory.pvd")] == \
        [f"frame_{k:06d}.vtu" for k in range(7)]


def test_fresh_run_replaces_old_frames(tiny, tmp_path):
    out = tmp_path / "out"
    run_scene(tiny, out, preview=False)
    run_scene(tiny, out, frames=2, preview=False)
    assert sorted(p.name for p in out.glob("frame_*.vtu")) == \
        [f"frame_{k:06d}.vtu" for k in range(3)]
    assert np.load(out / "trajectory.npz")["positions"].shape[0] == 3


def _moving_scene(extra):
    # the two top corners are dragged up at 0.5 m/s: the cloth moves without any force
    return Scene.from_dict({
        "scene": {"frames": 4},
        "cloth": {"resolution": [4, 4], "plane": "xy"},
        "springs": {"structural": 100.0, "shear": 100.0, "bending": 10.0},
        "effects": [{"kind": "pin", "vertices": [12, 15], "velocity": [0.0, 0.5, 0.0]}]
        + extra,
    })


@pytest.mark.parametrize("extra", [
    {"kind": "gravity", "acceleration": [0.0, 0.0, 0.0]},
    {"kind": "wind", "velocity": [3.0, 0.0, 1.0], "drag": 0.0},
    {"kind": "damping", "model": "velocity", "coefficient": 0.0},
], ids=lambda e: e["kind"])
def test_absent_effect_equals_zero_strength_effect(extra):
    pytest.importorskip("clothsim.effects").EFFECTS.get(extra["kind"]) or \
        pytest.skip(f"effect {extra['kind']!r} not registered")
    without = _moving_scene([]).build_simulation()
    assert without.effects_built == ["pin"]  # nothing else is built, no hook runs
    with_zero = _moving_scene([extra]).build_simulation()
    assert with_zero.effects_built == ["pin", extra["kind"]]
    without.run(4)
    with_zero.run(4)
    moved = np.abs(without.state.positions - without.model.mesh.vertices).max()
    assert moved > 0.05  # the comparison is not between two resting cloths
    np.testing.assert_allclose(with_zero.state.positions, without.state.positions,
                               rtol=0, atol=1e-12)
