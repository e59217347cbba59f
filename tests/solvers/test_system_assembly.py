"""The global step's factored system assembled without format round trips (issue 33): A_FF
taken in CSC from A's free columns, A_FP from its pinned ones, ‖A‖₁ without a copy of A —
the very arrays of the conversions they replace (A → CSR → rows → columns → CSC), so the
factor and every step are bit for bit the same."""

import numpy as np
import pytest
import scipy.sparse as sp

import clothsim as cs
from clothsim import matrices
from clothsim.factorization import Factor, _norm1
from clothsim.gallery import hanging_cloth


def _old_blocks(A, free, fixed):
    rows = A.tocsr()[free]
    A_FF = sp.csc_matrix(rows[:, free])
    A_FF.sort_indices()
    return A_FF, rows[:, fixed].tocsr()


def _same(a, b):
    assert a.format == b.format and a.shape == b.shape
    for name in ("data", "indices", "indptr"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))


@pytest.mark.parametrize("pins", ["constraint", "penalty", "none", "scattered"])
def test_free_blocks_are_the_old_arrays(pins):
    model, (gravity, pin) = hanging_cloth(17, pin_method="penalty" if pins == "penalty"
                                          else "constraint")
    effects = {"constraint": [gravity, pin], "penalty": [gravity, pin], "none": [gravity],
               "scattered": [gravity, cs.Pin([0, 5, 6, 7, 100, 288])]}[pins]
    sim = cs.Simulation(model, h=1 / 30, effects=effects)
    sim.prepare()
    sysf = sim.solver._cache
    old_FF, old_FP = _old_blocks(sysf.A, sysf.free, sysf.fixed)
    _same(sysf.A_FF_factor.A, old_FF)
    _same(sysf.A_FP, old_FP)
    # the factor of the old arrays solves bit for bit as the one made
    b = np.random.default_rng(1).standard_normal((3, len(sysf.free)))
    np.testing.assert_array_equal(sysf.A_FF_factor.solve_columns(b),
                                  Factor(old_FF, cholmod_mode=sysf.A_FF_factor.cholmod_mode)
                                  .solve_columns(b))


def test_norm1_is_scipys_column_sum():
    model, _ = hanging_cloth(9)
    A = matrices.system_matrix(model, 1 / 30)
    rng = np.random.default_rng(0)
    B = sp.random(40, 30, density=0.1, format="csc", random_state=rng) - 0.5 * sp.eye(
        40, 30, format="csc")
    B = sp.hstack([B[:, :7], sp.csc_matrix((40, 1)), B[:, 8:]], format="csc")  # empty column
    dup = sp.csc_matrix((np.array([1.0, -2.5, 4.0]), np.array([1, 1, 0]),
                         np.array([0, 2, 3])), shape=(2, 2))  # duplicates: |1 - 2.5| = 1.5
    for M in (A, B, dup, sp.csc_matrix((3, 3))):
        want = float(abs(M.copy()).sum(axis=0).max()) if M.shape[1] else 0.0
        assert _norm1(M.copy()) == want
    assert _norm1(dup) == 4.0
