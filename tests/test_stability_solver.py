"""Numerical stability of the solvers: stiffness, large steps, degenerate springs,
extreme deformation, mass extremes, and the system matrix / factorization checks.

Each test states its pass criterion as a figure. The ``measure_*`` helpers return the
measured figures; ``benchmarks/stability_figures.py`` prints them for docs/stability.md.
"""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import given, settings
from hypothesis import strategies as st

import clothsim as cs
from benchmarks.measure_stability import (
    degenerate_model,
    exact_condition,
    measure_degenerate_monotone,
    measure_energy_increase,
    measure_release,
    measure_stiffness_sweep,
    measure_symmetry,
    measure_zero_rest_collapse,
    one_step,
)
from clothsim import matrices
from clothsim.errors import ConditioningWarning, ConvergenceWarning, FactorizationError
from clothsim.factorization import CONDITION_WARNING_THRESHOLD, Factor, cholmod_available
from clothsim.gallery import GRAVITY
from clothsim.gallery import grid_cloth as make_grid_model
from clothsim.solvers import LocalGlobalSolver

BACKENDS = ["splu", pytest.param("cholmod", marks=pytest.mark.skipif(
    not cholmod_available(), reason="scikit-sparse (CHOLMOD) not installed"))]


def test_stiffness_sweep_iterations_grow_and_limit_warns():
    rows = measure_stiffness_sweep()
    its = [r["iterations"] for r in rows]
    res = [r["residual"] for r in rows]
    assert all(r["finite"] for r in rows)
    assert all(np.diff(its) >= 0), f"iterations to 1e-6 not non-decreasing in k: {its}"
    assert its[-1] > its[0]
    capped = [r for r in rows if not r["converged"]]
    assert capped, "expected the stiffest springs to hit the iteration limit"
    # beyond the limit, the residual left over grows with k
    assert all(np.diff([r["residual"] for r in capped]) >= 0), res
    for r in rows:
        if r["converged"]:
            assert r["residual"] <= 1e-6 and not r["warnings"]
        else:  # a ConvergenceWarning names the residual it stopped at
            assert len(r["warnings"]) == 1
            assert f"{r['residual']:.3e}" in r["warnings"][0]


@settings(max_examples=12, deadline=None)
@given(log_k=st.floats(2.0, 8.0))
def test_stiffness_any_k_finite_and_warns_iff_not_converged(log_k):
    k = 10.0 ** log_k
    sim, rec, caught = one_step(k, iterations=40)
    assert np.isfinite(sim.state.positions).all()
    assert rec.converged == (rec.residual <= 1e-6)
    assert len(caught) == (0 if rec.converged else 1)
    if caught:
        assert re.search(r"relative residual \d\.\d{3}e[+-]\d+ after 40 iterations",
                         str(caught[0].message))


@pytest.mark.parametrize("h", [1 / 24, 0.1, 1.0])
def test_large_steps_finite_and_never_gain_energy(h):
    out = measure_energy_increase(h)
    assert out["finite"]
    # pins fixed, gravity conservative: no external work, implicit Euler only dissipates
    assert out["max_relative_increase"] <= 1e-12, out
    assert out["energy_lost"] > 0


def test_coincident_vertices_objective_monotone_and_finite():
    out = measure_degenerate_monotone()
    assert out["max_relative_increase"] <= 1e-12, out


def test_local_step_keeps_a_length_r_direction_where_ends_coincide():
    model, x0 = degenerate_model()
    solver = LocalGlobalSolver(model)
    d = solver.local_step(x0)
    r = model.springs.spring_rest_length
    assert np.isfinite(d).all()
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), r, rtol=1e-14, atol=0)


def test_unloaded_zero_rest_spring_collapses():
    # implicit Euler shrinks the amplitude by (1 + ω²h²)^(-1/2) = 1/44.7 per step here
    assert measure_zero_rest_collapse() < 1e-9


@pytest.mark.parametrize("scale", [10.0, 0.01])
def test_extreme_stretch_or_crush_returns_to_rest(scale):
    out = measure_release(scale)
    assert out["finite"]
    assert out["start_strain"] > 0.9
    assert out["strain"] < 1e-3, out


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("mass, k, warns", [(1e-9, 800.0, False), (1e-9, 1e5, True),
                                            (1e3, 800.0, False), (1e3, 1e8, False)])
def test_mass_extremes_finite_and_warn_only_past_threshold(backend, mass, k, warns):
    model = make_grid_model(4, k=k, vertex_mass=mass)
    cond = exact_condition(model, 1 / 30)
    assert (cond > 1e12) == warns, cond  # 1.5e10, 1.8e12, 1.01 and 1.8e3 here

    def run():
        sim = cs.Simulation(model, h=1 / 30, effects=[cs.Gravity(GRAVITY)], backend=backend)
        sim.run(3)
        return sim

    if warns:
        with pytest.warns(ConditioningWarning, match=r"cond1 estimate \d\.\d+e\+\d+ > 1e\+12"):
            sim = run()
    else:
        sim = run()  # a ConditioningWarning here is an error (pyproject filterwarnings)
    assert np.isfinite(sim.state.positions).all()
    assert np.isfinite(sim.state.velocities).all()


@settings(max_examples=15, deadline=None)
@given(log_mass=st.floats(-9.0, 3.0))
def test_conditioning_warning_fires_iff_condition_passes_threshold(log_mass):
    model = make_grid_model(4, vertex_mass=10.0 ** log_mass)
    A = matrices.system_matrix(model, 1 / 30)
    cond = exact_condition(model, 1 / 30)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ConditioningWarning)
        factor = Factor(A, backend="splu")
    fired = any(issubclass(w.category, ConditioningWarning) for w in caught)
    # Higham's estimate is a lower bound (up to rounding of A⁻¹: cond·eps), within 3× here
    assert cond / 3 <= factor.condition_estimate <= cond * (1 + 1e-6)
    if cond > 3 * CONDITION_WARNING_THRESHOLD:
        assert fired
    if cond <= CONDITION_WARNING_THRESHOLD:
        assert not fired


def test_system_matrix_symmetric_and_positive_definite():
    assert measure_symmetry() <= 1e-14
    model = make_grid_model(5)
    A = matrices.system_matrix(model, 1 / 30).toarray()
    assert np.linalg.eigvalsh(A).min() > 0
    np.testing.assert_allclose(np.linalg.eigvalsh(A).min(), model.vertex_mass[0], rtol=1e-9)


INDEFINITE = {
    "swap": [[0.0, 1.0], [1.0, 0.0]],          # needs an off-diagonal pivot
    "saddle": [[1.0, 2.0], [2.0, 1.0]],        # eigenvalues 3, −1, positive diagonal
    "4x4": [[2.0, -1.0, 0.0, 0.0], [-1.0, -3.0, 1.0, 0.0], [0.0, 1.0, 2.0, 0.0],
            [0.0, 0.0, 0.0, 1.0]],
}


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("name", [*INDEFINITE, "shifted-system", "singular"])
def test_indefinite_matrix_raises_factorization_error(backend, name):
    if name == "shifted-system":  # M + h²L minus 2 m I: one negative eigenvalue, n = 25
        model = make_grid_model(5)
        A = matrices.system_matrix(model, 1 / 30) - 2 * model.vertex_mass[0] * sp.identity(25)
    elif name == "singular":
        A = sp.csc_matrix(np.array([[1.0, 1.0], [1.0, 1.0]]))
    else:
        A = sp.csc_matrix(np.array(INDEFINITE[name]))
    with pytest.raises(FactorizationError, match="not positive definite|singular"):
        Factor(A, backend=backend, check_conditioning=False)


@pytest.mark.parametrize("backend", BACKENDS)
def test_positive_definite_system_factors_and_solves(backend):
    model = make_grid_model(5)
    A = matrices.system_matrix(model, 1 / 30)
    b = np.random.default_rng(1).standard_normal((25, 3))
    x = Factor(A, backend=backend).solve(b)
    assert np.abs(A @ x - b).max() <= 1e-12 * np.abs(b).max()


# -- warnings are errors in the test suite ---------------------------------------------------
def capped_solve():
    model = make_grid_model(4, k=1e6)
    sim = cs.Simulation(model, h=1 / 30, effects=[cs.Gravity(GRAVITY), cs.Pin([0, 3])],
                        iterations=2, tolerance=1e-12)
    return sim.step()


def test_pytest_warns_catches_convergence_warning():
    with pytest.warns(ConvergenceWarning, match="after 2 iterations is above the tolerance"):
        capped_solve()


def test_uncaught_clothsim_warning_is_an_error_in_this_suite():
    # pyproject's filterwarnings turns every ClothsimWarning into an exception here
    with pytest.raises(ConvergenceWarning):
        capped_solve()
    # the same semantics, set up explicitly: "error" raises, "ignore" lets the step finish
    with warnings.catch_warnings():
        warnings.simplefilter("error", cs.ClothsimWarning)
        with pytest.raises(ConvergenceWarning):
            capped_solve()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", cs.ClothsimWarning)
        assert not capped_solve().converged
