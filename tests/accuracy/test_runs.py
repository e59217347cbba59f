"""One run per method and step gives every configuration's answer (clothsim.accuracy.runs):
the same, bit for bit, as a ``solve`` per configuration, on held contact steps and free
ones."""

import math
import warnings

import numpy as np
import pytest

from clothsim.accuracy import prepare_steps, record_problems, scene_factory
from clothsim.accuracy.limits import limit_stop
from clothsim.accuracy.runs import Stop, method_runs, stops
from clothsim.accuracy.study import chebyshev_rho, default_configurations

from .test_robust import small_drop_on_square
from .test_study import buckling_strip

METHODS = ("local-global", "chebyshev", "anderson", "lbfgs", "newton")


@pytest.fixture(scope="module")
def contact_steps():
    """The seed's demo at 6 × 6, 14 frames: it lands on the box; steps with held contacts."""
    scene = small_drop_on_square(6, 14)
    factory, model, _ = scene_factory(scene)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        recorded = record_problems(factory("newton", scene.h, 100, 1e-10), steps=14, count=4)
        steps = prepare_steps(model, recorded)
    assert any(s.measured and s.step.problem.has_contacts for s in steps)
    return model, steps


def _check_runs_equal_solves(model, steps, configs, extra=()):
    runs = method_runs(model, steps, {k: v + [s for s in extra if k[0] != "newton"]
                                      for k, v in stops(configs).items()})
    checked = 0
    for s in steps:
        if not s.measured:
            continue
        for c in configs:
            run = runs[(s.step.index, c.method, c.options, c.stop)]
            with warnings.catch_warnings(), np.errstate(all="ignore"):
                warnings.simplefilter("ignore")
                res = c.solver(model).solve(s.step.problem)
            assert run.iterations == res.iterations, (c.label, s.step.index)
            assert np.array_equal(run.x, res.x), (c.label, s.step.index)
            assert run.residual == res.residual or (
                math.isnan(run.residual) and math.isnan(res.residual))
            if c.tolerance is not None:
                assert run.converged == bool(res.converged), c.label
            checked += 1
    assert checked
    return runs


def test_runs_give_each_configuration_its_own_solve_on_held_contact_steps(contact_steps):
    model, steps = contact_steps
    rho = chebyshev_rho(model, steps)
    configs = default_configurations(METHODS, budgets=(1, 3, 40), tolerances=(1e-3, 1e-7),
                                     options={"chebyshev": {"rho": rho}}, cap=300)
    runs = _check_runs_equal_solves(model, steps, configs, extra=(limit_stop(300),))
    # the limit stop rode along: it stops no earlier than the tolerance 1e-7 setting
    s = next(s for s in steps if s.measured)
    for c in configs:
        if c.method != "newton" and c.tolerance == 1e-7:
            lim = runs[(s.step.index, c.method, c.options, limit_stop(300))]
            assert lim.iterations >= runs[(s.step.index, c.method, c.options, c.stop)].iterations


def test_runs_give_each_configuration_its_own_solve_on_a_buckling_step():
    """Without contact, where Anderson and L-BFGS may stop early (no descent left)."""
    sim = buckling_strip()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        steps = prepare_steps(sim.model, record_problems(sim, steps=1, count=1))
    configs = default_configurations(METHODS, budgets=(2, 25), tolerances=(1e-4, 1e-12),
                                     cap=400)
    _check_runs_equal_solves(sim.model, steps, configs)


def test_a_run_that_blows_up_marks_only_the_stops_it_did_not_reach(contact_steps, monkeypatch):
    """A method that raises at its 4th iterate: the stops at 1 and 3 iterations have their
    iterates, the later ones are diverged (x None), as a solve per configuration would be."""
    import clothsim.accuracy.runs as runs_module

    model, steps = contact_steps
    s = next(s for s in steps if s.measured)
    real = runs_module.make_solver

    def breaking(method, model, **kw):
        solver = real(method, model, **kw)
        iterates = solver.iterates

        def failing(problem, x0=None):
            for it in iterates(problem, x0):
                if it.k == 4:
                    raise FloatingPointError("blew up")
                yield it
        solver.iterates = failing
        return solver

    monkeypatch.setattr(runs_module, "make_solver", breaking)
    wanted = [Stop(1), Stop(3), Stop(10), Stop(100, 1e-9)]
    runs = method_runs(model, [s], {("local-global", ()): wanted})
    got = [runs[(s.step.index, "local-global", (), w)] for w in wanted]
    assert [g.iterations for g in got[:2]] == [1, 3]
    assert all(g.x is not None and np.all(np.isfinite(g.x)) for g in got[:2])
    assert all(g.x is None for g in got[2:])


def test_the_references_local_global_run_gives_the_local_global_settings(contact_steps):
    """The reference's local/global run (its own limit, capped) keeps the study's
    local/global settings: the same iterates as a solve per setting."""
    model, steps = contact_steps
    configs = default_configurations(("local-global",), budgets=(1, 7), tolerances=(1e-2,),
                                     cap=200)
    wanted = stops(configs)[("local-global", ())]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        again = prepare_steps(model, [s.step for s in steps], cap=200,
                              local_global_stops=wanted)
    for s in again:
        if not s.measured:
            continue
        ref = s.reference
        assert ref.local_global_runs[Stop(200, 1e-6)].iterations <= 200
        for c in configs:
            run = ref.local_global_runs[c.stop]
            res = c.solver(model).solve(s.step.problem)
            assert run.iterations == res.iterations and np.array_equal(run.x, res.x)


def test_the_extrapolation_reads_the_references_run_as_its_own_run(contact_steps):
    """Tail iterates kept by the references' local/global runs give the same tails as
    running local/global again."""
    from clothsim.accuracy.extrapolate import tail_runs, tail_stops

    model, steps = contact_steps
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        kept = prepare_steps(model, [s.step for s in steps], cap=120,
                             local_global_stops=tail_stops(120))
    fresh = [s for s in kept if s.measured]
    for measure in ("solver error", "objective gap"):
        read = tail_runs(model, kept, iterations=120, measure=measure)
        for s in fresh:
            s.reference.local_global_runs = {}
        again = tail_runs(model, kept, iterations=120, measure=measure)
        assert read and read == again
        kept = prepare_steps(model, [s.step for s in steps], cap=120,
                             local_global_stops=tail_stops(120))
        fresh = [s for s in kept if s.measured]
