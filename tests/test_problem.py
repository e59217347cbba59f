"""The step problem: its validation, the penalty-anchor helper, g and ∇g."""

import numpy as np
import pytest

from clothsim.errors import InputError
from clothsim.gallery import GRAVITY, grid_cloth
from clothsim.objective import objective, objective_gradient, relative
from clothsim.problem import PenaltyAnchors, StepProblem


def problem_with_anchors(seed=0):
    model = grid_cloth(4, k=300.0)
    rng = np.random.default_rng(seed)
    x = model.mesh.vertices + rng.normal(scale=0.05, size=(16, 3))
    p = StepProblem(0.02, x, rng.normal(size=x.shape), f_ext=model.vertex_mass[:, None] * GRAVITY,
                    anchor_vertices=[1, 5], anchor_positions=x[[1, 5]] + 0.1,
                    anchor_stiffness=[40.0, 900.0])
    return model, p, x


def test_anchor_terms_are_consistent():
    """The gradient is the energy's derivative; the right-hand side is its linear part."""
    _, p, x = problem_with_anchors()
    a = p.anchors
    assert isinstance(a, PenaltyAnchors) and len(a) == 2
    grad = a.add_gradient(np.zeros_like(x), x)
    eps = 1e-6
    for v in (1, 5):
        for c in range(3):
            e = np.zeros_like(x)
            e[v, c] = eps
            fd = (a.energy(x + e) - a.energy(x - e)) / (2 * eps)
            assert abs(fd - grad[v, c]) <= 1e-6 * max(1.0, abs(grad[v, c]))
    # K x − K q = gradient, with K q the right-hand side term
    k = np.zeros(16)
    k[[1, 5]] = [40.0, 900.0]
    np.testing.assert_allclose(k[:, None] * x - a.add_rhs(np.zeros_like(x)), grad, atol=1e-12)
    # relative to an origin: K (q − o)
    o = x + 1.0
    np.testing.assert_allclose(a.add_rhs(np.zeros_like(x), 2.0, origin=o),
                               2.0 * (a.add_rhs(np.zeros_like(x)) - k[:, None] * o),
                               atol=1e-12)


def test_objective_gradient_is_the_derivative_of_g():
    model, p, x = problem_with_anchors(1)
    g = objective_gradient(model, p, x)
    rng = np.random.default_rng(2)
    dx = rng.normal(size=x.shape)
    t = 1e-6
    fd = (objective(model, p, x + t * dx) - objective(model, p, x - t * dx)) / (2 * t)
    assert abs(fd - float(np.sum(g * dx))) <= 1e-6 * abs(fd)


def test_relative_handles_zero_reference():
    assert relative(0.0, 0.0) == 0.0
    assert relative(1.0, 0.0) == np.inf
    assert relative(1.0, 4.0) == 0.25


@pytest.mark.parametrize("kwargs, match", [
    ({"v": np.zeros((4, 3))}, r"state.velocities: expected shape \(16, 3\)"),
    ({"y": np.zeros(3)}, r"inertial_target: expected shape \(16, 3\)"),
    ({"f_ext": np.zeros((16, 2))}, r"external_force: expected shape \(16, 3\)"),
    ({"fixed_vertices": [0, 16], "fixed_positions": np.zeros((2, 3))}, "out of range"),
    ({"fixed_vertices": [0.5], "fixed_positions": np.zeros((1, 3))}, "integer vertex"),
    ({"fixed_vertices": [0, 1], "fixed_positions": np.zeros((1, 3))},
     r"pins.fixed_positions: expected shape \(2, 3\)"),
    ({"anchor_vertices": [0], "anchor_positions": np.zeros((1, 3)),
      "anchor_stiffness": [1.0, 2.0]}, "pins.anchor_stiffness"),
    ({"x": np.full((16, 3), np.nan)}, "state.positions"),
])
def test_bad_step_data_names_the_argument(kwargs, match):
    x = np.zeros((16, 3))
    args = {"h": 0.1, "x": x, "v": np.zeros_like(x)}
    args.update(kwargs)
    with pytest.raises(InputError, match=match):
        StepProblem(**args)
