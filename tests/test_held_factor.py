"""The held global step's factor (clothsim.solvers.tangent_system, HeldSystem): the step in
tangent coordinates equals the projected 3n system's, on box, sphere and mixed contact
sets, as the set changes, with both backends."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import clothsim as cs
from clothsim import contacts
from clothsim.effects.holding import tangent_frame
from clothsim.gallery import GRAVITY, grid_cloth
from clothsim.solvers import make_solver
from clothsim.solvers.held import held_start
from clothsim.solvers.tangent_system import tangent_matrix, vertex_directions

H = 1 / 30
N = 7
CENTER = np.array([0.0, -0.35, 0.0])   # a sphere under the sheet's middle
EX, EY, EZ = np.eye(3)


def sheet():
    return grid_cloth(N, center=(0.0, 0.0, 0.0))


def problem(model, vertices, normals, *, y_dtype=np.float64, pinned=(0,)):
    """A sheet falling sideways with the given vertices held on planes through them."""
    x = model.mesh.vertices
    normals = np.asarray(normals, dtype=np.float64).reshape(-1, 3)
    vertices = np.asarray(vertices, dtype=np.int64)
    pinned = np.asarray(pinned, dtype=np.int64)
    v = np.tile(np.array([0.4, -1.0, 0.25], dtype=y_dtype), (len(x), 1))
    return cs.StepProblem(H, x, v, f_ext=model.vertex_mass[:, None] * GRAVITY,
                          fixed_vertices=pinned, fixed_positions=x[pinned],
                          contact_vertices=vertices, contact_normals=normals,
                          contact_offsets=np.einsum("ij,ij->i", x[vertices], normals))


def sphere_normals(model, vertices, center=CENTER):
    d = model.mesh.vertices[vertices] - center
    return d / np.linalg.norm(d, axis=1)[:, None]


def contact_sets(model):
    """Box top, box top with an edge and a side, sphere cap, sphere with sticking vertices,
    everything held in all directions: (name, vertices, normals)."""
    n = model.vertex_count
    inner = np.flatnonzero((np.abs(model.mesh.vertices[:, [0, 2]]) < 0.3).all(axis=1))
    edge = inner[model.mesh.vertices[inner, 0] > 0.1]
    cap = inner
    stick = cap[::3]
    t1, t2 = tangent_frame(sphere_normals(model, stick))   # static friction's directions
    rest = np.setdiff1d(np.arange(n), [0])
    return [
        ("box top", inner, np.tile(EY, (len(inner), 1))),
        ("box edge", np.r_[inner, edge], np.r_[np.tile(EY, (len(inner), 1)),
                                               np.tile(EX, (len(edge), 1))]),
        ("sphere cap", cap, sphere_normals(model, cap)),
        ("sphere, some sticking", np.r_[cap, stick, stick],
         np.r_[sphere_normals(model, cap), t1, t2]),
        ("all held in 3 directions", np.r_[rest, rest, rest],
         np.r_[np.tile(EY, (len(rest), 1)), np.tile(EX, (len(rest), 1)),
               np.tile(EZ, (len(rest), 1))]),
    ]


def reference_step(solver, p, rhs, z, Az):
    """The seed's held global step: (P A P + α D) u = P (rhs − A z), 3n, solved directly."""
    sysf = solver.system(p)
    n = solver.model.vertex_count
    P, D = contacts.projector(n, p.contact_basis())
    A = sp.csr_matrix(sysf.A)
    K = P @ sp.kron(A, sp.identity(3)) @ P + A.diagonal().mean() * D
    dofs = (3 * sysf.free[:, None] + np.arange(3)).ravel()
    r = (P @ (rhs - Az).ravel())[dofs]
    u = np.zeros(3 * n)
    u[dofs] = spla.spsolve(sp.csc_matrix(K[dofs][:, dofs]), r)
    return p.y + z + (P @ u).reshape(n, 3)


def held_step(solver, p):
    held, x = held_start(solver, p)
    rhs = solver.displacement_right_hand_side(p, solver.local_step(x))
    z, Az = held.prepare(p)
    return held, held.global_step(p, rhs.copy(), z, Az), (rhs, z, Az)


#: The two steps solve the same linear system with different factorizations: they agree to
#: a few ulps of the displacement times the condition number of the small test matrices.
TOLERANCE = 1e-12


@pytest.mark.parametrize("backend", ["cholmod", "splu"])
def test_the_tangent_step_is_the_projected_step_on_every_contact_set(backend):
    model = sheet()
    solver = make_solver("local-global", model, backend=backend)
    for name, vertices, normals in contact_sets(model):
        p = problem(model, vertices, normals)
        held, x, args = held_step(solver, p)
        ref = reference_step(solver, p, *args)
        scale = np.abs(ref - p.y).max()
        assert np.abs(x - ref).max() <= TOLERANCE * scale, name
        assert held.tangent_factor.backend == backend, name
        # on the planes exactly (up to the rounding of the plane offsets)
        np.testing.assert_allclose(np.einsum("ij,ij->i", x[p.contact_vertices],
                                             p.contact_normals), p.contact_offsets,
                                   atol=1e-15, err_msg=name)


def test_the_step_follows_the_contact_set_as_it_enters_leaves_and_turns():
    """One solver through a sequence of sets (the cache, and the symbolic analysis reused
    when only oblique normals turn): each step equals a fresh solve of its own set."""
    model = sheet()
    solver = make_solver("local-global", model)
    inner = np.flatnonzero((np.abs(model.mesh.vertices[:, [0, 2]]) < 0.3).all(axis=1))
    grown = np.flatnonzero((np.abs(model.mesh.vertices[:, [0, 2]]) < 0.4).all(axis=1))
    off = CENTER + [0.02, 0.0, 0.01]          # no vertex straight above: every normal oblique
    turned = sphere_normals(model, inner, CENTER + [0.05, 0.0, -0.03])
    sets = [(inner, np.tile(EY, (len(inner), 1))),                   # box top
            (grown, np.tile(EY, (len(grown), 1))),                   # entering
            (inner, sphere_normals(model, inner, off)),              # normals turn
            (inner, turned),                                         # turn again
            (inner[::2], sphere_normals(model, inner[::2])),         # leaving
            (np.zeros(0, np.int64), np.zeros((0, 3))),               # none held
            (inner, np.tile(EY, (len(inner), 1)))]                   # back
    analyzed = []
    for vertices, normals in sets:
        p = problem(model, vertices, normals)
        if not p.has_contacts:
            solver.solve(p)
            continue
        held, x, args = held_step(solver, p)
        ref = reference_step(solver, p, *args)
        assert np.abs(x - ref).max() <= TOLERANCE * np.abs(ref - p.y).max()
        analyzed.append(held.tangent_factor.analyzed)
    assert analyzed[3] is False      # same pattern as the previous set: numeric only
    assert analyzed[0] and analyzed[1] and analyzed[2]


def test_columns_are_an_orthonormal_basis_of_the_free_directions():
    model = sheet()
    for name, vertices, normals in contact_sets(model):
        p = problem(model, vertices, normals)
        n = model.vertex_count
        free = np.setdiff1d(np.arange(n), p.fixed_vertices)
        dof, vectors, oblique = vertex_directions(n, free, p.contact_basis())
        present = dof >= 0
        T = np.zeros((3 * n, present.sum()))
        for v, s in zip(*np.nonzero(present)):
            T[3 * v: 3 * v + 3, dof[v, s]] = vectors[v, s]
        np.testing.assert_allclose(T.T @ T, np.eye(T.shape[1]), atol=1e-14, err_msg=name)
        P, _ = contacts.projector(n, p.contact_basis())
        keep = np.repeat(np.isin(np.arange(n), free), 3)
        np.testing.assert_allclose(T @ T.T, (P.toarray() * keep) * keep[:, None], atol=1e-14,
                                   err_msg=name)
        axis = np.setdiff1d(np.arange(n), oblique)
        on = present[axis]
        np.testing.assert_array_equal(vectors[axis][on], np.eye(3)[np.nonzero(on)[1]])


def test_axis_aligned_contacts_decouple_the_coordinates():
    """On box faces the system is three principal submatrices of M_s + h² L_s."""
    model = sheet()
    solver = make_solver("local-global", model)
    _, vertices, normals = contact_sets(model)[1]
    p = problem(model, vertices, normals)
    held, _, _ = held_step(solver, p)
    assert len(held.oblique) == 0
    K = sp.csr_matrix(held.tangent_factor.A)
    n = model.vertex_count
    free = np.setdiff1d(np.arange(n), p.fixed_vertices)
    dof, _, _ = vertex_directions(n, free, p.contact_basis())
    A = sp.csr_matrix(solver.system(p).A)
    for s in range(3):
        verts = np.flatnonzero(dof[:, s] >= 0)
        block = K[dof[verts, s]][:, dof[verts, s]]
        assert (block != A[verts][:, verts]).nnz == 0
        others = np.setdiff1d(np.arange(K.shape[0]), dof[verts, s])
        assert K[dof[verts, s]][:, others].nnz == 0
    twice, count = np.unique(vertices, return_counts=True)
    edge = twice[count == 2]                  # on the top and the side: move along z only
    assert len(edge) and np.all(dof[edge][:, :2] == -1) and np.all(dof[edge][:, 2] >= 0)


def test_free_inverse_is_the_projected_inverse_also_off_the_tangent_space():
    """HeldSystem.solve (L-BFGS's initial inverse Hessian) is (P A P + α D)⁻¹ on any
    vector over the free vertices, the constrained components included."""
    model = sheet()
    solver = make_solver("local-global", model)
    _, vertices, normals = contact_sets(model)[3]
    p = problem(model, vertices, normals)
    held, _, _ = held_step(solver, p)
    n = model.vertex_count
    P, D = contacts.projector(n, p.contact_basis())
    A = sp.csr_matrix(solver.system(p).A)
    K = (P @ sp.kron(A, sp.identity(3)) @ P + A.diagonal().mean() * D).toarray()
    dofs = (3 * held.free[:, None] + np.arange(3)).ravel()
    b = np.random.default_rng(3).standard_normal(len(dofs))
    ref = np.linalg.solve(K[np.ix_(dofs, dofs)], b)
    r = np.zeros((n, 3))
    r[held.free] = b.reshape(-1, 3)
    u = held.solve(r)[held.free].reshape(-1)
    np.testing.assert_allclose(u, ref, rtol=0, atol=1e-12 * np.abs(ref).max())


def test_float32_velocities_and_a_tiny_sheet_held_everywhere():
    """A float32 start gives the float64 step; a sheet whose every free vertex is held in
    all directions has an empty system and does not move."""
    model = sheet()
    solver = make_solver("local-global", model)
    _, vertices, normals = contact_sets(model)[2]
    x64 = held_step(solver, problem(model, vertices, normals))[1]
    x32 = held_step(solver, problem(model, vertices, normals, y_dtype=np.float32))[1]
    assert x32.dtype == np.float64
    assert np.abs(x32 - x64).max() < 1e-6
    tiny = grid_cloth(2)
    solver = make_solver("local-global", tiny)
    rest = np.array([1, 2, 3])
    p = problem(tiny, np.r_[rest, rest, rest],
                np.r_[np.tile(EY, (3, 1)), np.tile(EX, (3, 1)), np.tile(EZ, (3, 1))])
    held, x, _ = held_step(solver, p)
    assert held.tangent_factor.shape == (0, 0)
    np.testing.assert_array_equal(x, p.x)


def test_a_tangent_matrix_without_oblique_vertices_stores_no_cross_axis_entry():
    model = sheet()
    solver = make_solver("local-global", model)
    n = model.vertex_count
    p = problem(model, [], [])
    A = sp.csr_matrix(solver.system(p).A)
    free = np.arange(1, n)
    dof, vectors, oblique = vertex_directions(n, free, [])
    K = tangent_matrix(A, dof, vectors, oblique)
    assert K.nnz == 3 * A[free][:, free].nnz
