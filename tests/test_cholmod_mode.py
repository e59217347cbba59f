"""CHOLMOD's mode for the global step: chosen by its predicted cost (factor + the run's
expected solves), overridable, recorded."""

import json
import re
from pathlib import Path

import numpy as np
import pytest

import clothsim as cs
from clothsim import factorization
from clothsim.cli import main
from clothsim.factorization import (
    ASSUMED_SOLVES,
    MODE_COSTS,
    choose_cholmod_mode,
    predicted_costs,
)

MODES_TABLE = Path(__file__).resolve().parents[1] / "docs" / "data" / "cholmod-modes.md"
#: a made-up model with the measured shape: simplicial solves twice as fast, supernodal
#: factors cheaper from 10 000 unknowns up (factor c · n^p, solve c · n^p)
TOY = {"simplicial": ((1e-8, 1.6), (1e-8, 1.2)), "supernodal": ((1e-6, 1.1), (2e-8, 1.2))}

pytestmark = pytest.mark.skipif(not factorization.cholmod_available(),
                                reason="CHOLMOD (scikit-sparse) is not installed")


def test_small_grids_simplicial_large_ones_with_few_solves_supernodal():
    for solves in (None, 1, 50, 600, 10 ** 6):
        assert choose_cholmod_mode(33 * 33, "auto", solves)[0] == "simplicial"
    mode, reason = choose_cholmod_mode(1025 * 1025, "auto", 50)
    assert mode == "supernodal"
    assert reason.startswith("supernodal: 1050625 free vertices, 50 expected solves: predicted")
    f_simp, f_super = (predicted_costs(1025 * 1025)[m][0] for m in ("simplicial", "supernodal"))
    assert f"{f_super:.3g} s" in reason and f"{f_simp:.3g} s" in reason


def test_the_expected_solves_decide_between_the_sizes():
    n = 400 * 400          # toy model: the factors differ by 1.6 s, the solves by 18 ms
    assert choose_cholmod_mode(n, "auto", 10, TOY)[0] == "supernodal"
    mode, reason = choose_cholmod_mode(n, "auto", 10 ** 5, TOY)
    assert mode == "simplicial" and "100000 expected solves" in reason
    # the break-even solve count: (factor saved) / (solve lost)
    (fs, ss), (fS, sS) = (tuple(c * n ** p for c, p in TOY[m]) for m in ("simplicial",
                                                                             "supernodal"))
    even = (fs - fS) / (sS - ss)
    assert choose_cholmod_mode(n, "auto", int(even * 0.9), TOY)[0] == "supernodal"
    assert choose_cholmod_mode(n, "auto", int(even * 1.1) + 1, TOY)[0] == "simplicial"
    # unknown: the assumed count, and the reason says so
    mode, reason = choose_cholmod_mode(n, "auto", None, TOY)
    assert f"{ASSUMED_SOLVES} solves assumed (the run's count is unknown)" in reason


def test_requests_are_honoured_and_bad_ones_refused():
    for solves in (None, 5, 10 ** 6):
        assert choose_cholmod_mode(10, "supernodal", solves) == (
            "supernodal", "supernodal: requested by solver.cholmod_mode")
        assert choose_cholmod_mode(10 ** 6, "simplicial", solves)[0] == "simplicial"
    with pytest.raises(cs.InputError, match="solver.cholmod_mode"):
        choose_cholmod_mode(10, "fast")


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
    monkeypatch.setattr(factorization, "MODE_COSTS", cheap)
    assert step()[1].startswith("supernodal: 439 free vertices")


def test_a_run_passes_its_solve_count_and_a_resumed_run_keeps_it(tmp_path, monkeypatch):
    # a toy model where 30 solves favour supernodal and 300 simplicial (break-even 100)
    toy = {"simplicial": ((1e-4, 1.0), (1e-6, 1.0)), "supernodal": ((1e-9, 1.0), (2e-6, 1.0))}
    monkeypatch.setattr(factorization, "MODE_COSTS", toy)
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
    sim.run(30)                                          # the API: run(steps) tells it
    assert sim.solver.factorization.startswith("simplicial: 439 free vertices, 300 expected")


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
