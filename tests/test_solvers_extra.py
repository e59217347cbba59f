"""The symplectic Euler baseline (Chebyshev tests live in tests/solvers/test_chebyshev.py)."""

import math

import numpy as np
import pytest

import clothsim as cs
from clothsim.accuracy import single_spring
from clothsim.solvers import (
    StabilityWarning,
    SymplecticEulerSolver,
    stable_time_step,
)


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
    # below the limit: no warning (the test config turns warnings into errors)
    pin = cs.Pin(pin.vertices)  # an effect belongs to one simulation
    SymplecticEulerSolver(model).solve(
        cs.Simulation(model, h=0.9 * limit, solver="symplectic-euler", effects=[pin],
                      state=state).problem())
