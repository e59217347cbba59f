"""The run pipeline: every result file, interruption, bitwise resume, and that an effect a
scene does not declare costs nothing and changes nothing."""

import json
import textwrap

import numpy as np
import pytest

from clothsim import io
from clothsim.errors import InputError
from clothsim.runner import NonFiniteStateError, completed_frames, run_scene
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
    status = "interrupted" if isinstance(exc, KeyboardInterrupt) else "failed"
    assert run["status"] == status and run["last_frame"] == k - 1
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


# --------------------------------------------------------------------------- run records


def test_run_json_is_rewritten_after_every_frame(tiny, tmp_path):
    out = tmp_path / "out"
    seen = []

    def progress(k, total):
        run = json.loads((out / "run.json").read_text())
        seen.append((run["status"], run["last_frame"], len(run["frames"]),
                     run["trajectory_frames"], (out / "trajectory.npz").exists()))

    run_scene(tiny, out, progress=progress, preview=False)
    # trajectory.npz is written once, at the end: while the run goes on there is none, and
    # run.json says so (the frames are the record; a killed run is finished by --resume)
    assert seen == [("running", k, k, None, False) for k in range(1, 5)]
    run = json.loads((out / "run.json").read_text())
    assert (run["status"], run["trajectory_frames"]) == ("completed", 5)
    assert np.load(out / "trajectory.npz")["positions"].shape[0] == 5


def test_fresh_run_removes_every_file_of_an_earlier_run(tiny, tmp_path, monkeypatch):
    out = tmp_path / "out"
    run_scene(tiny, out, preview=True)
    (out / "obstacles.vtu").write_text("from an earlier run")
    _step_failing_at(monkeypatch, 2, KeyboardInterrupt())
    with pytest.raises(KeyboardInterrupt):
        run_scene(tiny, out, preview=False)
    left = sorted(p.name for p in out.iterdir() if not p.name.startswith("."))
    assert left == ["frame_000000.vtu", "frame_000001.vtu", "run.json", "trajectory.npz",
                    "trajectory.pvd"]
    assert np.load(out / "trajectory.npz")["positions"].shape[0] == 2


def test_frames_without_a_run_record_are_never_deleted(tiny, tmp_path):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "frame_000000.vtu").write_text("someone else's file")
    for resume in (False, True):
        with pytest.raises(InputError, match=r"not a clothsim run's folder.*frame_000000"):
            run_scene(tiny, out, preview=False, resume=resume)
    assert (out / "frame_000000.vtu").read_text() == "someone else's file"
    assert sorted(p.name for p in out.iterdir()) == ["frame_000000.vtu"]  # not even a lock


def test_resume_with_an_unreadable_index_keeps_every_frame(tiny, tmp_path, monkeypatch):
    full = tmp_path / "full"
    run_scene(tiny, full, preview=False)
    out = tmp_path / "out"
    with monkeypatch.context() as m:
        _step_failing_at(m, 4, KeyboardInterrupt())
        with pytest.raises(KeyboardInterrupt):
            run_scene(tiny, out, preview=False)
    (out / "trajectory.pvd").write_text("<VTKFile><Coll")  # truncated XML
    kept = {k: (out / f"frame_{k:06d}.vtu").read_bytes() for k in range(4)}
    result = run_scene(tiny, out, resume=True, preview=False)
    assert result.last_frame == 4 and json.loads((out / "run.json").read_text())[
        "resumed_from"] == 3
    for k, data in kept.items():
        assert (out / f"frame_{k:06d}.vtu").read_bytes() == data
    a, b = np.load(full / "trajectory.npz"), np.load(out / "trajectory.npz")
    assert all(np.array_equal(a[key], b[key]) for key in a.files)
    assert len(io.read_pvd(out / "trajectory.pvd")) == 5


def test_resume_refuses_a_different_scene(tiny, tmp_path):
    out = tmp_path / "out"
    run_scene(tiny, out, frames=2, preview=False)
    before = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}
    other = Scene.from_dict({**tiny.to_dict(), "springs": {**tiny.to_dict()["springs"],
                                                          "structural": 201.0}})
    assert other.build_model().vertex_count == 25
    with pytest.raises(InputError, match=r"holds a run of a different scene"):
        run_scene(other, out, frames=4, resume=True, preview=False)
    after = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}
    assert after == before
    # the frame count is not part of the scene: resuming with more frames is fine
    assert run_scene(tiny, out, frames=3, resume=True, preview=False).last_frame == 3


def test_resume_with_fewer_frames_cuts_the_index_and_keeps_the_files(tiny, tmp_path):
    out = tmp_path / "out"
    run_scene(tiny, out, frames=6, preview=False)
    result = run_scene(tiny, out, frames=2, resume=True, preview=False)
    assert result.status == "completed" and result.last_frame == 2
    assert [p.name for _, p in io.read_pvd(out / "trajectory.pvd")] == \
        [f"frame_{k:06d}.vtu" for k in range(3)]
    z = np.load(out / "trajectory.npz")
    assert z["positions"].shape[0] == 3 and z["time"].shape == (3,)
    run = json.loads((out / "run.json").read_text())
    assert run["last_frame"] == 2 and [r["frame"] for r in run["frames"]] == [1, 2]
    assert (out / "frame_000006.vtu").is_file()  # a valid frame is never deleted


BLOWUP = {"scene": {"name": "blowup", "frames": 60, "fps": 30},
          "cloth": {"resolution": [5, 5], "center": [0, 1, 0], "plane": "xy"},
          "springs": {"structural": 1e9, "shear": 1e9},
          "solver": {"method": "symplectic-euler"},
          "effects": [{"kind": "gravity"}, {"kind": "pin", "vertices": [20, 24]}]}


@pytest.mark.filterwarnings("ignore")
def test_a_blowup_stops_before_a_non_finite_frame(tmp_path):
    out = tmp_path / "out"
    with pytest.raises(NonFiniteStateError) as info:
        run_scene(Scene.from_dict(BLOWUP), out, preview=False)
    message = str(info.value)
    assert message.startswith("frame ") and "the state became non-finite (" in message
    k = int(message.split()[1].rstrip(":"))
    assert "\n" not in message and f"frame {k - 1} is the last one kept" in message
    run = json.loads((out / "run.json").read_text())
    assert run["status"] == "failed" and run["last_frame"] == k - 1
    assert run["error"].startswith("NonFiniteStateError: frame ")
    assert completed_frames(out) == k - 1 and not (out / f"frame_{k:06d}.vtu").exists()
    z = np.load(out / "trajectory.npz")
    assert z["positions"].shape[0] == k and np.isfinite(z["positions"]).all()
    for j in range(k):
        assert np.isfinite(io.read_frame(out / f"frame_{j:06d}.vtu")[0]).all()


def test_converged_is_null_without_a_tolerance(tiny, tmp_path):
    run_scene(tiny, tmp_path / "fixed", frames=2, preview=False)
    run = json.loads((tmp_path / "fixed" / "run.json").read_text())
    assert [r["converged"] for r in run["frames"]] == [None, None]
    assert all(r["residual"] > 1e-3 for r in run["frames"])  # 10 iterations: not converged
    doc = tiny.to_dict()
    doc["solver"] = {**doc["solver"], "tolerance": 1e-6, "iterations": 2000}
    run_scene(Scene.from_dict(doc), tmp_path / "tol", frames=2, preview=False)
    run = json.loads((tmp_path / "tol" / "run.json").read_text())
    assert [r["converged"] for r in run["frames"]] == [True, True]
    assert all(r["residual"] <= 1e-6 for r in run["frames"])


def test_memory_does_not_grow_with_the_number_of_frames(tmp_path):
    """Peak traced memory of a 33 × 33 run: 45 frames cost no more than 5 (the old runner
    kept every frame, 52 kB each here, and needed 2 MB more)."""
    import tracemalloc

    scene = Scene.from_dict({"scene": {"name": "mem", "frames": 45, "fps": 30},
                             "cloth": {"resolution": [33, 33], "center": [0, 1, 0]},
                             "springs": {"structural": 100.0, "shear": 100.0},
                             "solver": {"iterations": 2},
                             "effects": [{"kind": "gravity"}]})
    run_scene(scene, tmp_path / "warm", frames=2, preview=False)  # imports, caches
    peaks = []
    for frames in (5, 45):
        tracemalloc.start()
        run_scene(scene, tmp_path / f"f{frames}", frames=frames, preview=False)
        peaks.append(tracemalloc.get_traced_memory()[1])
        tracemalloc.stop()
    frame_bytes = 2 * 33 * 33 * 3 * 8
    assert peaks[1] - peaks[0] < 10 * frame_bytes, (peaks, frame_bytes)


def test_scene_hash_is_the_recorded_one_and_keeps_its_bytes(tiny, tmp_path):
    """run_scene hashes the model on a thread beside the simulation's build: run.json holds
    scene_hash's value, which is still SHA-256 of the scene's text and the arrays' bytes (a
    run.json written by an earlier clothsim resumes)."""
    import copy
    import hashlib

    from clothsim.runner import scene_hash

    scene = tiny
    model = scene.build_model()
    run_scene(scene, tmp_path / "out", frames=1, preview=False)
    recorded = json.loads((tmp_path / "out" / "run.json").read_text())["scene_hash"]
    doc = copy.deepcopy(scene.to_dict())
    doc["scene"].pop("frames")
    doc.pop("output", None)
    digest = hashlib.sha256(json.dumps(doc, sort_keys=True, default=str).encode())
    s = model.springs
    for a in (model.mesh.vertices, model.mesh.triangles, model.mesh.strands, s.spring_vertices,
              s.spring_stiffness, s.spring_rest_length, model.vertex_mass):
        digest.update(np.ascontiguousarray(a).tobytes())
    assert recorded == scene_hash(scene, model) == digest.hexdigest()[:16]
    assert len(model.mesh.strands) == 0   # an empty array hashed too


def test_touch_pages_leaves_every_value_as_it_was(monkeypatch):
    """run_scene touches the solver's large work arrays after the build (their first writes
    out of the first step): each byte it writes is itself, small, read-only and strided
    arrays are left alone, and a run's steps are those of a simulation never touched."""
    from types import SimpleNamespace

    import clothsim.runner as runner
    from clothsim.runner import TOUCH_FROM, touch_pages

    rng = np.random.default_rng(3)
    big = rng.standard_normal(TOUCH_FROM // 8 + 100)
    frozen = big.copy()
    frozen.flags.writeable = False
    owner = SimpleNamespace(big=big, ints=np.arange(TOUCH_FROM // 8, dtype=np.int64),
                            small=np.ones(10), frozen=frozen,
                            strided=np.zeros((2, TOUCH_FROM // 8))[:, ::2], text="x")
    before = {k: v.copy() for k, v in vars(owner).items() if isinstance(v, np.ndarray)}
    assert touch_pages(owner) == 2                        # big and ints
    for k, v in before.items():
        assert getattr(owner, k).tobytes() == v.tobytes(), k
    monkeypatch.setattr(runner, "TOUCH_FROM", 1 << 12)   # a small cloth's arrays too
    scene = load_scene("hanging", ["cloth.resolution=[41, 41]"])
    plain, touched = scene.build_simulation(), scene.build_simulation()
    assert touch_pages(touched.solver) >= 2               # its per-spring work arrays
    for _ in range(2):
        plain.step()
        touched.step()
    assert plain.state.positions.tobytes() == touched.state.positions.tobytes()
    assert plain.state.velocities.tobytes() == touched.state.velocities.tobytes()
