"""The performance benchmark's own arithmetic (its timings are never asserted)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from threadpoolctl import threadpool_limits

from clothsim.factorization import cholmod_available

pytestmark = pytest.mark.skipif(not cholmod_available(),
                                reason="the benchmark compares against bare CHOLMOD solves")


def test_performance_rows_are_complete_and_consistent(capsys):
    from benchmarks import performance

    with threadpool_limits(1), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = performance.run((9, 13), repeats=2, setup_repeats=1)
    rows = result["rows"]
    assert [r["n"] for r in rows] == [9, 13]
    for r in rows:
        assert r["vertices"] == r["n"] ** 2
        fastest = min(r["simplicial_ms"][0], r["supernodal_ms"][0])
        assert r["ratio"] == pytest.approx(r["iteration_ms"][0] / fastest)
        assert r["floor"] >= 1.0
        assert all(np.isfinite(v) and v > 0 for v in
                   (r["iteration_ms"][0], r["parts_ms"][0], r["setup_s"][0]))
        lo, med, hi = r["iteration_ms"][1], r["iteration_ms"][0], r["iteration_ms"][2]
        assert lo <= med <= hi
    assert np.isfinite(result["setup_exponent"])
    performance.report(result)
    out = capsys.readouterr().out
    assert "floor" in out and "13x13" in out and "the paper: 50 ms" in out


def test_numpy_parts_leave_the_measured_solver_untouched():
    """The floor's parts run on their own solver: the measured one keeps its buffers."""
    from benchmarks import performance

    case = performance.Case(9)
    before = case.solver.solve(case.problem).x
    case.measure_parts(repeats=1)
    assert case.parts_solver is not case.solver
    np.testing.assert_array_equal(case.solver.solve(case.problem).x, before)


def test_the_iteration_is_measured_after_the_automatic_modes_switch(monkeypatch):
    """Along run(3) and stepping on, the benchmark steps past a pending ski-rental switch
    (here a toy cost model: supernodal first, simplicial after 250 solves) and measures the
    factor the path settles in; without a pending switch it stops at 10 steps."""
    from benchmarks import performance
    from clothsim import factor_mode

    toy = {"simplicial": ((2.5e-4, 1.0), (1e-6, 1.0)), "supernodal": ((1e-9, 1.0), (2e-6, 1.0))}
    monkeypatch.setattr(factor_mode, "MODE_COSTS", toy)
    assert factor_mode.switch_point(79, "supernodal") == 250   # 9² minus two pinned corners
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        case = performance.Case(9)
        assert (case.mode, case.steps, case.solver.factor_count) == ("simplicial", 25, 2)
        both = {"simplicial": toy["simplicial"], "supernodal": ((1e-9, 1.0), (5e-7, 1.0))}
        monkeypatch.setattr(factor_mode, "MODE_COSTS", both)
        case = performance.Case(9)          # supernodal cheaper to factor and to solve: final
        assert (case.mode, case.steps, case.solver.factor_count) == ("supernodal", 10, 1)


def test_iteration_cost_ratios_are_complete(monkeypatch):
    """The per-iteration ratio benchmark's arithmetic on a tiny cloth (timings not asserted)."""
    from benchmarks import iteration_cost

    with threadpool_limits(1), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        monkeypatch.setattr(iteration_cost, "ITERATIONS", 5)
        res = iteration_cost.measure(9, repeats=2)
    assert set(res["ratios"]) == set(iteration_cost.METHODS)
    assert res["ratios"]["local-global"] == 1.0 == res["cpu_ratios"]["local-global"]
    assert all(np.isfinite(v) and v > 0 for v in res["ratios"].values())
    assert len(iteration_cost.commit()) >= 7


def test_factor_modes_rows_compare_the_automatic_mode_with_both(capsys):
    """benchmarks/factor_modes.py: per size, a short-run and a long-run row with the three
    modes' CPU seconds and the automatic mode's choice (timings never asserted)."""
    from benchmarks import factor_modes

    with threadpool_limits(1):
        lines = factor_modes.table([9], 5)
    rows = [line for line in lines if line.startswith("| 9² |")]
    assert len(rows) == 2 and "`run(3)`: 30 solves" in rows[0] and "50 solves" in rows[1]
    for row in rows:
        cells = [c.strip() for c in row.strip("|").split("|")]
        assert all(c.endswith(" s") and float(c[:-2]) >= 0 for c in cells[2:5]), row
        auto, better = float(cells[2][:-2]), min(float(cells[3][:-2]), float(cells[4][:-2]))
        if better > 0.005:                  # the cells are rounded to 0.01 s
            lo, hi = (auto - 0.005) / (better + 0.005), (auto + 0.005) / (better - 0.005)
            assert lo - 0.005 <= float(cells[5]) <= hi + 0.005, row
        assert cells[6] == "simplicial"
    assert any("auto's reason | simplicial: " in line for line in lines)


def test_large_vs_table_takes_medians_and_ratios():
    """benchmarks/large_vs.py's table from made-up runs (the runs themselves take minutes)."""
    from benchmarks import large_vs

    def first(s, f):
        return {"setup": s, "setup_cpu": s / 2, "first": f, "first_cpu": f / 2}

    res = {"old": {"first": [first(4, 30), first(6, 50)], "run": [{"wall": 20, "cpu": 18}]},
           "new": {"first": [first(3, 24), first(3, 26)], "run": [{"wall": 15, "cpu": 17}]}}
    lines = large_vs.table(res)
    assert lines[2] == "| 1025² setup | 5.0 s | 3.0 s | 0.60 | 2.5 s | 1.5 s | 0.60 |"
    assert lines[3] == "| 1025² first step | 40.0 s | 25.0 s | 0.62 | 20.0 s | 12.5 s | 0.62 |"
    assert lines[4] == ("| 513² clothsim run, 5 frames | 20.0 s | 15.0 s | 0.75 | 18.0 s | "
                        "17.0 s | 0.94 |")
