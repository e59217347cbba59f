"""Frame files written with their cells encoded once (clothsim.io.vtufile): byte for byte what
meshio.write writes for the same frame, read back bit for bit by clothsim and meshio."""

import meshio
import numpy as np
import pytest

from clothsim import io
from clothsim.io.vtufile import BLOCK, VtuTemplate, meshio_version
from clothsim.mesh import Mesh, grid
from clothsim.springs import grid_springs, springs_from_pairs


def cloths():
    """(name, mesh, springs) of every kind of cell block a frame holds."""
    sheet = grid(5, 4, size=(1.0, 0.8), plane="xy")
    big = grid(60, 50, size=(1.0, 1.0), plane="xz")    # arrays over several zlib blocks
    yarn = Mesh(np.c_[np.linspace(0, 1, 6), np.zeros((6, 2))], np.zeros((0, 3), np.int64),
                [[i, i + 1] for i in range(5)])
    net = Mesh(yarn.vertices, np.zeros((0, 3), np.int64))     # springs as line cells
    return [("sheet", sheet, grid_springs(sheet, structural=10.0, shear=5.0)),
            ("sheet and strand", Mesh(sheet.vertices, sheet.triangles, [[0, 6], [6, 12]]),
             grid_springs(sheet, structural=10.0)),
            ("big", big, grid_springs(big, structural=10.0, bending=1.0)),
            ("strands", yarn, None),
            ("spring network", net, springs_from_pairs(net, [[0, 2], [2, 5]], 3.0)),
            ("points", net, None)]                          # one vertex cell per vertex


@pytest.mark.parametrize("compression", ["zlib", "none"])
@pytest.mark.parametrize("pinned", [False, True])
@pytest.mark.parametrize("case", range(6))
def test_frames_are_the_bytes_meshio_writes(tmp_path, case, pinned, compression):
    name, mesh, springs = cloths()[case]
    n = mesh.vertex_count
    rng = np.random.default_rng(case)
    x = mesh.vertices + rng.standard_normal((n, 3)) * 1e-2
    v = rng.standard_normal((n, 3))
    x[0, 2] = 1e300      # stretch and area beyond float32: inf in both files
    mask = rng.random(n) < 0.3 if pinned else None
    fast = io.FrameWriter(tmp_path / "a", mesh, springs=springs, compression=compression)
    slow = io.FrameWriter(tmp_path / "b", mesh, springs=springs, compression=compression)
    slow._template = False          # meshio.write, as before
    for k in range(2):              # the second file from the template made by the first
        fast.write_file(tmp_path / f"a{k}.vtu", x + k, v, mask)
        slow.write_file(tmp_path / f"b{k}.vtu", x + k, v, mask)
        data = (tmp_path / f"a{k}.vtu").read_bytes()
        assert data == (tmp_path / f"b{k}.vtu").read_bytes(), name
        assert f"meshio v{meshio_version()}".encode() in data[:300]
        back = meshio.read(tmp_path / f"a{k}.vtu")
        assert np.array_equal(back.points, x + k) and np.array_equal(
            back.point_data["velocity"], v)
        xr, vr = io.read_frame(tmp_path / f"a{k}.vtu")
        assert np.array_equal(xr, x + k) and np.array_equal(vr, v)
        if pinned:
            assert np.array_equal(back.point_data["pinned"], mask.astype(np.uint8))


@pytest.mark.parametrize("size", [0, 1, BLOCK - 1, BLOCK, BLOCK + 1, 3 * BLOCK])
def test_zlib_blocks_as_meshio_cuts_them(tmp_path, size):
    """Arrays of a block's size and around it: the headers' counts and last block."""
    raw = np.arange(size, dtype=np.uint8)
    template = VtuTemplate([("vertex", np.zeros((1, 1), np.int64))], 1, "zlib")
    element = template.array("a", raw).decode()
    mesh = meshio.Mesh(np.zeros((1, 3)), [("vertex", np.zeros((1, 1), np.int64))],
                       point_data={"a": np.zeros(1)}, field_data={})
    mesh.point_data = {"a": raw}    # meshio checks the lengths of point data; not its writer
    meshio.write(tmp_path / "m.vtu", mesh, file_format="vtu", compression="zlib")
    assert element in (tmp_path / "m.vtu").read_text()
