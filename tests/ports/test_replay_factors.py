"""The check's replays share factors (clothsim.ports.replays.Factors): bit for bit the
replays of unshared factors, with fewer factorizations."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from clothsim.model import Model
from clothsim.ports.hypotheses import StepData
from clothsim.ports.replays import Factors, refine, replay
from clothsim.solvers import make_solver
from clothsim.springs import Springs

from ..test_held_contacts import held_problem


def changed(model, *, stiffness=1.0, rest=1.0, mass=1.0):
    """``model`` with its stiffnesses, rest lengths and masses scaled."""
    sp = model.springs
    springs = Springs(sp.spring_vertices, stiffness * sp.spring_stiffness,
                      rest * sp.spring_rest_length, sp.spring_family, sp.vertex_count,
                      sp.spring_damping)
    return Model(model.mesh, springs, mass * model.vertex_mass)


def replays(model, problem):
    """(model, problem) of a cause search: changed forces and rest lengths (the scene's
    matrix), a changed stiffness, mass and h (other matrices), and the scene's again."""
    heavier = dataclasses.replace(problem, f_ext=2.0 * problem.f_ext)
    return [(model, problem), (model, heavier), (changed(model, rest=1.01), problem),
            (changed(model, stiffness=1.5), problem), (changed(model, mass=2.0), heavier),
            (model, dataclasses.replace(problem, h=problem.h / 2)),
            (changed(model, rest=0.99), heavier), (model, problem)]


@pytest.mark.parametrize("method", ["local-global", "anderson", "lbfgs", "chebyshev"])
@pytest.mark.parametrize("contacts", [False, True], ids=["free", "held"])
def test_shared_factors_give_the_replays_of_unshared_ones(method, contacts):
    model, problem, _, _ = held_problem(n=5)
    if not contacts:
        problem = dataclasses.replace(problem, contact_vertices=np.zeros(0, int),
                                      contact_normals=np.zeros((0, 3)),
                                      contact_offsets=np.zeros(0))
    assert problem.has_contacts == contacts
    factors, factored = Factors(), []
    for m, p in replays(model, problem):
        alone = make_solver(method, m, iterations=10).solve(p).x
        solver = make_solver(method, m, iterations=10)
        shared = factors.solve(solver, m, p).x
        np.testing.assert_array_equal(shared, alone)
        factored.append(solver.factor_count)
    # the scene's matrix is factored once, by the first replay; the others take it
    assert factored[0] >= 1 and factored[1] == factored[2] == factored[6] == 0, factored
    assert factored[3] >= 1 and factored[4] >= 1 and factored[5] >= 1, factored
    assert factored[7] == 0, factored   # still kept: 4 matrices since


def test_the_least_recently_used_factor_is_dropped():
    model, problem, _, _ = held_problem(n=4)
    factors = Factors(size=2)
    scales = [1.0, 2.0, 3.0, 1.0, 3.0]   # 1, 2, 3: 1 dropped; 1 again: 2 dropped; 3 kept
    counts = []
    for s in scales:
        m = changed(model, stiffness=s)
        solver = make_solver("local-global", m, iterations=3)
        factors.solve(solver, m, problem)
        counts.append(solver.factor_count)
    assert [c > 0 for c in counts] == [True, True, True, True, False], counts


def test_a_large_cloth_keeps_one_factor(monkeypatch):
    """SHARED_VERTICES bounds the vertices of the factors kept: a cloth of more than half
    of them keeps one (the last), at least."""
    import clothsim.ports.replays as replays

    model, problem, _, _ = held_problem(n=4)
    monkeypatch.setattr(replays, "SHARED_VERTICES", 2 * model.vertex_count - 1)
    factors, counts = Factors(), []
    for s in [1.0, 2.0, 2.0, 1.0]:
        m = changed(model, stiffness=s)
        solver = make_solver("local-global", m, iterations=3)
        factors.solve(solver, m, problem)
        counts.append(solver.factor_count)
    assert [c > 0 for c in counts] == [True, True, False, True], counts


def test_a_solver_without_a_shared_factor_solves_as_it_does():
    # Newton factors its own Hessians: passed through; size 0 shares nothing
    model, problem, _, _ = held_problem(n=4)
    newton = make_solver("newton", model, iterations=30, tolerance=1e-8)
    x = Factors().solve(newton, model, problem).x
    np.testing.assert_array_equal(x, make_solver("newton", model, iterations=30, tolerance=1e-8)
                                  .solve(problem).x)
    none = Factors(size=0)
    for _ in range(2):
        solver = make_solver("local-global", model, iterations=3)
        none.solve(solver, model, problem)
        assert solver.factor_count >= 1


@pytest.mark.parametrize("hyp, theta0", [("stiffness", [0.3]), ("gravity", [0.0, -1.0, 0.0]),
                                         ("rest lengths", [-3.0])])   # a scale below −1
def test_refine_gives_the_distances_its_replays_measured(hyp, theta0):
    """refine(..., distances=True): the distances :func:`replay` gives at the returned θ,
    from the refinement's own replays, bit for bit (the cause search takes them instead
    of replaying the fitted steps again)."""
    model, problem, _, _ = held_problem(n=5)

    def solve(m, p):
        return make_solver("local-global", m, iterations=10).solve(p).x

    port = dataclasses.replace(problem, f_ext=1.1 * problem.f_ext)   # gravity × 1.1
    later = dataclasses.replace(problem, y=problem.y + 1e-3)
    steps = [StepData(k, model, p, solve(model, dataclasses.replace(p, f_ext=port.f_ext)),
                      1.0, 1e-9, 1.0, solve=solve) for k, p in ((0, problem), (1, later))]
    theta, d = refine(steps, hyp, np.array(theta0), 3, distances=True)
    np.testing.assert_array_equal(theta, refine(steps, hyp, np.array(theta0), 3))
    assert d == {s.k: replay(s, hyp, theta) for s in steps}
    assert (min(d.values()) < 1e-12) == (hyp == "gravity"), d   # the force reproduces
