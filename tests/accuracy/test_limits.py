"""Each method's own limit: "fast to a worse minimum" shows; on a convex step every limit
is x*."""

import csv
import functools
import json
import warnings

import numpy as np
import pytest

from clothsim.accuracy import (
    Configuration,
    measure,
    prepare_steps,
    record_problems,
    run_accuracy,
)
from clothsim.accuracy.limits import method_limits, worse_minimum_notes
from clothsim.accuracy.report import COLUMNS, rows, write_csv
from clothsim.accuracy.steps_report import steps_table
from clothsim.scene import Scene

from .test_study import TINY, buckling_strip

ROUNDING = 1e-12  # |gap| of two evaluations at one point: rounding only


@pytest.fixture(scope="module")
def strip():
    """The buckling strip's first step: Newton from y and local/global converge to two
    different certified minima (Newton's is the worse one)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sim = buckling_strip()
        steps = prepare_steps(sim.model, record_problems(sim, steps=1, count=1))
    return sim, steps


def test_two_methods_at_different_minima_show_their_basin_gaps(strip, tmp_path):
    sim, steps = strip
    method_limits(sim.model, steps, ("newton", "local-global"))
    step = steps[0]
    assert step.kind == "several-minima"
    newton, lg = step.limits["newton"], step.limits["local-global"]
    assert newton.certified and lg.certified
    for lim in (newton, lg):
        assert lim.gap >= -ROUNDING
    best = [lim for lim in (newton, lg) if lim.same_as_best]
    assert len(best) == 1 and abs(best[0].gap) <= ROUNDING
    worse = lg if best[0] is newton else newton
    assert worse.gap > 1e-6  # a different, higher minimum
    configs = [Configuration("newton", 100, 1e-12), Configuration("newton", 1),
               Configuration("local-global", 3)]
    table = rows(measure(sim.model, steps, configs), steps, h=sim.h)
    assert table[0].limit_error_max < 1e-8  # converged: at its own limit
    assert table[1].limit_error_max > 1e-3 and table[2].limit_error_max > 1e-2
    assert table[0].limit_gap_max == pytest.approx(newton.gap)
    assert table[2].limit_gap_max == pytest.approx(lg.gap, abs=ROUNDING)
    assert table[0].residual_max < 1e-10 < table[1].residual_max
    # the report names the method that converges to the worse minimum, and the step
    notes = worse_minimum_notes(steps, 1e-7)
    assert len(notes) == 1 and notes[0].startswith(f"{worse.method} converges to a worse "
                                                   f"minimum on step(s) {step.step.index} ")
    assert worse_minimum_notes(steps, 1.0) == []
    assert "x_best" in steps_table(steps).splitlines()[-1]
    header = write_csv(table, tmp_path / "a.csv").read_text().splitlines()[0].split(",")
    assert {"limit_error_median", "limit_error_p90", "limit_error_max", "limit_gap_max",
            "residual_p90"} <= set(header) and header == list(COLUMNS)


def test_a_limit_below_every_known_minimum_becomes_x_best(monkeypatch):
    """With Newton from y as the only start, the strip's step looks unique; local/global's
    own limit (run here, nothing to reuse) is a lower minimum: it joins the set, becomes
    x_best, and the step has several minima."""
    import clothsim.accuracy.study as study

    monkeypatch.setattr(study, "certified_reference",
                        functools.partial(study.certified_reference, second_start=False))
    sim = buckling_strip()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        steps = prepare_steps(sim.model, record_problems(sim, steps=1, count=1))
    assert steps[0].kind == "unique" and steps[0].reference.minima == 1
    method_limits(sim.model, steps, ("newton", "local-global"), cap=3000)
    ref, limits = steps[0].reference, steps[0].limits
    assert steps[0].kind == "several-minima" and ref.minima == 2
    assert limits["local-global"].certified and limits["local-global"].same_as_best
    assert np.array_equal(ref.x_best, limits["local-global"].x)
    assert ref.objective_difference < 0 and limits["newton"].gap > 1e-6


def test_on_a_convex_step_every_limit_is_x_star(tmp_path):
    """Hanging cloth (tiny): every step is unique, each method's own limit is x*, its
    basin gap 0, and the limit error equals the solver error."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        run_accuracy(Scene.from_dict(TINY), tmp_path, methods=("local-global", "lbfgs",
                     "newton"), problems=2, repeats=1, budgets=(1, 5),
                     tolerances=(1e-8,), time_steps=False, plots=False)
    with open(tmp_path / "accuracy.csv", newline="") as fh:
        table = list(csv.DictReader(fh))
    assert table and all(int(r["steps_several_minima"]) == 0 for r in table)
    for r in table:
        err, lim = float(r["solver_error_max"]), float(r["limit_error_max"])
        assert lim == pytest.approx(err, rel=1e-6, abs=1e-10), r["method"]
        assert abs(float(r["limit_gap_max"])) <= ROUNDING
    phases = json.loads((tmp_path / "accuracy.json").read_text())["phase_seconds"]
    # extrapolation: when no local/global setting reaches a printed level
    assert set(phases) - {"extrapolation"} == {"recording", "references", "limits", "errors",
                                               "timing"}
    steps_md = (tmp_path / "steps.md").read_text()
    assert "lbfgs: x_best" in steps_md and "newton: x_best" in steps_md
