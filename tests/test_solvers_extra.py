"""Chebyshev-accelerated local/global and the symplectic Euler baseline."""

import math

import numpy as np
import pytest

import clothsim as cs
from clothsim.accuracy import converged_solution, single_spring, trace_solver
from clothsim.errors import InputError
from clothsim.solvers import (
    SOLVERS,
    ChebyshevSolver,
    LocalGlobalSolver,
    StabilityWarning,
    SymplecticEulerSolver,
    estimate_spectral_radius,
    make_solver,
    stable_time_step,
)


def curtain(n=9, k=800.0, method="local-global", **kw):
    mesh = cs.grid(n, n, size=(1.0, 1.0), center=(0.0, 1.0, 0.0), plane="xy")
    springs = cs.grid_springs(mesh, structural=k, shear=k, bending=k / 10,
                              bending_pattern="every")
    model = cs.Model.build(mesh, springs, total_mass=1.0)
    return cs.Simulation(model, h=1 / 30, solver=method,
                         effects=[cs.Gravity((0.0, -9.81, 0.0)), cs.Pin([n * (n - 1), n * n - 1])],
                         **kw)


@pytest.fixture(scope="module")
def step():
    """A mid-swing step of a 9 × 9 curtain and its converged solution x*."""
    sim = curtain(k=3000.0, iterations=30)
    sim.run(8)
    problem = sim.problem()
    return sim.model, problem, converged_solution(sim.model, problem)


def test_registered():
    assert {"chebyshev", "symplectic-euler"} <= set(SOLVERS)
    assert isinstance(make_solver("chebyshev", curtain().model, rho=0.5), ChebyshevSolver)


def test_chebyshev_without_acceleration_is_local_global(step):
    """ρ = 0, γ = 1 makes every ω = 1 and x_{k+1} = x̂_{k+1}: plain local/global, bit for bit."""
    model, problem, _ = step
    a = ChebyshevSolver(model, iterations=7, rho=0.0, gamma=1.0).solve(problem)
    b = LocalGlobalSolver(model, iterations=7).solve(problem)
    np.testing.assert_allclose(a.x, b.x, rtol=0, atol=1e-14)
    # local/global's iteration reports ‖∇g‖ as the difference of consecutive right-hand
    # sides (computed on other buffers): equal to rounding, which moves this ‖∇g‖ (1e-7,
    # near its noise floor) by about 1e-9 of itself
    np.testing.assert_allclose(a.residual_history, b.residual_history, rtol=1e-8)


def test_chebyshev_converges_to_newton_in_fewer_iterations(step):
    model, problem, x_star = step
    rho = estimate_spectral_radius(model, problem, iterations=100, fit_last=30)
    assert 0.0 < rho < 1.0
    lg = trace_solver(LocalGlobalSolver(model), problem, x_star, iterations=2000)
    ch = trace_solver(ChebyshevSolver(model, rho=rho), problem, x_star, iterations=2000)
    it_lg, it_ch = lg.first_below(1e-8)[0], ch.first_below(1e-8)[0]
    # measured on this scene: 131 against 53 iterations (rho = 0.89)
    assert it_ch < 0.7 * it_lg, (it_ch, it_lg)
    res = ChebyshevSolver(model, rho=rho, iterations=2000, tolerance=1e-7).solve(problem)
    scale = np.linalg.norm(x_star - problem.x)
    assert res.converged and np.linalg.norm(res.x - x_star) / scale < 1e-6


def test_spectral_radius_matches_observed_contraction(step):
    """ρ fitted from update ratios agrees with the true error's decay rate of local/global."""
    model, problem, x_star = step
    rho = estimate_spectral_radius(model, problem, iterations=120, fit_last=40, safety=1.0)
    tr = trace_solver(LocalGlobalSolver(model), problem, x_star, iterations=120, min_error=0)
    e = tr.error[80:120]
    observed = math.exp(np.polyfit(np.arange(len(e)), np.log(e), 1)[0])
    assert abs(rho - observed) < 0.02, (rho, observed)


def test_chebyshev_solver_estimates_rho_on_first_step():
    sim = curtain(method="chebyshev", iterations=20)
    sim.step()
    assert 0.0 < sim.solver.rho < 1.0


@pytest.mark.parametrize("kw, field", [({"rho": 1.0}, "solver.rho"),
                                       ({"gamma": 0.0}, "solver.gamma"),
                                       ({"delay": -1}, "solver.delay")])
def test_chebyshev_rejects_bad_options(kw, field):
    with pytest.raises(InputError, match=field):
        ChebyshevSolver(curtain().model, **kw)


def test_symplectic_free_fall_is_exact():
    """Gravity only: v_n = n h g and x_n = x_0 + h² g n(n+1)/2 (symplectic Euler, exactly)."""
    mesh = cs.grid(3, 3, size=(1.0, 1.0), plane="xz")
    springs = cs.grid_springs(mesh, structural=100.0, shear=100.0, bending=10.0)
    model = cs.Model.build(mesh, springs, total_mass=1.0)
    h, n, g = 0.01, 25, np.array([0.0, -9.81, 0.0])
    sim = cs.Simulation(model, h=h, solver="symplectic-euler", effects=[cs.Gravity(g)])
    sim.run(n)
    np.testing.assert_allclose(sim.state.velocities, np.broadcast_to(n * h * g, (9, 3)),
                               atol=1e-12)
    np.testing.assert_allclose(sim.state.positions - mesh.vertices,
                               np.broadcast_to(h * h * g * n * (n + 1) / 2, (9, 3)), atol=1e-12)


def test_stable_time_step_two_masses():
    """Two masses m on a spring k: ω_max² = 2k/m, so h_max = 2 / sqrt(2k/m)."""
    model, _, _, _ = single_spring(stiffness=50.0, mass=2.0)
    assert stable_time_step(model) == pytest.approx(2.0 / math.sqrt(2 * 50.0 / 2.0), rel=1e-9)
    anchored = stable_time_step(model, anchor_vertices=[0], anchor_stiffness=[1e4])
    assert anchored < stable_time_step(model)


def test_symplectic_spring_keeps_amplitude_and_pins():
    """A pinned single spring oscillates without decay (implicit Euler would lose
    (1 + ω²h²)^(-50) ≈ 0.61 of its amplitude in these 100 steps)."""
    model, pin, state, omega = single_spring(stiffness=100.0, mass=1.0, amplitude=0.1)
    sim = cs.Simulation(model, h=0.01, solver="symplectic-euler", effects=[pin], state=state)
    ys = []
    for _ in range(100):
        sim.step()
        ys.append(sim.state.positions[1, 1] + 1.0)
    assert np.all(sim.state.positions[0] == 0.0)
    assert max(abs(y) for y in ys[-20:]) == pytest.approx(0.1, rel=0.05)


def test_symplectic_anchor_force():
    """One step with a penalty anchor: x1 = y + h² (f − k (x − q)) / m."""
    model, _, state, _ = single_spring(stiffness=10.0, mass=1.0, amplitude=0.0)
    sim = cs.Simulation(model, h=0.01, solver="symplectic-euler", state=state,
                        effects=[cs.Pin([0], method="penalty", stiffness=1e3,
                                        velocity=[1.0, 0.0, 0.0])])
    sim.step()
    # anchor target moved to (0.01, 0, 0): force k * 0.01 along x on vertex 0 (m = 1)
    assert sim.state.positions[0, 0] == pytest.approx(1e-4 * 1e3 * 0.01, rel=1e-12)


def test_symplectic_warns_above_stability_limit():
    model, pin, state, omega = single_spring(stiffness=100.0, mass=1.0)
    limit = stable_time_step(model)
    with pytest.warns(StabilityWarning, match="stability limit"):
        SymplecticEulerSolver(model).solve(
            cs.Simulation(model, h=1.1 * limit, solver="symplectic-euler",
                          check_stability=False, effects=[pin], state=state).problem())
    # below the limit: no warning (the test config turns warnings into errors); a new pin,
    # since an effect belongs to one simulation
    pin = single_spring(stiffness=100.0, mass=1.0)[1]
    SymplecticEulerSolver(model).solve(
        cs.Simulation(model, h=0.9 * limit, solver="symplectic-euler", effects=[pin],
                      state=state).problem())
