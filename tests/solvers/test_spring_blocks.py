"""Spring vectors by strided slices (clothsim.solvers.spring_blocks): the takes' values.

The blocks must describe their springs exactly, the gather must equal two takes bit for bit
on spring lists it was not written for (reversed, shuffled, mixed with irregular springs,
rectangular grids, a triangle mesh), and whole steps must not change by one bit.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import clothsim as cs
from clothsim.gallery import grid_cloth, top_corners
from clothsim.solvers import make_solver
from clothsim.solvers import spring_blocks as sb
from clothsim.solvers.spring_blocks import SpringGather, affine_blocks


def takes(xT, a, b):
    return xT[:, a] - xT[:, b]


def expand(blocks):
    """The springs' ends each block says it holds, with their spring indices."""
    ks, as_, bs = [], [], []
    for k0, rows, length, a0, ra, ca, b0, rb, cb in blocks:
        i, j = np.divmod(np.arange(rows * length), length)
        ks.append(k0 + i * length + j)
        as_.append(a0 + i * ra + j * ca)
        bs.append(b0 + i * rb + j * cb)
    if not ks:
        return (np.zeros(0, int),) * 3
    return np.concatenate(ks), np.concatenate(as_), np.concatenate(bs)


def check(a, b, n, k=3, seed=0):
    """Blocks exact, covering with the rest; the gather equal to the takes bit for bit."""
    a, b = np.asarray(a, np.intp), np.asarray(b, np.intp)
    blocks, rest = affine_blocks(a, b)
    k_, a_, b_ = expand(blocks)
    np.testing.assert_array_equal(a[k_], a_)
    np.testing.assert_array_equal(b[k_], b_)
    assert np.array_equal(np.sort(np.concatenate([k_, rest])), np.arange(len(a)))
    assert all(rows * length >= sb.MIN_BLOCK for _, rows, length, *_ in blocks)
    xT = np.random.default_rng(seed).normal(size=(k, n)) * 10.0 ** np.arange(k)[:, None]
    pT = np.full((k, len(a)), np.nan)
    gather = SpringGather(a, b)
    gather(xT, pT)
    assert np.array_equal(pT, takes(xT, a, b))
    return gather


@pytest.mark.parametrize("n, pattern", [(65, "alternate"), (65, "every"), (129, "alternate")])
def test_grid_cloths_are_all_blocks(n, pattern):
    model = grid_cloth(n, bending_pattern=pattern)
    a, b = model.springs.spring_vertices.T
    gather = check(a, b, model.vertex_count)
    assert len(gather.blocks) == 6 and gather._rest is None   # one per family direction


def test_rectangular_grid_reversed_and_offset_orders():
    mesh = cs.grid(97, 41, size=(2.0, 1.0), plane="xy")
    springs = cs.grid_springs(mesh, structural=1.0, shear=1.0, bending=0.1,
                              bending_pattern="alternate")
    a, b = springs.spring_vertices.T
    n = mesh.vertices.shape[0]
    assert check(a, b, n).blocks
    assert check(a[::-1], b[::-1], n).blocks            # negative strides
    assert check(b, a, n).blocks                        # ends swapped
    assert check(a + 7, b + 7, n + 7).blocks            # not starting at vertex 0


def test_irregular_springs_are_taken():
    rng = np.random.default_rng(1)
    model = grid_cloth(65, bending_pattern="every")
    a, b = model.springs.spring_vertices.T
    perm = rng.permutation(len(a))
    assert not check(a[perm], b[perm], model.vertex_count).blocks      # shuffled: no rows
    mesh = cs.grid(40, 40, size=(1.0, 1.0))           # a triangle mesh's edges, whatever order
    springs = cs.mesh_springs(mesh, structural=1.0, bending=0.1)
    check(*springs.spring_vertices.T, mesh.vertices.shape[0])
    # a grid's families with a few irregular springs among them: blocks plus a rest
    extra = rng.integers(0, model.vertex_count, size=(len(a) // 20, 2))
    at = np.concatenate([a[:len(a) // 2], extra[:, 0], a[len(a) // 2:]])
    bt = np.concatenate([b[:len(a) // 2], extra[:, 1], b[len(a) // 2:]])
    gather = check(at, bt, model.vertex_count)
    assert gather.blocks and gather._rest is not None


def test_other_layouts_fall_back_to_takes():
    model = grid_cloth(65, bending_pattern="alternate")
    a, b = model.springs.spring_vertices.T
    gather = SpringGather(a, b)
    n, s = model.vertex_count, len(a)
    x = np.random.default_rng(2).normal(size=(n, 3))
    pT = np.empty((3, s))
    gather(x.T, pT)                                     # a transposed view: not C-contiguous
    assert np.array_equal(pT, takes(x.T, a, b))
    wide = np.empty((3, 2 * s))
    gather(np.ascontiguousarray(x.T), wide[:, ::2])     # strided output
    assert np.array_equal(wide[:, ::2], takes(x.T, a, b))
    check(a, b, n, k=1)                                 # one row of positions


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.integers(1, 40), st.integers(1, 70), st.integers(-3, 3),
                          st.integers(-3, 3), st.integers(-90, 90), st.integers(-90, 90)),
                min_size=1, max_size=6),
       st.integers(0, 300))
def test_random_affine_families(families, noise):
    """Families of random shapes and steps (some too small for a block), with noise springs."""
    parts_a, parts_b = [], []
    for rows, length, ca, cb, ra, rb in families:
        i, j = np.divmod(np.arange(rows * length), length)
        parts_a.append(i * ra + j * ca)
        parts_b.append(i * rb + j * cb + 5)
    rng = np.random.default_rng(noise)
    parts_a.append(rng.integers(0, 500, noise))
    parts_b.append(rng.integers(0, 500, noise))
    a, b = np.concatenate(parts_a), np.concatenate(parts_b)
    low = min(a.min(), b.min())
    a, b = a - low, b - low
    check(a, b, int(max(a.max(), b.max())) + 1)


@pytest.mark.parametrize("method", ["local-global", "anderson", "lbfgs"])
def test_steps_are_bit_for_bit_the_takes(method, monkeypatch):
    """A whole step (energy comparisons included) with the blocks, then without them."""
    model = grid_cloth(65, k=800.0, plane="xz", center=(0.0, 1.0, 0.0),
                       bending_pattern="alternate")
    sim = cs.Simulation(model, h=1 / 30, iterations=10, initial_guess="x_n",
                        effects=[cs.Gravity((0.0, -9.81, 0.0)), cs.Pin(top_corners(65, "xz"))])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sim.run(2)
    problem = sim.problem()
    results = []
    for blocks in (True, False):
        solver = make_solver(method, model, iterations=8)
        if not blocks:
            solver._dirs._gather.blocks = []
        else:
            assert solver._dirs._gather.blocks
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            results.append(solver.solve(problem))
    assert np.array_equal(results[0].x, results[1].x)
    assert results[0].residual_history == results[1].residual_history
