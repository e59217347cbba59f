"""The obstacles' contact thickness (clothsim/effects/thickness.py): the covering radius of
a mesh, the "auto" rule, and the cloth over a box edge or a sphere with no obstacle point
through its triangles (measured by benchmarks/cloth_depth.py)."""

from __future__ import annotations

import numpy as np
import pytest

import clothsim as cs
from benchmarks.cloth_depth import depth_through_cloth, sphere_depth
from clothsim import energy
from clothsim.effects import Box, Plane, Sphere
from clothsim.effects.thickness import STRETCH_ALLOWANCE, auto_thickness, covering_radius
from clothsim.errors import InputError
from clothsim.scene import Scene

ONE = np.array([[0, 1, 2]])


def brute_cover(p: np.ndarray, samples: int = 200) -> float:
    """Max over a fine barycentric sampling of the distance to the nearest corner, and half
    the longest side."""
    s = np.linspace(0, 1, samples)
    u, v = np.meshgrid(s, s)
    keep = u + v <= 1
    q = (1 - u[keep] - v[keep])[:, None] * p[0] + u[keep, None] * p[1] + v[keep, None] * p[2]
    near = np.min([np.linalg.norm(q - c, axis=1) for c in p], axis=0).max()
    side = max(np.linalg.norm(p[i] - p[j]) for i, j in ((0, 1), (1, 2), (2, 0)))
    return max(near, side / 2)


@pytest.mark.parametrize("p, expected", [
    ([(0, 0, 0), (1, 0, 0), (0, 1, 0)], 2 ** -0.5),                      # right: hypotenuse/2
    ([(0, 0, 0), (1, 0, 0), (0.5, 3 ** 0.5 / 2, 0)], 3 ** -0.5),          # equilateral
    ([(0, 0, 0), (2, 0, 0), (1, 0.3, 0)], None),                           # obtuse
    ([(0, 0, 0), (2, 0, 0), (0.3, 0.5, 0.1)], None),                       # obtuse, skew
    ([(0, 0, 0), (1, 0.1, 0), (0.2, 0.9, 0.3)], None),                     # acute
    ([(0, 0, 0), (1, 0, 0), (2, 0, 0)], 1.0),                              # flat: a/2
])
def test_covering_radius_of_one_triangle(p, expected):
    p = np.array(p, float)
    r = covering_radius(p, ONE)
    assert r == pytest.approx(brute_cover(p), rel=2e-2)
    if expected is not None:
        assert r == pytest.approx(expected, rel=1e-12)


def test_covering_radius_of_a_grid_and_of_strands():
    mesh = cs.grid(5, 5, size=(0.4, 0.4))
    assert covering_radius(mesh.vertices, mesh.triangles) == pytest.approx(0.1 / 2 ** 0.5)
    p = np.array([(0, 0, 0), (0, 0.3, 0), (0, 0.5, 0)], float)
    assert covering_radius(p, np.zeros((0, 3), int), np.array([[0, 1], [1, 2]])) == 0.15


def test_auto_sphere_thickness_clears_every_triangle_of_that_covering_radius():
    """Random triangles with corners on the sphere R + δ (δ from their covering radius r):
    the ball of radius R stays out of each; with half of δ it reaches through most."""
    rng = np.random.default_rng(1)
    R, through = 0.3, 0
    for _ in range(200):
        d = rng.normal(size=(3, 3)) * 0.05 + (0, 1, 0)
        d /= np.linalg.norm(d, axis=1)[:, None]
        r = covering_radius(d * R, ONE)            # r grows with the radius: iterate once
        delta = auto_thickness("sphere", covering_radius(d * (R + r), ONE), radius=R)
        x = d * (R + delta)
        assert covering_radius(x, ONE) <= covering_radius(d * (R + r), ONE)
        assert sphere_depth((0, 0, 0), R, x, ONE) <= 1e-12
        through += sphere_depth((0, 0, 0), R, d * (R + delta / 2), ONE) > 0
    assert through > 150


def test_auto_rule_per_shape():
    assert auto_thickness("plane", 0.1) == 0.0
    assert auto_thickness("box", 0.1) == 0.1
    assert auto_thickness("sphere", 0.1, radius=0.3) == pytest.approx(np.hypot(0.3, 0.1) - 0.3)


def model_over_box_edge(n: int, size: float = 0.6):
    """A cloth of n² vertices centred over the box edge x = y = 0 (along z), falling."""
    mesh = cs.grid(n, n, size=(size, size), center=(0.0, 0.05, 0.0), plane="xz")
    springs = cs.grid_springs(mesh, structural=800.0, shear=800.0, bending=80.0)
    return cs.Model.build(mesh, springs, total_mass=0.36)


@pytest.mark.parametrize("n", [9, 17, 33])
def test_cloth_over_a_box_edge_hides_it_at_every_resolution(n):
    """With the "auto" thickness no box point lies in front of a triangle after the cloth
    has folded over the edge (30 steps); with thickness 0 the edge pokes through by a
    fraction of the spacing. Springs stay within 1.3x, no vertex inside the grown box."""
    depth = {}
    for thickness in ("auto", 0.0):
        model = model_over_box_edge(n)
        box = Box((-1.0, -1.0, -1.0), (0.0, 0.0, 1.0), friction=0.3, thickness=thickness)
        sim = cs.Simulation(model, h=1 / 30, effects=[cs.Gravity(), box])
        rest = model.springs.spring_rest_length
        for _ in range(30):
            sim.step()
            x = sim.state.positions
            assert not box.inside(x).any()
        assert (energy.spring_lengths(model, x) / rest).max() < 1.3
        assert x[:, 1].min() < -0.05                       # it did fold over the edge
        depth[thickness] = depth_through_cloth(box, x, model.mesh.triangles)
    spacing = 0.6 / (n - 1)
    assert box.margin == 0.0
    assert depth["auto"] == 0.0
    assert 0.1 * spacing < depth[0.0] < spacing


def test_cloth_over_a_sphere_hides_it():
    model = model_over_box_edge(17, size=0.5)
    depth = {}
    for thickness in ("auto", 0.0):
        sphere = Sphere((0.0, -0.3, 0.0), 0.3, friction=0.3, thickness=thickness)
        sim = cs.Simulation(model, h=1 / 30, effects=[cs.Gravity(), sphere])
        for _ in range(30):
            sim.step()
        depth[thickness] = depth_through_cloth(sphere, sim.state.positions,
                                               model.mesh.triangles)
        if thickness == "auto":
            r = STRETCH_ALLOWANCE * (0.5 / 16) / 2 ** 0.5
            assert sphere.margin == pytest.approx(np.hypot(0.3, r) - 0.3, rel=1e-12)
    assert depth["auto"] == 0.0 < depth[0.0]


def test_thickness_resolution_and_description():
    model = model_over_box_edge(9)
    box, sphere, plane = (Box((-1, -1, -1), (0, 0, 1)), Sphere((0, -1, 0), 0.5),
                          Plane((0, -2, 0), (0, 1, 0), thickness="auto"))
    assert box.thickness == "auto" and box.margin == 0.0        # resolved when bound
    cs.Simulation(model, h=1 / 30, effects=[box, sphere, plane])
    assert box.margin == pytest.approx(STRETCH_ALLOWANCE * 0.075 / 2 ** 0.5)
    assert plane.margin == 0.0
    d = box.describe()
    assert d["thickness"] == "auto" and d["margin"] == box.margin and d["max"] == [0, 0, 1]
    # the seed's mode reproduces the seed: no margin unless one is given
    post = Box((-1, -1, -1), (0, 0, 1), contact="post-solve")
    given = Box((-1, -1, -1), (0, 0, 1), contact="post-solve", thickness=0.01)
    cs.Simulation(model, h=1 / 30, effects=[post, given])
    assert post.margin == 0.0 and given.margin == 0.01
    assert given.inside(np.array([[0.005, -0.5, 0.0]])).all()


@pytest.mark.parametrize("kind, extra", [("box", {"min": [-1, -1, -1], "max": [0, 0, 1]}),
                                         ("sphere", {"center": [0, -1, 0], "radius": 0.5}),
                                         ("plane", {"point": [0, -1, 0], "normal": [0, 1, 0]})])
@pytest.mark.parametrize("bad", [-0.1, "thick", [0.1]])
def test_bad_thickness_names_the_key(kind, extra, bad):
    doc = {"cloth": {"resolution": [3, 3]}, "effects": [{"kind": kind, **extra,
                                                         "thickness": bad}]}
    with pytest.raises(InputError, match=r"effects\[0\]\.thickness"):
        Scene.from_dict(doc, source="s.toml")
    doc["effects"][0]["thickness"] = "auto"
    assert Scene.from_dict(doc, source="s.toml").build_effects()[0].thickness == "auto"
