"""Scene display: obstacle surfaces, obstacles.vtu, pictures that show the box, the impulse
demo's visible push."""

import numpy as np
import pytest

import clothsim as cs
from clothsim.display import OBSTACLE_COLORS, obstacle_surfaces, pinned_points, surfaces_mesh
from clothsim.gallery import grid_cloth
from clothsim.runner import run_scene
from clothsim.scene import load_scene


def test_box_surface_is_closed_with_outward_normals():
    (s,) = obstacle_surfaces([cs.Box([-1, 0, -2], [1, 3, 2])])
    assert s.vertices.shape == (8, 3) and s.triangles.shape == (12, 3)
    tri = s.vertices[s.triangles]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    out = np.einsum("ij,ij->i", n, tri.mean(axis=1) - s.vertices.mean(axis=0))
    assert np.all(out > 0)
    # divergence theorem: the volume from the oriented triangles is the box's, 2 * 3 * 4
    volume = np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])).sum() / 6
    assert volume == pytest.approx(24.0)


def test_sphere_surface_lies_on_the_sphere_and_is_closed():
    (s,) = obstacle_surfaces([cs.Sphere([0.5, 1.0, -0.2], 0.3)])
    r = np.linalg.norm(s.vertices - [0.5, 1.0, -0.2], axis=1)
    np.testing.assert_allclose(r, 0.3)
    edges = np.sort(s.triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    assert np.all(counts == 2)  # every edge shared by two triangles: closed
    tri = s.vertices[s.triangles]
    volume = np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])).sum() / 6
    assert 0.9 * 4 / 3 * np.pi * 0.027 < volume < 4 / 3 * np.pi * 0.027


def test_plane_quad_lies_in_the_plane_under_the_cloth():
    cloth = np.array([[-0.5, 2.0, -0.5], [0.5, 2.0, 0.5]])
    (s,) = obstacle_surfaces([cs.Plane([0, 0.1, 0], [0, 2.0, 0]), cs.Gravity()], cloth)
    np.testing.assert_allclose(s.vertices[:, 1], 0.1)
    assert s.vertices[:, 0].min() < -0.5 and s.vertices[:, 0].max() > 0.5


def test_surfaces_mesh_merges_and_labels():
    surfaces = obstacle_surfaces([cs.Box([0, 0, 0], [1, 1, 1]), cs.Sphere([3, 0, 0], 1)])
    x, t, ids = surfaces_mesh(surfaces)
    assert len(x) == len(ids) == 8 + len(surfaces[1].vertices)
    assert t.max() == len(x) - 1 and set(ids[t[12:]].ravel()) == {1}
    assert surfaces_mesh([])[0].shape == (0, 3)


def test_pinned_points_follow_bound_pins():
    model = grid_cloth(3)
    pin = cs.Pin([0, 2], velocity=[0.0, 1.0, 0.0])
    assert pinned_points([pin]).shape == (0, 3)  # not bound yet
    sim = cs.Simulation(model, h=0.01, effects=[pin])
    x0 = model.mesh.vertices[[0, 2]]
    np.testing.assert_array_equal(pinned_points(sim.effects), x0)
    np.testing.assert_allclose(pinned_points(sim.effects, t=2.0), x0 + [0, 2.0, 0])


def test_drop_on_square_writes_obstacles_and_final_png_shows_the_box(tmp_path):
    from matplotlib.image import imread

    from clothsim import io

    run_scene("drop-on-square", tmp_path, frames=3)
    obstacles = io.read_mesh(tmp_path / "obstacles.vtu")
    x = obstacles.vertices
    assert obstacles.triangle_count == 12 + 2
    assert len(x) == 8 + 4  # box corners and the floor quad
    assert x[:, 1].max() == pytest.approx(0.5)  # the box top
    img = imread(tmp_path / "final.png")[..., :3]
    assert min(img.shape[:2]) >= 480
    box = np.asarray(OBSTACLE_COLORS["box"])
    # shaded box faces: colour proportional to the box colour (shade factor 0.35..1)
    ratio = img / box
    shaded = np.all(np.abs(ratio - ratio[..., :1]) < 0.05, axis=-1) & (ratio[..., 0] > 0.3)
    assert shaded.sum() > 500
    from PIL import Image

    with Image.open(tmp_path / "preview.gif") as gif:
        assert min(gif.size) >= 480


def test_scene_without_obstacles_writes_no_obstacles_file(tmp_path):
    run_scene("hanging", tmp_path, frames=1, preview=False)
    assert not (tmp_path / "obstacles.vtu").exists()


def test_draw_into_axes_frames_cloth_and_obstacles():
    from matplotlib.figure import Figure

    from clothsim.plotting import draw

    mesh = grid_cloth(5, center=(0, 1, 0)).mesh
    ax = Figure().add_subplot()
    draw(ax, mesh, mesh.vertices, effects=[cs.Sphere([0, 0, 0], 0.4)])
    assert "[m]" in ax.get_xlabel() and "[m]" in ax.get_ylabel()
    lo, hi = ax.get_ylim()
    assert lo < -0.3 and hi > 0.9  # the sphere's bottom and the cloth are both in frame


@pytest.mark.slow
def test_impulse_demo_disk_rises_at_least_5_cm_above_the_surrounding_cloth(tmp_path):
    scene = load_scene("impulse")
    (imp,) = [e for e in scene.to_dict()["effects"] if e["kind"] == "impulse"]
    run_scene(scene, tmp_path, frames=20, preview=False)
    X = np.load(tmp_path / "trajectory.npz")["positions"]
    q = X[0] - np.asarray(imp["center"])
    dist = np.hypot(q[:, 0], q[:, 2])
    disk, surrounding = dist <= imp["radius"], dist >= 2 * imp["radius"]
    lift = X[:, disk, 1].mean(axis=1) - np.median(X[:, surrounding, 1], axis=1)
    assert lift.max() >= 0.05
    assert "iterations" in scene.description
