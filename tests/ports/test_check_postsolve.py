"""Post-solve contact decisions too close to call from a printed port's state.

drop-on-square's grid (spacing 1/24 m) puts vertices on the box's edges (x, z = ±0.25):
whether the post-solve projection catches such a vertex, and onto which face, is decided
by the rounding of the printed start. The check takes the port's decision there
(clothsim.ports.postsolve_margins); a port that ignores the box, or puts a vertex
elsewhere than any decision within the rounding would, still fails.
"""

from __future__ import annotations

import numpy as np
import pytest

import clothsim as cs
from clothsim.ports.check import check_steps

from .test_check_accelerated import _g
from .test_planted_faults import drop_on_square, port

FRAMES = 20   # through the landing (step 9 -> 10) and the slide off the edges


@pytest.fixture(scope="module")
def seed_demo(tmp_path_factory):
    """The seed's demo (10 local/global iterations, post-solve) and clothsim's own frames."""
    path = drop_on_square(tmp_path_factory.mktemp("drop"), FRAMES)
    return path, *port(path)


@pytest.mark.parametrize("precision", ["float64", "float32"])
def test_a_right_g_post_solve_port_passes_and_no_cause_is_named(seed_demo, precision):
    path, xs, vs = seed_demo
    report = check_steps(cs.load_scene(path), _g(xs), _g(vs), precision=precision)
    assert report.passed, report.summary()
    summary = report.summary()
    assert "model differs" not in summary and "exert no force" not in summary, summary
    landing = report.steps[9]
    assert "post-solve contact decision" in landing.note, landing.line()
    assert "too close to call" in landing.note and "vertex 156" in landing.note


def test_a_float32_post_solve_port_passes(seed_demo):
    path, xs, vs = seed_demo
    report = check_steps(cs.load_scene(path), xs.astype("float32"), vs.astype("float32"),
                         precision="float32")
    assert report.passed, report.summary()


def test_unprinted_frames_take_no_decision(seed_demo):
    """17 digits: clothsim's step from the port's start is its own: nothing to adopt."""
    path, xs, vs = seed_demo
    report = check_steps(cs.load_scene(path), xs[:12], vs[:12])
    assert report.passed and not any("too close" in s.note for s in report.steps)


def test_a_port_without_the_post_solve_projection_fails(tmp_path):
    """The port's box far away: its cloth falls through the scene's box."""
    path = drop_on_square(tmp_path, 12)
    xs, vs = port(path, "effects[1].min=[5.0, 0.0, 5.0]", "effects[1].max=[5.5, 0.5, 5.5]")
    report = check_steps(cs.load_scene(path), _g(xs), _g(vs))
    assert not report.passed
    assert report.steps[9].error > 1e-2, report.steps[9].line()


@pytest.mark.slow   # a variant; the suite's fast run keeps the main case
@pytest.mark.parametrize("shift", [[0.0, 0.0, 2e-3], [2e-3, 0.0, 0.0]])
def test_an_edge_vertex_off_its_faces_by_more_than_rounding_fails(seed_demo, shift):
    """Vertex 156 (on the box's edge) put 2 mm off where either decision leaves it."""
    path, xs, vs = seed_demo
    xs, vs = xs[:11].copy(), vs[:11].copy()
    xs[10, 156] += shift
    report = check_steps(cs.load_scene(path), _g(xs), _g(vs))
    step = report.steps[9]
    assert not step.passed and step.vertex == 156 and step.error > 1e-3, step.line()


def test_a_vertex_moved_onto_a_face_its_start_is_not_near_fails(seed_demo):
    """A vertex landing mid-top put on the box's +x face: no decision within the rounding."""
    path, xs, vs = seed_demo
    xs, vs = xs[:11].copy(), vs[:11].copy()
    v = int(np.argmin(np.linalg.norm(xs[10] - [0.0, 0.5, 0.0], axis=1)))
    xs[10, v, 0] = 0.25
    report = check_steps(cs.load_scene(path), _g(xs), _g(vs))
    step = report.steps[9]
    assert not step.passed and step.vertex == v, step.line()
