"""The helpers around a factor: one thread for BLAS and OpenMP, and the in-place product."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from threadpoolctl import threadpool_info

from clothsim.factorization import cholmod_available, single_threaded, spmv_add
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
