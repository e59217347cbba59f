"""Symplectic Euler through the shared iteration: one explicit "iteration" per step."""

import numpy as np

import clothsim as cs
from clothsim.gallery import hanging_cloth
from clothsim.solvers import SymplecticEulerSolver


def test_symplectic_step_is_one_iterate_and_not_checked():
    model, effects = hanging_cloth(4, k=50.0)
    sim = cs.Simulation(model, h=1e-3, effects=effects, solver="symplectic-euler")
    problem = sim.problem()
    solver = SymplecticEulerSolver(model)
    its = list(solver.iterates(problem))
    assert [it.k for it in its] == [0, 1]
    res = solver.solve(problem)
    assert res.iterations == 1 and res.converged is None and res.residual == 0.0
    # closed form: x = y + h² M⁻¹ (f − ∇E(x_n)), pins at their targets
    expected = problem.y + problem.h ** 2 * solver.force(problem, problem.x) \
        / model.vertex_mass[:, None]
    expected[problem.fixed_vertices] = problem.fixed_positions
    np.testing.assert_array_equal(res.x, expected)
    assert solver.get_state() == {}
