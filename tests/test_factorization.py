"""The helpers around a factor: one thread for BLAS and OpenMP, and the in-place product."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from threadpoolctl import threadpool_info

from clothsim import factorization, matrices
from clothsim.factorization import Factor, cholmod_available, single_threaded, spmv_add
from clothsim.gallery import GRAVITY, grid_cloth
from clothsim.problem import StepProblem
from clothsim.solvers import LocalGlobalSolver


def pools() -> dict[str, int]:
    """Thread count of every BLAS and OpenMP pool loaded, by library path."""
    return {p["filepath"]: p["num_threads"] for p in threadpool_info()
            if p["user_api"] in ("blas", "openmp")}


def test_single_threaded_limits_every_pool_and_restores_them():
    cholmod_available()       # CHOLMOD's libraries loaded (single_threaded loads them too)
    before = pools()
    with single_threaded():
        inside = pools()
    assert inside and set(inside.values()) == {1}
    assert pools() == before
    if cholmod_available():   # CHOLMOD's OpenMP runtime is among the limited pools
        with single_threaded():
            kinds = {p["user_api"] for p in threadpool_info() if p["num_threads"] == 1}
        assert "openmp" in kinds


def test_local_global_solve_and_its_factorization_run_single_threaded():
    seen = []

    class Watching(LocalGlobalSolver):
        def _factor(self, problem):
            seen.append(("factor", set(pools().values())))
            return super()._factor(problem)

        def iterates(self, problem, x0=None):
            seen.append(("iterate", set(pools().values())))
            yield from super().iterates(problem, x0)

    model = grid_cloth(5, k=100.0)
    x = model.mesh.vertices
    problem = StepProblem(1 / 30, x, np.zeros_like(x), f_ext=model.vertex_mass[:, None] * GRAVITY)
    Watching(model, iterations=2).solve(problem)
    assert [kind for kind, _ in seen] == ["iterate", "factor"]
    assert all(counts == {1} for _, counts in seen)


@pytest.mark.parametrize("shape", [(5, 7), (1, 1), (4, 0)])
def test_spmv_add_accumulates_like_the_product(shape):
    rng = np.random.default_rng(sum(shape))
    A = sp.random(*shape, density=0.5, format="csr", random_state=rng)
    v = rng.normal(size=shape[1])
    out = rng.normal(size=shape[0])
    expected = out + A @ v
    spmv_add(A, v, out)
    np.testing.assert_allclose(out, expected, rtol=1e-15, atol=1e-15)


@pytest.mark.parametrize("backend", ["splu", "cholmod"])
def test_a_known_eigenvalue_floor_bounds_the_condition_and_skips_the_estimate(backend):
    """Factor(eigenvalue_floor=λ): √n ‖A‖₁ / λ bounds the exact cond₁ from above; at or
    below the warning threshold the estimate (its solves) is skipped, above it it runs."""
    import warnings

    from clothsim.errors import ConditioningWarning
    from clothsim.factorization import CONDITION_WARNING_THRESHOLD, Factor

    if backend == "cholmod" and not cholmod_available():
        pytest.skip("CHOLMOD (scikit-sparse) is not installed")
    rng = np.random.default_rng(1)
    n = 40
    for mass_scale in (1.0, 1e-15):              # well conditioned, then cond ≈ 1e16
        m = rng.uniform(0.5, 2.0, n) * mass_scale
        m[0] = mass_scale * 0.5
        lap = sp.diags([-np.ones(n - 1), 2 * np.ones(n), -np.ones(n - 1)], [-1, 0, 1])
        A = (sp.diags(m) + 1e-3 * lap).tocsc()
        exact = np.linalg.cond(A.toarray(), 1)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", ConditioningWarning)
            f = Factor(A, backend=backend, eigenvalue_floor=m.min())
        assert f.condition_bound >= exact * (1 - 1e-12)
        proven = f.condition_bound <= CONDITION_WARNING_THRESHOLD
        assert proven == (mass_scale == 1.0)
        assert ("condition_estimate" in f.__dict__) == (not proven)   # the estimate ran
        assert any(issubclass(w.category, ConditioningWarning) for w in caught) == (
            exact > CONDITION_WARNING_THRESHOLD)
    plain = Factor(A, backend=backend)            # without a floor: always estimated
    assert plain.condition_bound is None and "condition_estimate" in plain.__dict__


needs_cholmod = pytest.mark.skipif(not cholmod_available(), reason="CHOLMOD not installed")


@needs_cholmod
@pytest.mark.parametrize("cores, threshold, factor, solve", [
    (2, 0, {2}, {1}), (8, 0, {2}, {1}), (1, 0, {1}, {1}), (2, 10 ** 9, {1}, {1})])
@pytest.mark.parametrize("threads", [{"factor": 2, "solve": 1}, {"factor": 2, "solve": 2}])
def test_cholmod_runs_on_more_threads_for_large_matrices_only(monkeypatch, cores, threshold,
                                                             factor, solve, threads):
    """Inside the step's one-thread limit, CHOLMOD's factorization (and its solves when
    asked) run on CHOLMOD_THREADS threads from THREADED_FROM rows (at most the cores there
    are), and the limit is one thread again around them; the answers agree to rounding."""
    import sksparse.cholmod

    monkeypatch.setattr(factorization, "THREADED_FROM", threshold)
    monkeypatch.setattr(factorization, "CHOLMOD_THREADS", threads)
    monkeypatch.setattr(factorization, "_cores", lambda: cores)
    if threads["solve"] == 2:
        solve = factor
    seen = []
    real = sksparse.cholmod.cholesky

    def watched(*args, **kw):
        seen.append(set(pools().values()))
        return real(*args, **kw)

    monkeypatch.setattr(sksparse.cholmod, "cholesky", watched)
    A = matrices.system_matrix(grid_cloth(40, k=100.0), 1 / 30).tocsc()   # a cloth's M + h² L
    b = np.random.default_rng(1).normal(size=(3, A.shape[0]))
    for mode in ("supernodal", "simplicial"):
        with single_threaded():
            f = Factor(A, backend="cholmod", cholmod_mode=mode, check_conditioning=False)
            f._factor = lambda rhs, inner=f._factor: (seen.append(set(pools().values())),
                                                      inner(rhs))[1]
            x = f.solve_columns(b)
            after = set(pools().values())
        assert seen[-2:] == [factor, solve] and after == {1}
        ref = np.linalg.solve(A.toarray(), b.T).T
        np.testing.assert_allclose(x, ref, rtol=1e-10, atol=1e-12 * np.abs(ref).max())
