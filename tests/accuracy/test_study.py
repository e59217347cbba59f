"""The study measures only steps with real work, on the same problems for every method."""

import math
import warnings

import numpy as np
import pytest

import clothsim as cs
from clothsim import gallery
from clothsim.accuracy import (
    Configuration,
    default_configurations,
    measure,
    prepare_steps,
    record_problems,
    run_accuracy,
)
from clothsim.accuracy.answer import answer_table
from clothsim.accuracy.report import COLUMNS, rows, write_csv
from clothsim.errors import InputError
from clothsim.scene import Scene
from clothsim.simulation import State


def two_minima_simulation(n: int = 7, seed: int = 1, amplitude: float = 1e-2):
    """A vertical 7 × 7 flag pinned along its left edge with a small random out-of-plane
    velocity: its second step has two minima (Newton from y and converged local/global end
    5.6e-7 J·s² apart in g, both with H ≻ 0)."""
    model = gallery.grid_cloth(n, k=800.0, bending=20.0, plane="xy", center=(0.0, 1.5, 0.0))
    left = [i for i in range(n * n) if i % n == 0]
    v = np.zeros((n * n, 3))
    v[:, 2] = amplitude * np.random.default_rng(seed).standard_normal(n * n)
    return cs.Simulation(model, h=1 / 30, solver="newton", tolerance=1e-10, iterations=100,
                         effects=[cs.Gravity(gallery.GRAVITY), cs.Pin(left)],
                         state=State(model.mesh.vertices.copy(), v))


def stiff_settling():
    """A stiff 5 × 5 sheet (k = 2000) pinned along one edge, no gravity, kicked in its plane:
    implicit Euler damps the stiff in-plane motion to rest within a few dozen steps."""
    model = gallery.grid_cloth(5, k=2000.0, plane="xz")
    v = np.zeros((25, 3))
    v[:, 0] = 0.3 * np.random.default_rng(7).standard_normal(25)
    v[:, 2] = 0.3 * np.random.default_rng(8).standard_normal(25)
    v[:5] = 0.0
    return cs.Simulation(model, h=1 / 30, solver="newton", tolerance=1e-12, iterations=100,
                         effects=[cs.Pin(list(range(5)))],
                         state=State(model.mesh.vertices.copy(), v))


def free_fall_onto_box():
    """A 5 × 5 sheet in free fall from 0.1 m above a small box: free-fall steps first, then
    contact."""
    model = gallery.grid_cloth(5, k=800.0, plane="xz", center=(0.0, 0.6, 0.0))
    return cs.Simulation(model, h=1 / 30, solver="newton", tolerance=1e-12, iterations=100,
                         effects=[cs.Gravity(gallery.GRAVITY),
                                  cs.Box((-0.2, 0.0, -0.2), (0.2, 0.5, 0.2))])


def check_real_work(steps):
    measured = [s for s in steps if s.measured]
    assert measured
    for s in measured:
        assert s.reference.residual <= 1e-8 or s.reference.floor_ratio < 1e3
        assert s.one_iteration_error >= 1e-3
    return measured


def test_stiff_cloth_at_rest_is_skipped_not_measured():
    sim = stiff_settling()
    recorded = record_problems(sim, steps=60, count=6)
    steps = prepare_steps(sim.model, recorded)
    kinds = [s.kind for s in steps]
    assert kinds[0] == "unique" and kinds.count("at-rest") >= 2, kinds
    check_real_work(steps)
    table = rows(measure(sim.model, steps, [Configuration("local-global", 5)]), steps,
                 h=sim.h)
    measured = kinds.count("unique") + kinds.count("several-minima")
    assert table[0].steps_measured == measured and table[0].steps_unique == kinds.count("unique")
    assert table[0].steps_skipped == len(kinds) - measured
    assert table[0].steps_at_rest == kinds.count("at-rest")
    assert table[0].solver_error_max > 1e-6  # real work left after 5 iterations


def test_free_fall_steps_are_trivial_and_contact_steps_measured():
    sim = free_fall_onto_box()
    recorded = record_problems(sim, steps=16, count=8)
    steps = prepare_steps(sim.model, recorded)
    kinds = [s.kind for s in steps]
    assert kinds[0] == "trivial" and "unique" in kinds, kinds
    check_real_work(steps)


def buckling_strip(seed: int = 1, amplitude: float = 1e-3):
    """The compressed 9 × 3 strip (tests/ports) with a tiny random out-of-plane velocity:
    its first step buckles, and Newton from y and from converged local/global reach two
    different minima (both certified, H ≻ 0)."""
    from tests.ports.test_check import compressed_strip

    sim = compressed_strip()
    v = np.zeros_like(sim.state.positions)
    v[:, 2] = amplitude * np.random.default_rng(seed).standard_normal(len(v))
    sim.state = State(sim.state.positions.copy(), v)
    return sim


def test_several_minima_are_measured_by_the_objective_gap(tmp_path):
    sim = buckling_strip()
    recorded = record_problems(sim, steps=2, count=2)
    steps = prepare_steps(sim.model, recorded)
    assert [s.kind for s in steps] == ["several-minima", "unique"]
    ref = steps[0].reference
    assert ref.two_minima and ref.minima >= 2 and math.isnan(ref.uncertainty)
    assert ref.certified and ref.min_eigenvalue > 0 and ref.objective_difference <= 0
    assert ref.objective_scale > 0
    problem = steps[0].step.problem
    assert ref.objective_gap(sim.model, problem, problem.initial_guess()) == pytest.approx(1)
    assert ref.objective_gap(sim.model, problem, ref.x_best) == 0.0
    results = measure(sim.model, steps, [Configuration("local-global", 3),
                                         Configuration("newton", 100, 1e-12)])
    table = rows(results, steps, h=sim.h)
    assert table[0].steps_several_minima == 1 and table[0].steps_measured == 2
    assert table[0].steps_unique == 1
    # every measured step has a gap; converged Newton is at a certified minimum: gap <= its
    # own basin's, and 3 local/global iterations are far from any minimum
    assert np.all(np.isfinite(results[0].gaps)) and len(results[0].gaps) == 2
    assert results[1].gaps.max() < 0.5 and results[0].gaps.max() > results[1].gaps.max()
    header = write_csv(table, tmp_path / "a.csv").read_text().splitlines()[0].split(",")
    assert {"steps_several_minima", "objective_gap_p90", "steps_saddle"} <= set(header)


def test_a_reference_that_is_not_certified_is_reported_as_such(monkeypatch):
    import clothsim.accuracy.reference as reference

    monkeypatch.setattr(reference, "REFERENCE_ITERATIONS", 1)
    sim = buckling_strip()
    steps = prepare_steps(sim.model, record_problems(sim, steps=1, count=1))
    assert steps[0].kind == "reference-failed" and not steps[0].reference.certified
    assert not steps[0].measured


def test_jobs_two_gives_the_same_errors_as_serial():
    sim = stiff_settling()
    steps = prepare_steps(sim.model, record_problems(sim, steps=4, count=2))
    configs = default_configurations(("local-global", "anderson", "newton"), budgets=(1, 5),
                                     tolerances=(1e-6,))
    serial = measure(sim.model, steps, configs, jobs=1)
    parallel = measure(sim.model, steps, configs, jobs=2)
    for a, b in zip(serial, parallel):
        np.testing.assert_array_equal(a.errors, b.errors)
        np.testing.assert_array_equal(a.iterations, b.iterations)


TINY = {"scene": {"name": "tiny", "frames": 6, "fps": 30},
        "cloth": {"resolution": [4, 4], "plane": "xy", "center": [0.0, 1.0, 0.0]},
        "springs": {"structural": 800.0, "shear": 800.0, "bending": 80.0},
        "effects": [{"kind": "gravity", "acceleration": [0.0, -9.81, 0.0]},
                    {"kind": "pin", "vertices": [12, 15]}]}


def test_run_accuracy_writes_csv_sidecar_and_answer(tmp_path):
    from clothsim.accuracy import run_accuracy

    scene = Scene.from_dict(TINY)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        text = run_accuracy(scene, tmp_path, methods=("local-global", "newton"), problems=3,
                            repeats=2, budgets=(1, 5), tolerances=(1e-6,),
                            time_steps=False, plots=False, target=1e-6)
    lines = (tmp_path / "accuracy.csv").read_text().splitlines()
    assert lines[0].split(",")[:len(COLUMNS)] == list(COLUMNS)
    assert len(lines) == 1 + 3 + 3  # per method: 2 budgets + 1 tolerance
    assert (tmp_path / "accuracy.json").exists() and "| 1e-06 |" in text
    assert "no setting reaches this" not in text  # converged Newton reaches 1e-6
    # the short answer comes before any table
    first_table = next(i for i, t in enumerate(text.splitlines()) if t.startswith("|"))
    answers = [i for i, t in enumerate(text.splitlines()) if t.startswith("answer for 1e-06")]
    assert answers and answers[0] < first_table, text


def test_answer_table_says_when_nothing_reaches_a_level():
    assert "no setting reaches this" in answer_table([], levels=(1e-3,))


def test_bad_options_are_one_line_errors(tmp_path):
    from clothsim.accuracy import run_accuracy
    from clothsim.errors import InputError

    with pytest.raises(InputError, match="accuracy.methods"):
        run_accuracy(Scene.from_dict(TINY), tmp_path, methods=("symplectic-euler",))
    with pytest.raises(InputError, match="accuracy.jobs"):
        run_accuracy(Scene.from_dict(TINY), tmp_path, jobs=0)


def test_paper_preset_reports_crossover_and_cost_ratio():
    from clothsim.accuracy import paper_report

    text = paper_report(n=5, frames=2, repeats=1, cap=500)
    assert "| 1e-01 |" in text and "| 1e-08 |" in text
    assert "of one Newton iteration" in text
    assert ("crossover: Newton is faster from error" in text
            or "no crossover within the measured levels" in text)


def test_cli_accuracy_command(tmp_path, capsys):
    from clothsim.cli import main

    scene = tmp_path / "tiny.toml"
    scene.write_text('[scene]\nname = "tiny"\nframes = 4\n[cloth]\nresolution = [4, 4]\n'
                     'plane = "xy"\ncenter = [0.0, 1.0, 0.0]\n[[effects]]\nkind = "gravity"\n'
                     '[[effects]]\nkind = "pin"\nvertices = [12, 15]\n')
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        code = main(["accuracy", str(scene), "--out", str(tmp_path / "out"), "--quick",
                     "--methods", "local-global,anderson", "--repeats", "1",
                     "--no-time-steps", "--no-plots", "--problems", "2"])
    out = capsys.readouterr().out
    assert code == 0 and "cheapest setting" in out and "Fixed budget" in out
    assert (tmp_path / "out" / "accuracy.csv").exists()
    assert main(["accuracy", str(scene), "--methods", "nope"]) == 2


def test_dask_scheduler_gives_the_same_errors_as_serial():
    distributed = pytest.importorskip(
        "dask.distributed", reason="dask.distributed is not installed (extra 'cluster')")
    sim = stiff_settling()
    steps = prepare_steps(sim.model, record_problems(sim, steps=4, count=2))
    configs = default_configurations(("local-global", "newton"), budgets=(1, 5),
                                     tolerances=(1e-6,))
    serial = measure(sim.model, steps, configs, jobs=1)
    with distributed.LocalCluster(processes=False, n_workers=1, threads_per_worker=1,
                                  dashboard_address=None) as cluster:
        remote = measure(sim.model, steps, configs, scheduler=cluster.scheduler_address)
    assert [r.config for r in remote] == configs
    for a, b in zip(serial, remote):
        np.testing.assert_array_equal(a.errors, b.errors)
        np.testing.assert_array_equal(a.iterations, b.iterations)


def test_a_scheduler_that_cannot_be_used_is_one_line_before_anything_runs(tmp_path,
                                                                          monkeypatch):
    pytest.importorskip("dask.distributed",
                        reason="dask.distributed is not installed (extra 'cluster')")
    from clothsim.accuracy import parallel

    monkeypatch.setattr(parallel, "CONNECT_TIMEOUT", 1)
    for address, why in (("garbage", "missing port"), ("tcp://127.0.0.1:1", "Connection refused")):
        with pytest.raises(InputError, match=f"^accuracy.scheduler: cannot use "
                                             f"'{address}': .*{why}"):
            run_accuracy(Scene.from_dict(TINY), tmp_path / "out", scheduler=address,
                         quick=True, plots=False)
        assert not (tmp_path / "out").exists()


def test_rho_per_step_matches_the_decay_of_the_local_global_error():
    from clothsim.accuracy.report import steps_table
    from clothsim.solvers import LocalGlobalSolver

    sim = two_minima_simulation()
    steps = prepare_steps(sim.model, record_problems(sim, steps=2, count=2))
    for s in steps:
        assert 0.0 < s.rho < 1.0, s.rho
    assert steps_table(steps).count("| unique |") == 2
    step = steps[0]  # measured: compare with the error decay against the certified x*
    errors = []
    for it in LocalGlobalSolver(sim.model, check_conditioning=False).iterates(
            step.step.problem):
        errors.append(float(np.linalg.norm(it.x - step.reference.x)))
        if it.k >= 150:
            break
    decay = (errors[150] / errors[100]) ** (1 / 50)
    assert abs(step.rho - decay) < 0.02, (step.rho, decay)
    table = steps_table(steps)
    lines = table.splitlines()
    head = next(i for i, line in enumerate(lines) if line.startswith("| step |"))
    assert "rho_local_global" in lines[head] and "several-minima:" in table
    assert f"{step.rho:.4f}" in lines[head + 2]


def box_factory(top: float = 0.5, gap: float = 0.1):
    """``factory(method, h, iterations, tolerance)``: a 4 × 4 sheet ``gap`` above a box
    (contact at its declared top: thickness 0, where "auto" would be 0.26 m at this spacing)."""
    def factory(method, h, iterations, tolerance):
        model = gallery.grid_cloth(4, k=800.0, plane="xz", center=(0.0, top + gap, 0.0))
        return cs.Simulation(model, h=h, solver=method, iterations=iterations,
                             tolerance=tolerance,
                             effects=[cs.Gravity(gallery.GRAVITY),
                                      cs.Box((-0.3, 0.0, -0.3), (0.3, top, 0.3),
                                             thickness=0.0)])
    return factory


def test_time_step_error_is_fitted_only_before_contact():
    from clothsim.accuracy.timestep import contact_free_window, time_step_study

    assert contact_free_window(np.array([0, 0, 1, 0, 0, 0, 1], bool)) == (3, 6)
    assert contact_free_window(np.array([1, 1], bool)) is None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ts = time_step_study(box_factory(), frame_time=1 / 30, frames=8,
                             time_steps=(1 / 30, 1 / 60, 1 / 120))
    a, b = ts.window
    # free fall of 0.1 m takes 0.143 s = 4.3 frames: the window is frames 0 … 4 at most
    assert a == 0 and 2 <= b <= 4 and ts.contact[b] and not ts.contact[:b].any()
    assert ts.reference[: b + 1, :, 1].min() > 0.5  # above the box all along the window
    assert ts.reference[-1, :, 1].min() < 0.5 + 1e-3  # and it lands on the box later
    assert len(ts.errors) == 3 and all(math.isfinite(e) and e > 0 for e in ts.errors)
    assert 0.8 < ts.slope < 1.2 and "frames 0–" in ts.note  # free fall: first order


def test_time_step_error_without_a_contact_free_window_is_empty(tmp_path):
    from clothsim.accuracy.timestep import time_step_study

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ts = time_step_study(box_factory(gap=0.0), frame_time=1 / 30, frames=2,
                             time_steps=(1 / 30, 1 / 60, 1 / 120))
    assert ts.window is None and all(math.isnan(e) for e in ts.errors)
    assert "no contact-free window" in ts.note and "\n" not in ts.note


def test_run_accuracy_leaves_time_step_error_empty_when_every_frame_has_contact(tmp_path):
    from clothsim.accuracy import run_accuracy

    lying = {"scene": {"name": "lying", "frames": 2, "fps": 30},
             "cloth": {"resolution": [4, 4], "plane": "xz", "center": [0.0, 0.5, 0.0]},
             "springs": {"structural": 800.0, "shear": 800.0, "bending": 80.0},
             "effects": [{"kind": "gravity", "acceleration": [0.0, -9.81, 0.0]},
                         {"kind": "box", "min": [-1.0, 0.0, -1.0], "max": [1.0, 0.5, 1.0]}]}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        text = run_accuracy(Scene.from_dict(lying), tmp_path, methods=("local-global",),
                            problems=2, repeats=1, budgets=(1,), tolerances=(),
                            plots=False)
    assert "no contact-free window" in text
    row = (tmp_path / "accuracy.csv").read_text().splitlines()[1].split(",")
    assert row[COLUMNS.index("time_step_error")] == ""


def test_a_scene_whose_steps_all_have_several_minima_is_answered_by_the_gap():
    from clothsim.accuracy.report import fixed_budget_measure, fixed_budget_table

    sim = buckling_strip()
    steps = prepare_steps(sim.model, record_problems(sim, steps=1, count=1))
    assert [s.kind for s in steps] == ["several-minima"]
    results = measure(sim.model, steps, [Configuration("local-global", 5),
                                         Configuration("local-global", 10)])
    for r in results:
        r.seconds = [1e-3]
    table = rows(results, steps, h=sim.h)
    answer = answer_table(table, levels=(1.0, 1e-12))
    assert "objective gap" in answer and "solver error" not in answer
    assert "local-global, 5 it/step" in answer.splitlines()[2]
    assert fixed_budget_measure(table) == "objective gap"
    assert "nan" not in fixed_budget_table(table, budgets=(5, 10))
