"""The report says what to do: the time-step note, and where an accelerated method at a small
budget is less accurate than plain local/global (detected from the rows)."""

import math
from types import SimpleNamespace

from clothsim.accuracy.report import worse_than_local_global
from clothsim.accuracy.timestep import what_to_do


def rows(gaps, unique=0):
    return [SimpleNamespace(method=m, iterations=b, tolerance=None, status="ok",
                            solver_error_p90=g, objective_gap_p90=g, steps_unique=unique)
            for m, per in gaps.items() for b, g in per.items()]


def test_chebyshev_worse_than_local_global_at_small_budgets_is_noted():
    # drop-on-square at 25 x 25 (the numbers): a contact scene, gap measured
    table = rows({"local-global": {5: 4.6e-3, 10: 2.4e-3, 20: 1.4e-3},
                  "chebyshev": {5: 1.6e-2, 10: 7.2e-3, 20: 7.3e-4},
                  "anderson": {5: 2.6e-3, 10: 8.9e-4, 20: 2.9e-4},
                  "newton": {5: 1e-9}})
    (note,) = worse_than_local_global(table)
    assert note == ("chebyshev is less accurate than plain local/global at 5, 10 iterations "
                    "per step (objective gap p90 1.6e-02, 7.2e-03 against 4.6e-03, 2.4e-03): "
                    "with a budget this small use local/global; chebyshev is ahead from 20 "
                    "iterations per step")


def test_a_gap_raised_while_the_solver_error_falls_is_noted():
    # unique steps (the table shows the solver error), where Chebyshev is ahead, but its
    # objective gap at 5 and 10 iterations is above local/global's: said in the gap
    table = rows({"local-global": {5: 0.3, 10: 0.29, 20: 0.27},
                  "chebyshev": {5: 0.26, 10: 0.17, 20: 0.1}}, unique=3)
    for r in table:
        r.objective_gap_p90 = {("local-global", 5): 4.6e-3, ("local-global", 10): 2.4e-3,
                               ("local-global", 20): 1.4e-3, ("chebyshev", 5): 1.6e-2,
                               ("chebyshev", 10): 7.2e-3,
                               ("chebyshev", 20): 7.3e-4}[(r.method, r.iterations)]
    (note,) = worse_than_local_global(table)
    assert note.startswith("chebyshev is less accurate than plain local/global at 5, 10 "
                           "iterations per step (objective gap p90 1.6e-02, 7.2e-03")
    assert note.endswith("chebyshev is ahead from 20 iterations per step")
    for r in table:   # and no note where it is ahead in both
        r.objective_gap_p90 = r.solver_error_p90
    assert worse_than_local_global(table) == []


def test_no_note_where_the_accelerated_methods_are_ahead_or_unmeasured():
    # hanging: Chebyshev better than local/global at every budget
    table = rows({"local-global": {5: 0.38, 10: 0.38}, "chebyshev": {5: 0.37, 10: 0.31}},
                 unique=3)
    assert worse_than_local_global(table) == []
    assert worse_than_local_global(rows({"chebyshev": {5: 0.5}})) == []
    nan = rows({"local-global": {5: math.nan}, "chebyshev": {5: 0.5}})
    assert worse_than_local_global(nan) == []


def test_the_time_step_note_says_what_to_do():
    first = what_to_do(0.012, 0.9, 1 / 30, 5e-4, 1 / 30)
    assert "0.012 off" in first and "--set scene.substeps=2" in first
    assert "cannot go below" in first
    damped = what_to_do(0.2, 0.45, 1 / 60, 4.88e-4, 1 / 30)
    assert "keep h" in damped and "--set scene.substeps=69" in damped
    assert "0.2 off" in damped and "removes only 27% of it (slope 0.45)" in damped
    assert "does not reduce it" in what_to_do(0.2, math.nan, 1 / 30, 5e-4, 1 / 30)
