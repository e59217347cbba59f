"""--jobs changes where the study's work runs, never its results (clothsim.accuracy.parallel)."""

import warnings

import numpy as np

from clothsim.accuracy import prepare_steps, record_problems, scene_factory
from clothsim.accuracy.limits import method_limits
from clothsim.accuracy.parallel import map_jobs

from .test_robust import small_drop_on_square


def _pair(a, b):
    return a, b


def test_map_jobs_keeps_the_order_and_calls_back_for_each_result():
    seen = []
    items = [(i, -i) for i in range(7)]
    for jobs in (1, 2):
        seen.clear()
        assert map_jobs(_pair, items, jobs=jobs, each=seen.append) == items
        assert sorted(seen) == sorted(items)
    assert map_jobs(_pair, [], jobs=2) == []


def test_references_and_own_limits_of_a_contact_scene_do_not_depend_on_jobs():
    """The seed's demo at 5 × 5 (landing on the box, crumpling): the steps' classes,
    references, minima and every method's own limit are the same from 2 workers."""
    scene = small_drop_on_square(5, 16)
    factory, model, _ = scene_factory(scene)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        recorded = record_problems(factory("newton", scene.h, 100, 1e-10), steps=16, count=3)
        runs = []
        for jobs in (1, 2):
            steps = prepare_steps(model, recorded, jobs=jobs)
            method_limits(model, steps, ("local-global", "anderson", "lbfgs", "newton"),
                          cap=400, jobs=jobs)
            runs.append(steps)
    one, two = runs
    assert any(s.measured for s in one)
    for s, t in zip(one, two, strict=True):
        assert (s.kind, s.step.index) == (t.kind, t.step.index)
        assert np.array_equal(s.rho, t.rho, equal_nan=True)
        if s.reference is None:
            assert t.reference is None
            continue
        assert np.array_equal(s.reference.x, t.reference.x)
        assert np.array_equal(s.reference.x_best, t.reference.x_best)
        assert s.reference.minima == t.reference.minima
        assert set(s.limits) == set(t.limits)
        for m, lim in s.limits.items():
            other = t.limits[m]
            assert (lim.converged, lim.certified) == (other.converged, other.certified)
            assert lim.x is None and other.x is None or np.array_equal(lim.x, other.x)
            assert np.array_equal(lim.gap, other.gap, equal_nan=True)


def test_the_time_step_study_does_not_depend_on_jobs():
    """Its converged runs (the reference's at h/8 and h/4, and h, h/2) in 2 workers give the
    serial study's errors, slope, contact window and reference, bit for bit."""
    from clothsim.accuracy.timestep import time_step_study

    scene = small_drop_on_square(5, 8)
    factory, _, frame_time = scene_factory(scene)
    h = scene.h
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        one, two = (time_step_study(factory, frame_time=frame_time, frames=8,
                                    time_steps=(h, h / 2, h / 4), reference_h=h / 8, jobs=j)
                    for j in (1, 2))
    assert one.time_steps == two.time_steps and one.window == two.window
    assert np.array_equal(one.errors, two.errors, equal_nan=True)
    assert np.array_equal(one.reference, two.reference)
    assert np.array_equal(one.contact, two.contact)
