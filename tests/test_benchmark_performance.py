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
    # --runs-only: the 513² runs alone, and each pair's ratios with its loads
    runs = {k: {"first": [], "run": [dict(r, load=1.5) for r in v["run"]]}
            for k, v in res.items()}
    assert large_vs.table(runs)[2:] == [lines[4]]
    assert large_vs.pairs(runs)[2:] == ["| 1 | 1.5, 1.5 | 0.75 | 0.94 |"]


def _result(sizes=(129, 257), ratios=(2.5, 2.0)):
    """A made-up measurement in the shape of performance.run's result."""
    rows = []
    for n, ratio in zip(sizes, ratios):
        t = (1e-3 * n / 100, 0.9e-3 * n / 100, 1.3e-3 * n / 100)
        rows.append({"n": n, "vertices": n * n, "springs": 5 * n * n, "mode": "simplicial",
                     "steps": 10, "iteration_ms": t, "simplicial_ms": (t[0] / ratio,) * 3,
                     "supernodal_ms": (2 * t[0],) * 3, "ratio": ratio,
                     "iteration_cpu_ms": t, "simplicial_cpu_ms": (t[0] / ratio,) * 3,
                     "supernodal_cpu_ms": (2 * t[0],) * 3, "ratio_cpu": ratio,
                     "setup_s": (1e-6 * n * n,) * 3, "condition_s": (1e-7 * n * n,) * 3,
                     "parts_ms": (t[0] / 2,) * 3, "floor": 1.5})
    return {"rows": rows, "setup_exponent": 1.0, "frame_s": (0.012, 0.011, 0.013),
            "commit": "abc1234", "load": (0.41, 0.52), "cores": 2, "repeats": 15}


def test_the_table_is_written_from_the_csv(tmp_path):
    """benchmarks.performance writes its CSV, then the page's table from that CSV alone:
    every figure, the guards' verdicts, the commit, load and the 81 × 81 frame."""
    from benchmarks import performance, performance_page

    csv_path, page_path = tmp_path / "p.csv", tmp_path / "p.md"
    performance.write_csv(_result(), csv_path)
    performance_page.write(csv_path, page_path)
    text = page_path.read_text()
    assert "at commit abc1234, 15 interleaved repeats, 2 cores, load average 0.41" in text
    assert "0.52 at the end" in text
    rows = [line for line in text.splitlines() if line.startswith("| 129² |")]
    assert rows == ["| 129² | 83,205 | simplicial (10) | 1.29 ms (1.16–1.68) [1.29] | 0.516 ms"
                    " | 2.58 ms | **2.50** [2.50] | 1.50 | 16.6 ms | 1.66 ms |"]
    assert "≤ 2.8 at 129²: holds (2.50); ≤ 1.9 at 257²: missed (2.00)" in text
    assert "≤ 1.8 at 129²: missed (2.50)" in text
    assert "(vertices)^1.00" in text                 # setup ∝ n² = vertices here
    assert "CPU time: 12.0 ms (11.0–13.0 ms), against the paper's 50.0 ms" in text
    assert "target ≤ 30.0 ms: met" in text

def test_from_csv_measures_nothing(monkeypatch):
    """``--from-csv [PATH]`` only rewrites the table, from PATH or the default CSV."""
    from benchmarks import performance

    sources = []
    monkeypatch.setattr(performance, "write_page", lambda src: sources.append(src) or src)
    monkeypatch.setattr(performance, "run", lambda *a, **k: pytest.fail("measured"))
    performance.main(["--from-csv", "elsewhere.csv"])
    performance.main(["--from-csv"])
    assert sources == ["elsewhere.csv", performance.CSV_PATH]


def test_the_table_from_an_older_csv_says_what_it_lacks(tmp_path):
    """A CSV without the run's columns (the committed one before this change) still gives
    the table; the commit, load and frame are named as not recorded, never invented. A size
    left out (--quick) reads "not measured"; a broken CSV is one InputError naming the field."""
    from benchmarks import performance, performance_page
    from clothsim.errors import InputError

    csv_path = tmp_path / "p.csv"
    performance.write_csv(_result(sizes=(33, 129), ratios=(5.0, 1.7)), csv_path)
    lines = csv_path.read_text().splitlines()
    keep = len(performance_page.RUN_COLUMNS)
    csv_path.write_text("\n".join(",".join(line.split(",")[:-keep]) for line in lines) + "\n")
    text = "\n".join(performance_page.page(performance_page.read_csv(csv_path)))
    assert "at a commit and load this CSV does not record" in text
    assert "≤ 1.9 at 257²: not measured" in text and "≤ 1.8 at 129²: holds (1.70)" in text
    assert "this CSV predates recording it" in text and "abc1234" not in text
    csv_path.write_text(csv_path.read_text().replace(",1.700,", ",fast,", 1))
    with pytest.raises(InputError, match=r"line 3: ratio is 'fast'") as err:
        performance_page.read_csv(csv_path)
    assert err.value.field == "ratio"
    (tmp_path / "q.csv").write_text("grid,vertices\n9x9,81\n")
    with pytest.raises(InputError, match="no column 'springs'"):
        performance_page.read_csv(tmp_path / "q.csv")


def test_the_committed_table_is_the_committed_csvs():
    """docs/data/performance.md is what --from-csv writes from docs/data/performance.csv:
    a hand edit of either, or a new CSV without its table, fails here."""
    from benchmarks import performance_page

    expected = "\n".join(performance_page.page(performance_page.read_csv())) + "\n"
    assert performance_page.PAGE.read_text(encoding="utf-8") == expected


def test_from_csv_names_a_missing_file_in_one_line(tmp_path):
    from benchmarks import performance

    with pytest.raises(SystemExit, match=r"benchmarks.performance: .*nothing.csv: cannot read"):
        performance.main(["--from-csv", str(tmp_path / "nothing.csv")])


def test_large_vs_writes_its_page_with_both_commits(tmp_path, monkeypatch):
    """``--write PAGE``: the tables a comparison printed, under the command that makes them
    and the commits of both trees (the runs made up; each takes seconds)."""
    from benchmarks import large_vs

    walls = iter([20.0, 15.0, 14.0, 21.0])   # old, new, then new, old
    monkeypatch.setattr(large_vs, "cli_run",
                        lambda tree, n: {"wall": next(walls), "cpu": 10.0})
    monkeypatch.setattr(large_vs, "commit", lambda tree=None: "old1234" if tree else "new5678")
    page = tmp_path / "large-vs.md"
    large_vs.main([str(tmp_path), "--repeats", "2", "--runs-only", "--write", str(page)])
    text = page.read_text()
    assert text.startswith("Measured by `python -m benchmarks.large_vs OLD_TREE --repeats 2 "
                           f"--runs-only --write {page}` at commit new5678 with OLD_TREE at "
                           "commit old1234: 2 interleaved repeats")
    assert "| 513² clothsim run, 5 frames | 20.5 s | 14.5 s | 0.71 |" in text
    assert "| 2 |" in text and "| 0.67 |" in text   # the second pair: 14 / 21
