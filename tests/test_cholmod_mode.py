"""CHOLMOD's mode for the global step: chosen by its predicted cost (factor + the run's
expected solves), overridable, recorded."""

import json
import re
from pathlib import Path

import numpy as np
import pytest

import clothsim as cs
from clothsim import factor_mode, factorization
from clothsim.cli import main
from clothsim.factor_mode import (
    ASSUMED_SOLVES,
    MODE_COSTS,
    break_even,
    choose_cholmod_mode,
    predicted_costs,
)

MODES_TABLE = Path(__file__).resolve().parents[1] / "docs" / "data" / "cholmod-modes.md"
#: a made-up model with the measured shape: simplicial solves twice as fast, supernodal
#: factors cheaper from 10 000 unknowns up (factor c · n^p, solve c · n^p)
TOY = {"simplicial": ((1e-8, 1.6), (1e-8, 1.2)), "supernodal": ((1e-6, 1.1), (2e-8, 1.2))}
#: a toy model whose break-even (1000 solves at every size) lies past ASSUMED_SOLVES
LATE = {"simplicial": ((1e-3, 1.0), (1e-6, 1.0)), "supernodal": ((1e-9, 1.0), (2e-6, 1.0))}

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
    # unknown: the assumed count, and the reason says so
    choice = choose_cholmod_mode(n, "auto", None, TOY)
    assert f"{ASSUMED_SOLVES} solves assumed (the run's count is unknown)" in choice.reason


def test_a_count_that_is_not_final_is_a_lower_bound_with_a_break_even():
    """Not final (Simulation.run, stepping by hand): the horizon is the largest of the bound,
    ASSUMED_SOLVES and the solves served, and a pick with the slower solves says when the
    other mode would have been cheaper from the start."""
    n = 400 * 400
    even = break_even(n, "supernodal", LATE)
    assert ASSUMED_SOLVES < even == 1000                      # the case that needs a switch
    short = choose_cholmod_mode(n, "auto", 30, LATE, final=False)
    assert (short.mode, short.switch_after, short.switch_to) == ("supernodal", even,
                                                                 "simplicial")
    assert "at least 30" in short.reason and f"simplicial after {even} solves" in short.reason
    # a bound or a history past the break-even: simplicial, and final (its solves are faster)
    for kw in ({"expected_solves": even + 1}, {"served": even + 1}):
        long = choose_cholmod_mode(n, "auto", final=False, costs=LATE, **kw)
        assert (long.mode, long.switch_after) == ("simplicial", None)
    # the same count given as final is the whole run: no switch
    assert choose_cholmod_mode(n, "auto", 30, LATE).switch_after is None
    assert choose_cholmod_mode(n, "supernodal", 30, LATE, final=False).switch_after is None


@pytest.mark.parametrize("n", [33 ** 2, 129 ** 2, 257 ** 2, 400 ** 2, 513 ** 2, 1025 ** 2])
@pytest.mark.parametrize("costs", [None, TOY, LATE])
def test_the_rule_never_costs_more_than_the_better_mode_by_more_than_one_factor(n, costs):
    """By the cost model, the policy (the pick for an unknown count, refactored in the other
    mode at the break-even) against the better of the two modes factored once for the same
    number of solves, whatever that number: at most one factorization in the mode with the
    faster solves more (the ski-rental bound, plus one solve: counts are whole), and in the
    long run the faster solves."""
    pred = predicted_costs(n, costs)
    faster = min(pred, key=lambda m: pred[m][1])
    choice = choose_cholmod_mode(n, "auto", None, costs, final=False)
    even = choice.switch_after
    counts = {0, 1, 10, 30, 600, 6000, 60000, 10 ** 6}
    if even is not None:
        assert choice.switch_to == faster
        counts |= {even - 1, even, even + 1, 2 * even}
    for solves in sorted(counts):
        f, s = pred[choice.mode]
        if even is not None and solves > even:
            f2, s2 = pred[choice.switch_to]
            policy, last = f + even * s + f2 + (solves - even) * s2, choice.switch_to
        else:
            policy, last = f + solves * s, choice.mode
        best = min(fm + solves * sm for fm, sm in pred.values())
        one_solve = abs(pred["simplicial"][1] - pred["supernodal"][1])   # counts are whole
        assert policy <= (best + pred[faster][0] + one_solve) * (1 + 1e-12), solves
        if even is None or solves < even:      # before the break-even: the better mode
            assert policy <= best * (1 + 1e-12) or choice.mode == faster
        if solves == 10 ** 6:
            assert last == faster


def test_the_constants_are_the_committed_measurement():
    """MODE_COSTS are the fits docs/data/cholmod-modes.md prints (benchmarks/scale_ladder.py)."""
    text = MODES_TABLE.read_text(encoding="utf-8")
    for mode, pairs in MODE_COSTS.items():
        for what, (c, p) in zip(("factor", "solve"), pairs):
            m = re.search(rf"\| {mode} {what} \| ([0-9.e+-]+) \| ([0-9.-]+) \|", text)
            assert m, f"{mode} {what} missing from {MODES_TABLE.name}"
            assert (float(m.group(1)), float(m.group(2))) == (c, p)


def test_both_modes_give_the_same_step(monkeypatch):
    def step(mode=None):
        scene = cs.load_scene("hanging", [] if mode is None else [f"solver.cholmod_mode={mode}"])
        sim = scene.build_simulation()
        sim.step()
        return sim.state.positions, sim.solver.factorization

    x_auto, why = step()
    assert why.startswith(f"simplicial: 439 free vertices, {ASSUMED_SOLVES} solves assumed")
    x_super, why = step("supernodal")
    assert why == "supernodal: requested by solver.cholmod_mode"
    assert np.abs(x_auto - x_super).max() < 1e-12
    cheap = {"simplicial": ((1.0, 1.0), (1e-9, 1.0)), "supernodal": ((1e-9, 1.0), (2e-9, 1.0))}
    monkeypatch.setattr(factor_mode, "MODE_COSTS", cheap)
    assert step()[1].startswith("supernodal: 439 free vertices")


def test_a_run_passes_its_solve_count_and_a_resumed_run_keeps_it(tmp_path, monkeypatch):
    # a toy model where 30 solves favour supernodal and 300 simplicial (break-even 100)
    toy = {"simplicial": ((1e-4, 1.0), (1e-6, 1.0)), "supernodal": ((1e-9, 1.0), (2e-6, 1.0))}
    monkeypatch.setattr(factor_mode, "MODE_COSTS", toy)
    out = tmp_path / "r"
    assert main(["run", "hanging", "--frames", "3", "--out", str(out), "--no-preview"]) == 0
    info = json.loads((out / "run.json").read_text())
    assert info["expected_solves"] == 30
    assert info["factorization"].startswith("supernodal: 439 free vertices, 30 expected solves")
    assert main(["run", "hanging", "--frames", "30", "--out", str(out), "--no-preview",
                 "--resume"]) == 0
    info = json.loads((out / "run.json").read_text())   # not 300: the run's first count
    assert info["expected_solves"] == 30 and info["factorization"].startswith("supernodal")
    sim = cs.load_scene("hanging").build_simulation()
    sim.run(3)                              # the API: run(steps) is a lower bound, not the run
    assert sim.solver.factorization.startswith(
        f"simplicial: 439 free vertices, {ASSUMED_SOLVES} solves assumed (the run's count is "
        "unknown; at least 30)")


def test_a_short_run_then_more_steps_ends_in_the_long_runs_mode(monkeypatch):
    """Simulation.run(3) on a toy model whose break-even lies past ASSUMED_SOLVES: supernodal
    first, then, once its factor has served the break-even, the mode the cost model picks
    for the long run; the steps agree with a simplicial run throughout."""
    monkeypatch.setattr(factor_mode, "MODE_COSTS", LATE)
    even = break_even(439, "supernodal")
    assert even == 1000 and choose_cholmod_mode(439, "auto", 10 ** 5).mode == "simplicial"
    sim = cs.load_scene("hanging").build_simulation()
    ref = cs.load_scene("hanging", ["solver.cholmod_mode=simplicial"]).build_simulation()
    sim.run(3)
    ref.run(3)
    solver = sim.solver
    assert solver.factorization.startswith("supernodal: 439 free vertices, 600 solves assumed")
    assert solver.factorization.endswith("simplicial after 1000 solves (the break-even)")
    steps = 3
    while solver.solve_count < even:
        sim.step()
        ref.step()
        steps += 1
        assert solver.factor_count == 1, steps          # no refactorization before it
    sim.step()                                          # the first step past the break-even
    ref.step()
    assert (solver.factor_count, solver.solve_count) == (2, 10 * (steps + 1))
    assert solver.factorization.startswith(
        f"simplicial: 439 free vertices, switched after {10 * steps} solves in supernodal")
    assert solver.backend == "cholmod" and solver.system(sim.problem()).mode.switch_after is None
    for _ in range(5):                                  # and it stays there
        sim.step()
        ref.step()
    assert solver.factor_count == 2
    assert np.abs(sim.state.positions - ref.state.positions).max() < 1e-10
    # a count given as the whole run (clothsim run, final) never switches
    sim = cs.load_scene("hanging").build_simulation()
    sim.expect_steps(3)
    for _ in range(110):
        sim.step()
    assert sim.solver.factor_count == 1 and sim.solver.factorization.startswith("supernodal")


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
    a long run, or a pick whose break-even switches to it; as a final count (clothsim run),
    30 solves keep the short run's pick (issue 33's regression was that pick, kept)."""
    for side in (9, 33, 65, 129, 193, 257, 385, 513, 769, 1025, 2049):
        n = side * side
        long = choose_cholmod_mode(n, "auto", 10 ** 7, costs).mode
        short = choose_cholmod_mode(n, "auto", 30, costs, final=False)
        assert short.mode == long or short.switch_to == long, side
        assert choose_cholmod_mode(n, "auto", 30, costs).switch_after is None
