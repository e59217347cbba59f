"""Converged runs in less time: warm-started Newton, and the h/4 run reused as the coarse
reference of the time-step study."""

import math
import warnings

import numpy as np
import pytest

from clothsim.accuracy import prepare_steps, record_problems
from clothsim.accuracy.converged import WarmNewtonSolver, warm_started
from clothsim.solvers import NewtonSolver

from ..test_held_contacts import held_problem
from .test_study import box_factory, buckling_strip, stiff_settling


def test_warm_newton_reaches_newtons_minimum_on_a_convex_step():
    sim = stiff_settling()
    problem = sim.problem()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        plain = NewtonSolver(sim.model, iterations=100, tolerance=1e-10).solve(problem)
        warm = WarmNewtonSolver(sim.model, iterations=100, tolerance=1e-10).solve(problem)
    scale = np.linalg.norm(plain.x - problem.x)
    assert np.linalg.norm(warm.x - plain.x) / scale < 1e-8
    assert warm.converged and warm.residual <= 1e-10
    assert warm.residual_history[0] == pytest.approx(1.0) and len(warm.residual_history) > 3


def test_warm_newton_ends_at_a_certified_minimum_on_a_buckling_step():
    sim = buckling_strip()
    problem = sim.problem()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        warm = WarmNewtonSolver(sim.model, iterations=100, tolerance=1e-15).solve(problem)
        steps = prepare_steps(sim.model, [*record_problems(sim, steps=1, count=1)])
    assert warm.certified and warm.at_floor and warm.positive_definite
    # it is one of the step's certified minima, or a new one: g is never above x_best's
    # basin's by more than rounding
    ref = steps[0].reference
    assert ref.objective_gap(sim.model, problem, warm.x) < 1e-3


def test_warm_started_swaps_only_a_plain_converged_newton():
    factory = box_factory()
    assert type(warm_started(factory("newton", 1 / 30, 100, 1e-10)).solver) is \
        WarmNewtonSolver
    assert type(warm_started(factory("newton", 1 / 30, 5, None)).solver) is NewtonSolver
    sim = warm_started(factory("local-global", 1 / 30, 5, None))
    assert sim.solver.name == "local-global"


def test_the_time_step_study_reuses_the_coarse_reference_run_at_h_over_4():
    from clothsim.accuracy.timestep import time_step_study

    calls = []
    base = box_factory()

    def factory(method, h, iterations, tolerance):
        calls.append(h)
        return base(method, h, iterations, tolerance)

    h = 1 / 30
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ts = time_step_study(factory, frame_time=h, frames=4, time_steps=(h, h / 2, h / 4),
                             reference_h=h / 8)
    runs = list(calls)
    # h/8 and h/4 (the reference pair), then h and h/2 only, then one sim for ω_max
    assert sorted(runs[:2]) == [h / 8, h / 4] and sorted(runs[2:4]) == [h / 2, h]
    assert len(runs) == 5
    assert len(ts.errors) == 3 and all(math.isfinite(e) and e > 0 for e in ts.errors)


def test_a_warm_started_run_factors_its_lbfgs_matrix_once():
    sim = warm_started(box_factory()("newton", 1 / 30, 100, 1e-10))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sim.run(1)
        lbfgs, factor = sim.solver._lbfgs, sim.solver._lbfgs._cache
        sim.run(3)
    assert sim.solver._lbfgs is lbfgs and lbfgs._cache is factor is not None
    assert lbfgs.analysis_count == 1


def test_warm_newton_is_plain_newton_on_a_held_step():
    """With held contacts the warm start is skipped: Newton's own iterates, bit for bit."""
    model, p, held, normal = held_problem(4)
    warm = WarmNewtonSolver(model, iterations=50, tolerance=1e-10).solve(p)
    plain = NewtonSolver(model, iterations=50, tolerance=1e-10).solve(p)
    assert warm.converged and warm.iterations == plain.iterations
    np.testing.assert_array_equal(warm.x, plain.x)
    np.testing.assert_allclose(warm.x[held] @ normal, p.contact_offsets, atol=1e-14)
