"""Planted faults of referee4's blind audit (faults the referee matrix does not hold) that
the referee got wrong: each port is clothsim's own run of a small hanging cloth with one
fault, checked as ``clothsim check`` checks it.

Before: a NaN in a frame before the last stopped the check with an InputError
(``state.positions[5, 0]: must be a finite number``) instead of a verdict; velocities of
the frame after (v_{k+1} written at frame k), or a frame 0 written otherwise than the port
starts, were "not a minimizer: the port's answer is its start point y itself: its solve
does not move the cloth", or UNDECIDED "start-dependent".
"""

from __future__ import annotations

import numpy as np

import clothsim as cs
from benchmarks.referee_matrix import edited, keys, run
from clothsim.ports.check import check_steps

from .test_referee_audit import checked, scene


def test_a_nan_before_the_last_frame_is_a_verdict_not_an_error(tmp_path):
    def blown(xs, vs, scene_):
        xs[3:, 5] = np.nan
        vs[3:, 5] = np.nan
        return xs, vs

    report, summary = checked(scene(tmp_path, frames=5), edited(blown))
    assert summary.startswith("FAIL at step 2 -> 3: not finite, max error inf m at vertex 5"), \
        summary
    assert "from frame 3 on: its run blew up there or wrote NaN" in summary, summary
    assert "3 of 5 steps fail: 3 not finite" in summary, summary
    assert [s.status for s in report.steps[:2]] == ["agrees", "agrees"]


def test_an_infinite_velocity_is_named_as_the_velocities(tmp_path):
    def blown(xs, vs, scene_):
        vs[2, 7, 1] = np.inf
        return xs, vs

    report, summary = checked(scene(tmp_path), edited(blown))
    assert "step 1 -> 2: not finite" in summary, summary
    assert "the port's velocities of frame 2 (the step's answer) are not finite" in summary
    assert report.steps[3].status == "agrees"   # frame 3 is finite again: judged


def test_velocities_of_the_frame_after_are_named(tmp_path):
    def ahead(xs, vs, scene_):   # v_{k+1} written at frame k
        return xs, np.concatenate([vs[1:], vs[-1:]])

    report, summary = checked(scene(tmp_path), edited(ahead))
    assert summary.startswith("FAIL at step 0 -> 1: start differs"), summary
    assert "frame 0 holds other velocities than the state it starts from" in summary
    for s in report.steps[1:3]:
        assert s.status == "start differs", s.line()
        assert "its velocities are those of the frame after" in s.note, s.line()
    assert "does not move the cloth" not in " ".join(s.note for s in report.steps)


def test_a_frame_0_written_otherwise_than_the_port_starts_is_named(tmp_path):
    def up(xs, vs, scene_):   # frame 0 written 1 cm up, the run from the scene's start
        xs[0, :, 1] += 0.01
        return xs, vs

    report, summary = checked(scene(tmp_path), edited(up))
    assert summary.startswith("FAIL at step 0 -> 1: start differs"), summary
    assert ("clothsim's step from the scene's initial state: the port's frame 0 holds other "
            "positions than the state it starts from") in summary, summary
    assert "1 of 4 steps fail" in summary, summary


def test_a_port_right_from_its_own_start_is_not_sent_to_the_scenes(tmp_path):
    """The scene's start is tried only where the port's step fails: a port started from its
    own state and right from it still passes."""
    path = scene(tmp_path)

    def moving(state):
        state.velocities[:, 0] += 0.1

    xs, vs = run(cs.load_scene(path), start=moving)
    report = check_steps(cs.load_scene(path), xs, vs)
    assert report.passed, report.summary()


def _noise(scale, pins=True):
    def noisy(xs, vs, scene_):
        sim = scene_.build_simulation()
        which = np.arange(xs.shape[1])
        if not pins:
            which = np.setdiff1d(which, sim.problem(sim.state).fixed_vertices)
        rng = np.random.default_rng(0)
        xs[1:, which] += scale * rng.standard_normal(xs[1:, which].shape)
        return xs, vs
    return noisy


def test_a_right_port_with_noise_is_noisy_not_undecided(tmp_path):
    """1e-6 m of noise on the free vertices (1000 × the tolerance) was UNDECIDED
    'start-dependent: the port iterates otherwise' (not the port's error)."""
    report, summary = checked(scene(tmp_path), edited(_noise(1e-6, pins=False)))
    assert summary.startswith("FAIL at step 0 -> 1: noisy"), summary
    assert "the difference from clothsim's step is noise" in summary, summary
    assert "4 of 4 steps fail: 4 noisy" in summary, summary


def test_pinned_vertices_off_by_the_noise_are_not_missing_pins(tmp_path):
    """Noise on every vertex, pinned ones too, was 'pinned vertex moved … its pins are
    missing or act elsewhere'."""
    report, summary = checked(scene(tmp_path), edited(_noise(1e-6)))
    assert summary.startswith("FAIL at step 0 -> 1: noisy"), summary
    assert "by the noise its free vertices carry too" in summary, summary
    assert "its pins are missing" not in summary, summary


def test_smooth_differences_are_not_called_noise(tmp_path):
    """A model difference (the structural springs left out: rough, 0.71 of noise's
    roughness) is named by the model fit, and an iteration count by the settings."""
    for fault, named in (("springs.structural=0", "the structural springs only"),
                         ("solver.iterations=9", "iterations = 9")):
        report, summary = checked(scene(tmp_path), keys(fault))
        assert named in summary and "noisy" not in summary, summary


def _builtin(tmp_path, name, frames, **subs):
    import re

    from clothsim.scene import builtin_scene_text
    text = re.sub(r"(?m)^frames = \d+", f"frames = {frames}", builtin_scene_text(name))
    for pattern, value in subs.items():
        text = re.sub(pattern, value, text)
    path = tmp_path / f"{name}.toml"
    path.write_text(text, encoding="utf-8")
    return path


def test_an_impulse_twice_as_strong_is_named_not_undecided(tmp_path):
    """The impulse's force × 2 was UNDECIDED 'start-dependent … the port iterates
    otherwise' (no few-parameter model reproduced a force on the disk alone)."""
    path = _builtin(tmp_path, "impulse", 6, **{r"resolution = \[25, 25\]": "resolution = [13, 13]"})
    report, summary = checked(path, keys("effects[1].force=[0.0, 12.0, 0.0]"))
    assert summary.startswith("FAIL at step 3 -> 4: model differs"), summary
    assert "the scene's external forces other than gravity × 2.000" in summary, summary
    assert "3 of 6 steps fail: 3 model differs" in summary, summary


def test_a_wind_of_twice_the_drag_is_named(tmp_path):
    path = _builtin(tmp_path, "flag", 2)
    report, summary = checked(path, keys("effects[2].drag=2.0"))
    assert summary.startswith("FAIL at step 0 -> 1: model differs"), summary
    assert "the scene's external forces other than gravity × 2.000" in summary, summary


def test_a_right_impulse_port_still_passes(tmp_path):
    path = _builtin(tmp_path, "impulse", 6, **{r"resolution = \[25, 25\]": "resolution = [13, 13]"})
    report, summary = checked(path, keys())
    assert report.passed, summary


def test_a_frozen_cloth_is_told_it_has_no_force_not_one_of_1e_15(tmp_path):
    """Every frame the first: the still cloth minimizes g without gravity; the fitted
    force was printed '(-1e-15, -4e-16, 0) N per vertex'."""
    def frozen(xs, vs, scene_):
        xs[1:] = xs[0]
        vs[:] = 0.0
        return xs, vs

    report, summary = checked(scene(tmp_path), edited(frozen))
    assert "the external force (0, 0, 0) N per vertex instead of (0, -0.0681, 0)" in summary, \
        summary
    assert "e-15" not in summary and "e-16" not in summary, summary


def test_a_post_solve_box_of_another_friction_is_named_not_undecided(tmp_path):
    """drop-on-square 13² in post-solve mode, starting 3 cm above the box: the box's
    friction 0.6 for 0.3 was UNDECIDED 'start-dependent' (only sizes were read off)."""
    path = _builtin(tmp_path, "drop-on-square", 6, **{
        r"resolution = \[25, 25\]": "resolution = [13, 13]",
        r"center = \[0.0, 1.0, 0.0\]": "center = [0.0, 0.53, 0.0]"})
    path.write_text(path.read_text() + '\n[contact]\nmode = "post-solve"\n')
    report, summary = checked(path, keys("effects[1].friction=0.6"))
    assert summary.startswith("FAIL at step 2 -> 3: model differs"), summary
    assert "with the box's friction coefficient 0.6 instead of 0.3" in summary, summary


def test_gravity_x2_in_free_fall_is_named_beside_the_inertia_it_cannot_be_told_from(tmp_path):
    """A falling cloth whose springs are at rest: the inertia term × 0.5 and gravity × 2
    make the same steps; only 'as if h were 0.04714 s' was named."""
    path = _builtin(tmp_path, "drop-on-square", 3,
                    **{r"resolution = \[25, 25\]": "resolution = [13, 13]"})
    report, summary = checked(path, keys("effects[0].acceleration=[0.0, -19.62, 0.0]"))
    assert "the inertia term M (x − y) / h² × 0.500" in summary, summary
    assert ("or, the same steps (the springs hardly act in them), the external force "
            "(0, -19.6, 0) m/s² × m on each vertex instead of (0, -9.81, 0) m/s² × m") \
        in summary, summary
