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
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

import clothsim as cs
from clothsim import energy
from clothsim.factorization import cholmod_available
from clothsim.gallery import GRAVITY
from clothsim.gallery import grid_cloth as make_grid_model

BACKENDS = ["splu", pytest.param("cholmod", marks=pytest.mark.skipif(
    not cholmod_available(), reason="scikit-sparse (CHOLMOD) not installed"))]


# -- case 6: free fall, full pinning, pin release --------------------------------------------
def measure_free_fall(solver: str = "local-global", steps: int = 60, h: float = 1 / 30) -> float:
    """Max |x_n − (x_0 + h² g n(n+1)/2)| [m] over all steps of an unpinned, stress-free cloth.

    Implicit Euler with forces m g only: v_{n+1} = v_n + h g, x_{n+1} = x_n + h v_{n+1}; with
    v_0 = 0, v_n = n h g and x_n = x_0 + h² g (1 + 2 + … + n) = x_0 + h² g n(n+1)/2. The
    springs stay at rest length (a translation), so they add nothing.
    """
    model = make_grid_model(5)
    sim = cs.Simulation(model, h=h, effects=[cs.Gravity(GRAVITY)], solver=solver)
    x0 = model.mesh.vertices
    worst = 0.0
    for n in range(1, steps + 1):
        sim.step()
        expected = x0 + h * h * GRAVITY * n * (n + 1) / 2
        worst = max(worst, float(np.abs(sim.state.positions - expected).max()))
    return worst


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


def measure_release_vs_refactor(steps_pinned: int = 6, steps_after: int = 12) -> float:
    """Max |Δx| [m] between a Pin(release=t_r) run and a pinned run restarted without the pin
    (a fresh solver and factor) at t_r, 12 steps after the release."""
    h = 1 / 30
    t_r = steps_pinned * h
    model = make_grid_model(5, plane="xy")
    a = cs.Simulation(model, h=h, effects=[cs.Gravity(GRAVITY), cs.Pin([20, 24], release=t_r)])
    a.run(steps_pinned + steps_after)
    b = cs.Simulation(model, h=h, effects=[cs.Gravity(GRAVITY), cs.Pin([20, 24])])
    b.run(steps_pinned)
    c = cs.Simulation(model, h=h, effects=[cs.Gravity(GRAVITY)], state=b.state.copy())
    c.run(steps_after)
    assert a.solver.factor_count == 2 and c.solver.factor_count == 1
    assert abs(a.state.time - c.state.time) < 1e-12
    return float(np.abs(a.state.positions - c.state.positions).max())


def test_pin_release_matches_refactor_from_state():
    assert measure_release_vs_refactor() <= 1e-10


# -- case 10: rotation and translation invariance ------------------------------------------
def run_scene(R=np.eye(3), t=np.zeros(3), steps: int = 10, solver: str = "local-global"):
    """A 5 × 5 cloth pinned at two corners falling for ``steps`` steps, moved rigidly
    (x → R x + t, gravity → R g)."""
    base = cs.grid(5, 5, size=(1.0, 1.0), plane="xz")
    mesh = cs.Mesh(base.vertices @ R.T + t, base.triangles, grid_shape=base.grid_shape)
    springs = cs.grid_springs(mesh, structural=800.0, shear=800.0, bending=80.0)
    model = cs.Model.build(mesh, springs, total_mass=1.0)
    sim = cs.Simulation(model, h=1 / 30, effects=[cs.Gravity(R @ GRAVITY), cs.Pin([0, 4])],
                        solver=solver)
    sim.run(steps)
    return sim.state.positions


_BASE: dict = {}


def base_positions(solver="local-global"):
    if solver not in _BASE:
        _BASE[solver] = run_scene(solver=solver)
    return _BASE[solver]


def measure_invariance(samples: int = 10, seed: int = 0) -> dict:
    """Worst rotation error [m] and worst translation error / max(1, |t|) over random
    rotations and translations with |t| up to 1e3 m."""
    rng = np.random.default_rng(seed)
    x = base_positions()
    rot, tra = 0.0, 0.0
    for _ in range(samples):
        R = Rotation.random(random_state=rng).as_matrix()
        rot = max(rot, float(np.abs(run_scene(R) - x @ R.T).max()))
        t = rng.standard_normal(3)
        t *= 10.0 ** rng.uniform(-1, 3) / np.linalg.norm(t)
        tra = max(tra, float(np.abs(run_scene(t=t) - (x + t)).max()) / max(1.0, np.linalg.norm(t)))
    return {"rotation": rot, "translation_per_metre": tra}


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


# -- case 11: analytic oscillator ------------------------------------------------------------
def measure_oscillator(steps: int = 200, *, m=1.0, k=100.0, r=1.0, amplitude=0.5,
                       h=0.05) -> float:
    """Max |x_n − x_n^recurrence| [m] of a pinned 1-D spring over ``steps`` steps.

    Vertex 0 is pinned at a = 0, vertex 1 (mass m) starts at rest at a + r + amplitude on
    the x axis; no gravity. While the spring does not flip (0 < x − a), its energy
    ½ k (x − a − r)² is quadratic in x, so implicit Euler,
    m (x_{n+1} − 2 x_n + x_{n−1}) = −h² k (x_{n+1} − a − r), is the linear recurrence
    (m + h² k) x_{n+1} = m (2 x_n − x_{n−1}) + h² k (a + r), with x_{−1} = x_0 (v_0 = 0).
    """
    a = 0.0
    mesh = cs.Mesh(np.array([[a, 0.0, 0.0], [a + r, 0.0, 0.0]]), strands=[[0, 1]])
    model = cs.Model.build(mesh, cs.mesh_springs(mesh, structural=k), vertex_mass=[m, m])
    x0 = mesh.vertices.copy()
    x0[1, 0] += amplitude
    sim = cs.Simulation(model, h=h, effects=[cs.Pin([0])], state=cs.State(x0, np.zeros((2, 3))))
    prev, cur = x0[1, 0], x0[1, 0]
    worst = 0.0
    for _ in range(steps):
        sim.step()
        prev, cur = cur, (m * (2 * cur - prev) + h * h * k * (a + r)) / (m + h * h * k)
        assert cur - a > 0  # the spring never flips, so the recurrence stays exact
        p = sim.state.positions
        worst = max(worst, abs(p[1, 0] - cur), float(np.abs(p[1, 1:]).max()))
    return worst


def test_one_spring_follows_implicit_euler_recurrence():
    assert measure_oscillator() <= 1e-10


# -- case 12: first order in h ---------------------------------------------------------------
def measure_convergence_order(Ns=(25, 50, 100, 200), T: float = 0.25) -> dict:
    """Log-log slope of the error at time T against a fine ODE reference.

    A 3 × 3 hanging cloth (k = 5 N/m, 1 kg, two top corners pinned) under gravity; the
    reference integrates m x'' = −∇E(x) + m g with scipy's DOP853 at rtol = atol = 1e-12.
    Steps solved by local/global to a relative residual of 1e-10.
    """
    mesh = cs.grid(3, 3, size=(1.0, 1.0), plane="xy")
    model = cs.Model.build(mesh, cs.grid_springs(mesh, structural=5.0, shear=5.0, bending=0.5),
                           total_mass=1.0)
    pins = [6, 8]
    m = model.vertex_mass[:, None]

    def rhs(_, z):
        x, v = z[:27].reshape(9, 3), z[27:].reshape(9, 3)
        acc = -energy.spring_gradient(model, x) / m + GRAVITY
        acc[pins] = 0.0
        return np.concatenate([v.ravel(), acc.ravel()])

    z0 = np.concatenate([mesh.vertices.ravel(), np.zeros(27)])
    ref = solve_ivp(rhs, (0.0, T), z0, method="DOP853", rtol=1e-12, atol=1e-12)
    x_ref = ref.y[:27, -1].reshape(9, 3)
    errors = []
    for N in Ns:
        sim = cs.Simulation(model, h=T / N, effects=[cs.Gravity(GRAVITY), cs.Pin(pins)],
                            iterations=200, tolerance=1e-10)
        sim.run(N)
        errors.append(float(np.abs(sim.state.positions - x_ref).max()))
    slope = float(np.polyfit(np.log(T / np.array(Ns)), np.log(errors), 1)[0])
    return {"slope": slope, "errors": errors}


def test_trajectory_error_is_first_order_in_h():
    out = measure_convergence_order()
    assert 0.9 <= out["slope"] <= 1.1, out
