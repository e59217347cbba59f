"""Held contacts: the step on contact planes (problem, solvers), the obstacles' "hold" mode
and the scene's [contact] mode."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.optimize import minimize

import clothsim as cs
from clothsim.errors import InputError, SceneError
from clothsim.gallery import GRAVITY, grid_cloth
from clothsim.objective import objective, objective_gradient
from clothsim.scene import Scene, builtin_scene_text, parse_toml
from clothsim.solvers import make_solver
from clothsim.solvers.descent import objective_difference

H = 1 / 30


def held_problem(n=4, tilt=0.3):
    """A falling n × n sheet with its middle row held on a tilted plane, one corner pinned."""
    model = grid_cloth(n, center=(0.0, 0.5, 0.0))
    x = model.mesh.vertices
    normal = np.array([np.sin(tilt), np.cos(tilt), 0.0])
    held = np.arange(n, 2 * n)
    problem = cs.StepProblem(H, x, np.tile([0.3, -1.0, 0.2], (len(x), 1)),
                             f_ext=model.vertex_mass[:, None] * GRAVITY,
                             fixed_vertices=[0], fixed_positions=x[[0]],
                             contact_vertices=np.r_[held, 0],
                             contact_normals=np.tile(normal, (n + 1, 1)),
                             contact_offsets=np.r_[x[held] @ normal, 0.0])
    return model, problem, held, normal


def test_problem_keeps_held_vertices_on_their_planes():
    model, p, held, normal = held_problem()
    assert 0 not in p.contact_vertices                      # the pin wins over a contact
    x0 = p.initial_guess()
    np.testing.assert_allclose(x0[held] @ normal, p.contact_offsets, atol=1e-15)
    g = objective_gradient(model, p, x0)
    np.testing.assert_allclose(g[held] @ normal, 0.0, atol=1e-15)   # tangential only
    full = objective_gradient(model, p, x0, feasible=False)
    assert np.abs(full[held] @ normal).max() > 1e-6


@pytest.mark.parametrize("bad,message", [
    (dict(contact_normals=[[0.0, 2.0, 0.0]]), r"^contacts\.normals: must be unit vectors"),
    (dict(contact_offsets=[0.0, 1.0]), r"^contacts\.offsets: expected one per contact"),
    (dict(contact_vertices=[99]), r"^contacts\.vertices\[0\]: vertex 99 out of range"),
])
def test_bad_held_contacts_name_the_field(bad, message):
    x = np.zeros((4, 3))
    args = dict(contact_vertices=[1], contact_normals=[[0.0, 1.0, 0.0]], contact_offsets=[0.0])
    with pytest.raises(InputError, match=message):
        cs.StepProblem(H, x, x, **{**args, **bad})


def slsqp_minimum(model, p, normal):
    """The held step's minimizer by SLSQP (scipy), the plane and pin constraints written out."""
    n = model.vertex_count

    def f(z):
        return objective(model, p, z.reshape(n, 3))

    def grad(z):
        return objective_gradient(model, p, z.reshape(n, 3), feasible=False).ravel()

    cons = [{"type": "eq", "fun": lambda z, v=v, o=o: z.reshape(n, 3)[v] @ normal - o}
            for v, o in zip(p.contact_vertices, p.contact_offsets)]
    cons += [{"type": "eq", "fun": lambda z: z.reshape(n, 3)[0] - p.fixed_positions[0]}]
    ref = minimize(f, p.initial_guess().ravel(), jac=grad, constraints=cons, method="SLSQP",
                   options={"ftol": 1e-15, "maxiter": 500}).x.reshape(n, 3)
    return ref


def test_local_global_reaches_the_constrained_minimum_an_independent_solver_finds():
    """SLSQP against local/global's held global step and Newton's projected steps."""
    model, p, held, normal = held_problem(3)
    ref = slsqp_minimum(model, p, normal)
    for method, its in (("local-global", 3000), ("newton", 50)):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            x = make_solver(method, model, iterations=its, tolerance=1e-11).solve(p).x
        np.testing.assert_allclose(x[held] @ normal, p.contact_offsets, atol=1e-12)
        assert np.abs(x - ref).max() < 1e-6, method


@pytest.mark.parametrize("method", ["chebyshev", "anderson", "lbfgs", "symplectic-euler"])
def test_every_solver_keeps_held_vertices_on_their_planes(method):
    model, p, held, normal = held_problem()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = make_solver(method, model, iterations=20).solve(p)
    np.testing.assert_allclose(result.x[held] @ normal, p.contact_offsets, atol=1e-12)
    np.testing.assert_array_equal(result.x[0], p.fixed_positions[0])


ACCELERATED = ["chebyshev", "anderson", "lbfgs"]


def quiet_solve(method, model, p, **options):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return make_solver(method, model, **options).solve(p)


@pytest.mark.parametrize("method", ACCELERATED)
def test_accelerated_solvers_reach_the_held_minimum(method):
    """Chebyshev, Anderson and L-BFGS on a held step: on the planes, at SLSQP's minimizer."""
    model, p, held, normal = held_problem(3)
    ref = slsqp_minimum(model, p, normal)
    result = quiet_solve(method, model, p, iterations=3000, tolerance=1e-11)
    assert result.converged
    np.testing.assert_allclose(result.x[held] @ normal, p.contact_offsets, atol=1e-14)
    np.testing.assert_array_equal(result.x[0], p.fixed_positions[0])
    assert np.abs(result.x - ref).max() < 1e-6


@pytest.mark.parametrize("method", ACCELERATED)
def test_accelerated_solvers_beat_held_local_global_to_1e6(method):
    """The held step is accelerated, not handed to plain local/global (4 x 4 sheet:
    local/global needs ~1000 iterations to 1e-6, the accelerated ones ~80-120)."""
    model, p, _, _ = held_problem(4)
    plain = quiet_solve("local-global", model, p, iterations=20000, tolerance=1e-6)
    fast = quiet_solve(method, model, p, iterations=20000, tolerance=1e-6)
    assert plain.converged and fast.converged
    assert fast.iterations < plain.iterations / 3, (fast.iterations, plain.iterations)


@pytest.mark.parametrize("method", ACCELERATED)
def test_every_accelerated_iterate_is_on_the_planes_also_on_an_edge(method):
    """Every iterate, not only the last, is feasible; a vertex held by two planes (a box
    edge) moves only along their intersection."""
    model, p, held, normal = held_problem(4)
    side = np.array([0.0, 0.0, 1.0])
    edge = held[1]
    x = p.initial_guess()
    p = cs.StepProblem(p.h, p.x, p.v, f_ext=p.f_ext, fixed_vertices=p.fixed_vertices,
                       fixed_positions=p.fixed_positions,
                       contact_vertices=np.r_[p.contact_vertices, edge],
                       contact_normals=np.r_[p.contact_normals, side[None]],
                       contact_offsets=np.r_[p.contact_offsets, x[edge] @ side])
    solver = make_solver(method, model)
    for it in solver.iterates(p):
        np.testing.assert_allclose(it.x[held] @ normal, p.contact_offsets[:len(held)],
                                   atol=1e-14)
        assert it.x[edge] @ side == pytest.approx(x[edge] @ side, abs=1e-14)
        np.testing.assert_array_equal(it.x[0], p.fixed_positions[0])
        if it.k == 150:
            break
    assert it.k == 150


@pytest.mark.parametrize("method", ["anderson", "lbfgs"])
def test_the_energy_never_increases_on_a_held_step(method):
    """Anderson's safeguard and L-BFGS's Armijo search hold on the planes: each iterate's g
    is at most its predecessor's (exact difference, descent.objective_difference), up to
    the rounding of the planes: a held vertex is on its plane to eps |x|, and g changes by
    that times the contact force (~1e-18 here; the decreases start at 1e-4)."""
    model, p, held, _ = held_problem(4)
    force = objective_gradient(model, p, p.initial_guess(), feasible=False)[held]
    rounding = 8 * np.finfo(float).eps * np.abs(force).sum()
    previous = None
    for it in make_solver(method, model).iterates(p):
        if previous is not None:
            assert objective_difference(model, p, previous, it.x - previous) <= rounding
        previous = it.x.copy()
        if it.k == 200:
            break


@pytest.mark.parametrize("method", ACCELERATED)
def test_a_cloth_at_rest_on_a_plane_stays_put_with_every_accelerated_solver(method):
    model, plane = lying_sheet(friction=0.5)
    sim = cs.Simulation(model, h=H, effects=[cs.Gravity(GRAVITY), plane],
                        solver=make_solver(method, model, iterations=200, tolerance=1e-6))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sim.run(20)
    assert sim.problem().has_contacts
    assert np.abs(sim.state.positions[:, 1]).max() == 0.0
    assert np.abs(sim.state.velocities).max() < 1e-9


def lying_sheet(contact="hold", friction=0.0):
    model = grid_cloth(6, center=(0.0, 0.0, 0.0))
    plane = cs.Plane((0, 0, 0), (0, 1, 0), friction=friction, contact=contact)
    return model, plane


def test_a_cloth_at_rest_on_a_plane_refactors_nothing():
    model, plane = lying_sheet(friction=0.5)
    sim = cs.Simulation(model, h=H, effects=[cs.Gravity(GRAVITY), plane])
    sim.run(5)
    count = sim.solver.factor_count
    sim.run(30)
    assert sim.solver.factor_count == count
    assert len(plane.hold_contacts(0.0)) >= model.vertex_count
    assert np.abs(sim.state.positions[:, 1]).max() == 0.0


def test_contact_only_pushes_a_lifted_cloth_leaves_the_plane():
    """A sheet on the floor lifted by one corner: the vertices the cloth pulls up are
    released (no adhesion), those still pressed stay on the floor, none goes below it."""
    model, plane = lying_sheet(friction=0.3)
    corner = model.vertex_count - 1
    lift = cs.Pin([corner], motion=lambda t: np.array([0.0, 0.6 * t, 0.0]))
    sim = cs.Simulation(model, h=H, effects=[cs.Gravity(GRAVITY), lift, plane])
    sim.run(30)
    y = sim.state.positions[:, 1]
    assert y.min() >= 0.0
    assert y[corner] == pytest.approx(0.6, abs=1e-9)
    lifted = np.count_nonzero(y > 1e-3)
    assert 3 <= lifted < model.vertex_count - 3
    assert set(np.flatnonzero(y > 1e-3)).isdisjoint(plane.hold_contacts(0.0).vertices)


def test_modes_are_named_and_the_seed_mode_holds_nothing():
    with pytest.raises(InputError, match=r"^sphere\.contact: must be one of 'hold', "
                                         r"'post-solve', got 'glue'"):
        cs.Sphere((0, 0, 0), 1.0, contact="glue")
    model, plane = lying_sheet(contact="post-solve")
    sim = cs.Simulation(model, h=H, effects=[cs.Gravity(GRAVITY), plane])
    sim.run(3)
    assert not sim.problem().has_contacts
    assert plane.describe()["contact"] == "post-solve"


def test_scene_contact_mode_reaches_every_obstacle_and_is_checked():
    doc = parse_toml(builtin_scene_text("drop-on-square"), "drop-on-square.toml")
    for mode in ("hold", "post-solve"):
        scene = Scene.from_dict({**doc, "contact": {"mode": mode}})
        kinds = {e.kind: e.contact for e in scene.build_effects() if hasattr(e, "contact")}
        assert kinds == {"box": mode, "plane": mode}
    assert Scene.from_dict(doc).data["contact"] == {"mode": "hold"}      # the default
    with pytest.raises(SceneError, match=r"contact\.mode: .*'hold'.*'post-solve'"):
        Scene.from_dict({**doc, "contact": {"mode": "glue"}})
    with pytest.raises(SceneError, match=r"effects\[1\]\.contact"):
        Scene.from_dict({**doc, "effects": [doc["effects"][0],
                                            {**doc["effects"][1], "contact": "hold"}]})


MU = 0.5


def tilted_pull(pull, steps=30):
    """A sheet lying on a floor of friction μ = 0.5 under gravity with a horizontal part
    ``pull`` × μ g: per vertex the floor's normal force is m g and the pull m a."""
    model, plane = lying_sheet(friction=MU)
    a = pull * MU * 9.81
    sim = cs.Simulation(model, h=H, effects=[cs.Gravity((a, -9.81, 0.0)), plane])
    records = []
    for _ in range(steps):
        sim.step()
        records.append((sim.state.velocities[:, 0].copy(), sim.solver.factor_count,
                        int(plane._holding.stick.sum())))
    return sim, plane, records


def test_inside_the_friction_cone_a_sheet_sticks_at_rest():
    """Pulled at half of μ m g: static friction holds every vertex; nothing moves, the
    contact set (and so the factor) stays the same after the landing."""
    sim, plane, records = tilted_pull(0.5)
    assert np.abs(sim.state.velocities).max() == 0.0
    assert all(r[2] == sim.model.vertex_count for r in records[2:])
    assert records[-1][1] == records[2][1]


def test_past_the_friction_cone_a_sheet_slides_with_kinetic_friction_from_its_first_step():
    """Pulled at 1.2 μ m g the sheet slips and then slides steadily with acceleration
    a − μ g = 0.2 μ g: friction acts from the first sliding step (opposing the pull, as
    the vertices have no velocity yet) and the slide goes on instead of sticking and
    slipping again (which refactors in every step). Before: no friction in the first
    sliding step, then vertices stuck whenever |v_t| <= μ F_n h / m and slipped again."""
    sim, plane, records = tilted_pull(1.2, steps=40)
    sliding = [k for k, r in enumerate(records) if r[2] == 0]
    start = sliding[0]
    assert sliding == list(range(start, len(records)))          # never sticks again
    assert records[-1][1] == records[start + 1][1]   # one factor for the whole slide
    v = np.array([r[0].mean() for r in records])
    accel = np.diff(v[start + 1:]) / H
    np.testing.assert_allclose(accel, 0.2 * MU * 9.81, rtol=0.05)
    # the first sliding step already has friction: v after it is (a − μ g) h, not a h
    assert v[start] == pytest.approx(0.2 * MU * 9.81 * H, rel=0.05)


@pytest.mark.parametrize("force,kept", [(-1e-4, False), (-1e-2, False), (0.0, True)])
def test_a_held_vertex_pulled_away_at_all_leaves_even_within_the_force_noise(force, kept):
    """Contact only pushes, also within the forces' noise (ContactSet.noise, 1e-3 N here):
    a release margin of NOISE_MARGIN × noise (hysteresis against release chatter) was
    measured and rejected, as it kept 51 vertices clinging to the sphere below its equator
    in drape-sphere at 25²."""
    from clothsim.effects.holding import Holding

    model, plane = lying_sheet(friction=0.0)
    plane.bind(model, H)
    x = model.mesh.vertices.copy()
    plane._holding = Holding(x, np.array([7]), np.array([[0.0, 1.0, 0.0]]))
    plane._holding.planes.forces = np.array([force])
    plane._holding.planes.noise = 1e-3
    state = cs.State(x, np.zeros_like(x), 0.0, 0)
    out = plane.correct_positions(H, state, x)
    assert (7 in plane.hold_contacts(H).vertices) == kept
    assert out[:, 1].min() >= 0.0


@pytest.mark.parametrize("name", ["drop-on-square", "drape-sphere"])
def test_the_contact_scenes_declare_their_damping_and_the_seed_runs_without_it(name):
    """The two contact scenes declare Anderson acceleration: drop-on-square 30 iterations,
    rigid damping 0.1 and 4 s, drape-sphere 50 iterations, rigid damping 0.2 and 5 s,
    which its finer cloths need (docs/effects.md, "Coming to rest"); the seed had no
    damping, 10 local/global iterations and 3 s: with [contact] mode = "post-solve", the
    coefficient set to 0 and the seed's solver and frames (the documented --set) the run
    is the seed's scene without the damping effect, bit for bit."""
    doc = parse_toml(builtin_scene_text(name), f"{name}.toml")
    c, k, frames = {"drop-on-square": (0.1, 30, 120), "drape-sphere": (0.2, 50, 210)}[name]
    assert doc["effects"][3] == {"kind": "damping", "model": "rigid", "coefficient": c}
    assert doc["solver"] == {"method": "anderson", "iterations": k}
    assert doc["scene"]["frames"] == frames
    seed = {**doc, "contact": {"mode": "post-solve"},
            "solver": {**doc["solver"], "method": "local-global", "iterations": 10},
            "scene": {**doc["scene"], "frames": 90}}
    zero = {**seed, "effects": doc["effects"][:3] + [{**doc["effects"][3], "coefficient": 0.0}]}
    none = {**seed, "effects": doc["effects"][:3]}
    runs = []
    for d in (zero, none, seed):
        sim = Scene.from_dict(d).build_simulation()
        sim.run(15)
        runs.append(sim.state.velocities)
    np.testing.assert_array_equal(runs[0], runs[1])
    assert np.abs(runs[2] - runs[1]).max() > 1e-6          # the declared damping acts


def test_a_layer_of_normals_all_parallel_to_earlier_ones_is_dropped_not_indexed():
    """A vertex held twice along the same normal (two parallel planes), then along another:
    the second layer keeps nothing, and the third must still be orthogonalized (it raised
    IndexError on an empty layer: drape-sphere under 1e60 m/s² gravity at frame 5)."""
    from clothsim.contacts import contact_basis

    ey, ex = np.array([0.0, 1.0, 0.0]), np.array([1.0, 0.0, 0.0])
    layers = contact_basis(np.array([4, 4, 4, 7]), np.array([ey, ey, ex + ey, ex]))
    assert [v.tolist() for v, _ in layers] == [[4, 7], [4]]
    np.testing.assert_allclose(layers[0][1], [ey, ex])
    np.testing.assert_allclose(layers[1][1], [ex])
