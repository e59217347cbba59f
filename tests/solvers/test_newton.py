"""Newton: the reference solver, its iterates and its indefinite-Hessian handling."""

import warnings

import numpy as np
import pytest

from clothsim.errors import InputError
from clothsim.solvers import NewtonSolver, objective_gradient

from .cases import buckling_step, convex_step


def test_newton_iterates_start_at_y_and_reach_the_floor():
    model, problem = convex_step()
    its = list(NewtonSolver(model).iterates(problem))
    assert its[0].k == 0 and np.array_equal(its[0].x, problem.initial_guess())
    assert its[-1].gradient_norm < 1e-10 * its[0].gradient_norm  # at its rounding floor
    assert len(its) < 12  # quadratic convergence


@pytest.mark.parametrize("indefinite", ["shift", "project"])
def test_newton_on_buckling_steps_converges_in_few_iterations(indefinite):
    """The sheet held at two corners buckles (H indefinite at y); Newton reaches its
    rounding floor in a few dozen iterations, not hundreds."""
    model, problem = buckling_step()
    solver = NewtonSolver(model, iterations=60, tolerance=1e-13, indefinite=indefinite)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no ConvergenceWarning
        res = solver.solve(problem)
    assert res.converged and res.iterations < 40, res.iterations
    g = np.linalg.norm(objective_gradient(model, problem, res.x))
    g0 = np.linalg.norm(objective_gradient(model, problem, problem.initial_guess()))
    assert g < 1e-10 * g0


def test_newton_stalled_at_rest_counts_as_converged():
    """Started at its own solution, Newton cannot improve: converged, no warning."""
    model, problem = convex_step()
    x_star = NewtonSolver(model).solve(problem).x
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        res = NewtonSolver(model, tolerance=1e-15).solve(problem, x0=x_star)
    assert res.converged and res.iterations <= 2


def test_newton_rejects_unknown_indefinite_option():
    model, _ = convex_step(4)
    with pytest.raises(InputError, match="solver.indefinite"):
        NewtonSolver(model, indefinite="flip")


def flat_compressed_strip():
    """The 9 × 3 strip of tests/ports whose springs want to be 30 % longer, both ends
    pinned, at rest and exactly flat: y is flat, so the gradient has no out-of-plane part
    and the flat stationary point is a saddle (the strip must buckle)."""
    from tests.ports.test_check import compressed_strip

    sim = compressed_strip()
    return sim.model, sim.problem()


def test_newton_leaves_the_saddle_of_a_flat_compressed_strip():
    model, problem = flat_compressed_strip()
    solver = NewtonSolver(model, iterations=100, tolerance=1e-15)  # to the rounding floor
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        res = solver.solve(problem)
    assert res.converged and res.certified and res.positive_definite and res.at_floor
    assert solver.escapes >= 1
    assert np.abs(res.x[:, 2]).max() > 0.05  # buckled out of the plane
    assert solver.smallest_eigenvalue(problem, res.x) > 0.0  # dense λ_min: a minimum
    # the flat stationary point it left is a saddle: with the old rule it was the answer
    flat = NewtonSolver(model, iterations=100, tolerance=1e-13, indefinite="project")
    x_flat = flat.solve(problem).x
    assert np.abs(x_flat[:, 2]).max() == 0.0
    assert solver.smallest_eigenvalue(problem, x_flat) < 0.0


def test_newton_result_is_not_certified_when_stopped_early():
    model, problem = flat_compressed_strip()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = NewtonSolver(model, iterations=2, tolerance=1e-13).solve(problem)
    assert not res.converged and not res.certified and not res.at_floor


def test_newton_reuses_one_symbolic_analysis_and_never_uses_lu(monkeypatch):
    """Every factorization of a buckling step (shifted or not) and of later steps shares
    one CHOLMOD analysis; no sparse LU runs."""
    import scipy.sparse.linalg as spla

    from clothsim.factorization import cholmod_available

    if not cholmod_available():
        pytest.skip("needs CHOLMOD (scikit-sparse)")

    def no_lu(*args, **kwargs):
        raise AssertionError("splu called")

    monkeypatch.setattr(spla, "splu", no_lu)
    model, problem = buckling_step()
    solver = NewtonSolver(model, iterations=60, tolerance=1e-13)
    res = solver.solve(problem)
    res2 = solver.solve(problem, x0=problem.x)
    assert res.certified and res2.certified
    assert solver.factor_count > 8 and solver._cholesky.analyses == 1


def test_newton_on_a_scene_without_springs():
    """A scene with no [springs] section: the Hessian is assembled from masses alone."""
    from clothsim.scene import Scene

    scene = Scene.from_dict({"scene": {"name": "bare", "frames": 1},
                             "cloth": {"resolution": [3, 3]},
                             "effects": [{"kind": "gravity", "acceleration": [0, -9.81, 0]},
                                         {"kind": "pin", "vertices": [0]}]})
    sim = scene.build_simulation(method="newton", iterations=20, tolerance=1e-15)
    res = NewtonSolver(sim.model, tolerance=1e-15).solve(sim.problem())
    assert res.converged and res.positive_definite and res.iterations <= 3
