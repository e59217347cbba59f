"""Every writer goes through io.common.atomic_path: a failed write leaves the previous file
whole and no temporary file behind; the temporary name keeps the suffix, so writers that
choose a format by it (matplotlib, meshio, np.savetxt) write the format asked for."""

import json
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from clothsim import io
from clothsim.accuracy import plots as acc_plots
from clothsim.accuracy.report import write_sidecar
from clothsim.gallery import grid_cloth
from clothsim.io.common import atomic_path, write_text


def leftovers(folder):
    return sorted(p.name for p in folder.iterdir() if ".tmp" in p.name)


def test_the_temporary_name_keeps_the_suffix_and_is_removed_on_failure(tmp_path):
    target = tmp_path / "a.vtu"
    with atomic_path(target) as tmp:
        assert tmp.parent == tmp_path and tmp.suffix == ".vtu" and tmp.name.startswith(".")
        tmp.write_text("x")
    assert target.read_text() == "x" and leftovers(tmp_path) == []
    with pytest.raises(RuntimeError), atomic_path(target) as tmp:
        tmp.write_text("half")
        raise RuntimeError("killed")
    assert target.read_text() == "x" and leftovers(tmp_path) == []
    missing = tmp_path / "no" / "such.txt"
    with pytest.raises(FileNotFoundError) as caught:   # errors name the asked-for file
        write_text(missing, "x")
    assert caught.value.filename == str(missing) and str(missing) in str(caught.value)


def test_a_failed_write_keeps_the_previous_file(tmp_path, monkeypatch):
    path = write_sidecar({"scene": "a"}, tmp_path / "accuracy.json")
    before = path.read_text()

    def half_then_full(self, text, *args, **kwargs):   # the disk fills up mid-write
        with open(self, "w") as fh:
            fh.write(text[:len(text) // 2])
        raise OSError("disk full")

    monkeypatch.setattr(Path, "write_text", half_then_full)
    with pytest.raises(OSError):
        write_sidecar({"scene": "b"}, path)
    assert path.read_text() == before and json.loads(before) == {"scene": "a"}
    assert leftovers(tmp_path) == []


@pytest.mark.parametrize("suffix, head", [(".png", b"\x89PNG"), (".svg", b"<?xml"),
                                          (".pdf", b"%PDF")])
def test_figures_are_written_in_the_format_of_their_suffix(tmp_path, suffix, head):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path = acc_plots._save(plt, plt.figure(), tmp_path / f"fig{suffix}")
    assert path.read_bytes().startswith(head) and leftovers(tmp_path) == []


def test_text_matrices_vectors_and_meshes_round_trip_through_the_temporary_file(tmp_path):
    write_text(tmp_path / "steps.md", "| a |\n")
    assert (tmp_path / "steps.md").read_text() == "| a |\n"
    A = sp.random(6, 6, density=0.5, random_state=1, format="csr")
    io.write_matrix(tmp_path / "A.mtx", A)
    assert abs(io.read_matrix(tmp_path / "A.mtx") - A).max() == 0
    v = np.linspace(0.0, 1.0, 7) / 3.0
    io.write_vector(tmp_path / "v.txt.gz", v)       # compressed: np.savetxt reads the suffix
    assert (tmp_path / "v.txt.gz").read_bytes()[:2] == b"\x1f\x8b"
    assert np.array_equal(np.loadtxt(tmp_path / "v.txt.gz"), v)
    mesh = grid_cloth(3).mesh
    for name in ("m.obj", "m.vtk"):
        io.write_mesh(tmp_path / name, mesh)
        assert np.array_equal(io.read_mesh(tmp_path / name).vertices, mesh.vertices)
    assert leftovers(tmp_path) == []
