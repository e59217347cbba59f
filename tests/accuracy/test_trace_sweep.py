"""The accuracy sweep machinery (clothsim.accuracy) on small scenes."""

import math

import numpy as np
import pytest

import clothsim as cs
from clothsim import accuracy as acc
from clothsim.errors import InputError
from clothsim.solvers import LocalGlobalSolver, objective, objective_gradient


def sheet(n, k, plane, pins, *, method, h, iterations, tolerance):
    """A 1 m, 1 kg n × n cloth in ``plane`` with gravity and exact ``pins``."""
    mesh = cs.grid(n, n, size=(1.0, 1.0), center=(0.0, 1.0, 0.0), plane=plane)
    springs = cs.grid_springs(mesh, structural=k, shear=k, bending=k / 10,
                              bending_pattern="every")
    model = cs.Model.build(mesh, springs, total_mass=1.0)
    return cs.Simulation(model, h=h, solver=method, iterations=iterations or 10,
                         tolerance=tolerance,
                         effects=[cs.Gravity((0.0, -9.81, 0.0)), cs.Pin(pins)])


def curtain(n=7, k=800.0, *, method="local-global", h=1 / 30, iterations=10, tolerance=None):
    """A vertical curtain hanging from its two top corners."""
    return sheet(n, k, "xy", [n * (n - 1), n * n - 1], method=method, h=h,
                 iterations=iterations, tolerance=tolerance)


def factory(method, h, iterations, tolerance):
    return curtain(method=method, h=h, iterations=iterations, tolerance=tolerance)


@pytest.fixture(scope="module")
def step():
    sim = curtain(k=2000.0)
    sim.run(6)
    problem = sim.problem()
    return sim.model, problem, acc.converged_solution(sim.model, problem)


def test_newton_solution_satisfies_optimality(step):
    """Independent check of x*: ∇g(x*) ≈ 0 relative to ∇g(x_0), and finite differences of
    g along random directions vanish to second order."""
    model, problem, x_star = step
    g0 = np.linalg.norm(objective_gradient(model, problem, problem.initial_guess()))
    assert np.linalg.norm(objective_gradient(model, problem, x_star)) / g0 < 1e-9
    rng = np.random.default_rng(0)
    free = problem.free_mask(model.vertex_count)
    for _ in range(3):
        u = rng.standard_normal(x_star.shape) * free[:, None]
        u /= np.linalg.norm(u)
        eps = 1e-6
        fd = (objective(model, problem, x_star + eps * u)
              - objective(model, problem, x_star - eps * u)) / (2 * eps)
        # slope of g along u at x* vanishes next to its slope at the initial guess (FD
        # rounding ~1e-12 and O(eps²) truncation bound what can be seen)
        g_init = objective_gradient(model, problem, problem.initial_guess())
        slope0 = abs(float(np.sum(g_init * u)))
        assert slope0 > 1e-8
        assert abs(fd) < 1e-4 * slope0


def test_all_methods_converge_to_the_same_step(step):
    model, problem, x_star = step
    traces = acc.solver_accuracy(model, problem, iterations=1500, newton_iterations=20,
                                 x_star=x_star)
    assert set(traces) == {"local-global", "chebyshev", "anderson", "lbfgs", "newton"}
    for name, tr in traces.items():
        assert tr.error[0] > 0.1, name          # the initial guess y is far from x*
        assert tr.error.min() < 1e-8, (name, tr.error.min())
        assert np.all(np.diff(tr.seconds) >= 0)


def test_local_global_errors_non_increasing(step):
    """Local/global: the objective gap never increases (block coordinate descent), and on
    this scene neither does the relative error."""
    model, problem, x_star = step
    tr = acc.trace_solver(LocalGlobalSolver(model), problem, x_star, iterations=150)
    assert len(tr.error) == 151
    rounding = 16 * np.finfo(float).eps * abs(objective(model, problem, x_star))
    assert np.all(np.diff(tr.objective_gap) <= rounding)
    assert np.all(np.diff(tr.error) <= 1e-12)
    assert tr.error[-1] < 1e-3 * tr.error[0]


def test_newton_crossover_in_iterations(step):
    """Newton needs far fewer iterations than local/global for 1e-8 (quadratic vs linear)."""
    model, problem, x_star = step
    traces = acc.solver_accuracy(model, problem, methods=("local-global", "newton"),
                                 iterations=1500, x_star=x_star)
    assert traces["newton"].first_below(1e-8)[0] <= 8
    assert traces["local-global"].first_below(1e-8)[0] > 30


def test_implicit_euler_damping_matches_closed_form():
    """Single linear spring: implicit Euler scales ω²x² + v² by exactly 1/(1 + ω²h²) per
    step, so amplitude (1 + ω²h²)^(-n/2); the sweep's closed-form line is this."""
    model, pin, state, omega = acc.single_spring(stiffness=100.0, mass=1.0, amplitude=0.1)
    h, steps = 1 / 30, 40
    sim = cs.Simulation(model, h=h, effects=[pin], state=state, solver="newton",
                        tolerance=1e-13, iterations=20)
    sim.run(steps)
    x = sim.state.positions[1, 1] + 1.0
    v = sim.state.velocities[1, 1]
    amplitude = math.sqrt(x * x + (v / omega) ** 2)
    expected = 0.1 * acc.implicit_euler_amplitude(omega, h, steps)
    assert expected < 0.05  # visibly damped: 0.1 → ~0.004 in 40 steps
    assert amplitude == pytest.approx(expected, rel=1e-8)


def test_sweep_rows_and_trends(tmp_path):
    rows = acc.run_sweep(factory, time_steps=(1 / 30, 1 / 60), frame_time=1 / 30, frames=6,
                         methods=("local-global", "newton", "symplectic-euler"),
                         iterations=(1, 30), newton_iterations=(4,), reference_h=1 / 240)
    assert len(rows) == 2 * 2 + 2 + 1
    by = {(r.method, r.h, r.iterations): r for r in rows}
    for h in (1 / 30, 1 / 60):
        few, many = by["local-global", h, 1], by["local-global", h, 30]
        assert many.solver_error < 0.1 * few.solver_error
        assert many.seconds_per_frame > few.seconds_per_frame
        assert by["newton", h, 4].solver_error < 1e-6
    # implicit Euler is first order: halving h reduces the trajectory error
    assert by["newton", 1 / 60, 4].trajectory_error < 0.8 * by["newton", 1 / 30, 4].trajectory_error
    se = [r for r in rows if r.method == "symplectic-euler"][0]
    assert se.h < 1 / 60 and se.steps_per_frame * se.h == pytest.approx(1 / 30)
    assert math.isfinite(se.trajectory_error) and math.isnan(se.solver_error)
    path = acc.write_csv(rows, tmp_path / "accuracy.csv")
    lines = path.read_text().splitlines()
    assert lines[0].split(",") == list(acc.CSV_FIELDS) and len(lines) == len(rows) + 1
    best = dict(acc.cheapest(rows, levels=(1.0, 1e-30)))
    assert best[1e-30] is None
    assert best[1.0] == min(rows, key=lambda r: r.seconds_per_frame)
    front = acc.pareto_front(rows)
    errs = [r.trajectory_error for r in front]
    assert errs == sorted(errs, reverse=True)


@pytest.mark.slow
def test_plots_are_written(tmp_path, step):
    model, problem, x_star = step
    traces = acc.solver_accuracy(model, problem, iterations=30, newton_iterations=3,
                                 x_star=x_star)
    rows = acc.run_sweep(factory, time_steps=(1 / 30,), frame_time=1 / 30, frames=2,
                         methods=("local-global",), iterations=(1, 5))
    for p in (acc.plot_solver_accuracy(traces, tmp_path / "s.png"),
              acc.plot_frontier(rows, tmp_path / "f.png"),
              acc.plot_damping(tmp_path / "d.png", steps=20)):  # ~3 s, mostly matplotlib
        assert p.stat().st_size > 5000


def test_time_step_must_divide_frame():
    with pytest.raises(InputError, match="accuracy.time_steps"):
        acc.steps_per_frame(1 / 30, 0.025)
    assert acc.steps_per_frame(1 / 30, 1 / 120) == 4


def test_cli_arguments_and_scene_factory():
    """The command's arguments are in clothsim.cli; the factory derives substeps from the
    frame time 1 / fps (so a scene with substeps > 1 works)."""
    from clothsim.cli import build_parser

    args = build_parser().parse_args(["accuracy", "--quick", "--jobs", "2"])
    assert args.scene == "hanging" and args.quick and args.out is None and args.jobs == 2

    class FakeScene:
        fps = 30.0
        substeps = 3
        h = 1 / 90

        def build_model(self):
            return curtain().model

        def build_simulation(self, model=None, *, method=None, iterations=None,
                             tolerance=None, substeps=None):
            return cs.Simulation(model, h=1 / (self.fps * substeps), solver=method,
                                 iterations=iterations, tolerance=tolerance)

    make, model, frame_time = acc.scene_factory(FakeScene())
    assert frame_time == pytest.approx(1 / 30)
    sim = make("local-global", 1 / 90, 3, None)
    assert sim.h == pytest.approx(1 / 90) and sim.model is model


def swing(n=5, k=800.0, *, method="newton", h=1 / 30, iterations=50, tolerance=1e-10):
    """A horizontal sheet hinged along one edge (row 0 pinned), released from rest."""
    return sheet(n, k, "xz", list(range(n)), method=method, h=h, iterations=iterations,
                 tolerance=tolerance)


def swing_factory(method, h, iterations, tolerance):
    return swing(method=method, h=h, iterations=iterations, tolerance=tolerance)


def test_trajectory_error_is_first_order_against_extrapolated_reference():
    """Converged implicit Euler on the swinging sheet (0.2 s, the free edge falls ~0.2 m):
    halving h halves the trajectory error, log-log slope 1 ± 0.1 (measured 0.99 at 6 × 6);
    the Richardson-extrapolated reference is far closer to the limit than its error estimate
    ‖X(h) − X(2h)‖ suggests for X(h) alone."""
    ref, estimate = acc.reference_trajectory(swing_factory, h=1 / 480, frames=6,
                                             frame_time=1 / 30)
    fine, _ = acc.reference_trajectory(swing_factory, h=1 / 960, frames=6, frame_time=1 / 30,
                                       extrapolate=False)
    assert 1e-3 < estimate < 0.05
    assert acc.trajectory_error(ref, fine) < 0.6 * estimate  # X(h/2) is ~estimate/2 away
    rows = acc.run_sweep(swing_factory, time_steps=(1 / 30, 1 / 60, 1 / 120), frame_time=1 / 30,
                         frames=6, methods=("newton",), newton_iterations=(50,), reference=ref)
    errors = [r.trajectory_error for r in rows]
    assert errors[0] > 0.05  # a visible error at h = 1/30: the scene resolves it
    slope = acc.convergence_slope(rows, method="newton", iterations=50)
    assert 0.9 <= slope <= 1.1, (slope, errors)
    assert math.isnan(acc.convergence_slope(rows, method="chebyshev", iterations=50))


def test_mechanical_energy_of_a_stretched_spring():
    """½kΔ² + ½mv² + m g y summed by hand for the single spring, with gravity."""
    model, pin, state, _ = acc.single_spring(stiffness=100.0, mass=2.0, amplitude=0.1)
    state.velocities[1] = [0.0, 0.5, 0.0]
    sim = cs.Simulation(model, h=1 / 30, state=state,
                        effects=[pin, cs.Gravity((0.0, -9.81, 0.0))])
    expected = 0.5 * 100.0 * 0.1 ** 2 + 0.5 * 2.0 * 0.25 + 2.0 * 9.81 * (-1.1)
    assert acc.mechanical_energy(sim) == pytest.approx(expected, rel=1e-12)
    traj = acc.run_trajectory(sim, frames=3, frame_time=1 / 30, record_energy=True)
    assert traj.energy.shape == (4,) and traj.energy[0] == pytest.approx(expected)


def test_representative_problem_has_real_motion():
    """On a curtain that settles, the chosen step's ‖∇g(y)‖ is the largest of the steps
    scanned and many orders above the gradient's rounding floor."""
    from clothsim.solvers.base import gradient_noise_floor

    sim = curtain()
    problem = acc.representative_problem(sim, steps=8)
    assert sim.state.step == 8
    norm = np.linalg.norm(objective_gradient(sim.model, problem, problem.initial_guess()))
    assert norm > 1e6 * gradient_noise_floor(sim.model, problem, problem.initial_guess())
    later = sim.problem()
    assert norm > np.linalg.norm(objective_gradient(sim.model, later, later.initial_guess()))
