"""Every file a run writes, clothsim reads back, for every cloth shape: frames (read_frame,
trajectory.pvd), trajectory.npz, the run folder (--resume continues bit for bit, compare
passes against itself), including cloths with no triangles (springs only) and one vertex.
Frames carry pinned, stretch and area_ratio for ParaView."""

import json

import meshio
import numpy as np
import pytest

from clothsim import cli, io
from clothsim.io.cells import vertex_stretch
from clothsim.mesh import grid
from clothsim.runner import run_scene
from clothsim.scene import load_scene

from ..data_sets import write_assignment_scene

GRAVITY = '[[effects]]\nkind = "gravity"\n'


def files_scene(tmp, name, vertices, triangles=None, springs=None, pin=None):
    """A ``shape = "files"`` scene in ``tmp``: plain-text vertices, triangles, spring table."""
    rows = (" ".join(repr(float(c)) for c in v) for v in vertices)
    (tmp / f"{name}-v.txt").write_text("\n".join(rows))
    cloth = f'shape = "files"\nvertices = "{name}-v.txt"\nmass = 0.5\n'
    if triangles is not None:
        (tmp / f"{name}-t.txt").write_text("\n".join(" ".join(map(str, t)) for t in triangles))
        cloth += f'triangles = "{name}-t.txt"\n'
    text = f'[scene]\nname = "{name}"\nframes = 2\n[cloth]\n{cloth}'
    if springs is not None:
        (tmp / f"{name}-s.txt").write_text("\n".join(" ".join(repr(c) for c in s) for s in springs))
        text += f'[springs]\ntable = "{name}-s.txt"\n'
    elif triangles is not None:
        text += "[springs]\nstructural = 100.0\n"
    text += GRAVITY
    if pin is not None:
        text += f'[[effects]]\nkind = "pin"\nvertices = {pin}\n'
    path = tmp / f"{name}.toml"
    path.write_text(text)
    return path


def shapes(tmp):
    """(label, scene path or name) for every cloth shape, the degenerate ones included."""
    out = []
    sheet = grid(3, 3, size=(0.2, 0.2))
    io.write_mesh(tmp / "sheet.obj", sheet)
    (tmp / "grid.toml").write_text(
        '[scene]\nname = "g"\nframes = 2\n[cloth]\nshape = "grid"\nresolution = [4, 3]\n'
        '[springs]\nstructural = 100.0\n' + GRAVITY + '[[effects]]\nkind = "pin"\n'
        'vertices = [0]\n')
    out.append(("grid", tmp / "grid.toml"))
    (tmp / "mesh.toml").write_text(
        '[scene]\nname = "m"\nframes = 2\n[cloth]\nshape = "mesh"\nmesh = "sheet.obj"\n'
        '[springs]\nstructural = 100.0\n' + GRAVITY)
    out.append(("mesh", tmp / "mesh.toml"))
    (tmp / "polygon.toml").write_text(
        '[scene]\nname = "p"\nframes = 2\n[cloth]\nshape = "polygon"\n'
        'outline = [[0, 0], [0.3, 0], [0.15, 0.25]]\nspacing = 0.1\n'
        '[springs]\nstructural = 100.0\n' + GRAVITY)
    out.append(("polygon", tmp / "polygon.toml"))
    out.append(("files", files_scene(tmp, "tri", sheet.vertices, sheet.triangles, pin=[0])))
    chain = [[0.1 * i, 0.0, 0.0] for i in range(4)]
    out.append(("springs only", files_scene(
        tmp, "chain", chain, springs=[[i, i + 1, 200.0, 0.1] for i in range(3)], pin=[0])))
    out.append(("one vertex", files_scene(tmp, "dot", [[0.0, 1.0, 0.0]])))
    out.append(("one vertex on a pin spring", files_scene(
        tmp, "bob", [[0.0, 1.0, 0.0]], springs=[[0, -1, 50.0, 0.0]])))
    # the assignment's format (JSON + OBJ): scenes like its chain and single spring
    out += [("jacobson strands", write_assignment_scene(tmp / "a", "chain")),
            ("jacobson one mass", write_assignment_scene(tmp / "a", "spring"))]
    return out


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("shapes")
    done = {}
    for label, scene in shapes(tmp):
        out = tmp / label.replace(" ", "-")
        # the pictures are drawn (and checked) once per shape, at the resumed run's end
        run_scene(scene, out, frames=2, preview=False)
        resumed = run_scene(scene, out, frames=4, resume=True, preview=True)
        whole = run_scene(scene, tmp / (out.name + "-whole"), frames=4, preview=False)
        done[label] = (scene, out, resumed, whole)
    return done


LABELS = ["grid", "mesh", "polygon", "files", "springs only", "one vertex",
          "one vertex on a pin spring", "jacobson strands", "jacobson one mass"]


@pytest.mark.parametrize("label", LABELS)
def test_every_file_reads_back_and_resume_continues_bitwise(runs, label, capsys):
    scene, out, resumed, whole = runs[label]
    assert resumed.status == "completed" and resumed.last_frame == 4
    z = np.load(out / "trajectory.npz")
    w = np.load(whole.out_dir / "trajectory.npz")
    assert z["positions"].shape[0] == 5
    # resumed from frame 2 read back from its .vtu: identical to an uninterrupted run
    assert np.array_equal(z["positions"], w["positions"])
    assert np.array_equal(z["velocities"], w["velocities"])
    entries = io.read_pvd(out / "trajectory.pvd")
    assert [p.name for _, p in entries] == [f"frame_{k:06d}.vtu" for k in range(5)]
    for k, (_, path) in enumerate(entries):
        x, v = io.read_frame(path)
        assert np.array_equal(x, z["positions"][k]) and np.array_equal(v, z["velocities"][k])
        cells = meshio.read(path).cells
        assert cells and sum(len(c.data) for c in cells) > 0  # never a file without cells
    assert json.loads((out / "run.json").read_text())["status"] == "completed"
    assert (out / "final.png").stat().st_size > 0 and (out / "preview.gif").stat().st_size > 0
    # compare: the frames against the trajectory, and the folder against itself
    assert cli.main(["compare", str(out / "trajectory.pvd"), str(out / "trajectory.npz")]) == 0
    assert cli.main(["compare", str(out), str(whole.out_dir)]) == 0
    assert "PASS" in capsys.readouterr().out


def test_springs_only_frames_hold_the_springs_as_lines(runs):
    _, out, _, _ = runs["springs only"]
    m = meshio.read(out / "frame_000004.vtu")
    assert [c.type for c in m.cells] == ["line"]
    assert m.cells[0].data.tolist() == [[0, 1], [1, 2], [2, 3]]
    _, out, _, _ = runs["one vertex"]
    m = meshio.read(out / "frame_000004.vtu")
    assert [c.type for c in m.cells] == ["vertex"] and m.cells[0].data.tolist() == [[0]]


def test_frames_carry_pinned_stretch_and_area_ratio(runs):
    """meshio finds them; stretch and area_ratio are 0 and 1 at rest and match a direct
    computation on a stretched frame."""
    scene, out, _, _ = runs["grid"]
    model = load_scene(scene).build_model()
    rest = meshio.read(out / "frame_000000.vtu")
    assert rest.point_data["pinned"].tolist() == [1] + [0] * 11
    np.testing.assert_array_equal(rest.point_data["stretch"], 0.0)
    np.testing.assert_allclose(rest.cell_data["area_ratio"][0], 1.0, rtol=1e-6)
    m = meshio.read(out / "frame_000004.vtu")
    x = m.points
    ij, r = model.springs.spring_vertices, model.springs.spring_rest_length
    assert np.abs(np.linalg.norm(x[ij[:, 0]] - x[ij[:, 1]], axis=1) / r - 1).max() > 1e-3
    direct = np.zeros(len(x))  # one spring at a time
    count = np.zeros(len(x))
    for (a, b), r0 in zip(ij, r):
        s = abs(np.linalg.norm(x[a] - x[b]) / r0 - 1.0)
        direct[[a, b]] += s
        count[[a, b]] += 1
    assert m.point_data["stretch"].dtype == np.float32  # for colouring: small files
    np.testing.assert_allclose(m.point_data["stretch"], direct / count, rtol=1e-6, atol=1e-12)
    t = model.mesh.triangles
    area = lambda p: 0.5 * np.linalg.norm(np.cross(p[t[:, 1]] - p[t[:, 0]],  # noqa: E731
                                                   p[t[:, 2]] - p[t[:, 0]]), axis=1)
    np.testing.assert_allclose(m.cell_data["area_ratio"][0], area(x) / area(model.mesh.vertices),
                               rtol=1e-6)
    assert np.ptp(m.cell_data["area_ratio"][0]) > 1e-4  # not a constant


def test_vertex_stretch_without_springs_is_zero():
    x = np.zeros((3, 3))
    np.testing.assert_array_equal(vertex_stretch(x, np.zeros((0, 2), int), np.zeros(0)), 0.0)
    x = np.array([[0.0, 0, 0], [2.0, 0, 0], [2.0, 3.0, 0]])
    s = vertex_stretch(x, [[0, 1], [1, 2]], [1.0, 2.0])  # strains 1 and 0.5
    np.testing.assert_allclose(s, [1.0, 0.75, 0.5])


def test_obstacles_are_part_of_the_time_series(tmp_path):
    import xml.etree.ElementTree as ET

    out = tmp_path / "r"
    run_scene("drop-on-square", out, frames=2, preview=False)
    root = ET.parse(out / "trajectory.pvd").getroot()
    sets = [(d.get("timestep"), d.get("part"), d.get("file")) for d in root.iter("DataSet")]
    frames = [s for s in sets if s[1] == "0"]
    obstacles = [s for s in sets if s[1] == "1"]
    assert [f for _, _, f in frames] == [f"frame_{k:06d}.vtu" for k in range(3)]
    # the obstacles at every time of the series, so ParaView shows them throughout
    assert [(t, f) for t, _, f in obstacles] == [(t, "obstacles.vtu") for t, _, _ in frames]
    assert (out / "obstacles.vtu").is_file()
    # the readers still see the cloth's frames only
    assert [p.name for _, p in io.read_pvd(out / "trajectory.pvd")] == [f for *_, f in frames]
