"""Pictures of a large cloth touch what they draw only: at most ``MAX_TRIANGLES`` triangles,
and only the vertices those use are projected, shaded and framed (counts, no timing); the
picture is the one the whole vertex array would give."""

import numpy as np
import pytest

import clothsim as cs
from clothsim.camera import View
from clothsim.display import decimate, picture_mesh
from clothsim.scene import load_scene

pytest.importorskip("matplotlib")


@pytest.mark.parametrize("shape", ["grid", "file", "strands"])
def test_picture_mesh_is_the_decimated_mesh_on_the_vertices_it_uses(shape):
    grid = cs.grid(81, 61, size=(1.6, 1.2))
    mesh = {"grid": grid, "file": cs.Mesh(grid.vertices, grid.triangles),  # no grid shape
            "strands": cs.Mesh(grid.vertices, grid.triangles, [[0, 4940], [7, 8]])}[shape]
    full, note = decimate(mesh, 1000)
    drawn, take, note2 = picture_mesh(mesh, 1000)
    assert note2 == note != ""
    assert drawn.triangle_count == full.triangle_count <= 1000
    np.testing.assert_array_equal(take[drawn.triangles], full.triangles)
    np.testing.assert_array_equal(take[drawn.strands], mesh.strands)
    np.testing.assert_array_equal(drawn.vertices, mesh.vertices[take])
    # exactly the vertices used, in order: a fraction of the cloth's
    used = np.unique(np.concatenate([full.triangles.ravel(), mesh.strands.ravel()]))
    np.testing.assert_array_equal(take, used)
    assert len(take) < mesh.vertex_count / 3


def test_a_513_grid_is_drawn_from_8192_triangles_on_4225_vertices():
    """The figures picture_mesh's docstring gives."""
    from clothsim.plotting import MAX_TRIANGLES

    mesh = cs.grid(513, 513)
    drawn, take, note = picture_mesh(mesh, MAX_TRIANGLES)
    assert (drawn.triangle_count, len(take), mesh.vertex_count) == (8192, 4225, 263169)
    assert note == "every 8th row and column drawn"


def test_picture_mesh_of_a_small_cloth_is_the_cloth():
    mesh = cs.grid(20, 20)
    assert picture_mesh(mesh, 10_000) == (mesh, None, "")
    tiny = cs.grid(2, 2)  # 2 triangles, the smallest budget
    assert picture_mesh(tiny, 2) == (tiny, None, "")


def test_a_large_cloth_is_drawn_from_at_most_max_triangles_and_their_vertices(tmp_path,
                                                                              monkeypatch):
    from matplotlib.collections import PolyCollection

    from clothsim.plotting import MAX_TRIANGLES, write_final_image, write_preview

    n = 201
    sim = load_scene("hanging", [f"cloth.resolution=[{n}, {n}]"]).build_simulation()
    mesh = sim.model.mesh  # 80 000 triangles
    assert mesh.triangle_count > 5 * MAX_TRIANGLES
    drawn, take, _ = picture_mesh(mesh, MAX_TRIANGLES)
    rows, polygons = [], []
    project, set_verts = View.project, PolyCollection.set_verts

    def spy_project(self, x):
        rows.append(np.asarray(x).reshape(-1, 3).shape[0])
        return project(self, x)

    def spy_verts(self, verts, *args, **kw):
        polygons.append(len(verts))
        return set_verts(self, verts, *args, **kw)

    monkeypatch.setattr(View, "project", spy_project)
    monkeypatch.setattr(PolyCollection, "set_verts", spy_verts)
    x = np.array(mesh.vertices)
    x[:, 2] += 0.1 * np.sin(3 * x[:, 0])  # not flat
    frames = np.stack([mesh.vertices, x, x + [0.0, -0.05, 0.0]])
    write_preview(tmp_path / "p.gif", frames, mesh, times=np.arange(3) / 30,
                  effects=sim.effects)
    write_final_image(tmp_path / "f.png", frames[-1], mesh, effects=sim.effects, t=0.1)
    assert polygons and max(polygons) <= MAX_TRIANGLES  # no obstacle here
    assert 0 < max(rows) <= 3 * len(take)  # the framing of 3 frames
    assert len(take) < mesh.vertex_count / 8


def test_pins_of_a_decimated_cloth_are_drawn_where_they_are_even_off_the_drawn_grid():
    from matplotlib.figure import Figure

    from clothsim.plotting import MAX_TRIANGLES, draw
    from clothsim.scene import Scene

    n = 101
    pinned = [n * (n - 1) + 1, n * n // 2 + 1]  # top row, 2nd column; by the middle
    scene = Scene.from_dict({
        "scene": {"name": "pins", "frames": 1},
        "cloth": {"shape": "grid", "resolution": [n, n], "plane": "xy"},
        "effects": [{"kind": "gravity"}, {"kind": "pin", "vertices": pinned}]})
    sim = scene.build_simulation()
    mesh = sim.model.mesh
    _, take, note = picture_mesh(mesh, MAX_TRIANGLES)
    assert note and not set(pinned) & set(take)  # neither is a vertex drawn
    x = np.array(mesh.vertices) + [0.0, 0.0, 0.3]
    ax = Figure().add_subplot()
    draw(ax, mesh, x, effects=sim.effects)
    (dots,) = ax.lines
    want = View().project(x[pinned])[:, :2]
    np.testing.assert_allclose(np.column_stack(dots.get_data()), want)


def test_a_decimated_picture_is_the_picture_from_the_whole_vertex_array(tmp_path):
    """Drawing from the used vertices only changes nothing: same pixels as the decimated
    mesh drawn on the cloth's whole vertex array."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from clothsim.painter import SceneArtist, frame_axes
    from clothsim.plotting import MAX_TRIANGLES, draw

    scene = load_scene("drape-sphere", ["cloth.resolution=[90, 90]"])
    sim = scene.build_simulation()
    mesh = sim.model.mesh
    x = np.array(mesh.vertices)
    x[:, 1] -= 0.4 * np.exp(-4 * (x[:, 0] ** 2 + x[:, 2] ** 2))  # sags onto the sphere
    images = []
    for compact in (True, False):
        fig = Figure(figsize=(4, 4), dpi=100)
        canvas = FigureCanvasAgg(fig)
        ax = fig.add_axes((0, 0, 1, 1))
        if compact:
            draw(ax, mesh, x, effects=sim.effects)
        else:  # the decimated mesh indexing all vertices, framed on those it uses
            full, _ = decimate(mesh, MAX_TRIANGLES)
            used = np.unique(full.triangles)
            surfaces = cs.display.obstacle_surfaces(sim.effects, x[used])
            view = View()
            depth = frame_axes(ax, view, x[used], surfaces)
            SceneArtist(ax, full, view, x, False, surfaces, sim.effects, True,
                        depth).update(x)
        canvas.draw()
        images.append(np.asarray(canvas.buffer_rgba()).copy())
    assert mesh.triangle_count > MAX_TRIANGLES
    np.testing.assert_array_equal(images[0], images[1])


def test_pictures_vs_table_takes_medians_and_ratios():
    """benchmarks/pictures_vs.py's table from made-up runs (the runs take a minute)."""
    from benchmarks import pictures_vs

    def run(i, p, f):
        return {"import": i, "preview": p, "final": f, "all": i + p + f}

    res = {"old": [run(0.4, 1.0, 0.2), run(0.6, 1.4, 0.3), run(0.5, 1.2, 0.2)],
           "new": [run(0.4, 0.6, 0.1), run(0.4, 0.5, 0.2)]}
    lines = pictures_vs.table(res, True)
    assert lines[2] == "| matplotlib import | 0.500 s | 0.400 s | 0.80 |"
    assert lines[3] == "| preview.gif | 1.200 s | 0.550 s | 0.46 |"
    assert lines[5] == "| pictures in all | 1.900 s | 1.100 s | 0.58 |"
    assert lines[-1].endswith("yes.")
    assert pictures_vs.table(res, False)[-1].endswith("NO.")


def test_pictures_vs_tells_one_changed_pixel(tmp_path):
    from PIL import Image

    from benchmarks.pictures_vs import same_pixels

    rgb = np.zeros((8, 8, 3), np.uint8)
    changed = rgb.copy()
    changed[3, 4] = (255, 0, 0)
    for name, last in (("a", rgb), ("b", rgb), ("c", changed)):
        (tmp_path / name).mkdir()
        frames = [Image.fromarray(f) for f in (changed, rgb)]
        frames[0].save(tmp_path / name / "preview.gif", save_all=True,
                       append_images=frames[1:])
        Image.fromarray(last).save(tmp_path / name / "final.png")  # one pixel differs in c
    assert same_pixels(tmp_path / "a", tmp_path / "b")
    assert not same_pixels(tmp_path / "a", tmp_path / "c")
