"""Anderson and L-BFGS: g never increases beyond rounding; the exact energy difference."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from clothsim import gallery
from clothsim.errors import InputError
from clothsim.solvers import AndersonSolver, LBFGSSolver, objective
from clothsim.solvers.descent import objective_difference

from .cases import convex_step


def test_objective_difference_matches_two_evaluations():
    model, problem = convex_step(5)
    rng = np.random.default_rng(3)
    x = problem.initial_guess()
    dx = 1e-2 * rng.standard_normal(x.shape)
    dx[problem.fixed_vertices] = 0
    exact = objective(model, problem, x + dx) - objective(model, problem, x)
    assert objective_difference(model, problem, x, dx) == pytest.approx(exact, rel=1e-9)


def test_objective_difference_resolves_tiny_steps():
    """At δ = 1e-10 m two evaluations of g see only rounding; the difference is still
    first-order exact: (g(x+δ) − g(x)) / ‖δ‖ matches ∇g·δ/‖δ‖."""
    from clothsim.solvers import objective_gradient

    model, problem = convex_step(5)
    x = problem.initial_guess()
    u = np.zeros_like(x)
    u[5] = [1.0, 0.5, -0.25]
    t = 1e-10
    slope = float(np.sum(objective_gradient(model, problem, x) * u))
    assert objective_difference(model, problem, x, t * u) / t == pytest.approx(slope, rel=1e-5)


@settings(max_examples=12, deadline=None)
@given(seed=st.integers(0, 2 ** 16), method=st.sampled_from(["anderson", "lbfgs"]),
       window=st.integers(1, 10), k=st.sampled_from([50.0, 800.0, 2e4]),
       kick=st.floats(0.0, 2.0))
def test_g_never_increases(seed, method, window, k, kick):
    """On random cloths with random velocities, g(x_{k+1}) − g(x_k) ≤ rounding."""
    from clothsim.simulation import State

    model = gallery.grid_cloth(4, k=k, plane="xz")
    v = kick * np.random.default_rng(seed).standard_normal((16, 3))
    from clothsim import Gravity, Pin, Simulation

    sim = Simulation(model, h=1 / 30, effects=[Gravity(gallery.GRAVITY), Pin([0, 3])],
                     state=State(model.mesh.vertices.copy(), v))
    problem = sim.problem()
    cls = AndersonSolver if method == "anderson" else LBFGSSolver
    x_prev = None
    scale = abs(objective(model, problem, problem.initial_guess())) + 1e-30
    for it in cls(model, window=window).iterates(problem):
        if x_prev is not None:
            assert objective_difference(model, problem, x_prev, it.x - x_prev) <= 1e-13 * scale
        x_prev = it.x.copy()
        if it.k >= 40:
            break


@pytest.mark.parametrize("cls", [AndersonSolver, LBFGSSolver])
def test_window_is_checked(cls):
    with pytest.raises(InputError, match="solver.window"):
        cls(gallery.grid_cloth(3), window=0)
