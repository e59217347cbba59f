"""Timing repeats only for settings an answer could choose (clothsim.accuracy.dominance)."""

import math

from clothsim.accuracy.decide import MAX_REPEATS
from clothsim.accuracy.dominance import MARGIN, dominated
from clothsim.accuracy.timing import median_iqr
from clothsim.accuracy.trace import ACCURACY_LEVELS

from .test_robust import read, study

NAN = math.nan


def test_a_slower_setting_no_more_accurate_anywhere_is_dominated():
    methods = ["anderson", "newton", "newton"]
    seconds = [1.0, 2.5, 1.5]
    errors = [(1e-6, 1e-7, 0.1), (1e-6, 1e-7, 0.1), (1e-8, 1e-7, 0.1)]
    # newton 2.5 s: anderson is as accurate and 2.5x faster; newton 1.5 s: more accurate
    assert dominated(methods, seconds, errors) == {1}


def test_the_margin_is_respected():
    errors = [(1e-6,), (1e-6,)]
    assert dominated(["lbfgs", "newton"], [1.0, MARGIN * 0.99], errors) == set()
    assert dominated(["lbfgs", "newton"], [1.0, MARGIN], errors) == {1}


def test_every_error_an_answer_uses_must_be_as_good():
    # faster and better in two errors, worse in the trajectory error: both can be answers
    errors = [(1e-8, 1e-9, 0.2), (1e-6, 1e-7, 0.1)]
    assert dominated(["anderson", "newton"], [1.0, 10.0], errors) == set()
    # an error the slow one has and the fast one lacks (NaN) protects the slow one
    assert dominated(["anderson", "newton"], [1.0, 10.0],
                     [(1e-8, NAN), (1e-6, 1e-7)]) == set()
    # an error the slow one lacks cannot be asked of it
    assert dominated(["anderson", "newton"], [1.0, 10.0],
                     [(1e-8, NAN), (1e-6, NAN)]) == {1}


def test_local_global_is_the_baseline_and_only_its_own_settings_dominate_it():
    errors = [(1e-6,), (1e-3,), (1e-3,)]
    methods = ["lbfgs", "local-global", "local-global"]
    # lbfgs beats both local/global settings, but the report's "N x faster than
    # local/global" needs local/global's own cheapest: only the 10 s one goes
    assert dominated(methods, [0.1, 1.0, 10.0], errors) == {2}


def test_untimed_or_diverged_settings_take_no_part():
    errors = [(1e-6,), (1e-6,), (math.inf,)]
    assert dominated(["a", "b", "c"], [NAN, 10.0, math.inf], errors) == set()


def test_one_repeat_has_a_median_but_no_spread():
    med, iqr = median_iqr([0.25])
    assert med == 0.25 and math.isnan(iqr)
    assert median_iqr([1.0, 2.0, 3.0, 4.0, 5.0]) == (3.0, 2.0)


def test_the_study_repeats_only_what_an_answer_could_choose(tmp_path):
    """A tiny study: every setting it times twice only is beaten at half its fastest time,
    at every level, by another, and every setting the answers name was timed at least 3
    times (more when the answer was not yet decided, never more than the cap)."""
    text = study(tmp_path, methods=("local-global", "chebyshev", "newton"), repeats=3,
                 budgets=(1, 2, 5), tolerances=(1e-4, 1e-8))
    rows = read(tmp_path / "accuracy.csv")
    cols = ("solver_error_p90", "objective_gap_p90")

    def reaches_all(o, r):
        return all(not float(r[c]) <= lev or float(o[c]) <= lev
                   for c in cols for lev in ACCURACY_LEVELS)

    twice = [r for r in rows if r["repeats"] == "2"]
    assert len(twice) < len(rows)
    for r in twice:
        fastest = float(r["seconds_per_step_min"])
        assert fastest <= float(r["seconds_per_step_median"])
        assert any(float(o["seconds_per_step_median"]) * MARGIN <= fastest * 1.5
                   and reaches_all(o, r) for o in rows if o is not r), r
    for r in rows:
        assert r["repeats"] == "2" or 3 <= int(r["repeats"]) <= MAX_REPEATS
    answered = [line.split("|")[3].strip() for line in text.splitlines()
                if line.startswith("| 1e-") and "no setting" not in line
                and "not measurable" not in line]
    assert answered
    timed3 = {r["method"] + (f", tolerance {float(r['tolerance']):g}" if r["tolerance"]
                             else f", {r['iterations']} it/step") for r in rows
              if int(r["repeats"]) >= 3}
    for name in answered:
        assert name in timed3, (name, timed3)
    if twice:
        assert "timed twice only" in text


def test_levels_make_errors_below_every_target_equal():
    # Newton's exact 0 and L-BFGS's 1.7e-12 are equal for targets down to 1e-8
    errors = [(1.7e-12, 1e-7), (0.0, 2e-6)]
    levels = (ACCURACY_LEVELS, ACCURACY_LEVELS)
    assert dominated(["lbfgs", "newton"], [1.0, 4.0], errors) == set()
    assert dominated(["lbfgs", "newton"], [1.0, 4.0], errors, levels=levels) == {1}
    # a level the slow one reaches and the fast one misses keeps the slow one
    assert dominated(["lbfgs", "newton"], [1.0, 4.0], [(1.7e-12, 2e-6), (0.0, 1e-7)],
                     levels=levels) == set()


def test_dominated_settings_are_timed_twice_and_the_report_says_so(tmp_path, monkeypatch):
    """The plumbing, with a rule that declares every Newton setting dominated: those rows
    keep two timings (unless an answer row still has to tell them apart: the rule here is
    not a real domination), the others get every repeat, and the report says why."""
    import clothsim.accuracy.timing as timing

    seen = {}

    def newton_dominated(methods, seconds, errors, **kw):
        seen["errors"], seen["levels"] = errors, kw["levels"]
        return {i for i, m in enumerate(methods) if m == "newton"}

    monkeypatch.setattr(timing, "dominated", newton_dominated)
    text = study(tmp_path, methods=("local-global", "newton"), repeats=3, budgets=(1, 5),
                 tolerances=(1e-6,))
    rows = read(tmp_path / "accuracy.csv")
    for r in rows:
        if r["method"] == "newton":   # two, and more only where an answer needed them
            setting = ("newton, " + (f"tolerance {float(r['tolerance']):g}" if r["tolerance"]
                                     else f"{r['iterations']} it/step"))
            assert r["repeats"] == "2" or setting in text
        else:
            assert 3 <= int(r["repeats"]) <= MAX_REPEATS
        assert float(r["seconds_per_step_median"]) > 0
    # the rule saw the errors the answers read: solver error, gap, trajectory error
    assert len(seen["errors"]) == len(rows) and all(len(e) == 3 for e in seen["errors"])
    assert len(seen["levels"]) == 3 and 1e-3 in seen["levels"][0] and not seen["levels"][2]
    assert "3 configuration(s) timed twice only" in text


def test_a_single_repeat_study_says_nothing_about_domination(tmp_path):
    text = study(tmp_path, repeats=1)
    assert "timed twice only" not in text
    rows = read(tmp_path / "accuracy.csv")
    # one repeat each, and more only for the settings an answer had to tell apart
    assert all(1 <= int(r["repeats"]) <= MAX_REPEATS for r in rows)
    assert any(r["repeats"] == "1" for r in rows) or "repeats" in text


def test_trajectory_errors_are_the_same_for_any_number_of_jobs():
    """The trajectory runs in parallel workers give the serial runs' errors, bit for bit."""
    import warnings

    from clothsim.accuracy import scene_factory
    from clothsim.accuracy.study import default_configurations
    from clothsim.accuracy.timestep import time_step_study, trajectory_errors
    from clothsim.scene import Scene

    from .test_study import TINY

    factory, model, frame_time = scene_factory(Scene.from_dict(TINY))
    h = frame_time
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ts = time_step_study(factory, frame_time=frame_time, frames=4, time_steps=(h, h / 2),
                             reference_h=h / 8)
        configs = default_configurations(("local-global", "anderson"), budgets=(1, 5, 50),
                                         tolerances=(1e-6,))
        serial = trajectory_errors(factory, configs, ts.reference, h=h, frame_time=frame_time)
        parallel = trajectory_errors(factory, configs, ts.reference, h=h,
                                     frame_time=frame_time, jobs=2)
    assert len(serial) == 6 and serial == parallel     # budget 50 is not a trajectory budget
    assert all(0 < e < math.inf for e in serial.values())
