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


def test_local_global_reaches_the_constrained_minimum_an_independent_solver_finds():
    """SLSQP (scipy) on g with the plane and pin constraints written out, against
    local/global's held global step and Newton's projected steps."""
    model, p, held, normal = held_problem(3)
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
