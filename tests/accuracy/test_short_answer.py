"""accuracy opens with the answer to the student's question: the cheapest setting for 1e-3."""

from types import SimpleNamespace

from clothsim.accuracy.answer import short_answer


def row(method, setting, err, ms, unique=3, repeats=5, iterations=10):
    return SimpleNamespace(method=method, setting=setting, solver_error_p90=err,
                           objective_gap_p90=err, seconds_per_step_median=ms / 1e3,
                           seconds_per_step_min=ms / 1e3, repeats=repeats, status="ok",
                           steps_unique=unique, iterations=iterations, tolerance=None)


def test_cheapest_setting_and_its_speedup_over_local_global():
    table = [row("local-global", "local-global, 200 it/step", 5e-4, 40.0, iterations=200),
             row("local-global", "local-global, 10 it/step", 2e-1, 2.0),
             row("chebyshev", "chebyshev, 40 it/step", 8e-4, 10.0, iterations=40)]
    (line,) = short_answer(table)
    assert line.startswith("answer for 1e-03 (solver error): chebyshev, 40 it/step, 10 ms/step "
                           "(next cheapest is 4x slower (local-global, 200 it/step), 5 timing "
                           "repeats); 4x faster than local/global"), line
    assert "4x faster than local/global (local-global, 200 it/step, 40 ms/step" in line


def test_no_setting_and_the_gap_when_no_step_is_unique():
    table = [row("local-global", "local-global, 10 it/step", 5e-2, 2.0, unique=0)]
    assert short_answer(table, (1e-3, 1e-1)) == [
        "answer for 1e-03 (objective gap): no setting measured reaches it",
        "answer for 1e-01 (objective gap): local-global, 10 it/step, 2 ms/step (the only "
        "setting that reaches it, 5 timing repeats); local/global itself is the cheapest"]
