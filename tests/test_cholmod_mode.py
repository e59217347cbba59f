"""CHOLMOD's mode for the global step: chosen by its predicted cost (factor + the run's
expected solves; the ski-rental rule when the count is unknown), overridable, recorded."""

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

import clothsim as cs
from clothsim import factor_mode, factorization
from clothsim.cli import main
from clothsim.factor_mode import (
    MODE_COSTS,
    break_even,
    choose_cholmod_mode,
    predicted_costs,
    switch_point,
)

MODES_TABLE = Path(__file__).resolve().parents[1] / "docs" / "data" / "cholmod-modes.md"
#: a made-up model with the measured shape: simplicial solves twice as fast, supernodal
#: factors cheaper from 10 000 unknowns up (factor c · n^p, solve c · n^p)
TOY = {"simplicial": ((1e-8, 1.6), (1e-8, 1.2)), "supernodal": ((1e-6, 1.1), (2e-8, 1.2))}
#: a toy model with whole numbers: at n unknowns simplicial factors in n/1000 s and solves
#: in n/10⁶ s, supernodal factors in n/4000 s and solves in 2n/10⁶ s; break-even 750
#: solves (751 the first where simplicial costs less), switch point 1000
LATE = {"simplicial": ((1e-3, 1.0), (1e-6, 1.0)), "supernodal": ((2.5e-4, 1.0), (2e-6, 1.0))}
#: the hanging scene's free vertices (21² minus the two pinned corners)
HANGING = 439

pytestmark = pytest.mark.skipif(not factorization.cholmod_available(),
                                reason="CHOLMOD (scikit-sparse) is not installed")


def test_small_grids_simplicial_large_ones_with_few_solves_supernodal():
    for solves in (None, 1, 50, 600, 10 ** 6):
        assert choose_cholmod_mode(33 * 33, "auto", solves).mode == "simplicial"
    choice = choose_cholmod_mode(1025 * 1025, "auto", 50)
    assert choice.mode == "supernodal" and choice.switch_after is None   # a known count
    assert choice.reason.startswith("supernodal: 1050625 free vertices, 50 expected solves: "
                                    "predicted")
    f_simp, f_super = (predicted_costs(1025 * 1025)[m][0] for m in ("simplicial", "supernodal"))
    assert f"{f_super:.3g} s" in choice.reason and f"{f_simp:.3g} s" in choice.reason


def test_the_expected_solves_decide_between_the_sizes():
    n = 400 * 400          # toy model: the factors differ by 1.6 s, the solves by 18 ms
    assert choose_cholmod_mode(n, "auto", 10, TOY).mode == "supernodal"
    choice = choose_cholmod_mode(n, "auto", 10 ** 5, TOY)
    assert choice.mode == "simplicial" and "100000 expected solves" in choice.reason
    # the break-even solve count: (factor saved) / (solve lost)
    (fs, ss), (fS, sS) = (tuple(c * n ** p for c, p in TOY[m]) for m in ("simplicial",
                                                                             "supernodal"))
    even = (fs - fS) / (sS - ss)
    assert choose_cholmod_mode(n, "auto", int(even * 0.9), TOY).mode == "supernodal"
    assert choose_cholmod_mode(n, "auto", int(even * 1.1) + 1, TOY).mode == "simplicial"
    assert break_even(n, "supernodal", TOY) == int(even) + 1
    assert break_even(n, "simplicial", TOY) is None         # its solves are the faster
    # the ski-rental point: simplicial's whole factorization paid in extra solve time
    assert switch_point(n, "supernodal", TOY) == math.ceil(fs / (sS - ss)) > even
    assert switch_point(n, "simplicial", TOY) is None
    for count in (1, 10, int(even), 10 ** 5):                # a known count: never a switch
        assert choose_cholmod_mode(n, "auto", count, TOY).switch_after is None


@pytest.mark.parametrize("side", [129, 257, 513, 1025])
def test_an_unknown_count_starts_in_the_mode_cheaper_to_factor(side):
    """Hand stepping at the measured model's sizes: the factor that costs least now
    (supernodal from about 78² up), with the switch to simplicial's faster solves at the
    point where the extra solve time reaches simplicial's factorization."""
    n = side * side - 2
    pred = predicted_costs(n)
    assert pred["supernodal"][0] < pred["simplicial"][0]
    assert pred["simplicial"][1] < pred["supernodal"][1]
    for bound in (None, 0, 30):
        choice = choose_cholmod_mode(n, "auto", bound, final=False)
        assert (choice.mode, choice.switch_to) == ("supernodal", "simplicial")
        after = choice.switch_after
        assert after == switch_point(n, "supernodal")
        extra = pred["supernodal"][1] - pred["simplicial"][1]
        assert (after - 1) * extra < pred["simplicial"][0] <= after * extra
        assert f"simplicial after {after} solves" in choice.reason
        assert "cheaper to factor" in choice.reason and "ski rental" in choice.reason
    assert choose_cholmod_mode(n, "auto", None).switch_after == after   # None: unknown


def test_a_lower_bound_past_the_break_even_takes_the_faster_solves_at_once():
    n = 1000                                   # LATE: break-even 750, switch point 1000
    assert (break_even(n, "supernodal", LATE), switch_point(n, "supernodal", LATE)) == (751,
                                                                                        1000)
    for bound in (None, 30, 750):
        short = choose_cholmod_mode(n, "auto", bound, LATE, final=False)
        assert (short.mode, short.switch_after, short.switch_to) == ("supernodal", 1000,
                                                                     "simplicial")
    assert "at least 30" in choose_cholmod_mode(n, "auto", 30, LATE, final=False).reason
    long = choose_cholmod_mode(n, "auto", 751, LATE, final=False)
    assert (long.mode, long.switch_after) == ("simplicial", None)
    assert "past the break-even (751 solves)" in long.reason
    # the same count given as final is the whole run: no switch
    assert choose_cholmod_mode(n, "auto", 30, LATE).switch_after is None
    assert choose_cholmod_mode(n, "supernodal", 30, LATE, final=False).switch_after is None
    # a mode cheaper both to factor and to solve: final, whatever the count
    both = choose_cholmod_mode(33 ** 2, "auto", None, final=False)
    assert (both.mode, both.switch_after) == ("simplicial", None)
    assert "cheaper to factor and to solve" in both.reason


def rule_cost(choice, pred, solves: int, step: int) -> tuple[float, str]:
    """What the rule's factors cost for ``solves`` solves served ``step`` per step (the
    solver looks at its count after each step), and the mode it ends in."""
    f, s = pred[choice.mode]
    if choice.switch_after is None:
        return f + solves * s, choice.mode
    served = -(-choice.switch_after // step) * step   # the end of the step it falls in
    if solves <= served:                              # no solve after the switch: not paid
        return f + solves * s, choice.mode
    f2, s2 = pred[choice.switch_to]
    return f + served * s + f2 + (solves - served) * s2, choice.switch_to


@pytest.mark.parametrize("n", [33 ** 2, 129 ** 2, 257 ** 2, 400 ** 2, 513 ** 2, 1025 ** 2])
@pytest.mark.parametrize("costs", [None, TOY, LATE])
def test_the_rule_never_costs_more_than_the_ski_rental_bound(n, costs):
    """By the cost model, the rule for an unknown count against the better of the two modes
    factored once for the same number of solves, whatever that number: at most F_a + F_b
    more (a: the mode cheaper to factor, b: the faster solves; plus the extra solve time of
    the step in which the switch point falls), so at most (2 + F_a/F_b) times it; at most
    F_a more before the switch point; and in the long run the faster solves."""
    pred = predicted_costs(n, costs)
    fast = min(pred, key=lambda m: pred[m][1])
    cheap = min(pred, key=lambda m: pred[m][0])
    choice = choose_cholmod_mode(n, "auto", None, costs, final=False)
    assert choice.mode == cheap
    after, step = choice.switch_after, 10
    counts = {0, 1, 10, 30, 600, 6000, 60000, 10 ** 6}
    if after is not None:
        assert choice.switch_to == fast
        counts |= {after - 1, after, after + 1, after + step, 2 * after}
    slack = step * abs(pred["simplicial"][1] - pred["supernodal"][1])  # whole steps
    F_a, F_b = pred[cheap][0], pred[fast][0]
    for solves in sorted(counts):
        policy, last = rule_cost(choice, pred, solves, step)
        best = min(fm + solves * sm for fm, sm in pred.values())
        assert policy <= (best + F_a + F_b + slack) * (1 + 1e-12), solves
        assert policy <= (2 + F_a / F_b) * best + slack * (1 + 1e-12), solves
        if after is None or solves < after:
            assert policy <= (best + F_a) * (1 + 1e-12), solves
        if solves == 10 ** 6:
            assert last == fast


def test_the_constants_are_the_committed_measurement():
    """MODE_COSTS are the fits docs/data/cholmod-modes.md prints (benchmarks/scale_ladder.py)."""
    text = MODES_TABLE.read_text(encoding="utf-8")
    for mode, pairs in MODE_COSTS.items():
        for what, (c, p) in zip(("factor", "solve"), pairs):
            m = re.search(rf"\| {mode} {what} \| ([0-9.e+-]+) \| ([0-9.-]+) \|", text)
            assert m, f"{mode} {what} missing from {MODES_TABLE.name}"
            assert (float(m.group(1)), float(m.group(2))) == (c, p)
    # the page's picks are the rule's with these constants, the unknown count's too
    rows = re.findall(r"^\| ([0-9,]+) \| (\w+) \| (\w+) \| (\w+) \| (\w+) \| ([^|]+) \|$",
                      text, re.M)
    assert len(rows) == 6
    for row in rows:
        n = int(row[0].replace(",", ""))
        assert list(row[1:5]) == [choose_cholmod_mode(n, "auto", k).mode
                                  for k in (50, 600, 6000, 60000)]
        ski = choose_cholmod_mode(n, "auto", None, final=False)
        assert row[5].strip() == ski.mode + ("" if ski.switch_after is None else
                                             f", {ski.switch_to} after {ski.switch_after} "
                                             "solves")


def test_both_modes_give_the_same_step(monkeypatch):
    def step(mode=None):
        scene = cs.load_scene("hanging", [] if mode is None else [f"solver.cholmod_mode={mode}"])
        sim = scene.build_simulation()
        sim.step()
        return sim.state.positions, sim.solver.factorization

    x_auto, why = step()
    assert why.startswith(f"simplicial: {HANGING} free vertices, the run's count is unknown: "
                          "cheaper to factor and to solve")
    x_super, why = step("supernodal")
    assert why == "supernodal: requested by solver.cholmod_mode"
    assert np.abs(x_auto - x_super).max() < 1e-12
    cheap = {"simplicial": ((1.0, 1.0), (1e-9, 1.0)), "supernodal": ((1e-9, 1.0), (2e-9, 1.0))}
    monkeypatch.setattr(factor_mode, "MODE_COSTS", cheap)
    assert step()[1].startswith(f"supernodal: {HANGING} free vertices")


def test_a_run_passes_its_solve_count_and_a_resumed_run_keeps_it(tmp_path, monkeypatch):
    # a toy model where 30 solves favour supernodal and 300 simplicial (break-even 100)
    toy = {"simplicial": ((1e-4, 1.0), (1e-6, 1.0)), "supernodal": ((1e-9, 1.0), (2e-6, 1.0))}
    monkeypatch.setattr(factor_mode, "MODE_COSTS", toy)
    out = tmp_path / "r"
    assert main(["run", "hanging", "--frames", "3", "--out", str(out), "--no-preview"]) == 0
    info = json.loads((out / "run.json").read_text())
    assert info["expected_solves"] == 30
    assert info["factorization"].startswith(f"supernodal: {HANGING} free vertices, 30 "
                                            "expected solves")
    assert main(["run", "hanging", "--frames", "30", "--out", str(out), "--no-preview",
                 "--resume"]) == 0
    info = json.loads((out / "run.json").read_text())   # not 300: the run's first count
    assert info["expected_solves"] == 30 and info["factorization"].startswith("supernodal")
    sim = cs.load_scene("hanging").build_simulation()
    sim.run(3)                              # the API: run(steps) is a lower bound, not the run
    assert sim.solver.factorization.startswith(
        f"supernodal: {HANGING} free vertices, the run's count is unknown, at least 30: "
        "cheaper to factor")
    assert sim.solver.factor_count == 1


def test_a_short_run_then_stepping_switches_at_the_ski_rental_point(monkeypatch):
    """Simulation.run(3), then stepping by hand: supernodal (cheaper to factor) until its
    factor has served the switch point, then simplicial for good; the steps agree with a
    simplicial run throughout."""
    monkeypatch.setattr(factor_mode, "MODE_COSTS", LATE)
    after = switch_point(HANGING, "supernodal")
    assert (after, break_even(HANGING, "supernodal")) == (1000, 751)
    sim = cs.load_scene("hanging").build_simulation()
    ref = cs.load_scene("hanging", ["solver.cholmod_mode=simplicial"]).build_simulation()
    sim.run(3)
    ref.run(3)
    solver = sim.solver
    assert solver.factorization.startswith(f"supernodal: {HANGING} free vertices, the run's "
                                           "count is unknown, at least 30")
    assert "simplicial after 1000 solves" in solver.factorization
    steps = 3
    while solver.solve_count < after:
        sim.step()
        ref.step()
        steps += 1
        assert solver.factor_count == 1, steps          # no refactorization before it
    assert solver.solve_count == after == 10 * steps    # served: refactored at the next step
    sim.step()
    ref.step()
    assert (solver.factor_count, solver.solve_count) == (2, 10 * (steps + 1))
    assert solver.factorization.startswith(
        f"simplicial: {HANGING} free vertices, switched after {after} solves in supernodal")
    assert solver.backend == "cholmod" and solver.system(sim.problem()).mode.switch_after is None
    for _ in range(5):                                  # and it stays there
        sim.step()
        ref.step()
    assert solver.factor_count == 2
    assert np.abs(sim.state.positions - ref.state.positions).max() < 1e-10
    # a count given as the whole run (clothsim run, final) decides once: never a switch
    sim = cs.load_scene("hanging").build_simulation()
    sim.expect_steps(3)
    for _ in range(110):
        sim.step()
    assert sim.solver.factor_count == 1 and sim.solver.factorization.startswith(
        f"supernodal: {HANGING} free vertices, 30 expected solves")
    # a long API run: its lower bound is past the break-even, simplicial at once
    sim = cs.load_scene("hanging").build_simulation()
    sim.run(76)
    assert sim.solver.factor_count == 1 and sim.solver.factorization.startswith(
        f"simplicial: {HANGING} free vertices, the run's count is unknown, at least 760: "
        "past the break-even")


def test_with_a_tolerance_a_short_run_promises_one_solve_a_step(monkeypatch):
    monkeypatch.setattr(factor_mode, "MODE_COSTS", LATE)
    sim = cs.load_scene("hanging", ["solver.tolerance=1e-3"]).build_simulation()
    sim.expect_steps(75, final=False)
    assert (sim.solver.expected_solves, sim.solver.expected_final) == (75, False)
    sim.expect_steps(75)                     # the whole run: its most solves, as before
    assert (sim.solver.expected_solves, sim.solver.expected_final) == (750, True)


def test_run_records_the_choice_and_newton_refuses_the_key(tmp_path):
    assert main(["run", "hanging", "--set", "solver.cholmod_mode=supernodal", "--frames", "1",
                 "--out", str(tmp_path / "r"), "--no-preview"]) == 0
    info = json.loads((tmp_path / "r" / "run.json").read_text())
    assert info["factorization"] == "supernodal: requested by solver.cholmod_mode"
    scene = cs.load_scene("hanging", ["solver.cholmod_mode=simplicial", "solver.method=newton"])
    with pytest.raises(cs.InputError, match="solver.cholmod_mode: applies to the local/global"):
        scene.build_simulation()


def test_a_refactorization_of_the_same_pattern_reuses_the_analysis():
    import dataclasses

    scene = cs.load_scene("hanging")
    sim = scene.build_simulation()
    solver = sim.solver
    p1 = sim.problem()
    solver.system(p1)
    p2 = dataclasses.replace(p1, h=p1.h / 2)           # h changed: same pattern
    x_reused = solver.solve(p2).x.copy()
    assert (solver.factor_count, solver.analysis_count) == (2, 1)
    fresh = cs.load_scene("hanging").build_simulation().solver
    assert np.abs(fresh.solve(p2).x - x_reused).max() < 1e-13
    assert fresh.analysis_count == 1
    solver.invalidate()                                # after invalidate: analyzed afresh
    solver.system(p2)
    assert solver.analysis_count == 2


@pytest.mark.parametrize("costs", [None, TOY, LATE])
def test_a_short_api_run_either_picks_the_long_runs_mode_or_switches_to_it(costs):
    """Simulation.run(3) (30 solves, not final) at every size: the mode the model picks for
    a long run, or a pick that switches to it; as a final count (clothsim run), 30 solves
    keep the short run's pick (issue 33's regression was that pick, kept)."""
    for side in (9, 33, 65, 129, 193, 257, 385, 513, 769, 1025, 2049):
        n = side * side
        long = choose_cholmod_mode(n, "auto", 10 ** 7, costs).mode
        short = choose_cholmod_mode(n, "auto", 30, costs, final=False)
        assert short.mode == long or short.switch_to == long, side
        assert choose_cholmod_mode(n, "auto", 30, costs).switch_after is None
