"""Simulation.prepare: the next step's factorization done ahead of the step, answers unchanged;
``clothsim run`` hands frame 0 to its writer after it (issue 33: a large cloth's
factorization runs on both cores)."""

import dataclasses
import json

import numpy as np
import pytest

import clothsim as cs
from clothsim import runner
from clothsim.gallery import hanging_cloth
from clothsim.io.runfolder import RunFolder, completed_frames
from clothsim.solvers import LocalGlobalSolver


def _pair(build):
    """Two simulations built alike, the first prepared: their 4 steps, bit for bit."""
    sims = [build(), build()]
    for sim in sims:   # as run(4) would tell the solver first (the factor's mode)
        sim.expect_steps(4, final=False)
    sims[0].prepare()
    assert sims[0].solver.factor_count == 1   # factored ahead, not again by the step
    for sim in sims:
        sim.run(4)
    a, b = (s.state for s in sims)
    np.testing.assert_array_equal(a.positions, b.positions)
    np.testing.assert_array_equal(a.velocities, b.velocities)
    assert [s.solver.factor_count for s in sims] == [1, 1]
    assert sims[0].solver.factorization == sims[1].solver.factorization
    return sims


@pytest.mark.parametrize("solver", ["local-global", "chebyshev", "anderson", "lbfgs"])
@pytest.mark.parametrize("pins", ["constraint", "penalty"])
def test_prepared_steps_equal_unprepared_ones(solver, pins):
    def build():
        model, effects = hanging_cloth(9, pin_method=pins)
        return cs.Simulation(model, h=1 / 30, effects=effects, solver=solver)
    _pair(build)


def test_prepared_from_x_n_at_a_later_time_with_a_pin_released():
    """Prepared mid-run (t = 2h), from x_n, with the pins the next step has: one of the two
    corners released at t = 3h (the factor of the step ending at 3h has one pin)."""
    def build():
        model, (gravity, _pin) = hanging_cloth(9)
        top = [72, 80]
        sim = cs.Simulation(model, h=0.1, effects=[gravity, cs.Pin([top[0]]),
                                                    cs.Pin([top[1]], release=0.25)],
                            initial_guess="x_n")
        sim.run(2)
        sim.solver.factor_count = 0   # count the factorizations from here
        return sim
    sims = _pair(build)
    assert sims[0].pinned_vertices(0.3).tolist() == [72]


def test_prepared_contact_scene_equals_unprepared():
    """drop-on-square (a box held by contact planes: the held system is built by the step,
    the prepared factor is the plain one's)."""
    def build():
        return cs.load_scene("drop-on-square", ["cloth.resolution=[13, 13]"]).build_simulation()
    _pair(build)


def test_prepare_does_nothing_without_a_cached_factor():
    model, effects = hanging_cloth(7)
    newton = cs.Simulation(model, h=1 / 30, effects=effects, solver="newton")
    newton.prepare()
    damped_model, effects = hanging_cloth(7)
    s = damped_model.springs
    damped_model = cs.Model(damped_model.mesh, dataclasses.replace(
        s, spring_damping=np.full(len(s.spring_rest_length), 0.5)), damped_model.vertex_mass)
    damped = cs.Simulation(damped_model, h=1 / 30, effects=effects)
    damped.prepare()    # its step factors a model of its own (k + c/h, at x_n)
    assert isinstance(damped.solver, LocalGlobalSolver) and damped.solver.factor_count == 0
    before = damped.state.positions.copy()
    damped.step()
    assert not np.array_equal(damped.state.positions, before)


def test_run_hands_frame_0_over_after_the_first_factorization(tmp_path, monkeypatch):
    events = []
    factor, write = LocalGlobalSolver._factor, RunFolder.write_frame

    def factored(self, problem):
        events.append("factor")
        return factor(self, problem)

    def written(self, k, *args, **kwargs):
        events.append(f"frame {k}")
        return write(self, k, *args, **kwargs)

    monkeypatch.setattr(LocalGlobalSolver, "_factor", factored)
    monkeypatch.setattr(RunFolder, "write_frame", written)
    runner.run_scene(cs.load_scene("hanging", ["cloth.resolution=[9, 9]"]), tmp_path / "a",
                     frames=2, preview=False)
    assert events == ["factor", "frame 0", "frame 1", "frame 2"]
    events.clear()
    runner.run_scene(cs.load_scene("hanging", ["cloth.resolution=[9, 9]"]), tmp_path / "b",
                     frames=0, preview=False)   # nothing to step: nothing factored
    assert events == ["frame 0"]


def test_interrupted_during_the_first_factorization(tmp_path, monkeypatch):
    """Ctrl-C before frame 0 is handed over: an interrupted run of no frame, no file left
    half-written; resume starts it afresh."""
    def interrupted(self):
        raise KeyboardInterrupt

    scene = cs.load_scene("hanging", ["cloth.resolution=[9, 9]"])
    with monkeypatch.context() as m:
        m.setattr(cs.Simulation, "prepare", interrupted)
        with pytest.raises(KeyboardInterrupt):
            runner.run_scene(scene, tmp_path / "out", frames=2, preview=False)
    out = tmp_path / "out"
    run = json.loads((out / "run.json").read_text())
    assert run["status"] == "interrupted" and run["last_frame"] is None
    assert completed_frames(out) is None
    assert not list(out.glob("frame_*.vtu")) and not list(out.glob(".*.tmp*"))
    done = runner.run_scene(scene, out, frames=2, preview=False, resume=True)
    fresh = runner.run_scene(scene, tmp_path / "fresh", frames=2, preview=False)
    assert done.status == "completed" and done.last_frame == 2
    a, b = (np.load(r.out_dir / "trajectory.npz") for r in (done, fresh))
    np.testing.assert_array_equal(a["positions"], b["positions"])
