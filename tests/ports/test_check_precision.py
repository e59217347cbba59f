"""The precision a port is judged at: its printed digits, float32, and a whole output.

A correct solution printed with ``%g`` (6 significant digits) passes, saying so; float32
values checked as float64 are named with the flag to use; a converged float32 port is held
to what a converged float32 computation reaches (not to clothsim's own float32 iterations),
so a float32 solver stopping 2e-5 m short fails; an output cut short fails naming both
frame counts.
"""

from pathlib import Path

import numpy as np
import pytest

import clothsim as cs
from clothsim.cli import main
from clothsim.ports.check import check_steps, step_tolerance
from clothsim.ports.formats import write_trajectory
from clothsim.ports.precision import float32_valued, significant_digits
from clothsim.ports.rounding import (
    converged_float32_floor,
    float32_deviation,
    float32_newton_stagnation,
)

from .test_check import run

ENGINE = Path(__file__).resolve().parents[2] / "examples" / "engines" / "newton-springs"


def printed(a, digits):
    """``a`` written with ``%.{digits}g`` and read back."""
    return np.vectorize(lambda v: float(f"{v:.{digits}g}"))(a)


def hanging():
    model, effects = cs.gallery.hanging_cloth(9)
    return cs.Simulation(model, h=1 / 30, effects=effects)


def newton_sheet():
    """A converged method (Newton's): float32 ports are held to the converged floor."""
    model, effects = cs.gallery.hanging_cloth(11, k=1000.0, total_mass=1.21)
    return cs.Simulation(model, h=1 / 60, effects=effects, solver="newton", iterations=50)


# -- printed digits ---------------------------------------------------------------------------
def test_digits_are_read_off_the_numbers():
    xs, vs = run(hanging, 3)
    assert significant_digits(xs) >= 16
    assert significant_digits(printed(xs, 6)) == 6
    assert significant_digits(printed(xs, 9)) == 9
    # a handful of short numbers are exact, not printed: full precision
    v = np.zeros((2, 81, 3))
    v[:, :, 2] = 0.01
    assert significant_digits(v) == 17
    x32 = xs.astype(np.float32)
    assert float32_valued(x32.astype(np.float64))
    assert float32_valued(printed(x32, 9), 9)
    assert not float32_valued(printed(xs, 9), 9) and not float32_valued(xs)


@pytest.mark.parametrize("stored", [True, False], ids=["velocities", "derived"])
def test_a_correct_solution_printed_with_g_passes_at_that_precision(stored):
    xs, vs = run(hanging, 6)
    report = check_steps(hanging, printed(xs, 6), printed(vs, 6) if stored else None)
    assert report.passed, report.summary()
    assert report.summary().endswith("the output is printed with 6 significant digits: "
                                     "judged at that precision"), report.summary()
    # the printing's bound holds with room: the errors are well inside it
    assert max(s.error / s.tolerance for s in report.steps) < 0.5
    # printed in full, the tolerance is the float64 one and nothing is said
    full = check_steps(hanging, xs, vs)
    assert full.passed and "printed" not in full.summary()


def test_a_fault_printed_with_g_still_fails():
    def heavier():
        model, effects = cs.gallery.hanging_cloth(9, total_mass=1.1)
        return cs.Simulation(model, h=1 / 30, effects=effects)

    xs, vs = run(heavier, 3)   # masses 10 % off: 1e-4 m per step, far above 6 digits' 1e-5
    report = check_steps(hanging, printed(xs, 6), printed(vs, 6))
    assert not report.passed and report.first_failure.k == 0, report.summary()
    assert "printed with 6 significant digits" in report.summary()


def test_numbers_too_coarse_to_judge_are_not_passed():
    xs, vs = run(hanging, 2)
    moved = xs.copy()
    moved[1:, 40] += 1e-3
    report = check_steps(hanging, printed(moved, 3), printed(vs, 3))
    assert not report.passed, report.summary()
    assert any("too coarse to judge" in n for n in report.notes), report.notes


def test_printing_that_rounds_by_more_than_a_thousandth_of_the_cloth_is_too_coarse():
    def far():   # a 1 m cloth 1 km from the origin: 6 digits round it by millimetres
        model, effects = cs.gallery.hanging_cloth(9, center=(1e3, 1.0, 0.0))
        return cs.Simulation(model, h=1 / 30, effects=effects)

    xs, vs = run(far, 3)
    report = check_steps(far, printed(xs, 6), printed(vs, 6))
    assert not report.passed, report.summary()
    assert any("too coarse to judge a step" in n and "on a 1.41 m cloth" in n
               for n in report.notes), report.notes
    assert check_steps(far, printed(xs, 9), printed(vs, 9)).passed


def test_float32_values_checked_as_float64_name_the_flag():
    xs, vs = run(hanging, 3)
    for x32, v32 in [(xs.astype(np.float32).astype(np.float64),
                      vs.astype(np.float32).astype(np.float64)),
                     (printed(xs.astype(np.float32), 9), printed(vs.astype(np.float32), 9))]:
        report = check_steps(hanging, x32, v32)
        first = report.first_failure
        assert first.status == "float32 rounding", report.summary()
        assert "check with --precision float32" in first.note, first.line()
        assert check_steps(hanging, x32, v32, precision="float32").passed


# -- whole outputs ----------------------------------------------------------------------------
def test_an_output_cut_short_fails_naming_both_counts(tmp_path, capsys):
    scene = cs.load_scene("hanging")            # 90 frames
    xs, vs = run(lambda: scene.build_simulation(scene.build_model()), 2)
    report = check_steps(scene, xs, vs, expected_steps=scene.frames)
    assert not report.passed and report.first_failure is None
    assert report.summary().startswith("FAIL: the port's output has 3 frames (2 steps), the "
                                       "scene asks for 90"), report.summary()
    assert check_steps(scene, xs, vs, expected_steps=2).passed
    write_trajectory(tmp_path / "x.npy", xs)
    assert main(["check", "hanging", str(tmp_path / "x.npy")]) == 1
    assert "has 3 frames (2 steps), the scene asks for 90" in capsys.readouterr().out
    assert main(["check", "hanging", str(tmp_path / "x.npy"), "--steps", "2"]) == 0
    # a faulty short output names the count and the first failing step
    bad = xs.copy()
    bad[2, 30] += 1e-3
    text = check_steps(scene, bad, vs, expected_steps=90).summary()
    assert text.startswith("FAIL: the port's output has 3 frames") and "step 1 -> 2" in text


# -- float32: the converged floor -------------------------------------------------------------
def test_converged_float32_floor_is_far_below_clothsims_float32_iterations():
    sim = newton_sheet()
    p, m = sim.problem(), sim.step_model()
    sim.step()
    floor = converged_float32_floor(m, p, sim.state.positions)
    ulp = float(np.spacing(np.float32(np.abs(sim.state.positions).max())))
    assert ulp * 0.8 < floor < 10 * ulp        # the rounding of x and of ∇g, a few ulp
    assert float32_deviation(m, p, 50) > 10 * floor
    assert step_tolerance(newton_sheet(), sim.state.positions, "float32") < 10 * floor


def test_converged_trajectory_in_float32_passes_and_one_2e5_short_fails():
    xs, vs = run(newton_sheet, 5)
    x32, v32 = (a.astype(np.float32).astype(np.float64) for a in (xs, vs))
    report = check_steps(newton_sheet, x32, v32, precision="float32")
    assert report.passed, report.summary()
    assert max(s.tolerance for s in report.steps) < 2e-6
    # a float32 solver stopping 2e-5 m short of each step's minimizer (on the way from its
    # start point y, as an unconverged iteration is)
    sim = newton_sheet()
    xs_p, vs_p = [x32[0]], [v32[0]]
    for _ in range(5):
        sim.state = cs.State(xs_p[-1].copy(), vs_p[-1].copy(), sim.state.time, sim.state.step)
        start = sim.problem().initial_guess()
        sim.step()
        x = sim.state.positions.copy()
        back = start - x
        x += 2e-5 * back / np.linalg.norm(back, axis=1).max()
        xs_p.append(x.astype(np.float32).astype(np.float64))
        vs_p.append(((xs_p[-1] - xs_p[-2]) / sim.h).astype(np.float32).astype(np.float64))
    report = check_steps(newton_sheet, np.stack(xs_p), np.stack(vs_p), precision="float32")
    assert {s.status for s in report.steps} == {"not converged"}, report.summary()
    assert all(1.5e-5 < s.error < 3e-5 for s in report.steps), report.summary()


def test_converged_floor_bounds_where_a_float32_newton_stagnates():
    sim = newton_sheet()
    p, m = sim.problem(), sim.step_model()
    sim.step()
    x = sim.state.positions
    assert float32_newton_stagnation(m, p, x) <= converged_float32_floor(m, p, x)


@pytest.mark.parametrize("iterations, passes", [(200, False), (1000, True)])
def test_newtons_vbd_runs_are_judged_without_newton(iterations, passes):
    """newton's VBD, recorded by examples/engines/newton_vbd.py --save: 200 iterations stop
    4e-6 to 2e-5 m short of the minimizer and fail, 1000 reach 1.4e-7 m and pass."""
    scene = cs.load_scene(ENGINE / "scene.toml")
    with np.load(ENGINE / f"vbd-{iterations}.npz") as run32:
        xs, vs = run32["positions"].astype(np.float64), run32["velocities"].astype(np.float64)
    report = check_steps(scene, xs, vs, precision="float32", steps=3)
    assert report.passed == passes, report.summary()
    assert max(s.tolerance for s in report.steps) < 1e-6
    if not passes:
        assert {s.status for s in report.steps} == {"not converged"}, report.summary()
        assert min(s.error for s in report.steps) > 4 * max(s.tolerance for s in report.steps)


def test_float32_printed_with_fewer_than_9_digits_gets_a_conditional_hint():
    """A float32 run (clothsim's own step in float32) printed with 8 digits: float32 and
    float64 cannot be told apart, so the hint is conditional; with 6 digits the printing
    covers the float32 rounding and the step agrees."""
    from clothsim.ports.rounding import _Step

    sim = hanging()
    xs, vs = [sim.state.positions.copy()], [sim.state.velocities.copy()]
    for k in range(3):
        state = cs.State(xs[-1], vs[-1], k * sim.h, k)
        p, m = sim.problem(state), sim.step_model(state)
        x = _Step(m, p, np.float32).iterate(p.initial_guess(), sim.solver.iterations)
        x = x.astype(np.float32).astype(np.float64)
        vs.append(((x - xs[-1]) / sim.h).astype(np.float32).astype(np.float64))
        xs.append(x)
    xs, vs = np.stack(xs), np.stack(vs)
    first = check_steps(hanging, printed(xs, 8), printed(vs, 8)).first_failure
    assert first.status == "float32 rounding", first.line()
    assert "if the port computes in float32, check with --precision float32" in first.note
    assert check_steps(hanging, printed(xs, 8), printed(vs, 8), precision="float32").passed
    assert check_steps(hanging, printed(xs, 6), printed(vs, 6)).passed


def test_cli_judges_text_frames_printed_with_g(tmp_path, capsys):
    scene = cs.load_scene("hanging")
    xs, vs = run(lambda: scene.build_simulation(scene.build_model()), 3)
    port = tmp_path / "port"
    port.mkdir()
    for name, frames in (("positions", xs), ("velocities", vs)):   # C++'s std::cout default
        np.savetxt(port / f"{name}.txt", frames.reshape(len(frames), -1), fmt="%g")
    assert main(["check", "hanging", str(port), "--steps", "3"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("PASS: 3 steps agree") and "printed with 6 significant digits" in out
    # an explicit --tolerance is taken as given: the printing then fails the check
    assert main(["check", "hanging", str(port), "--steps", "3", "--tolerance", "1e-9"]) == 1
