"""The accelerated solvers on local/global's fused iteration (clothsim.solvers.fused).

Their ‖∇g‖ is not computed from its definition but carried: a = A_FF δ as the same
combination of right-hand sides as δ is of global steps (Chebyshev, Anderson), or through
the pairs' A_FF s (L-BFGS). These tests recompute ∇g from its definition at every iterate,
on cases the fused kernel was not tuned on: penalty pins, a start at x_n, gravity with
exact pins, a cloth far from the origin.
"""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest

import clothsim as cs
from clothsim.solvers import gradient_noise_floor, make_solver
from clothsim.solvers.descent import objective_difference
from clothsim.solvers.fused import FusedStep

from .cases import buckling_step

METHODS = ["local-global", "chebyshev", "anderson", "lbfgs"]


def penalty_step(offset=(0.0, 0.0, 0.0)):
    """A 7 × 7 curtain held by two penalty pins, mid-swing, optionally far from the origin."""
    mesh = cs.grid(7, 7, size=(1.0, 1.0), center=np.add((0.0, 1.0, 0.0), offset), plane="xy")
    springs = cs.grid_springs(mesh, structural=900.0, shear=900.0, bending=90.0,
                              bending_pattern="every")
    model = cs.Model.build(mesh, springs, total_mass=1.0)
    sim = cs.Simulation(model, h=1 / 30, iterations=30,
                        effects=[cs.Gravity((0.0, -9.81, 0.0)),
                                 cs.Pin([42, 48], method="penalty", stiffness=2e4)])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sim.run(5)
    return model, sim.problem()


def cases():
    model, problem = buckling_step(7, frames=10)
    yield "exact pins", model, problem
    yield "x_n start", model, dataclasses.replace(problem, start="x_n")
    yield "penalty pins", *penalty_step()
    yield "far away", *penalty_step((300.0, -40.0, 120.0))


@pytest.mark.parametrize("method", METHODS)
def test_carried_gradient_is_the_gradient(method):
    for label, model, problem in cases():
        opts = {"rho": 0.95} if method == "chebyshev" else {}
        solver = make_solver(method, model, **opts)
        lg = make_solver("local-global", model)
        floor = None
        for it in solver.iterates(problem):
            x = it.x.copy()
            direct = float(np.linalg.norm(lg.gradient(problem, x, lg.local_step(x))))
            # both are exact to their rounding floors (objective.gradient_noise_floor)
            floor = floor or 10 * gradient_noise_floor(model, problem, x)
            assert it.gradient_norm == pytest.approx(direct, rel=1e-6, abs=floor), \
                (label, it.k)
            if it.k >= 40:
                break


def test_trial_is_the_objective_difference():
    """FusedStep.trial equals objective_difference at steps from 1e-2 down to 1e-9 of δ,
    penalty pins and far from the origin included."""
    rng = np.random.default_rng(3)
    for offset in [(0.0, 0.0, 0.0), (300.0, -40.0, 120.0)]:
        model, problem = penalty_step(offset)
        solver = make_solver("anderson", model)
        step = FusedStep(solver, problem, energy=True)
        step.advance(step.solve())
        x = step.x.copy()
        for scale in (1e-2, 1e-5, 1e-9):
            cand = step.delta + scale * rng.normal(size=step.delta.shape)
            fused = step.trial(cand)
            x_new = x.copy()
            x_new[step.free] = problem.y[step.free] + cand.T
            ref = objective_difference(model, problem, x, x_new - x)
            assert fused == pytest.approx(ref, rel=1e-6, abs=1e-22), (offset, scale)


@pytest.mark.parametrize("given", [False, True])
def test_accept_is_advance(given):
    """Moving by trial + accept (spring vectors p' = p + Δp from the trial) gives the same
    iterate and directions as advance (gathered afresh), bit for bit, and the same
    right-hand side to rounding (bit for bit where accept re-syncs p from the positions):
    with two exact pins at one point (their spring's ends coincide at every iterate, its
    direction is carried), a spring whose ends coincide in y, gravity and a penalty pin."""
    from clothsim.gallery import grid_cloth
    from clothsim.solvers.base import StepProblem
    from clothsim.solvers.fused import RESYNC

    model = grid_cloth(6, k=400.0, plane="xy", total_mass=0.5)
    rng = np.random.default_rng(7)
    x = model.mesh.vertices + rng.normal(scale=0.02, size=model.mesh.vertices.shape)
    v = rng.normal(scale=0.3, size=x.shape)
    a, b = model.springs.spring_vertices[0]
    v[b], x[b] = v[a], x[a]                     # ends coincide in y = x + h v
    problem = StepProblem(1 / 30, x, v, f_ext=model.vertex_mass[:, None] * [0.0, -9.81, 0.0],
                          fixed_vertices=[30, 31, 35],
                          fixed_positions=model.mesh.vertices[[30, 30, 35]],
                          anchor_vertices=[0], anchor_positions=x[[0]] + 0.01,
                          anchor_stiffness=[50.0])
    x0 = problem.initial_guess()
    if given:   # pins away from their targets at x_0
        x0 = x0 + rng.normal(scale=0.01, size=x0.shape)
    solver, other = make_solver("anderson", model), make_solver("anderson", model)
    fused = FusedStep(solver, problem, x0 if given else None, energy=True)
    plain = FusedStep(other, problem, x0 if given else None, energy=True)
    floor = gradient_noise_floor(model, problem, problem.y)
    for k in range(RESYNC + 4):
        cand = fused.solve() + (0.0 if k % 2 else 1e-3 * rng.normal(size=fused.delta.shape))
        fused.trial(cand)
        fused.accept()
        plain.advance(cand.copy())
        np.testing.assert_array_equal(fused.x, plain.x)
        np.testing.assert_array_equal(fused.current_directions()(),
                                      plain.current_directions()())
        if k % RESYNC == 0:     # re-synced: the same spring vectors
            np.testing.assert_array_equal(fused.rhs, plain.rhs)
        assert np.linalg.norm(fused.rhs - plain.rhs) <= floor, k


def test_start_gradient_is_the_definition():
    """x_0's gradient as one product A_FF δ_F − rhs(x_0) (a start at x_n) equals the
    definition's, on every start: y, x_n with exact pins, penalty pins, far away."""
    for label, model, problem in [*cases(), ("far away, x_n", *_far_x_n())]:
        solver = make_solver("local-global", model)
        step = FusedStep(solver, problem)
        x = problem.initial_guess()
        g = solver.gradient(problem, x, solver.local_step(x))
        assert np.allclose(step.a0 - step.rhs, g.T, rtol=0, atol=1e-12 * np.abs(g).max()), label
        assert step.norm0 == pytest.approx(float(np.linalg.norm(g)), rel=1e-12), label


def _far_x_n():
    model, problem = penalty_step((300.0, -40.0, 120.0))
    return model, dataclasses.replace(problem, start="x_n")
