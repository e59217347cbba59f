"""Answers that do not hang on one timing sample (clothsim.accuracy.decide)."""

import re
import warnings
from types import SimpleNamespace

import numpy as np
import pytest

import clothsim.accuracy.timing as timing
from clothsim.accuracy import run_accuracy
from clothsim.accuracy.decide import MAX_REPEATS, MIN_REPEATS, choose, undecided
from clothsim.scene import Scene

from .test_study import TINY


def row(method, its, err, samples, tolerance=None):
    s = np.asarray(samples, dtype=float)
    q1, q3 = np.quantile(s, [0.25, 0.75]) if len(s) > 1 else (np.nan, np.nan)
    setting = (f"{method}, tolerance {tolerance:g}" if tolerance else f"{method}, {its} it/step")
    return SimpleNamespace(method=method, iterations=its, tolerance=tolerance,
                           iterations_median=its, setting=setting, solver_error_p90=err,
                           seconds_per_step_median=float(np.median(s)),
                           seconds_per_step_iqr=q3 - q1, seconds_per_step_min=float(s.min()),
                           repeats=len(s), status="ok")


def test_one_slow_sample_does_not_decide_and_equal_work_is_a_tie():
    # the case: chebyshev 1 it does local/global's work and one sample took 6x
    lg, cheb = [0.42e-3], [2.53e-3]
    c = choose([row("local-global", 1, 0.3, lg), row("chebyshev", 1, 0.3, cheb)], 0.5)
    assert not c.decided                                # one sample each: time again
    assert {r.method for r in c.pending} == {"local-global", "chebyshev"}
    lg, cheb = [0.42e-3, 0.43e-3, 0.41e-3], [2.53e-3, 0.42e-3, 0.41e-3]
    c = choose([row("local-global", 1, 0.3, lg), row("chebyshev", 1, 0.3, cheb)], 0.5)
    assert not c.decided and c.row.method == "local-global"
    # at the cap: a tie within noise, named by preference (local/global), whichever is faster
    for fast, slow in (("local-global", "chebyshev"), ("chebyshev", "local-global")):
        table = [row(fast, 1, 0.3, [0.40e-3] * MAX_REPEATS),
                 row(slow, 1, 0.3, [0.41e-3] * (MAX_REPEATS - 1) + [2.5e-3])]
        c = choose(table, 0.5)
        assert c.decided and c.row.method == "local-global"
        assert [t.method for t in c.tied] == ["chebyshev"]
        assert c.sureness().startswith("tie within noise with chebyshev, 1 it/step")


def test_a_clear_difference_is_decided_after_three_repeats_and_far_ones_after_two():
    table = [row("anderson", 10, 1e-3, [1.0e-3, 1.3e-3, 1.0e-3]),
             row("lbfgs", 10, 1e-3, [1.25e-3, 1.3e-3, 1.9e-3]),
             row("newton", 2, 1e-4, [2.2e-3, 9e-3])]
    c = choose(table, 1e-3)
    assert c.decided and c.row.method == "anderson" and c.runner_up.method == "lbfgs"
    assert c.sureness() == ("next cheapest is 1.2x slower (lbfgs, 10 it/step), 3 timing "
                            "repeats")
    # newton with one sample is not far until a second confirms it
    table[2] = row("newton", 2, 1e-4, [2.2e-3])
    assert [r.method for r in choose(table, 1e-3).pending] == ["anderson", "newton"]
    assert undecided(table, [("solver_error_p90", 1e-3, None)]) == {0, 2}
    assert choose(table, 1e-5).row is None and choose(table, 1e-5).decided


def _fake_clock(outlier):
    """A deterministic timer: each setting's cost is its iterations times a per-method
    cost, with a 2 % deterministic jitter; ``outlier`` = (solver class, iterations,
    tolerance, which call) makes that call of that setting 6 times too slow."""
    per_iteration = {"LocalGlobalSolver": 1.0, "ChebyshevSolver": 1.0,
                     "AndersonSolver": 1.5, "NewtonSolver": 25.0}
    calls = {}

    def time_once(solver, problems, clock=None):
        its = sum(solver.solve(p).iterations for p in problems) / len(problems)
        key = (type(solver).__name__, solver.iterations, solver.tolerance)
        calls[key] = calls.get(key, 0) + 1
        jitter = 1 + 0.02 * np.sin(3.0 * sum(calls.values()))
        slow = 6.0 if outlier is not None and key + (calls[key],) == outlier else 1.0
        return 1e-4 * per_iteration[key[0]] * max(its, 1) * jitter * slow

    return time_once


def _answers(text):
    rows = [line.split("|")[3].strip() for line in text.splitlines() if line.startswith("| ")
            and not line.startswith("| target")]
    short = [re.sub(r", [\d.]+ ms/step.*", "", line) for line in text.splitlines()
             if line.startswith("answer for")]
    return rows + short


# the issue's case and a later sample run in make test; the other rows' leaders (about 2 s
# of CPU each) are variants CI runs with -m slow
_LEADER = pytest.mark.slow
@pytest.mark.parametrize("outlier", [("ChebyshevSolver", 1, None, 1),       # the issue's
                                     pytest.param(("AndersonSolver", 5, None, 1),
                                                  marks=_LEADER),           # 1e-1's leader
                                     pytest.param(("ChebyshevSolver", 5000, 1e-6, 1),
                                                  marks=_LEADER),           # 1e-3's leader
                                     ("ChebyshevSolver", 5000, 1e-6, 2),    # a later sample
                                     pytest.param(("AndersonSolver", 20, None, 1),
                                                  marks=_LEADER)])          # 1e-7's leader
def test_a_six_times_slow_sample_gives_the_same_answers(tmp_path, monkeypatch, outlier):
    """The whole study, timed by a deterministic clock, answers every row the same with and
    without one 6x slow sample of a setting (the first, or a later one); the settings
    chosen are the leaders of answer rows, whose one slow sample named another setting
    when each was timed once."""
    kw = dict(methods=("local-global", "chebyshev", "anderson", "newton"), problems=3,
              repeats=1, budgets=(1, 5, 20), tolerances=(1e-6,), time_steps=False,
              plots=False)
    scene = Scene.from_dict(TINY)
    texts = []
    for i, slow in enumerate((None, outlier)):
        monkeypatch.setattr(timing, "_time_once", _fake_clock(slow))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            texts.append(run_accuracy(scene, tmp_path / str(i), **kw))
    plain, noisy = map(_answers, texts)
    assert plain == noisy and len(plain) > 4, (plain, noisy)
    assert "provisional" not in texts[0] + texts[1]
    for line in texts[1].splitlines():
        if line.startswith("| 1e-") and "no setting" not in line:
            n = int(re.search(r"(\d+) timing repeat", line).group(1))
            assert MIN_REPEATS <= n <= MAX_REPEATS


def test_trajectory_answers_are_decided_too(tmp_path, monkeypatch):
    """The trajectory-error rows are asked while timing, with the trajectory errors (they
    were left provisional when the timing read rows without them)."""
    monkeypatch.setattr(timing, "_time_once", _fake_clock(None))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        text = run_accuracy(Scene.from_dict(TINY), tmp_path, methods=("local-global",
                            "chebyshev"), problems=2, repeats=1, budgets=(1, 5),
                            tolerances=(1e-6,), plots=False)
    rows = [line for line in text.splitlines() if "| trajectory error |" in line
            and "no setting" not in line]
    assert rows and not any("provisional" in line for line in rows), text


def test_settings_closer_than_their_own_scatter_are_not_told_apart():
    """The 21 x 21 seed demo under a load of 10: lbfgs 20 it's fastest of 3 samples was 1.16x
    below chebyshev 20 it's while its own median stood 1.3x above its fastest; the next study
    had them the other way round. Not decided at 3 samples; a tie at the cap, named by
    preference (chebyshev before lbfgs), whichever was faster."""
    lbfgs, cheb = [18.7e-3, 24.3e-3, 26.0e-3], [21.6e-3, 22.0e-3, 22.1e-3]
    c = choose([row("lbfgs", 20, 0.09, lbfgs), row("chebyshev", 20, 0.09, cheb)], 0.1)
    assert not c.decided
    for fast, slow in (("lbfgs", "chebyshev"), ("chebyshev", "lbfgs")):
        table = [row(fast, 20, 0.09, [18.7e-3] + [24.3e-3] * (MAX_REPEATS - 1)),
                 row(slow, 20, 0.09, [21.6e-3, 22.0e-3] * (MAX_REPEATS // 2))]
        c = choose(table, 0.1)
        assert c.decided and c.row.method == "chebyshev" and len(c.tied) == 1
    # a steady pair 1.16x apart is still told apart after 3 samples
    c = choose([row("lbfgs", 20, 0.09, [18.7e-3] * 3), row("chebyshev", 20, 0.09, cheb)],
               0.1)
    assert c.decided and c.row.method == "lbfgs"


def test_a_setting_that_becomes_a_candidate_late_gets_its_samples(monkeypatch):
    """The undecided rounds go on until the rows are decided, not for a fixed number of
    rounds: a setting named only after the first one reached its cap is timed to the cap
    too (a 21 x 21 study left a 1e-1 row "provisional" at 10 rounds)."""
    from types import SimpleNamespace as NS

    class Quiet:
        iterations, tolerance = 1, None

        def solve(self, problem):
            return None

    monkeypatch.setattr(timing, "_time_once", lambda solver, problems, clock: 1e-3)
    results = [NS(config=NS(solver=lambda model: Quiet()), seconds=[], diverged=0)
               for _ in range(2)]
    steps = [NS(measured=True, step=NS(problem=None))]

    def undecided():   # setting 0 until it has the cap, then setting 1
        return {0} if len(results[0].seconds) < MAX_REPEATS else {1}

    timing.time_configurations(None, steps, results, repeats=1, undecided=undecided)
    assert [len(r.seconds) for r in results] == [MAX_REPEATS, MAX_REPEATS]
