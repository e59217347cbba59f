"""A study that never loses its work: blow-ups recorded, CSV kept, steps saved and re-run."""

import csv
import json
import math
import os
import warnings

import numpy as np
import pytest

import clothsim as cs
from clothsim import gallery
from clothsim.accuracy import record_problems, run_accuracy
from clothsim.accuracy.problems import load_problems, save_problems
from clothsim.errors import InputError
from clothsim.scene import Scene
from clothsim.solvers.anderson import AndersonSolver

from .test_study import TINY


def study(tmp_path, **kw):
    args = dict(methods=("local-global", "anderson"), problems=3, repeats=1, budgets=(1, 5),
                tolerances=(1e-6,), time_steps=False, plots=False)
    args.update(kw)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return run_accuracy(Scene.from_dict(TINY), tmp_path, **args)


@pytest.fixture(scope="module")
def saved(tmp_path_factory):
    """One study of TINY with the default arguments, for the tests that only read its folder
    (its problems.npz and accuracy.csv)."""
    folder = tmp_path_factory.mktemp("study")
    study(folder)
    return folder


def read(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def test_a_configuration_that_blows_up_is_a_diverged_row_and_the_rest_is_measured(
        tmp_path, monkeypatch):
    original = AndersonSolver.iterates

    def blow_up(self, problem, x0=None):   # Anderson's 5th iterate has a nan force
        for it in original(self, problem, x0):
            if it.k == 5:
                raise InputError("external_force[0, 0]: must be a finite number, got nan")
            yield it

    monkeypatch.setattr(AndersonSolver, "iterates", blow_up)
    text = study(tmp_path, time_steps=True)
    table = {(r["method"], r["iterations"], r["tolerance"]): r
             for r in read(tmp_path / "accuracy.csv")}
    # its settings that stop before the 5th iterate are measured, the others diverged
    bad = [r for r in table.values() if r["status"] == "diverged"]
    assert table[("anderson", "5", "")] in bad and len(bad) <= 2
    assert all(r["method"] == "anderson" for r in bad)
    for r in bad:
        assert int(r["steps_diverged"]) >= 1 and math.isinf(float(r["solver_error_max"]))
    assert math.isinf(float(table[("anderson", "5", "")]["trajectory_error"]))
    others = [r for r in table.values() if r not in bad]
    assert len(others) >= 4 and table[("anderson", "1", "")] in others
    for r in others:
        assert r["status"] == "ok" and math.isfinite(float(r["solver_error_max"]))
        assert math.isfinite(float(r["seconds_per_step_median"]))
    assert "diverged" in text and "anderson, 5 it/step" in text


def test_a_crash_keeps_the_measured_errors(tmp_path, monkeypatch):
    import clothsim.accuracy.command as command

    def crash(*args, **kwargs):
        raise RuntimeError("the machine went away")

    monkeypatch.setattr(command, "time_configurations", crash)
    with pytest.raises(RuntimeError):
        study(tmp_path)
    rows = read(tmp_path / "accuracy.csv")
    assert len(rows) == 6 and all(math.isfinite(float(r["solver_error_max"])) for r in rows)
    assert (tmp_path / "problems.npz").exists()
    monkeypatch.undo()
    record = json.loads((tmp_path / "accuracy.json").read_text())
    assert record["status"] == "failed" and "the machine went away" in record["error"]
    study(tmp_path)  # the crashed study's folder is still a study's: re-run in place
    assert json.loads((tmp_path / "accuracy.json").read_text())["status"] == "complete"


def test_a_new_study_removes_the_earlier_one_before_it_writes(tmp_path, monkeypatch):
    import clothsim.accuracy.command as command

    study(tmp_path, plots=True)
    assert {"accuracy.csv", "steps.md"} <= set(os.listdir(tmp_path))

    def crash(*args, **kwargs):
        raise RuntimeError("killed while computing the references")

    monkeypatch.setattr(command, "prepare_steps", crash)
    with pytest.raises(RuntimeError):
        study(tmp_path, problems=2)
    # never the old table beside the new steps: the new study's record and steps only
    assert sorted(p for p in os.listdir(tmp_path) if not p.startswith(".")) == [
        "accuracy.json", "problems.npz"]
    assert json.loads((tmp_path / "accuracy.json").read_text())["status"] == "failed"
    assert len(load_problems(tmp_path / "problems.npz")) == 2


def test_a_folder_of_other_files_is_refused_unless_forced(tmp_path):
    mine = tmp_path / "accuracy.csv"
    mine.write_text("my own table\n")
    with pytest.raises(InputError, match="is not a clothsim accuracy study's folder: it "
                                         "holds 'accuracy.csv'"):
        study(tmp_path)
    assert mine.read_text() == "my own table\n" and sorted(os.listdir(tmp_path)) == [
        "accuracy.csv"]
    study(tmp_path, force=True)
    assert len(read(mine)) == 6
    (tmp_path / "notes.txt").write_text("x")    # a study's folder with a file beside it
    study(tmp_path)
    with pytest.raises(InputError, match="is not a folder"):
        study(tmp_path / "notes.txt")


def test_no_solver_or_no_frame_is_refused_by_name(tmp_path):
    with pytest.raises(InputError, match="^accuracy.methods: no solver given"):
        study(tmp_path / "a", methods=())
    with pytest.raises(InputError, match="^accuracy.frames: must be >= 1"):
        study(tmp_path / "b", frames=0)
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()


def test_saved_steps_are_re_measured_exactly(saved, tmp_path):
    study(tmp_path / "b", steps_file=saved / "problems.npz", problems=1)
    a, b = load_problems(saved / "problems.npz"), load_problems(
        tmp_path / "b" / "problems.npz")
    assert [s.index for s in a] == [s.index for s in b] and len(a) == 3
    for s, t in zip(a, b):
        for name in ("x", "v", "y", "f_ext", "fixed_vertices", "anchor_stiffness"):
            u, w = getattr(s.problem, name), getattr(t.problem, name)
            assert (u is None and w is None) or np.array_equal(u, w), name
    ra, rb = read(saved / "accuracy.csv"), read(tmp_path / "b" / "accuracy.csv")
    cols = ("solver_error_median", "solver_error_max", "iterations_max", "steps_measured")
    assert [[r[c] for c in cols] for r in ra] == [[r[c] for c in cols] for r in rb]
    with pytest.raises(InputError, match="accuracy.steps"):
        study(tmp_path / "c", steps_file=tmp_path / "missing.npz")


def with_changes(**changes):
    """TINY with some of its sections replaced (a deep copy)."""
    import copy

    data = copy.deepcopy(TINY)
    for section, values in changes.items():
        data[section].update(values)
    return data


def test_saved_steps_of_another_cloth_or_h_are_refused_by_name(saved, tmp_path):
    saved = saved / "problems.npz"

    def again(data, name):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return run_accuracy(Scene.from_dict(data), tmp_path / name, steps_file=saved,
                                methods=("local-global",), repeats=1, budgets=(1,),
                                tolerances=(), time_steps=False, plots=False)

    cases = {"n": (with_changes(cloth={"resolution": [5, 5]}), "16 vertices; this scene's "
                   "cloth has 25"),
             "k": (with_changes(springs={"structural": 50.0}), "another cloth"),
             "m": (with_changes(cloth={"mass": 2.0}), "another cloth"),
             "h": (with_changes(scene={"substeps": 2}), "recorded at h = 0.0333333 s")}
    for name, (data, message) in cases.items():
        with pytest.raises(InputError, match="^accuracy.steps: .*" + message):
            again(data, name)
        assert not (tmp_path / name / "accuracy.csv").exists()
    again(TINY, "same")  # the same cloth at the same h: re-measured
    assert (tmp_path / "same" / "accuracy.csv").exists()


def test_saved_steps_without_a_model_digest_still_load(saved, tmp_path):
    from clothsim.accuracy.command import scene_factory

    _, model, _ = scene_factory(Scene.from_dict(TINY))
    recorded = load_problems(saved / "problems.npz", model, 1 / 30)
    old = save_problems(recorded, tmp_path / "old.npz")   # as earlier versions wrote it
    with np.load(old) as z:
        assert "model_digest" not in z.files
    assert len(load_problems(old, model, 1 / 30)) == len(recorded)


def test_recorded_steps_that_missed_their_tolerance_are_marked(tmp_path):
    model = gallery.grid_cloth(4, k=800.0, plane="xy", center=(0.0, 1.0, 0.0))
    sim = cs.Simulation(model, h=1 / 30, solver="newton", iterations=1, tolerance=1e-14,
                        effects=[cs.Gravity(gallery.GRAVITY), cs.Pin([12, 15])])
    recorded = record_problems(sim, steps=3, count=3)
    assert [r.converged for r in recorded] == [False, False, False]
    back = load_problems(save_problems(recorded, tmp_path / "p.npz"))
    assert [r.converged for r in back] == [False, False, False]
    assert np.array_equal(back[1].problem.y, recorded[1].problem.y)


def small_drop_on_square(n: int = 7, frames: int = 24):
    from clothsim.scene import load_scene

    data = load_scene("drop-on-square").to_dict()
    data["cloth"]["resolution"] = [n, n]
    data["scene"]["frames"] = frames
    return Scene.from_dict(data)


def test_references_of_a_contact_scene_are_certified_minima_never_saddles():
    """The seed's demo at 7 × 7: the cloth lands on the box and crumples; every step with
    work has a certified reference (λ_min > 0), none is a saddle or a failed reference."""
    from clothsim.accuracy import prepare_steps, scene_factory

    scene = small_drop_on_square()
    factory, model, _ = scene_factory(scene)
    sim = factory("newton", scene.h, 100, 1e-10)
    recorded = record_problems(sim, steps=scene.frames, count=4)
    assert sim.state.positions[:, 1].min() < 0.55  # it reached the box top (y = 0.5)
    steps = prepare_steps(model, recorded)
    kinds = [s.kind for s in steps]
    assert "saddle" not in kinds and "reference-failed" not in kinds, kinds
    worked = [s for s in steps if s.kind not in ("at-rest", "trivial")]
    assert len(worked) >= 2, kinds
    for s in worked:
        assert s.reference.certified and s.reference.min_eigenvalue > 0, s.reference
    assert all(r.converged for r in recorded)


def test_quick_stops_early_when_no_step_can_be_measured(tmp_path, monkeypatch):
    """A sheet in free fall: every step is trivial, so --quick times nothing and runs no
    time-step study; the CSV still says how the steps were classified."""
    import clothsim.accuracy.command as command

    def never(*args, **kwargs):
        raise AssertionError("ran although nothing can be measured")

    monkeypatch.setattr(command, "time_configurations", never)
    monkeypatch.setattr("clothsim.accuracy.timestep.time_step_study", never)
    falling = {"scene": {"name": "falling", "frames": 4, "fps": 30},
               "cloth": {"resolution": [4, 4], "plane": "xz", "center": [0.0, 1.0, 0.0]},
               "springs": {"structural": 800.0, "shear": 800.0, "bending": 80.0},
               "effects": [{"kind": "gravity", "acceleration": [0.0, -9.81, 0.0]}]}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        text = run_accuracy(Scene.from_dict(falling), tmp_path, methods=("local-global",),
                            quick=True, plots=False)
    assert "no recorded step can be measured" in text
    rows = read(tmp_path / "accuracy.csv")
    assert rows and all(r["steps_measured"] == "0" and r["steps_trivial"] == "4"
                        for r in rows)


def test_quick_measures_without_trajectory_errors(tmp_path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        text = run_accuracy(Scene.from_dict(TINY), tmp_path, methods=("local-global",),
                            quick=True, plots=False)
    rows = read(tmp_path / "accuracy.csv")
    assert [int(r["iterations"]) for r in rows] == [1, 5, 10, 20, 100, 1000, 1000]
    assert all(r["trajectory_error"] == "nan" for r in rows)
    # one timing repeat, more only where an answer row had to be decided (quick too)
    assert any(r["repeats"] == "1" for r in rows) and all(int(r["repeats"]) >= 1 for r in rows)
    assert "trajectory error" not in text and "| 1e-01 |" in text
    assert "provisional" not in text


def test_the_same_study_twice_records_the_same_steps_and_classes():
    from clothsim.accuracy import prepare_steps, scene_factory

    def once():
        scene = small_drop_on_square(5, 16)
        factory, model, _ = scene_factory(scene)
        recorded = record_problems(factory("newton", scene.h, 100, 1e-10), steps=16, count=3)
        return recorded, [s.kind for s in prepare_steps(model, recorded)]

    (a, ka), (b, kb) = once(), once()
    assert ka == kb
    for s, t in zip(a, b):
        assert s.index == t.index and np.array_equal(s.problem.y, t.problem.y)
