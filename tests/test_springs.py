"""Spring builders: counts, uniqueness, and bad input."""

import numpy as np
import pytest

import clothsim as cs
from clothsim.errors import InputError
from clothsim.springs import bending_pairs


def alternating_grid(nx=21, ny=21):
    """A grid mesh whose cells alternate their diagonal (a checkerboard of diagonals)."""
    base = cs.grid(nx, ny, size=(1.0, 1.0), plane="xy")
    tris = []
    for i in range(ny - 1):
        for j in range(nx - 1):
            a, b, c, d = i * nx + j, i * nx + j + 1, (i + 1) * nx + j, (i + 1) * nx + j + 1
            if (i + j) % 2:
                tris += [(a, b, d), (a, d, c)]
            else:
                tris += [(a, b, c), (b, d, c)]
    return cs.Mesh(base.vertices, np.array(tris))


def test_mesh_springs_adds_each_bending_pair_once():
    mesh = alternating_grid()
    raw = np.sort(mesh.interior_edge_opposites, axis=1)
    unique = np.unique(raw, axis=0)
    assert len(raw) > len(unique)        # the triangulation does produce repeated pairs
    springs = cs.mesh_springs(mesh, structural=10.0, bending=1.0)
    bend = springs.spring_vertices[springs.spring_family == 2]
    assert len(bend) == len(unique)
    assert len(np.unique(np.sort(bend, axis=1), axis=0)) == len(bend)
    # the same pairs, none lost
    assert {tuple(p) for p in bend} == {tuple(p) for p in unique}


def test_bending_pairs_unchanged_without_repeats():
    mesh = cs.grid(6, 5, size=(1.0, 1.0), plane="xy")
    np.testing.assert_array_equal(bending_pairs(mesh), mesh.interior_edge_opposites)


def test_springs_of_another_mesh_are_rejected():
    small = cs.grid(3, 3)
    big = cs.grid(4, 4)
    springs = cs.grid_springs(small, structural=1.0)
    with pytest.raises(InputError, match="springs: built for a mesh of 9 vertices"):
        cs.Model.build(big, springs)
    far = cs.grid_springs(big, structural=1.0)
    with pytest.raises(InputError, match="out of range"):
        cs.Model.build(small, far.__class__(far.spring_vertices, 1.0, 1.0, 0))


@pytest.mark.parametrize("pairs, match", [
    ([[0.0, 1.5]], "integer vertex indices"),
    ([[0, -1]], "negative"),
    ([[0, 1, 2]], r"shape \(s, 2\)"),
])
def test_bad_spring_indices_are_named(pairs, match):
    with pytest.raises(InputError, match=match):
        cs.Springs(pairs, 1.0, 1.0, 0)


def test_whole_float_indices_are_accepted_and_shape_mismatch_named():
    s = cs.Springs(np.array([[0.0, 1.0]]), 1.0, 1.0, 0)
    assert s.spring_vertices.dtype == np.int64
    with pytest.raises(InputError, match="spring_stiffness: expected one value or 2"):
        cs.Springs([[0, 1], [1, 2]], [1.0, 2.0, 3.0], 1.0, 0)


def test_a_negative_index_names_its_spring_after_good_ones():
    with pytest.raises(InputError, match=r"spring_vertices\[2\]: vertex index -3 is negative"):
        cs.Springs([[0, 1], [1, 2], [4, -3], [-1, 0]], 1.0, 1.0, 0)


def test_joined_springs_equal_one_set_made_whole():
    """Springs.concatenate joins checked parts without checking them again: the same arrays
    (values, dtypes, read-only) as the whole set made and checked at once."""
    mesh = cs.grid(7, 6, size=(1.0, 1.0), plane="xy")
    a = cs.grid_springs(mesh, structural=10.0, shear=5.0)
    b = cs.Springs(np.array([[0, 8], [3, 9]]), [2.0, 3.0], [0.1, 0.2], 2, mesh.vertex_count,
                   spring_damping=[0.0, 0.5])
    joined = cs.Springs.concatenate([a, b])
    whole = cs.Springs(*(np.concatenate([getattr(a, n), getattr(b, n)]) for n in (
        "spring_vertices", "spring_stiffness", "spring_rest_length", "spring_family")),
        mesh.vertex_count, spring_damping=np.concatenate([a.spring_damping, b.spring_damping]))
    for name in ("spring_vertices", "spring_stiffness", "spring_rest_length", "spring_family",
                 "spring_damping"):
        got, want = getattr(joined, name), getattr(whole, name)
        assert got.dtype == want.dtype and not got.flags.writeable
        np.testing.assert_array_equal(got, want)
    assert joined.vertex_count == mesh.vertex_count == cs.Model.build(mesh, joined).vertex_count
    assert cs.Springs.concatenate([a]).spring_count == a.spring_count
    assert cs.Springs.concatenate([]).spring_count == 0
    with pytest.raises(InputError, match="meshes of different sizes"):
        cs.Springs.concatenate([a, cs.grid_springs(cs.grid(3, 3), structural=1.0)])
