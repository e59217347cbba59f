"""--resume on a cloth in contact: bit for bit, as an uninterrupted run (docs/reliability.md).

In the obstacles' default contact mode, ``"hold"``, a step starts from the contacts the
previous step held (which vertices, their planes, sticking or sliding, normal forces:
:class:`clothsim.effects.holding.Holding`). ``clothsim run`` saves them with every frame
(``state/frame_%06d.npz``, :mod:`clothsim.io.effectstate`) and ``--resume`` restores them;
without them a run resumed while the cloth lies on the box leaves the uninterrupted
trajectory at once (1–2 cm at the next frame on drop-on-square, drape-sphere and impulse,
at 9² to 65²: the old-folder test below measures it).
"""

import json
import logging
import shutil
import signal

import numpy as np
import pytest

from clothsim.effects.base import effect_states, restore_effect_states
from clothsim.effects.holding import Holding
from clothsim.errors import InputError
from clothsim.io.effectstate import planned_state_bytes, read_state, state_files, state_path
from clothsim.runner import run_scene
from clothsim.scene import load_scene
from clothsim.simulation import State

from .test_interrupts import start_run, wait_for_frame

#: scene, frames of the first run (in contact by then), frames of the resumed one
SCENES = [("drop-on-square", 25, 30), ("drape-sphere", 25, 32), ("impulse", 22, 27)]


def small(name, *overrides):
    return load_scene(name, ["cloth.resolution=[9, 9]", *overrides])


def held_count(out, k) -> int:
    state = read_state(out, k)
    return sum(len(a) for key, a in state.items() if key.endswith(".vertices"))


def resumed_and_full(tmp_path, *overrides, name="drop-on-square", cut=25, frames=30):
    scene = small(name, *overrides)
    part, full = tmp_path / "part", tmp_path / "full"
    run_scene(scene, part, frames=cut, preview=False)        # on the obstacle by then
    run_scene(scene, part, frames=frames, preview=False, resume=True)
    run_scene(scene, full, frames=frames, preview=False)
    return (np.load(part / "trajectory.npz")["positions"],
            np.load(full / "trajectory.npz")["positions"])


def test_resume_in_post_solve_contact_is_bit_for_bit(tmp_path):
    a, b = resumed_and_full(tmp_path, 'contact.mode="post-solve"')
    assert np.array_equal(a, b)
    assert not state_files(tmp_path / "full")      # nothing carried, nothing written


@pytest.mark.parametrize("name, cut, frames", SCENES, ids=[s[0] for s in SCENES])
def test_resume_in_held_contact_is_bit_for_bit(tmp_path, name, cut, frames):
    a, b = resumed_and_full(tmp_path, name=name, cut=cut, frames=frames)
    assert held_count(tmp_path / "part", cut) > 0      # the resume point is in contact
    assert np.array_equal(a[:cut + 1], b[:cut + 1])     # the frames before the resume
    assert np.array_equal(a, b), f"{np.abs(a - b).max():.3e} m apart after the resume"
    run = json.loads((tmp_path / "part" / "run.json").read_text())
    assert run["resumed_from"] == cut and run["effect_state_restored"] is True


def test_state_file_of_frame_k_is_the_state_in_memory_after_frame_k(tmp_path):
    """Step the scene as the runner does, and compare every frame's file with memory."""
    scene, frames = small("drop-on-square"), 24
    out = tmp_path / "run"
    result = run_scene(scene, out, frames=frames, preview=False)
    assert set(state_files(out)) <= set(result.files)
    sim = scene.build_simulation()
    sim.expect_steps(frames * scene.substeps)
    contact = 0
    for k in range(frames + 1):
        if k:
            s = sim.state
            sim.state = State(s.positions.copy(), s.velocities.copy(), (k - 1) / scene.fps,
                              (k - 1) * scene.substeps)
            for _ in range(scene.substeps):
                sim.step()
        memory, disk = effect_states(sim.effects), read_state(out, k)
        assert memory.keys() == disk.keys() and memory, k
        for key in memory:
            assert memory[key].dtype == disk[key].dtype, (k, key)
            assert np.array_equal(memory[key], disk[key]), (k, key)
        contact += held_count(out, k) > 0
    assert contact > 5                                  # the comparison covers held frames
    assert [p.name for p in state_files(out)] == [f"frame_{k:06d}.npz"
                                                  for k in range(frames + 1)]


def test_old_folder_without_state_resumes_with_a_warning(tmp_path, caplog):
    scene, part = small("drop-on-square"), tmp_path / "part"
    run_scene(scene, part, frames=25, preview=False)
    shutil.rmtree(part / "state")                      # as a clothsim before it wrote one
    with caplog.at_level(logging.WARNING):
        run_scene(scene, part, frames=30, preview=False, resume=True)
    warnings = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert len(warnings) == 1 and "\n" not in warnings[0]
    assert "frame 25 has no saved effect state" in warnings[0]
    assert "held contacts start empty" in warnings[0]
    run = json.loads((part / "run.json").read_text())
    assert run["status"] == "completed" and run["effect_state_restored"] is False
    full = tmp_path / "full"
    run_scene(scene, full, frames=30, preview=False)
    a = np.load(part / "trajectory.npz")["positions"]
    b = np.load(full / "trajectory.npz")["positions"]
    assert np.array_equal(a[:26], b[:26])
    assert np.abs(a - b).max() > 1e-4                  # what the saved state is for
    assert state_path(part, 30).exists()               # the frames it computed have theirs


def test_resume_from_frame_zero_of_an_old_folder_needs_no_state(tmp_path, caplog):
    scene, out = small("drop-on-square"), tmp_path / "run"
    run_scene(scene, out, frames=0, preview=False)
    shutil.rmtree(out / "state")
    with caplog.at_level(logging.WARNING):
        run_scene(scene, out, frames=3, preview=False, resume=True)
    assert not [r for r in caplog.records if r.levelno == logging.WARNING]
    assert json.loads((out / "run.json").read_text())["effect_state_restored"] is True


def test_a_fresh_run_removes_the_earlier_runs_state_files(tmp_path):
    out = tmp_path / "run"
    run_scene(small("drop-on-square"), out, frames=4, preview=False)
    assert len(state_files(out)) == 5
    run_scene(small("drop-on-square", 'contact.mode="post-solve"'), out, frames=2,
              preview=False)
    assert not state_files(out)


def test_unreadable_state_file_refuses_naming_it(tmp_path):
    scene, out = small("drop-on-square"), tmp_path / "run"
    run_scene(scene, out, frames=3, preview=False)
    state_path(out, 3).write_bytes(b"not a zip")
    before = {p.name: p.stat().st_mtime_ns for p in out.iterdir() if p.is_file()}
    with pytest.raises(InputError, match=r"state/frame_000003\.npz: cannot read"):
        run_scene(scene, out, frames=5, preview=False, resume=True)
    after = {p.name: p.stat().st_mtime_ns for p in out.iterdir() if p.is_file()}
    assert after == before                              # refused before anything is written


def test_sigint_mid_run_then_resume_is_bit_for_bit(tmp_path):
    """A real SIGINT while the cloth lies on the box: every frame on disk has its state,
    and the resumed run is the uninterrupted one."""
    out = tmp_path / "run"
    proc = start_run("drop-on-square", out, "--set", "cloth.resolution=[9, 9]", "--frames",
                     "2000")
    wait_for_frame(out, 22, proc, timeout=120)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 128 + signal.SIGINT, err
    last = json.loads((out / "run.json").read_text())["last_frame"]
    assert last >= 22 and held_count(out, last) > 0
    assert all(state_path(out, k).exists() for k in range(last + 1))
    frames = last + 5
    run_scene(small("drop-on-square"), out, frames=frames, preview=False, resume=True)
    run_scene(small("drop-on-square"), tmp_path / "full", frames=frames, preview=False)
    a = np.load(out / "trajectory.npz")["positions"]
    b = np.load(tmp_path / "full" / "trajectory.npz")["positions"]
    assert np.array_equal(a, b), f"{np.abs(a - b).max():.3e} m apart after the resume"


def test_holding_round_trip_and_bad_arrays():
    x = np.random.default_rng(0).normal(size=(6, 3))
    n = np.tile([0.0, 1.0, 0.0], (3, 1))
    held = Holding(x, np.array([1, 4, 5]), n, np.array([True, False, True]),
                   np.array([0.5, 0.0, 2.0]), np.zeros((3, 3)))
    back = Holding.from_arrays(held.arrays(), 6)
    for key, a in held.arrays().items():
        assert np.array_equal(a, back.arrays()[key]), key
    for attr in ("vertices", "normals", "offsets"):
        assert np.array_equal(getattr(held.planes, attr), getattr(back.planes, attr))
    assert len(held.planes) == 3 + 2 * 2
    bad = held.arrays() | {"offsets": np.zeros(3)}
    with pytest.raises(InputError, match="'offsets' has shape"):
        Holding.from_arrays(bad, 6, "f.npz")
    with pytest.raises(InputError, match="out of range"):
        Holding.from_arrays(held.arrays(), 5, "f.npz")
    with pytest.raises(InputError, match="no array 'pull'"):
        Holding.from_arrays({k: a for k, a in held.arrays().items() if k != "pull"}, 6)
    empty = Holding.from_arrays(Holding().arrays(), 6)
    assert len(empty.planes) == 0


def test_restore_refuses_state_of_another_scene():
    sim = small("drop-on-square").build_simulation()
    saved = effect_states(sim.effects)
    other = small("hanging").build_simulation()
    with pytest.raises(InputError, match="f.npz: holds"):
        restore_effect_states(other.effects, saved, "f.npz")
    with pytest.raises(InputError, match="holds nothing for effects"):
        restore_effect_states(sim.effects, {}, "f.npz")


def test_frames_down_then_up_resumes_from_the_earlier_frames_state(tmp_path):
    """--frames below what is on disk, then up again: the run continues from frame 22,
    whose state is still there (each frame keeps its own file), bit for bit."""
    scene, out = small("drop-on-square"), tmp_path / "run"
    run_scene(scene, out, frames=28, preview=False)
    run_scene(scene, out, frames=22, preview=False, resume=True)      # cuts the index
    run_scene(scene, out, frames=30, preview=False, resume=True)
    assert json.loads((out / "run.json").read_text())["resumed_from"] == 22
    assert held_count(out, 22) > 0
    run_scene(scene, tmp_path / "full", frames=30, preview=False)
    a = np.load(out / "trajectory.npz")["positions"]
    b = np.load(tmp_path / "full" / "trajectory.npz")["positions"]
    assert np.array_equal(a, b), f"{np.abs(a - b).max():.3e} m apart after the resume"


@pytest.mark.parametrize("compression", ["zlib", "none"])
def test_the_disk_plan_counts_the_state_files(tmp_path, compression):
    """Each state file fits what the run planned for it, and the plan grows by that."""
    plans = {}
    for mode in ("hold", "post-solve"):
        out = tmp_path / mode
        scene = small("drop-on-square", f'contact.mode="{mode}"',
                      f'output.frame_compression="{compression}"')
        run_scene(scene, out, frames=25, preview=False)
        plans[mode] = json.loads((out / "run.json").read_text())["disk_estimate"]["frame"]
    sim = small("drop-on-square").build_simulation()
    n, obstacles = sim.model.vertex_count, [e for e in sim.effects if e.get_state()]
    assert [e.kind for e in obstacles] == ["box", "plane"]
    planned = planned_state_bytes(2 * Holding.max_bytes(n), compression)
    assert plans["hold"] - plans["post-solve"] == planned
    sizes = [p.stat().st_size for p in state_files(tmp_path / "hold")]
    assert len(sizes) == 26 and max(sizes) <= planned
