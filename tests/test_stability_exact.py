"""Closed forms and invariances the time stepping must reproduce: free fall,
full pinning, pin release, rotation/translation invariance, the 1-D oscillator recurrence,
and first-order convergence in h.

The ``measure_*`` helpers return the measured figures (see benchmarks/stability_figures.py).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

import clothsim as cs
from benchmarks.measure_stability import (
    base_positions,
    measure_convergence_order,
    measure_free_fall,
    measure_oscillator,
    measure_release_vs_refactor,
    run_scene,
)
from clothsim.factorization import cholmod_available
from clothsim.gallery import GRAVITY
from clothsim.gallery import grid_cloth as make_grid_model

BACKENDS = ["splu", pytest.param("cholmod", marks=pytest.mark.skipif(
    not cholmod_available(), reason="scikit-sparse (CHOLMOD) not installed"))]


@pytest.mark.parametrize("solver", ["local-global", "newton"])
def test_unpinned_cloth_free_falls_exactly(solver):
    # after 60 steps the cloth has fallen 20.0 m
    assert measure_free_fall(solver) <= 1e-8


@pytest.mark.parametrize("backend", BACKENDS)
def test_fully_pinned_cloth_stays_bitwise_still(backend):
    model = make_grid_model(4)
    sim = cs.Simulation(model, h=1 / 30, effects=[cs.Gravity(GRAVITY), cs.Pin(np.arange(16))],
                        backend=backend)
    sim.run(5)
    assert np.array_equal(sim.state.positions, model.mesh.vertices)
    assert not np.any(sim.state.velocities)


def test_pin_release_matches_refactor_from_state():
    assert measure_release_vs_refactor() <= 1e-10


unit = st.floats(-1.0, 1.0)


@settings(max_examples=10, deadline=None)
@given(rotvec=st.tuples(unit, unit, unit), angle=st.floats(0.0, np.pi))
def test_rotating_the_scene_rotates_the_result(rotvec, angle):
    axis = np.array(rotvec)
    if np.linalg.norm(axis) < 1e-3:
        axis = np.array([0.0, 0.0, 1.0])
    R = Rotation.from_rotvec(angle * axis / np.linalg.norm(axis)).as_matrix()
    assert np.abs(run_scene(R) - base_positions() @ R.T).max() <= 1e-12


@settings(max_examples=10, deadline=None)
@given(direction=st.tuples(unit, unit, unit), log_size=st.floats(-3.0, 3.0))
def test_translating_the_scene_translates_the_result(direction, log_size):
    t = np.array(direction)
    t = t / np.linalg.norm(t) * 10.0 ** log_size if np.linalg.norm(t) > 1e-3 else np.zeros(3)
    size = max(1.0, float(np.linalg.norm(t)))
    assert np.abs(run_scene(t=t) - (base_positions() + t)).max() <= 2e-11 * size


def test_translation_invariance_newton_far_from_origin():
    t = np.array([600.0, -700.0, 400.0])
    err = np.abs(run_scene(t=t, steps=4, solver="newton")
                 - (run_scene(steps=4, solver="newton") + t)).max()
    assert err <= 2e-11 * np.linalg.norm(t)


def test_one_spring_follows_implicit_euler_recurrence():
    assert measure_oscillator() <= 1e-10


def test_trajectory_error_is_first_order_in_h():
    out = measure_convergence_order()
    assert 0.9 <= out["slope"] <= 1.1, out
