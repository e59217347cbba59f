"""Pictures show what happened: cloth lying on an obstacle is drawn on it, cloth behind an
obstacle is hidden by it (rendered with a flat palette and read back pixel by pixel); large
cloths are drawn decimated with their outline kept; shading follows the cloth's shape."""

from functools import cache

import numpy as np
import pytest

import clothsim as cs
from clothsim.camera import View, hidden_triangles, shade, solid_depth
from clothsim.display import OBSTACLE_COLORS, decimate, obstacle_surfaces
from clothsim.painter import FACE_COLOR
from clothsim.plotting import draw
from clothsim.scene import load_scene

pytest.importorskip("matplotlib")


#: Frames after which a built-in scene's cloth rests on its obstacle as at its last frame,
#: where that comes much earlier: drape-sphere lies on the sphere from about 1 s on (61
#: vertices on it in view at 2 s and at its last frame, 7 s: 4 s of CPU against 10 s).
RESTING = {"drape-sphere": 60}


@cache
def last_frame(name: str):
    """The simulation of a built-in scene after all its frames, or after its cloth comes to
    lie on the obstacle (:data:`RESTING`); run once for the tests of this module, which
    only read it."""
    scene = load_scene(name)
    sim = scene.build_simulation()
    for _ in range(RESTING.get(name, scene.frames) * scene.substeps):
        sim.step()
    return sim


def render(mesh, x, effects, view: View, points=None):
    """Flat-palette picture (one colour for the cloth, one per obstacle, no shading or
    edges) and the pixel (row, column) of each vertex (or of ``points`` (k, 3))."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6, 6), dpi=100)
    canvas = FigureCanvasAgg(fig)
    ax = fig.add_axes((0, 0, 1, 1))
    draw(ax, mesh, x, effects=effects, view=view, shading=False, edges=False)
    canvas.draw()
    rgb = np.asarray(canvas.buffer_rgba())[..., :3] / 255.0
    xy = ax.transData.transform(view.project(x if points is None else points)[:, :2])
    height = rgb.shape[0]
    pixel = np.column_stack([height - 1 - np.floor(xy[:, 1]), np.floor(xy[:, 0])]).astype(int)
    return rgb, pixel


def colour_of(rgb, pixel):
    return rgb[pixel[:, 0], pixel[:, 1]]


def is_colour(c, ref):
    return np.all(np.abs(np.asarray(c) - np.asarray(ref)) < 2.5 / 255, axis=-1)


def interior(mesh) -> np.ndarray:
    ny, nx = mesh.grid_shape
    i, j = np.divmod(np.arange(mesh.vertex_count), nx)
    return (i > 0) & (i < ny - 1) & (j > 0) & (j < nx - 1)


def resting_in_view(mesh, x, surface, view, *, facing: float = 0.3,
                    margin: float = 0.0) -> np.ndarray:
    """Interior vertices on the obstacle's contact surface (within 0.1 mm; ``margin`` [m]
    off the drawn solid, its contact thickness) whose surface faces the camera (outward
    normal · direction to the camera > ``facing``)."""
    on = np.abs(solid_depth(surface, x) + margin) < 1e-4
    if surface.kind == "sphere":
        center = surface.vertices.mean(axis=0)
        normal = (x - center) / np.linalg.norm(x - center, axis=1, keepdims=True)
    else:
        lo, hi = surface.vertices.min(axis=0), surface.vertices.max(axis=0)
        gap = np.stack([x - hi, lo - x], axis=1)  # (n, 2, 3): outside by, per face
        normal = np.zeros_like(x)
        side = np.argmax(gap.reshape(len(x), 6), axis=1)
        normal[np.arange(len(x)), side % 3] = np.where(side < 3, 1.0, -1.0)
    return on & interior(mesh) & (normal @ view.toward > facing)


@pytest.mark.parametrize("name, kind, at_least", [("drape-sphere", "sphere", 40),
                                                  ("drop-on-square", "box", 80)])
def test_cloth_resting_on_an_obstacle_is_drawn_on_it(name, kind, at_least):
    sim = last_frame(name)
    mesh, x, view = sim.model.mesh, sim.state.positions, View()
    surface = next(s for s in obstacle_surfaces(sim.effects, x) if s.kind == kind)
    margin = next(e for e in sim.effects if e.kind == kind).margin     # the "auto" thickness
    assert margin > 0
    on = resting_in_view(mesh, x, surface, view, margin=margin)
    # a set of vertices: the top and the camera-facing sides (measured with the "auto"
    # thickness: 87 on the box, of them 65 on its top; 100 and more on the bare box)
    assert on.sum() >= at_least
    # and the centroids of the triangles with three such corners, folds over a front edge
    # of the box included (their centroid is inside the solid)
    lying = on[mesh.triangles].all(axis=1)
    points = np.vstack([x[on], x[mesh.triangles[lying]].mean(axis=1)])
    rgb, pixel = render(mesh, x, sim.effects, view, points)
    seen = colour_of(rgb, pixel)
    assert is_colour(seen, FACE_COLOR).all(), (
        f"{(~is_colour(seen, FACE_COLOR)).sum()} of {len(points)} points not cloth")
    # the obstacle is drawn too (not hidden by mistake under a cloth drawn everywhere)
    assert is_colour(rgb, OBSTACLE_COLORS[kind]).sum() > 1000


def test_cloth_lying_on_the_floor_is_drawn_on_it():
    mesh = cs.grid(11, 11, size=(1.0, 1.0))  # at y = 0, on the plane's surface
    floor = cs.Plane([0.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    rgb, pixel = render(mesh, np.array(mesh.vertices), [floor], View())
    assert is_colour(colour_of(rgb, pixel[interior(mesh)]), FACE_COLOR).all()
    assert is_colour(rgb, OBSTACLE_COLORS["plane"]).sum() > 1000  # the floor around it


def test_cloth_draped_on_a_sphere_seen_from_below_is_hidden_by_it():
    """The same frame, camera under the sphere: the cloth on its top is behind it."""
    sim = last_frame("drape-sphere")
    mesh, x = sim.model.mesh, sim.state.positions
    view = View(azimuth=35.0, elevation=-70.0)
    sphere = next(s for s in obstacle_surfaces(sim.effects, x) if s.kind == "sphere")
    center = sphere.vertices.mean(axis=0, keepdims=True)
    rgb, pixel = render(mesh, x, sim.effects, view, center)
    assert is_colour(colour_of(rgb, pixel), OBSTACLE_COLORS["sphere"]).all()
    # the cloth is in the picture, around the sphere
    assert is_colour(rgb, FACE_COLOR).sum() > 1000


def test_cloth_hanging_against_the_back_of_a_sphere_is_hidden():
    view = View(azimuth=0.0, elevation=0.0)  # camera on +z
    mesh = cs.grid(21, 21, size=(1.0, 1.0), center=(0.0, 0.5, -0.3), plane="xy")
    sphere = cs.Sphere([0.0, 0.5, 0.0], 0.3)  # touches the cloth at its back pole
    x = np.array(mesh.vertices)
    rgb, pixel = render(mesh, x, [sphere], view, np.array([[0.0, 0.5, 0.0]]))
    assert is_colour(colour_of(rgb, pixel), OBSTACLE_COLORS["sphere"]).all()
    # and the cloth around it shows: near its corners (pixels moved inward)
    _, pixel = render(mesh, x, [sphere], view)
    corner = pixel[[0, 20, 420, 440]] + [[-3, 3], [-3, -3], [3, 3], [3, -3]]
    assert is_colour(colour_of(rgb, corner), FACE_COLOR).all()


def test_hidden_rule_per_triangle():
    """On the sphere: resting triangles in front drawn, behind hidden; off it: the ray."""
    (s,) = obstacle_surfaces([cs.Sphere([0.0, 0.0, 0.0], 1.0)])
    view = View(azimuth=0.0, elevation=0.0)  # toward = +z
    # small flat triangles with corners on the unit sphere, at the front and back poles
    a = 0.1
    front = np.array([[0, a, 1], [-a, -a, 1], [a, -a, 1]], float)
    front /= np.linalg.norm(front, axis=1, keepdims=True)
    back = front * [1, 1, -1]
    behind_off = back * 1.5  # well behind, not touching
    in_front_off = front * 1.5
    x = np.vstack([front, back, behind_off, in_front_off])
    tris = np.arange(12).reshape(4, 3)
    hidden = hidden_triangles([s], view, x, tris, 1e-4)
    np.testing.assert_array_equal(hidden, [False, True, True, False])
    # the centroid of the resting triangle is inside the sphere (its sag), as in the issue
    assert solid_depth(s, x[tris[0]].mean(axis=0, keepdims=True))[0] > 1e-4


def test_hidden_rule_on_a_box_edge_and_beside_it():
    (s,) = obstacle_surfaces([cs.Box([-1, -1, -1], [1, 1, 1])])
    view = View(azimuth=0.0, elevation=30.0)  # sees the top (+y) and the front (+z)
    # a triangle folded over the front-top edge (centroid inside), one over the back-top
    # edge (one corner on the visible top), one lying on the back face, one far beside
    fold_front = [[0, 1, 0.9], [0.1, 1, 0.9], [0.05, 0.9, 1]]
    fold_back = [[0, 1, -0.9], [0.1, 1, -0.9], [0.05, 0.9, -1]]
    on_back = [[0, 0, -1], [0.1, 0, -1], [0.05, 0.1, -1]]
    beside = [[-5, 0, -2], [-5.1, 0, -2], [-5.05, 0.1, -2]]  # behind the front plane only
    x = np.array(fold_front + fold_back + on_back + beside, float)
    hidden = hidden_triangles([s], view, x, np.arange(12).reshape(4, 3), 1e-4)
    np.testing.assert_array_equal(hidden, [False, False, True, False])


def test_decimated_grid_keeps_the_outline_within_one_step():
    sim = last_frame("drop-on-square")
    x = sim.state.positions
    mesh = sim.model.mesh  # 25 × 25 vertices, 1152 triangles
    small, note = decimate(mesh, 200)
    assert small.triangle_count <= 200 and "every 3rd row and column" in note
    step = 3 * np.linalg.norm(x[mesh.triangles[:, 0]] - x[mesh.triangles[:, 1]], axis=1).max()
    kept = np.unique(small.triangles)
    for p in (x, View().project(x)):  # in space and on the screen
        lo, hi = p.min(axis=0), p.max(axis=0)
        klo, khi = p[kept].min(axis=0), p[kept].max(axis=0)
        assert np.all(klo - lo <= step) and np.all(hi - khi <= step)
    # the grid's corners are kept, so at rest the outline is exact
    rest = mesh.vertices
    np.testing.assert_array_equal(np.ptp(rest[kept], axis=0), np.ptp(rest, axis=0))


def test_decimated_mesh_keeps_the_outline_within_one_step():
    # a grid without its grid shape (as read from a file): vertex clustering
    grid = cs.grid(81, 61, size=(1.6, 1.2))
    mesh = cs.Mesh(grid.vertices, grid.triangles)
    small, note = decimate(mesh, 1000)
    assert small.triangle_count <= 1000 and note.endswith(f"of {mesh.triangle_count:,} "
                                                          "triangles drawn")
    assert small.triangle_count > 250  # not needlessly coarse
    kept = np.unique(small.triangles)
    step = np.sqrt(2 * 1.6 * 1.2 / 1000) * 1.25 ** 3
    lo, hi = mesh.vertices.min(axis=0), mesh.vertices.max(axis=0)
    klo, khi = mesh.vertices[kept].min(axis=0), mesh.vertices[kept].max(axis=0)
    assert np.all(klo - lo <= step) and np.all(hi - khi <= step)
    # orientation kept: every normal still points along the grid's +y
    t = mesh.vertices[small.triangles]
    n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    assert np.all(n[:, 1] > 0)
    assert decimate(mesh, 10**6) == (mesh, "")


def test_pictures_of_a_large_cloth_say_they_are_decimated(tmp_path, monkeypatch):
    from matplotlib.figure import Figure

    from clothsim.plotting import MAX_TRIANGLES, write_final_image, write_preview

    titles = []
    suptitle = Figure.suptitle

    def spy(self, text, **kw):
        titles.append(text)
        return suptitle(self, text, **kw)

    monkeypatch.setattr(Figure, "suptitle", spy)
    mesh = cs.grid(90, 90)  # 15 842 triangles
    assert mesh.triangle_count > MAX_TRIANGLES
    write_final_image(tmp_path / "f.png", mesh.vertices, mesh, title="big")
    write_preview(tmp_path / "p.gif", np.stack([mesh.vertices] * 2), mesh)
    small = cs.grid(20, 20)
    write_final_image(tmp_path / "s.png", small.vertices, small, title="small")
    assert titles == ["big, every 2nd row and column drawn", "every 2nd row and column drawn",
                      "small"]


def test_shading_shows_a_fold_that_flat_shading_would_show_only_by_its_edges():
    """A cylinder-like fold lit from the camera: brightness varies smoothly across it, and
    a flat sheet facing the camera is uniformly bright."""
    mesh = cs.grid(41, 41, size=(1.0, 1.0), plane="xy")
    view = View(azimuth=0.0, elevation=0.0)
    flat = shade(view, mesh.vertices, mesh.triangles)
    assert np.ptp(flat) < 1e-12
    x = np.array(mesh.vertices)
    x[:, 2] = 0.2 * np.sin(2 * np.pi * x[:, 0])  # folds along y
    lit = shade(view, x, mesh.triangles)
    assert np.ptp(lit) > 0.2
    # per-vertex normals: neighbouring triangles across an edge differ less than their
    # face normals would make them
    faceted = shade(view, x, mesh.triangles, smooth=False)
    assert np.abs(np.diff(lit[::2])).max() < np.abs(np.diff(faceted[::2])).max()


def test_a_large_flat_sheet_shows_its_tilt_without_edges():
    """Above the edge limit a flat sheet is not one flat colour: it darkens with distance
    from the camera (and no triangle edges are drawn)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from clothsim.painter import EDGE_COLOR
    from clothsim.plotting import EDGE_LIMIT

    mesh = cs.grid(60, 60, size=(1.0, 1.0))  # lies flat: every normal the same
    assert mesh.triangle_count > EDGE_LIMIT
    view = View()
    fig = Figure(figsize=(6, 6), dpi=100)
    canvas = FigureCanvasAgg(fig)
    ax = fig.add_axes((0, 0, 1, 1))
    draw(ax, mesh, mesh.vertices, view=view)
    canvas.draw()
    rgb = np.asarray(canvas.buffer_rgba())[..., :3] / 255.0
    depth = view.project(mesh.vertices)[:, 2]
    inner = interior(mesh)
    near = np.flatnonzero(inner)[np.argmax(depth[inner])]
    far = np.flatnonzero(inner)[np.argmin(depth[inner])]
    xy = ax.transData.transform(view.project(mesh.vertices[[near, far]])[:, :2])
    rows = (rgb.shape[0] - 1 - np.floor(xy[:, 1])).astype(int)
    near_rgb, far_rgb = rgb[rows, np.floor(xy[:, 0]).astype(int)]
    assert far_rgb.sum() < 0.8 * near_rgb.sum()
    assert not is_colour(rgb, EDGE_COLOR).any()


# thickness 0 (its own 120-frame run) shows that the measure can fail: a variant (-m slow);
# make test keeps the demo's own "auto" case
@pytest.mark.parametrize("thickness", ["auto", pytest.param(0.0, marks=pytest.mark.slow)])
def test_the_box_top_edges_under_the_demo_cloth_are_hidden(thickness):
    """The demo's last frame: points along the middle of the box's four top edges, which
    the cloth drapes over, are drawn as cloth. With the vertices on the box itself
    (thickness 0) the edge stands in front of the triangles between them: the box's rim
    shows through (the strip the "auto" thickness removes) at 50 of the 100 points."""
    if thickness == "auto":          # the demo's own setting: its last frame, shared
        sim = last_frame("drop-on-square")
    else:
        scene = load_scene("drop-on-square", [f"effects[1].thickness={thickness!r}"])
        sim = scene.build_simulation()
        sim.run(scene.frames)
    box = next(e for e in sim.effects if e.kind == "box")
    assert box.thickness == thickness
    lo, hi = box.min, box.max
    s = np.linspace(0.2, 0.8, 25)[:, None]
    edges = [(lo[[0, 1, 2]], [1, 0, 0]), (lo[[0, 1, 2]], [0, 0, 1]),
             ([lo[0], 0, hi[2]], [1, 0, 0]), ([hi[0], 0, lo[2]], [0, 0, 1])]
    points = np.vstack([np.asarray(p, float) + s * (hi - lo) * d for p, d in edges])
    points[:, 1] = hi[1]
    rgb, pixel = render(sim.model.mesh, sim.state.positions, sim.effects, View(), points)
    cloth = is_colour(colour_of(rgb, pixel), FACE_COLOR)
    if thickness == "auto":
        assert cloth.all(), f"{(~cloth).sum()} of {len(points)} edge points not cloth"
    else:
        assert (~cloth).sum() >= 25      # measured: 50 of the 100
