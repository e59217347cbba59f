"""The per-step checker on cases it was not tuned on: buckling, rest, free fall, damping."""

import numpy as np
import pytest

import clothsim as cs
from clothsim.cli import main
from clothsim.gallery import GRAVITY, grid_cloth
from clothsim.ports.check import check_steps
from clothsim.ports.formats import write_trajectory
from clothsim.solvers.newton import NewtonSolver
from clothsim.springs import Springs


def compressed_strip():
    """A 9 × 3 strip whose springs want to be 30 % longer, both ends pinned: it buckles."""
    mesh = cs.grid(9, 3, size=(1.0, 0.25), plane="xy")
    s = cs.grid_springs(mesh, structural=100.0, shear=100.0, bending=1.0)
    s = Springs(s.spring_vertices, s.spring_stiffness, 1.3 * s.spring_rest_length,
                s.spring_family)
    model = cs.Model.build(mesh, s, total_mass=0.01)
    x = mesh.vertices
    ends = np.flatnonzero((x[:, 0] == x[:, 0].min()) | (x[:, 0] == x[:, 0].max()))
    return cs.Simulation(model, h=0.1, effects=[cs.Pin(ends)], solver="newton",
                         iterations=100, tolerance=1e-12)


def run(factory, steps):
    sim = factory()
    xs, vs = [sim.state.positions.copy()], [sim.state.velocities.copy()]
    for _ in range(steps):
        sim.step()
        xs.append(sim.state.positions.copy())
        vs.append(sim.state.velocities.copy())
    return np.stack(xs), np.stack(vs)


def test_buckling_step_with_two_minima_is_non_unique():
    sim = compressed_strip()
    x0 = sim.state.positions.copy()
    v0 = np.zeros_like(x0)
    v0[:, 2] = 0.01  # a slight push out of the plane: clothsim buckles one way
    sim.state = cs.State(x0, v0)
    problem = sim.problem()
    sim.step()
    x_cs = sim.state.positions.copy()
    mirror = x_cs * np.array([1.0, 1.0, -1.0])
    x_other = NewtonSolver(sim.model, iterations=100, tolerance=1e-13).solve(problem, mirror).x
    assert np.abs(x_other - x_cs).max() > 0.1  # Newton from two starts: two minimizers
    xs = np.stack([x0, x_other])
    report = check_steps(compressed_strip, xs, np.stack([v0, (x_other - x0) / sim.h]))
    step = report.steps[0]
    assert step.status == "non-unique" and "both optimal" in step.note, step.line()
    assert report.passed and "non-unique" in report.summary()
    # the same answer displaced a little is no minimizer
    bad = xs.copy()
    bad[1, 13, 2] += 0.01
    report = check_steps(compressed_strip, bad, np.stack([v0, v0]))
    first = report.first_failure
    # the line names the vertex of largest error (the other buckling branch), the note the
    # vertex where the port's gradient is wrong
    assert first.status == "not a minimizer" and "at vertex 13:" in first.note, first.line()
    assert first.vertex == int(np.argmax(np.linalg.norm(bad[1] - x_cs, axis=1)))


def hanging():
    model, effects = cs.gallery.hanging_cloth(5)
    return cs.Simulation(model, h=1 / 30, effects=effects)


def test_cloth_at_rest_and_free_fall_agree():
    def rest():
        return cs.Simulation(grid_cloth(4), h=1 / 30)

    x = np.repeat(rest().state.positions[None], 4, axis=0)
    assert check_steps(rest, x, np.zeros_like(x)).passed

    def fall():
        return cs.Simulation(grid_cloth(4, center=(1e3, 0, 0)), h=1 / 30,
                             effects=[cs.Gravity(GRAVITY)])

    xs, vs = run(fall, 5)
    report = check_steps(fall, xs, vs)
    assert report.passed and max(s.error for s in report.steps) < 1e-9
    # without velocities they are derived from positions (right without damping)
    assert check_steps(fall, xs).passed


def test_damping_difference_shows_in_velocities():
    def damped():
        model, effects = cs.gallery.hanging_cloth(5)
        return cs.Simulation(model, h=1 / 30, effects=effects + [cs.Damping("velocity", 0.1)])

    xs, vs = run(hanging, 4)  # the "port" forgot the damping
    report = check_steps(damped, xs, vs)
    assert not report.passed
    assert report.first_failure.k == 0
    xs, vs = run(damped, 4)
    assert check_steps(damped, xs, vs).passed


def test_bad_input_is_one_clear_error():
    xs, vs = run(hanging, 2)
    with pytest.raises(cs.InputError, match="positions: expected"):
        check_steps(hanging, xs[:, :5], vs)
    with pytest.raises(cs.InputError, match="at least 2 frames"):
        check_steps(hanging, xs[:1], vs[:1])
    with pytest.raises(cs.InputError, match="precision"):
        check_steps(hanging, xs, vs, precision="float16")
    with pytest.raises(cs.InputError, match="steps: must be >= 1"):
        check_steps(hanging, xs, vs, steps=0)


def test_float32_port_checked_at_float64_gets_a_hint():
    xs, vs = run(hanging, 3)
    x32, v32 = (a.astype(np.float32).astype(np.float64) for a in (xs, vs))
    report = check_steps(hanging, x32, v32)
    first = report.first_failure
    assert first.status == "float32 rounding" and "precision float32" in first.note, first.line()
    assert check_steps(hanging, x32, v32, precision="float32").passed


def test_cli_check_on_a_scene_file(tmp_path, capsys):
    scene = cs.load_scene("hanging")
    sim = scene.build_simulation(scene.build_model())
    xs, vs = [sim.state.positions.copy()], [sim.state.velocities.copy()]
    for _ in range(3):
        sim.step()
        xs.append(sim.state.positions.copy())
        vs.append(sim.state.velocities.copy())
    port = tmp_path / "port"
    port.mkdir()
    write_trajectory(port / "positions.txt", np.stack(xs))
    write_trajectory(port / "velocities.txt", np.stack(vs))
    assert main(["check", "hanging", str(port), "--steps", "3"]) == 0
    assert capsys.readouterr().out.strip().startswith("PASS: 3 steps agree")
    # a whole output is checked: 3 of the scene's 90 steps fail, naming both counts
    assert main(["check", "hanging", str(port)]) == 1
    assert capsys.readouterr().out.strip().startswith(
        "FAIL: the port's output has 4 frames (3 steps), the scene asks for 90")
    moved = np.stack(xs)
    moved[2:, 100] += 1e-3
    write_trajectory(port / "positions.txt", moved)
    assert main(["check", "hanging", str(port), "--steps", "3"]) == 1
    assert "step 1 -> 2" in capsys.readouterr().out
    write_trajectory(tmp_path / "x.npy", np.stack(xs))
    assert main(["check", "hanging", str(tmp_path / "x.npy"), "--steps", "1"]) == 0
    assert main(["check", "hanging", str(port), "--tolerance", "-1"]) == 2
    assert main(["check", "hanging", str(port), "--optimality", "1e-3", "--verbose-steps",
                 "--steps", "3"]) == 1
    assert "step 0 -> 1: agrees" in capsys.readouterr().out
