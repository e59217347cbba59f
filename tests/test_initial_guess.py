"""The initial guess: y (the paper) or x_n (the ports), through the API, scenes and export."""

import json

import numpy as np
import pytest

import clothsim as cs
from clothsim import ports
from clothsim.errors import InputError
from clothsim.gallery import GRAVITY, grid_cloth, top_corners
from clothsim.problem import StepProblem
from clothsim.scene import Scene, SceneError


def moving_problem(start):
    model = grid_cloth(4, k=300.0)
    rng = np.random.default_rng(1)
    x = model.mesh.vertices + rng.normal(scale=0.01, size=(16, 3))
    v = rng.normal(size=(16, 3))
    return StepProblem(1 / 30, x, v, fixed_vertices=[3], fixed_positions=[[9.0, 8.0, 7.0]],
                       anchor_vertices=[5], anchor_positions=[[1.0, 2.0, 3.0]],
                       anchor_stiffness=[1e3], start=start)


def test_initial_guess_starts_at_y_or_x_n_with_exact_pins_applied():
    py, px = moving_problem("y"), moving_problem("x_n")
    gy, gx = py.initial_guess(), px.initial_guess()
    free = np.ones(16, bool)
    free[3] = False
    np.testing.assert_array_equal(gy[free], py.y[free])
    np.testing.assert_array_equal(gx[free], px.x[free])
    # an exact pin starts at its target, a penalty pin where the start puts it
    assert gx[3].tolist() == gy[3].tolist() == [9.0, 8.0, 7.0]
    assert gx[5].tolist() == px.x[5].tolist() != gy[5].tolist()
    gx[0] = 99.0
    assert px.x[0, 0] != 99.0  # a new array, not a view of x_n


@pytest.mark.parametrize("bad", ["x", "Y", "xn", None, 0])
def test_an_unknown_initial_guess_is_one_line_error(bad):
    with pytest.raises(InputError, match="initial_guess"):
        moving_problem(bad)
    with pytest.raises(InputError, match="initial_guess"):
        cs.Simulation(grid_cloth(3), h=0.01, initial_guess=bad)


def hanging(initial_guess, **kw):
    n = 6
    model = grid_cloth(n, k=500.0, plane="xy")
    return cs.Simulation(model, h=1 / 30, effects=[cs.Gravity(GRAVITY), cs.Pin(top_corners(n))],
                         initial_guess=initial_guess, **kw)


def test_fixed_iterations_depend_on_the_start_a_converged_step_does_not():
    a, b = hanging("y", iterations=2), hanging("x_n", iterations=2)
    assert b.initial_guess == "x_n" and a.initial_guess == "y"
    # from rest y = x_n: the first step is the same, bit for bit
    a.step(), b.step()
    np.testing.assert_array_equal(a.state.positions, b.state.positions)
    # moving: two iterations from different starts give different answers
    a.step(), b.step()
    assert np.abs(a.state.positions - b.state.positions).max() > 1e-6
    # the problem from the same state starts where it says
    p = b.problem(a.state)
    np.testing.assert_array_equal(p.initial_guess()[:-6], a.state.positions[:-6])
    # converged, the start does not matter (the same minimizer)
    c = hanging("y", iterations=500, tolerance=1e-12)
    d = hanging("x_n", iterations=500, tolerance=1e-12)
    c.run(4), d.run(4)
    assert np.abs(c.state.positions - d.state.positions).max() < 1e-9


def test_x_n_start_in_free_fall_and_on_a_plane():
    # free fall without springs: the step is y + h² g whatever the start (one iteration
    # is exact, since M + h² L = M)
    mesh = cs.grid(3, 3, center=(0.0, 1.0, 0.0))
    model = cs.Model.build(mesh, cs.mesh_springs(mesh), total_mass=2.0)
    assert model.spring_count == 0
    h = 0.05
    sim = cs.Simulation(model, h=h, effects=[cs.Gravity(GRAVITY)], iterations=1,
                        initial_guess="x_n")
    sim.run(3)
    # implicit Euler free fall: y_k = y_0 − g h² k(k+1)/2, here k = 3
    np.testing.assert_allclose(sim.state.positions[:, 1], 1.0 - 9.81 * h * h * 6, rtol=1e-14)
    # contact: a cloth draped over a sphere stays outside it with either start, and the
    # fixed-iteration answers differ
    sims = [cs.Simulation(grid_cloth(7, k=300.0, center=(0.0, 0.05, 0.0)), h=1 / 60,
                          effects=[cs.Gravity(GRAVITY), cs.Sphere([0.0, -0.3, 0.0], 0.3)],
                          iterations=5, initial_guess=g) for g in ("y", "x_n")]
    for s in sims:
        s.run(30)
        r = np.linalg.norm(s.state.positions - [0.0, -0.3, 0.0], axis=1)
        assert r.min() >= 0.3 * (1 - 1e-9)
        assert s.state.positions[:, 1].min() < -0.1  # the edges hang down
    assert np.abs(sims[0].state.positions - sims[1].state.positions).max() > 1e-6


SCENE = {"cloth": {"shape": "grid", "resolution": [5, 5], "plane": "xy"},
         "springs": {"structural": 200.0, "shear": 200.0},
         "solver": {"iterations": 3, "initial_guess": "x_n"},
         "effects": [{"kind": "gravity"}, {"kind": "pin", "vertices": [20, 24]}]}


def test_scene_key_reaches_the_simulation_problem_and_export(tmp_path):
    scene = Scene.from_dict(SCENE)
    assert scene.data["solver"]["initial_guess"] == "x_n"
    sim = scene.build_simulation()
    assert sim.initial_guess == "x_n"
    sim.step()
    p = sim.problem()
    assert p.start == "x_n"
    np.testing.assert_array_equal(p.initial_guess(), sim.state.positions)
    # an override of the method keeps the key
    assert scene.build_simulation(method="newton", iterations=2).initial_guess == "x_n"
    manifest = ports.export_port(scene, tmp_path, frames=3, iterate_steps=2)
    assert manifest["solver"]["initial_guess"] == "x_n"
    assert json.loads((tmp_path / "manifest.json").read_text())["solver"]["initial_guess"] \
        == "x_n"
    # the recorded iterates start at x_n: step 1's x_0 is frame 1 (pins included)
    it = np.load(tmp_path / "iterates" / "step_0001.npz")
    frames = np.load(tmp_path / "trajectory.npz")["positions"]
    np.testing.assert_array_equal(it["x"][0], frames[1])


def test_check_of_an_x_n_run_against_its_scene(tmp_path):
    scene = Scene.from_dict(SCENE)
    ports.export_port(scene, tmp_path, frames=6, iterate_steps=1)
    t = np.load(tmp_path / "trajectory.npz")
    report = ports.check_steps(scene, t["positions"], t["velocities"])
    assert report.passed, report.summary()
    assert {s.status for s in report.steps} == {"agrees"}
    assert max(s.error for s in report.steps) < 1e-12


@pytest.mark.parametrize("bad", ["x", 1, "X_N"])
def test_scene_key_is_checked(bad):
    d = {**SCENE, "solver": {"initial_guess": bad}}
    with pytest.raises(SceneError, match="solver.initial_guess"):
        Scene.from_dict(d)


@pytest.mark.filterwarnings("ignore::clothsim.errors.ConvergenceWarning")
@pytest.mark.parametrize("method", ["local-global", "chebyshev", "anderson", "newton"])
def test_every_solver_starts_where_the_problem_says(method):
    # start = "x_n" gives the same iterates as the paper's problem handed x_n as x0
    model = grid_cloth(4, k=300.0)
    py, px = moving_problem("y"), moving_problem("x_n")
    kw = {"tolerance": 1e-30} if method == "newton" else {}
    solver = cs.solvers.make_solver(method, model, iterations=3, **kw)
    a = solver.solve(px).x
    b = solver.solve(py, x0=px.initial_guess()).x
    c = solver.solve(py).x
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-14)
    assert np.abs(a - c).max() > 1e-6
