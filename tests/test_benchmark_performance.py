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
