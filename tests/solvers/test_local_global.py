"""The paper's claims about the local/global solver, each as a test that could fail."""

import warnings

import numpy as np
import pytest
import scipy.spatial
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import clothsim as cs
from clothsim import reference
from clothsim.factorization import cholmod_available
from clothsim.gallery import curtain, grid_cloth
from clothsim.objective import gradient_noise_floor
from clothsim.solvers import (
    Iterate,
    LocalGlobalSolver,
    NewtonSolver,
    StepProblem,
    augmented_objective,
    objective,
    objective_gradient,
)

G = np.array([0.0, -9.81, 0.0])


def hanging(n=7, k=200.0, plane="xy", total_mass=0.5):
    return grid_cloth(n, k=k, plane=plane, total_mass=total_mass)


def random_model(data):
    """A random grid or Delaunay mesh with random stiffness, masses and a jittered shape."""
    seed = data.draw(st.integers(0, 2**31 - 1), label="seed")
    rng = np.random.default_rng(seed)
    if data.draw(st.booleans(), label="grid"):
        nx, ny = data.draw(st.integers(2, 6)), data.draw(st.integers(2, 6))
        mesh = cs.grid(nx, ny, size=(1.0, 1.0), plane="xy")
        springs = cs.grid_springs(mesh, structural=1.0, shear=1.0, bending=1.0)
    else:
        pts = rng.uniform(-0.5, 0.5, size=(data.draw(st.integers(4, 25)), 2))
        tri = scipy.spatial.Delaunay(pts).simplices
        mesh = cs.Mesh(np.c_[pts, np.zeros(len(pts))], tri)
        springs = cs.mesh_springs(mesh, structural=1.0, bending=1.0)
    k = 10.0 ** rng.uniform(0, 5, springs.spring_count)
    model = cs.Model.build(mesh, springs.with_stiffness(k),
                           vertex_mass=10.0 ** rng.uniform(-3, 0, mesh.vertex_count))
    # start from a jittered (stressed) shape, rest lengths from the mesh
    x = mesh.vertices + rng.normal(scale=0.1, size=mesh.vertices.shape)
    v = rng.normal(scale=0.5, size=x.shape)
    h = 10.0 ** data.draw(st.floats(-3, -0.3), label="log10 h")
    f = model.vertex_mass[:, None] * G if data.draw(st.booleans(), label="gravity") else None
    fixed = np.array([0]) if data.draw(st.booleans(), label="pinned") else np.zeros(0, int)
    problem = StepProblem(h, x, v, f_ext=f, fixed_vertices=fixed,
                          fixed_positions=mesh.vertices[fixed])
    return model, problem


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.data())
def test_objective_never_increases_across_half_steps(data):
    """ĝ(x, d) is non-increasing across every local and every global half step (slack 1e-12)."""
    model, problem = random_model(data)
    solver = LocalGlobalSolver(model, check_conditioning=False)
    x = problem.initial_guess()
    d = solver.local_step(x)
    g_prev = augmented_objective(model, problem, x, d)
    for _ in range(15):
        x = solver.global_step(problem, d)
        g_global = augmented_objective(model, problem, x, d)
        assert g_global <= g_prev + 1e-12 * abs(g_prev)
        d = solver.local_step(x)
        g_local = augmented_objective(model, problem, x, d)
        assert g_local <= g_global + 1e-12 * abs(g_global)
        # after a local step ĝ(x, d(x)) is the true objective g(x)
        assert g_local == pytest.approx(objective(model, problem, x), rel=1e-10, abs=1e-300)
        g_prev = g_local


# ---- an independent Newton's method: dense, one spring at a time, its own line search ----
def dense_newton(model, problem, iters=30):
    n = model.vertex_count
    m = np.repeat(model.vertex_mass, 3)
    h2 = problem.h ** 2
    y = problem.y.ravel()
    f = np.zeros(3 * n) if problem.f_ext is None else problem.f_ext.ravel()
    free = np.ones(3 * n, bool)
    for v in problem.fixed_vertices:
        free[3 * v:3 * v + 3] = False

    def g(x):
        return (0.5 * np.sum(m * (x - y) ** 2)
                + h2 * (reference.spring_energy(model, x.reshape(n, 3)) - x @ f))

    def grad_hess(x):
        gr = m * (x - y) - h2 * f
        H = np.diag(m)
        for (a, b), k, r in zip(model.springs.spring_vertices, model.springs.spring_stiffness,
                                model.springs.spring_rest_length):
            p = x[3 * a:3 * a + 3] - x[3 * b:3 * b + 3]
            length = np.linalg.norm(p)
            u = p / length
            fs = k * (length - r) * u
            Hs = k * (np.outer(u, u) + max(0.0, 1 - r / length) * (np.eye(3) - np.outer(u, u)))
            for i, sgn in ((a, 1), (b, -1)):
                gr[3 * i:3 * i + 3] += sgn * h2 * fs
            for i, j, sgn in ((a, a, 1), (b, b, 1), (a, b, -1), (b, a, -1)):
                H[3 * i:3 * i + 3, 3 * j:3 * j + 3] += sgn * h2 * Hs
        return gr, H

    x = problem.initial_guess().ravel()
    for _ in range(iters):
        gr, H = grad_hess(x)
        step = np.zeros(3 * n)
        step[free] = -np.linalg.solve(H[np.ix_(free, free)], gr[free])
        t, g0, slope = 1.0, g(x), gr @ step
        if -slope > 1e-13 * abs(g0):  # else the decrease is below g's rounding: full step
            while g(x + t * step) > g0 + 1e-4 * t * slope:
                t /= 2
        x = x + t * step
    return x.reshape(n, 3)


@pytest.mark.parametrize("pinned", [False, True])
def test_converged_local_global_equals_independent_newton(pinned):
    model = hanging(n=5, k=300.0)
    rng = np.random.default_rng(4)
    x0 = model.mesh.vertices
    v0 = rng.normal(scale=0.3, size=x0.shape)
    fixed = np.array([20, 24]) if pinned else np.zeros(0, int)
    problem = StepProblem(1 / 30, x0, v0, f_ext=model.vertex_mass[:, None] * G,
                          fixed_vertices=fixed, fixed_positions=x0[fixed])
    x_newton = dense_newton(model, problem)
    lg = LocalGlobalSolver(model, iterations=20000, tolerance=1e-11).solve(problem)
    assert lg.converged
    scale = np.linalg.norm(x_newton - x0)
    assert np.linalg.norm(lg.x - x_newton) / scale <= 1e-8
    # the package's sparse Newton agrees too and satisfies the optimality condition
    nt = NewtonSolver(model).solve(problem)
    assert np.linalg.norm(nt.x - x_newton) / scale <= 1e-10
    grad = objective_gradient(model, problem, nt.x)
    scale0 = np.linalg.norm(model.vertex_mass[:, None] * (x0 - problem.y))
    assert np.linalg.norm(grad) <= 1e-9 * scale0


def test_stress_free_free_fall_matches_closed_form():
    """Gravity only, stress-free cloth: x_n = x_0 + h² g n(n+1)/2 exactly for implicit Euler."""
    model = hanging(n=9, k=1e4, plane="xz")
    h, steps = 1 / 60, 120
    sim = cs.Simulation(model, h=h, effects=[cs.Gravity(G)], iterations=3)
    sim.run(steps)
    expected = model.mesh.vertices + h * h * G * steps * (steps + 1) / 2
    assert np.abs(sim.state.positions - expected).max() <= 1e-8
    np.testing.assert_allclose(sim.state.velocities, np.tile(h * G * steps, (81, 1)), atol=1e-8)


def test_linear_momentum_conserved_without_pins_or_forces():
    model = hanging(n=6, k=500.0)
    rng = np.random.default_rng(7)
    x = model.mesh.vertices + rng.normal(scale=0.05, size=model.mesh.vertices.shape)
    v = rng.normal(scale=1.0, size=x.shape)
    sim = cs.Simulation(model, h=1 / 30, iterations=4, state=cs.State(x, v))
    m = model.vertex_mass[:, None]
    p0 = (m * v).sum(axis=0)
    for _ in range(50):
        sim.step()
        p = (m * sim.state.velocities).sum(axis=0)
        assert np.linalg.norm(p - p0) <= 1e-10 * np.linalg.norm(p0)


def test_exact_pins_are_bitwise_still_and_penalty_pins_converge_to_them():
    model = hanging(n=7, k=300.0)
    pins = [42, 48]
    h, steps = 1 / 30, 20

    def run(**pin):
        sim = cs.Simulation(model, h=h, effects=[cs.Gravity(G), cs.Pin(pins, **pin)],
                            solver="newton")
        sim.run(steps)
        return sim.state.positions

    exact = run()
    assert np.array_equal(exact[pins], model.mesh.vertices[pins])  # bitwise
    errs = [np.abs(run(method="penalty", stiffness=k) - exact).max() for k in (1e3, 1e5, 1e7)]
    assert errs[0] > errs[1] > errs[2]
    assert errs[2] < 1e-5
    # the penalty pin's sag is O(1/k): two decades of k give about two decades of error
    assert errs[0] / errs[1] > 30 and errs[1] / errs[2] > 30


def test_factor_is_cached_and_rebuilt_only_when_pins_change():
    model = hanging(n=5)
    sim = cs.Simulation(model, h=1 / 30, effects=[cs.Gravity(G), cs.Pin([20, 24], release=0.5)])
    sim.run(10)
    assert sim.solver.factor_count == 1
    sim.run(10)  # the pin is released at t = 0.5: exactly one refactor
    assert sim.solver.factor_count == 2
    sim.solver.invalidate()
    sim.step()
    assert sim.solver.factor_count == 3


@pytest.mark.skipif(not cholmod_available(), reason="scikit-sparse (CHOLMOD) not installed")
def test_cholmod_and_superlu_agree():
    model = hanging(n=9, k=1e3)
    rng = np.random.default_rng(2)
    x0 = model.mesh.vertices
    problem = StepProblem(1 / 30, x0, rng.normal(size=x0.shape),
                          f_ext=model.vertex_mass[:, None] * G, fixed_vertices=[72, 80],
                          fixed_positions=x0[[72, 80]])
    a = LocalGlobalSolver(model, iterations=10, backend="cholmod")
    b = LocalGlobalSolver(model, iterations=10, backend="splu")
    ra, rb = a.solve(problem), b.solve(problem)
    assert (a.backend, b.backend) == ("cholmod", "splu")
    assert np.linalg.norm(ra.x - rb.x) <= 1e-10 * np.linalg.norm(ra.x)


def test_auto_backend_falls_back_to_superlu_with_a_warning(monkeypatch, caplog):
    from clothsim import factorization

    monkeypatch.setattr(factorization, "cholmod_available", lambda: False)
    monkeypatch.setattr(factorization, "_warned_fallback", False)
    with caplog.at_level("WARNING", logger="clothsim.factorization"):
        assert factorization.resolve_backend("auto") == "splu"
    assert "falling back to scipy's SuperLU" in caplog.text
    sim = cs.Simulation(hanging(n=4), h=0.01, effects=[cs.Gravity(G)])
    sim.step()
    assert sim.solver.backend == "splu"


def test_local_step_with_coincident_ends_keeps_previous_direction():
    model = hanging(n=3)
    solver = LocalGlobalSolver(model)
    x = model.mesh.vertices.copy()
    d_before = solver.local_step(x).copy()
    a, b = model.springs.spring_vertices[0]
    x[b] = x[a]
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no divide-by-zero RuntimeWarning
        d = solver.local_step(x)
    assert np.all(np.isfinite(d))
    np.testing.assert_array_equal(d[0], d_before[0])
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), model.springs.spring_rest_length)


def test_tolerance_mode_stops_early_and_reports_residual():
    model = hanging(n=7, k=100.0)
    sim = cs.Simulation(model, h=1 / 30, effects=[cs.Gravity(G), cs.Pin([42, 48])],
                        iterations=500, tolerance=1e-6)
    rec = sim.step()
    assert rec.converged and rec.residual <= 1e-6 and 1 < rec.iterations < 500
    assert rec.residual_history[0] == 1.0 and rec.residual_history[-1] == rec.residual
    fixed = cs.Simulation(model, h=1 / 30, effects=[cs.Gravity(G), cs.Pin([42, 48])],
                          iterations=2)
    rec2 = fixed.step()
    assert rec2.iterations == 2 and rec2.residual > rec.residual


def test_convergence_warning_names_the_residual():
    model = hanging(n=7, k=1e5)
    sim = cs.Simulation(model, h=1 / 30, effects=[cs.Gravity(G), cs.Pin([42, 48])],
                        iterations=2, tolerance=1e-10)
    with pytest.warns(cs.ConvergenceWarning, match=r"relative residual \d\.\d+e[-+]\d+"):
        rec = sim.step()
    assert not rec.converged


def test_step_at_rest_stops_at_rounding_floor_without_warning():
    """A settled cloth: ‖∇g(x_0)‖ is rounding noise, so a tight tolerance is unreachable;
    the solvers stop at the noise floor and count the step as converged (no warning)."""
    from clothsim.solvers.base import gradient_noise_floor

    model = hanging(n=9, k=3000.0)
    sim = cs.Simulation(model, h=1 / 30, effects=[cs.Gravity(G), cs.Pin([72, 80])],
                        solver="newton")
    sim.run(60)  # settle to equilibrium (Newton: exact implicit Euler steps)
    problem = sim.problem()
    floor = gradient_noise_floor(model, problem, problem.x)
    for solver in (LocalGlobalSolver(model, iterations=5000, tolerance=1e-14),
                   NewtonSolver(model, tolerance=1e-14)):
        result = solver.solve(problem)  # a ConvergenceWarning would fail the test
        assert result.converged
        grad = objective_gradient(model, problem, result.x)
        assert np.linalg.norm(grad) <= floor
    # a step with real motion is not cut short by the floor
    moving = StepProblem(1 / 30, model.mesh.vertices, np.zeros((81, 3)),
                         f_ext=model.vertex_mass[:, None] * G, fixed_vertices=[72, 80],
                         fixed_positions=model.mesh.vertices[[72, 80]])
    res = LocalGlobalSolver(model, iterations=5000, tolerance=1e-9).solve(moving)
    assert res.residual <= 1e-9


def test_global_step_solves_the_papers_equation():
    """The displacement-form global step solves (M + h²L) x = h² J d + M y + h² f + h² K q
    (the paper's right-hand side, LocalGlobalSolver.right_hand_side) on the free vertices."""
    from clothsim import matrices

    model = hanging(n=6, k=400.0)
    rng = np.random.default_rng(11)
    x0 = model.mesh.vertices + rng.normal(scale=0.02, size=model.mesh.vertices.shape)
    problem = StepProblem(1 / 30, x0, rng.normal(scale=0.3, size=x0.shape),
                          f_ext=model.vertex_mass[:, None] * G, fixed_vertices=[30, 35],
                          fixed_positions=model.mesh.vertices[[30, 35]],
                          anchor_vertices=[0], anchor_positions=x0[[0]] + 0.01,
                          anchor_stiffness=[50.0])
    solver = LocalGlobalSolver(model)
    d = solver.local_step(problem.initial_guess())
    x = solver.global_step(problem, d)
    A = matrices.system_matrix(model, problem.h, anchor_vertices=[0], anchor_stiffness=[50.0])
    residual = (A @ x - solver.right_hand_side(problem, d))[problem.free_mask(36)]
    assert np.abs(residual).max() <= 1e-12 * np.abs(solver.right_hand_side(problem, d)).max()
    np.testing.assert_array_equal(x[[30, 35]], model.mesh.vertices[[30, 35]])


@pytest.mark.parametrize("pins", ["exact", "penalty", "none"])
def test_fast_iteration_equals_the_plain_half_steps(pins):
    """iterates() (buffers, per-step constants, residual from consecutive right-hand sides)
    against the previous implementation's loop of the plain half steps, mid-motion."""
    from clothsim.gallery import curtain

    sim = curtain(9, k=3000.0, iterations=30)
    if pins == "penalty":
        sim = cs.Simulation(sim.model, h=sim.h, effects=[cs.Gravity(G),
                            cs.Pin([72, 80], method="penalty", stiffness=1e4)])
    elif pins == "none":
        sim = cs.Simulation(sim.model, h=sim.h, effects=[cs.Gravity(G)])
    sim.run(8)
    problem = sim.problem()
    plain = LocalGlobalSolver(sim.model)
    x = problem.initial_guess()
    xs, norms = [], []
    for _ in range(12):
        d = plain.local_step(x)
        xs.append(x)
        norms.append(float(np.linalg.norm(plain.gradient(problem, x, d))))
        x = plain.global_step(problem, d)
    fast = LocalGlobalSolver(sim.model)
    floor = gradient_noise_floor(sim.model, problem, problem.x)
    for it, x_ref, n_ref in zip(fast.iterates(problem), xs, norms):
        scale = np.abs(x_ref).max()
        assert np.abs(it.x - x_ref).max() <= 1e-12 * scale
        assert abs(it.gradient_norm - n_ref) <= 1e-8 * n_ref + floor
    # the solve() path returns the same x and a C-ordered copy
    res = LocalGlobalSolver(sim.model, iterations=11).solve(problem)
    assert res.x.flags.c_contiguous and np.abs(res.x - xs[-1]).max() <= 1e-12 * scale


def plain_iterates(model, problem, x, count, *, directions=False):
    """x_0 .. x_count from the plain half steps (local_step, global_step), from x (and
    d(x_0) .. d(x_{count−1}) with ``directions``)."""
    plain = LocalGlobalSolver(model)
    xs, ds = [x], []
    for _ in range(count):
        ds.append(plain.local_step(x))
        x = plain.global_step(problem, ds[-1])
        xs.append(x)
    return (xs, ds) if directions else xs


@pytest.mark.parametrize("case", ["x0 given", "coincident ends", "pinned spring ends",
                                  "ends pinned together", "x0 given, ends pinned together"])
def test_fast_iteration_paths_equal_the_plain_half_steps(case):
    """The iteration's other paths: a given x_0 (spring vectors gathered, not taken from
    p(y)), springs whose ends coincide in y (previous direction kept), springs between
    two exactly pinned vertices, and two exact pins at one point (their spring's ends
    coincide at every iterate: the carried direction is carried again, from x_0's own
    direction when x_0 is given with the pins elsewhere); with gravity, exact and penalty
    pins."""
    model = hanging(n=6, k=400.0)
    rng = np.random.default_rng(5)
    x = model.mesh.vertices + rng.normal(scale=0.02, size=model.mesh.vertices.shape)
    v = rng.normal(scale=0.3, size=x.shape)
    given = case.startswith("x0 given")
    fixed = [30, 35] if case in ("x0 given", "coincident ends") else [30, 31, 35]
    targets = model.mesh.vertices[[30, 30, 35] if "together" in case else fixed]
    if case == "coincident ends":     # vertex 1 lands exactly on vertex 0 in y = x + h v
        a, b = model.springs.spring_vertices[0]
        v[b] = v[a]
        x[b] = x[a]
    problem = StepProblem(1 / 30, x, v, f_ext=model.vertex_mass[:, None] * G,
                          fixed_vertices=fixed, fixed_positions=targets,
                          anchor_vertices=[0], anchor_positions=x[[0]] + 0.01,
                          anchor_stiffness=[50.0])
    x0 = problem.initial_guess()
    if given:     # the pins too start away from their targets
        x0 = x0 + rng.normal(scale=0.01, size=x0.shape)
    xs, ds = plain_iterates(model, problem, x0, 6, directions=True)
    fast = LocalGlobalSolver(model)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no divide-by-zero RuntimeWarning
        its = fast.iterates(problem, x0 if given else None)
        got = [(it.x.copy(), it.d.copy()) for it, _ in zip(its, range(7))]
        # not reading d: the carried directions come from the kept positions instead
        its = LocalGlobalSolver(model).iterates(problem, x0 if given else None)
        unread = [it.x.copy() for it, _ in zip(its, range(7))]
    for (x_fast, _), x_unread in zip(got, unread):
        np.testing.assert_array_equal(x_unread, x_fast)
    scale = np.abs(xs[0]).max()
    for k, ((x_fast, d_fast), x_ref) in enumerate(zip(got, xs)):
        if k < len(ds):
            np.testing.assert_allclose(d_fast, ds[k], rtol=0, atol=1e-14)
        if k == 0 and given:
            np.testing.assert_array_equal(x_fast, x0)
            continue
        assert np.all(np.isfinite(x_fast))
        assert np.abs(x_fast - x_ref).max() <= 1e-12 * scale
        np.testing.assert_array_equal(x_fast[fixed], targets)
    if "together" in case:   # one direction (the rest mesh's, or x_0's), carried throughout
        (spring,) = np.flatnonzero((model.springs.spring_vertices == [30, 31]).all(axis=1))
        first = x0[30] - x0[31] if given else model.mesh.vertices[30] - model.mesh.vertices[31]
        expected = first * (model.springs.spring_rest_length[spring] / np.linalg.norm(first))
        for _, d_fast in got:
            np.testing.assert_allclose(d_fast[spring], expected, rtol=0, atol=1e-15)


def test_iterates_carry_the_local_steps_directions():
    """Iterate.d is d(x_k) of the local step (what a port is checked against, half step by
    half step): equal to the plain local step at the same x."""
    sim = curtain(7, k=800.0)
    sim.run(5)                       # mid-swing: directions differ from the rest shape
    problem = sim.problem()
    solver = LocalGlobalSolver(sim.model)
    plain = LocalGlobalSolver(sim.model)
    for it in solver.iterates(problem):
        np.testing.assert_allclose(it.d, plain.local_step(it.x.copy()), rtol=0, atol=1e-14)
        if it.k == 4:
            break


def test_iterate_d_is_built_only_when_read(monkeypatch):
    """The fast iteration keeps no d: Iterate.d rebuilds it on first read, once."""
    from clothsim.solvers import directions

    calls = []
    current = directions.SpringDirections.current
    monkeypatch.setattr(directions.SpringDirections, "current",
                        lambda self: calls.append(1) or current(self))
    sim = curtain(7, k=800.0)
    sim.run(2)
    problem = sim.problem()
    solver = LocalGlobalSolver(sim.model, iterations=5)
    solver.solve(problem)
    assert calls == []                      # a plain solve never builds d
    it = next(solver.iterates(problem))
    first = it.d
    assert it.d is first and len(calls) == 1
    assert first.shape == (sim.model.spring_count, 3)
    np.testing.assert_allclose(first, LocalGlobalSolver(sim.model).local_step(it.x.copy()),
                               rtol=0, atol=1e-14)
    plain = Iterate(0, it.x, 0.0, first)    # an array is kept as given
    assert plain.d is first and Iterate(0, it.x, 0.0).d is None
