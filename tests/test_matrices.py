"""M, L, J against the paper's definitions, the loop-based reference, and their invariants."""

import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import given, settings
from hypothesis import strategies as st

import clothsim as cs
from clothsim import matrices, reference
from clothsim.springs import grid_pairs


def small_model(nx=4, ny=3, seed=0, plane="xz"):
    rng = np.random.default_rng(seed)
    mesh = cs.grid(nx, ny, size=(1.0, 0.7), plane=plane)
    springs = cs.grid_springs(mesh, structural=10.0, shear=5.0, bending=1.0)
    k = rng.uniform(0.5, 50.0, springs.spring_count)
    return cs.Model.build(mesh, springs.with_stiffness(k),
                          vertex_mass=rng.uniform(0.1, 2.0, mesh.vertex_count))


def test_matrices_equal_loop_reference():
    model = small_model()
    np.testing.assert_allclose(matrices.mass_matrix(model).toarray(),
                               reference.mass_matrix(model), rtol=0, atol=0)
    np.testing.assert_allclose(matrices.stiffness_matrix(model).toarray(),
                               reference.stiffness_matrix(model), rtol=1e-15, atol=1e-13)
    np.testing.assert_allclose(matrices.spring_matrix(model).toarray(),
                               reference.spring_matrix(model), rtol=0, atol=0)


def test_shapes_and_interleaved_layout():
    model = small_model()
    n, s = model.vertex_count, model.spring_count
    L, J, M = (matrices.stiffness_matrix(model), matrices.spring_matrix(model),
               matrices.mass_matrix(model))
    assert L.shape == (3 * n, 3 * n) and M.shape == (3 * n, 3 * n) and J.shape == (3 * n, 3 * s)
    # spring 0 joins a -> b: J[3a + c, 3*0 + c] = k, J[3b + c, c] = -k, other coordinates 0
    a, b = model.springs.spring_vertices[0]
    k = model.springs.spring_stiffness[0]
    Jd = J.toarray()
    for c in range(3):
        assert Jd[3 * a + c, c] == k and Jd[3 * b + c, c] == -k
        assert Jd[3 * a + (c + 1) % 3, c] == 0


def test_scalar_forms_expand_to_paper_forms():
    model = small_model()
    for fn in (matrices.mass_matrix, matrices.stiffness_matrix, matrices.spring_matrix):
        small = fn(model, expand=False)
        big = fn(model)
        assert (sp.kron(small, np.eye(3)) - big).count_nonzero() == 0


def test_L_equals_J_times_incidence_and_energy_identity():
    """½ xᵀLx − xᵀJd + ½ Σ k|d|² = Σ ½ k |p − d|² (the paper's Eq. 8 expansion)."""
    model = small_model(seed=3)
    rng = np.random.default_rng(1)
    x = rng.normal(size=(model.vertex_count, 3))
    d = rng.normal(size=(model.spring_count, 3))
    L, J = matrices.stiffness_matrix(model), matrices.spring_matrix(model)
    xf, df = x.ravel(), d.ravel()
    k = model.springs.spring_stiffness
    lhs = 0.5 * xf @ (L @ xf) - xf @ (J @ df) + 0.5 * np.sum(k * np.sum(d * d, axis=1))
    a, b = model.springs.spring_vertices.T
    rhs = 0.5 * np.sum(k * np.sum((x[a] - x[b] - d) ** 2, axis=1))
    assert lhs == pytest.approx(rhs, rel=1e-12)


@settings(max_examples=25, deadline=None)
@given(nx=st.integers(2, 7), ny=st.integers(2, 7), seed=st.integers(0, 10_000))
def test_L_symmetric_psd_translation_nullspace(nx, ny, seed):
    model = small_model(nx, ny, seed)
    L = matrices.stiffness_matrix(model)
    assert abs(L - L.T).max() == 0
    eig = np.linalg.eigvalsh(L.toarray())
    assert eig.min() >= -1e-10 * eig.max()
    for c in range(3):
        t = np.zeros((model.vertex_count, 3))
        t[:, c] = 1.0
        assert np.abs(L @ t.ravel()).max() <= 1e-12 * abs(L).max()


def test_mass_sums_to_total_mass():
    mesh = cs.grid(9, 5, size=(2.0, 1.0))
    springs = cs.grid_springs(mesh, structural=1.0)
    for lumping in ("uniform", "area"):
        model = cs.Model.build(mesh, springs, total_mass=3.7, mass_lumping=lumping)
        M = matrices.mass_matrix(model)
        assert M.sum() == pytest.approx(3 * 3.7, rel=1e-14)
        assert model.total_mass == pytest.approx(3.7, rel=1e-14)
    area = cs.Model.build(mesh, springs, total_mass=1.0, mass_lumping="area").vertex_mass
    ny, nx = mesh.grid_shape
    # corner (0,0) touches 2 triangles of the cell, an interior vertex 6: 2/6 of interior mass
    assert area[0] < area[nx + 1]
    assert area[nx + 1] == pytest.approx(area[2 * nx + 2])


@pytest.mark.parametrize("n", [3, 4, 5, 8, 9, 33])
def test_spring_counts_match_formulas(n):
    mesh = cs.grid(n, n)
    every = cs.grid_springs(mesh, structural=1.0, shear=1.0, bending=1.0)
    assert every.family_count("structural") == 2 * n * (n - 1)
    assert every.family_count("shear") == 2 * (n - 1) ** 2
    assert every.spring_count == 6 * n * n - 10 * n + 2
    alt = cs.grid_springs(mesh, structural=1.0, shear=1.0, bending=1.0, bending_pattern="alternate")
    if n % 2 == 1:  # the student report's count holds for odd n
        assert alt.spring_count == (n - 1) * (5 * n - 2)
    # rectangular grids, either pattern: count bending pairs directly
    for nx, ny in ((n, n + 3), (n + 1, n)):
        ev = grid_pairs(nx, ny, "bending", "every")
        assert len(ev) == ny * (nx - 2) + nx * (ny - 2)
        al = grid_pairs(nx, ny, "bending", "alternate")
        assert len(al) == ny * ((nx - 1) // 2) + nx * ((ny - 1) // 2)


def test_grid_springs_join_the_right_neighbours_and_rest_lengths():
    mesh = cs.grid(4, 3, size=(3.0, 2.0))  # unit spacing
    springs = cs.grid_springs(mesh, structural=1.0, shear=2.0, bending=3.0)
    fam = springs.spring_family
    r = springs.spring_rest_length
    np.testing.assert_allclose(r[fam == 0], 1.0)
    np.testing.assert_allclose(r[fam == 1], np.sqrt(2.0))
    np.testing.assert_allclose(r[fam == 2], 2.0)
    np.testing.assert_array_equal(springs.spring_stiffness[fam == 1], 2.0)
    assert (0, 1) in set(map(tuple, springs.spring_vertices[fam == 0]))
    assert (0, 5) in set(map(tuple, springs.spring_vertices[fam == 1]))


def test_absent_family_is_not_built():
    mesh = cs.grid(5, 5)
    springs = cs.grid_springs(mesh, structural=1.0)
    assert springs.family_count("shear") == 0 and springs.family_count("bending") == 0


def test_mesh_springs_edges_and_bending_across_interior_edges():
    mesh = cs.grid(3, 3)
    springs = cs.mesh_springs(mesh, structural=1.0, bending=0.5)
    # 3x3 grid: 12 axis edges + 4 diagonals = 16 edges; interior edges: 16 - 8 boundary = 8
    assert springs.family_count("structural") == 16
    assert springs.family_count("bending") == 8
    a, b = springs.spring_vertices[springs.spring_family == 2].T
    assert np.all(a != b)


def test_grid_orientation_normals():
    for plane, normal in (("xz", [0, 1, 0]), ("xy", [0, 0, 1])):
        mesh = cs.grid(3, 4, plane=plane)
        x, t = mesh.vertices, mesh.triangles
        nrm = np.cross(x[t[:, 1]] - x[t[:, 0]], x[t[:, 2]] - x[t[:, 0]])
        nrm /= np.linalg.norm(nrm, axis=1)[:, None]
        np.testing.assert_allclose(nrm, np.tile(normal, (len(t), 1)), atol=1e-15)
        assert mesh.triangle_areas().sum() == pytest.approx(1.0)


def test_system_matrix_with_anchors_and_expand():
    model = small_model()
    h = 0.05
    A = matrices.system_matrix(model, h)
    ref = reference.mass_matrix(model) + h * h * reference.stiffness_matrix(model)
    np.testing.assert_allclose(matrices.system_matrix(model, h, expand=True).toarray(), ref,
                               rtol=1e-14, atol=1e-14)
    Aa = matrices.system_matrix(model, h, anchor_vertices=[2], anchor_stiffness=[7.0])
    assert (Aa - A)[2, 2] == pytest.approx(h * h * 7.0)
    assert (Aa - A).count_nonzero() == 1


def test_L_and_J_are_canonical_and_equal_the_triplet_sums():
    """stiffness_matrix sums each vertex's diagonal before the triplets are sorted, and
    spring_matrix is built column by column: both equal the plain triplet construction (4s
    and 2s triplets summed by scipy), with sorted indices, J bit for bit, L's diagonal to
    its last bit (scipy sums a row's duplicates in an order of its own)."""
    mesh = cs.grid(9, 7, size=(1.0, 0.7), plane="xz")
    family = cs.Model.build(mesh, cs.grid_springs(mesh, structural=800.0, shear=80.0,
                                                  bending=0.3))
    for model in (family, small_model(9, 7, seed=3)):
        n, s = model.vertex_count, model.spring_count
        a, b = model.springs.spring_vertices.T
        k = model.springs.spring_stiffness
        L_ref = sp.coo_matrix((np.concatenate([k, k, -k, -k]),
                               (np.concatenate([a, b, a, b]), np.concatenate([a, b, b, a]))),
                              shape=(n, n)).tocsr()
        cols = np.arange(s)
        J_ref = sp.coo_matrix((np.concatenate([k, -k]), (np.concatenate([a, b]),
                                                         np.concatenate([cols, cols]))),
                              shape=(n, s)).tocsr()
        for got, ref, rtol in ((matrices.stiffness_matrix(model, expand=False), L_ref, 4e-16),
                               (matrices.spring_matrix(model, expand=False), J_ref, 0)):
            assert got.has_canonical_format and got.format == "csr"
            np.testing.assert_array_equal(got.indptr, ref.indptr)
            np.testing.assert_array_equal(got.indices, ref.indices)
            np.testing.assert_allclose(got.data, ref.data, rtol=rtol, atol=0)
