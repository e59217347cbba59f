"""The Python API validates like the scene loader: no coercion of bools, text or complex
numbers, no truncated indices, no silently ignored argument, no mutation of the caller's
arrays, and shapes checked with a one-line InputError."""

import numpy as np
import pytest

import clothsim as cs
from clothsim.errors import InputError

X = np.array([[0, 0, 0], [1, 0, 0], [1, 0, 1], [0, 0, 1.0]])
T = np.array([[0, 1, 2], [0, 2, 3]])


@pytest.mark.parametrize("vertices", [X.astype(complex), X.astype(str), X.astype(bool),
                                      X.tolist()[:3] + [["a", 0, 0]]])
def test_vertices_must_be_real_numbers(vertices):
    with pytest.raises(InputError, match="vertices: must be real numbers"):
        cs.Mesh(vertices, T)


def test_float_triangle_indices_are_not_truncated():
    with pytest.raises(InputError, match=r"triangles\[0, 1\]: vertex indices must be integers"):
        cs.Mesh(X, np.array([[0, 1.5, 2], [0, 2, 3]]))
    assert cs.Mesh(X, T.astype(float)).triangles.tolist() == T.tolist()  # whole numbers
    with pytest.raises(InputError, match="triangles: expected shape"):
        cs.Mesh(X, np.arange(7))


def _model(**kw):
    mesh = cs.Mesh(X, T)
    return cs.Model.build(mesh, cs.mesh_springs(mesh, structural=10.0), **kw)


@pytest.mark.parametrize("kw, field", [
    ({"total_mass": True}, "mass"),
    ({"total_mass": "1"}, "mass"),
    ({"vertex_mass": [1, 1, 1, 1j]}, "vertex_mass"),
    ({"total_mass": 1.0, "vertex_mass": 0.25}, "total_mass"),
    ({"vertex_mass": np.ones(3)}, "vertex_mass"),
])
def test_model_arguments_are_checked(kw, field):
    with pytest.raises(InputError, match=f"^{field}"):
        _model(**kw)


def test_model_leaves_the_callers_array_alone():
    m = np.full(4, 0.25)
    model = _model(vertex_mass=m)
    assert m.flags.writeable
    m[0] = 9.0
    assert model.vertex_mass[0] == 0.25


@pytest.mark.parametrize("kw, field", [
    ({"h": "0.03"}, "h"), ({"h": True}, "h"), ({"iterations": True}, "solver.iterations"),
    ({"iterations": 2.5}, "solver.iterations"), ({"tolerance": "1e-6"}, "solver.tolerance"),
])
def test_simulation_arguments_are_checked(kw, field):
    kw = {"h": 1 / 30, **kw}
    with pytest.raises(InputError, match=f"^{field}"):
        cs.Simulation(_model(total_mass=1.0), **kw)
