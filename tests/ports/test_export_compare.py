"""Reference exports for other ports, and the trajectory comparison tool."""

import json

import numpy as np
import pytest

import clothsim as cs
from clothsim import io, matrices, reference
from clothsim.errors import InputError
from clothsim.ports.compare import compare_arrays, compare_trajectories
from clothsim.ports.export import export_matrices
from clothsim.ports.matrices import compare_matrices


@pytest.fixture
def model():
    mesh = cs.grid(4, 3, plane="xy")
    return cs.Model.build(mesh, cs.grid_springs(mesh, structural=50.0, shear=20.0, bending=5.0),
                          total_mass=0.3)


def test_export_writes_paper_matrices_exactly(model, tmp_path):
    manifest = export_matrices(model, 1 / 30, tmp_path)
    assert json.loads((tmp_path / "manifest.json").read_text()) == manifest
    L = io.read_matrix(tmp_path / "L.mtx").toarray()
    np.testing.assert_array_equal(L, matrices.stiffness_matrix(model).toarray())
    np.testing.assert_allclose(io.read_matrix(tmp_path / "J.mtx").toarray(),
                               reference.spring_matrix(model), rtol=0, atol=0)
    A = io.read_matrix(tmp_path / "A.mtx").toarray()
    assert A.shape == (3 * model.vertex_count,) * 2
    np.testing.assert_array_equal(io.read_vector(tmp_path / "x0.txt"), model.mesh.vertices.ravel())
    pairs = np.loadtxt(tmp_path / "spring_vertices.txt", dtype=int)
    np.testing.assert_array_equal(pairs, model.springs.spring_vertices)
    assert set(manifest["files"]) <= {p.name for p in tmp_path.iterdir()}


def test_compare_passes_within_and_fails_beyond_tolerance(tmp_path):
    rng = np.random.default_rng(0)
    ref = rng.normal(size=(5, 7, 3))
    near = ref + 1e-10
    far = ref.copy()
    far[3, 4, 1] += 1e-3
    np.savez(tmp_path / "ref.npz", positions=ref)
    np.savez(tmp_path / "near.npz", positions=near)
    np.savez(tmp_path / "far.npz", positions=far)
    ok = compare_trajectories(tmp_path / "near.npz", tmp_path / "ref.npz", rtol=0, atol=1e-9)
    assert ok.passed and ok.max_abs_error == pytest.approx(1e-10, rel=1e-3)
    bad = compare_trajectories(tmp_path / "far.npz", tmp_path / "ref.npz", rtol=1e-6, atol=1e-9)
    assert not bad.passed and (bad.worst_frame, bad.worst_vertex) == (3, 4)
    assert "FAIL" in bad.summary() and "frame 3 vertex 4" in bad.summary()
    first = compare_trajectories(tmp_path / "far.npz", tmp_path / "ref.npz", rtol=0, atol=1e-9,
                                 frames=3)
    assert first.passed and first.frames == 3


def test_compare_rejects_nan_and_shape_mismatch():
    a = np.zeros((2, 3, 3))
    b = a.copy()
    b[1, 2, 0] = np.nan
    assert not compare_arrays(b, a, rtol=1, atol=1).passed
    with pytest.raises(InputError, match="shapes differ"):
        compare_arrays(a, np.zeros((2, 4, 3)), rtol=0, atol=0)


def test_compare_matrices(model, tmp_path):
    io.write_matrix(tmp_path / "a.mtx", matrices.stiffness_matrix(model))
    io.write_matrix(tmp_path / "b.mtx", matrices.stiffness_matrix(model) * (1 + 1e-9))
    assert compare_matrices(tmp_path / "a.mtx", tmp_path / "a.mtx").passed
    assert not compare_matrices(tmp_path / "b.mtx", tmp_path / "a.mtx", rtol=1e-12).passed


def test_compare_reads_pvd_frames(model, tmp_path):
    writer = io.FrameWriter(tmp_path, model.mesh)
    x = model.mesh.vertices
    for i in range(3):
        writer.write(i, i * 0.1, x + i, np.zeros_like(x))
    traj = np.stack([x + i for i in range(3)])
    np.savez(tmp_path / "ref.npz", positions=traj)
    assert compare_trajectories(tmp_path, tmp_path / "ref.npz", rtol=0, atol=0).passed


def test_cli_export_and_compare(tmp_path, capsys):
    from clothsim.cli import main

    assert main(["export", "hanging", "--out", str(tmp_path / "m")]) == 0
    assert (tmp_path / "m" / "L.mtx").is_file() and (tmp_path / "m" / "manifest.json").is_file()
    manifest = json.loads((tmp_path / "m" / "manifest.json").read_text())
    assert manifest["pinned_vertices"], "the hanging scene's pins are recorded"
    assert main(["run", "hanging", "--frames", "2", "--no-preview",
                 "--out", str(tmp_path / "a")]) == 0
    assert main(["run", "hanging", "--frames", "2", "--no-preview",
                 "--out", str(tmp_path / "b")]) == 0
    capsys.readouterr()
    assert main(["compare", str(tmp_path / "a"), str(tmp_path / "b"), "--atol", "0",
                 "--rtol", "0"]) == 0
    assert capsys.readouterr().out.startswith("PASS")
    traj = np.load(tmp_path / "b" / "trajectory.npz")
    moved = dict(traj)
    moved["positions"] = traj["positions"] + 1e-6
    np.savez(tmp_path / "moved.npz", **moved)
    assert main(["compare", str(tmp_path / "moved.npz"), str(tmp_path / "b"),
                 "--atol", "1e-9", "--rtol", "0"]) == 1
    assert main(["compare", str(tmp_path / "a"), str(tmp_path / "b"), "--rtol", "-1"]) == 2
