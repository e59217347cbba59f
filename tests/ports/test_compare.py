"""Trajectory comparison: per-vertex distances, first failure, vertex order, float32, plot."""

import numpy as np
import pytest

from clothsim.cli import main
from clothsim.errors import InputError
from clothsim.gallery import grid_cloth
from clothsim.ports.compare import (
    compare_arrays,
    condition_number,
    match_vertices,
    plot_deviation,
)
from clothsim.ports.matrices import attachment_columns, compare_matrices


@pytest.fixture
def traj():
    rng = np.random.default_rng(1)
    x0 = grid_cloth(5, size=10.0).mesh.vertices
    return x0 + np.cumsum(rng.normal(scale=0.01, size=(8, 25, 3)), axis=0)


def test_first_failing_frame_is_reported_not_only_the_worst(traj):
    a = traj.copy()
    a[2, 7] += [1e-6, 0, 0]      # first failure, small
    a[5, 3] += [0, 1e-3, 0]      # worst
    result = compare_arrays(a, traj)
    assert not result.passed
    assert (result.first_frame, result.first_vertex) == (2, 7)
    assert (result.worst_frame, result.worst_vertex) == (5, 3)
    assert "first failing frame 2 vertex 7" in result.summary()
    assert result.max_error[5] == pytest.approx(1e-3)
    assert "FAIL" in result.table()


def test_coordinates_near_zero_do_not_blow_up_the_error(traj):
    a = traj.copy()
    a[..., 1] = 0.0
    b = a + 1e-12  # every coordinate off by 1e-12 m; many are exactly 0 in b's neighbour
    result = compare_arrays(a, b)
    assert result.passed and result.max_error.max() / result.size < 1e-12


def test_other_vertex_order_is_matched(traj):
    perm = np.random.default_rng(2).permutation(25)
    shuffled = traj[:, perm]
    assert not compare_arrays(shuffled, traj).passed
    assert compare_arrays(shuffled, traj, match=True, rtol=0, atol=0).passed
    assert np.array_equal(shuffled[0][match_vertices(shuffled[0], traj[0])], traj[0])
    twin = traj[0].copy()
    twin[1] = twin[0]
    with pytest.raises(InputError, match="ambiguous"):
        match_vertices(twin, twin)
    with pytest.raises(InputError, match="no vertex within"):
        match_vertices(traj[0] + 1.0, traj[0])


def test_float32_tolerance_comes_from_the_condition_number(traj, tmp_path):
    model = grid_cloth(5, size=10.0)
    kappa = condition_number(model, 1 / 30)
    from clothsim import matrices

    A = matrices.system_matrix(model, 1 / 30)
    bound = abs(A).sum(axis=1).max() / model.vertex_mass.min()  # Gershgorin; λ_min >= min m
    assert 1 < kappa < bound
    x32 = traj.astype(np.float32).astype(np.float64)
    assert compare_arrays(x32, traj, precision="float32", kappa=kappa).passed
    assert not compare_arrays(x32, traj).passed
    with pytest.raises(InputError, match="κ"):
        compare_arrays(x32, traj, precision="float32")
    result = compare_arrays(x32, traj, precision="float32", kappa=kappa)
    assert result.tolerance[3] == pytest.approx(3 * result.tolerance[1])
    plot_deviation(result, tmp_path / "dev.png")
    assert (tmp_path / "dev.png").stat().st_size > 1000


def test_cli_compare_prints_table_and_plot(traj, tmp_path, capsys):
    np.save(tmp_path / "a.npy", traj)
    np.savetxt(tmp_path / "b.csv", traj.reshape(8, -1), delimiter=",", fmt="%.17g")
    assert main(["compare", str(tmp_path / "a.npy"), str(tmp_path / "b.csv"),
                 "--plot", str(tmp_path / "p.png")]) == 0
    out = capsys.readouterr().out
    assert out.startswith("PASS") and "max/size" in out and (tmp_path / "p.png").is_file()
    assert main(["compare", str(tmp_path / "a.npy"), str(tmp_path / "b.csv"),
                 "--precision", "float32"]) == 2
    np.save(tmp_path / "short.npy", traj[:5])
    assert main(["compare", str(tmp_path / "short.npy"), str(tmp_path / "b.csv"),
                 "--no-table"]) == 1
    assert "has 5 frames" in capsys.readouterr().out


def test_sparse_matrices_with_attachment_columns():
    import scipy.sparse as sp

    from clothsim import matrices

    model = grid_cloth(4)
    J = matrices.spring_matrix(model)
    n = model.vertex_count
    att = sp.lil_matrix((3 * n, 6))
    for c, v in enumerate((0, 3)):
        for i in range(3):
            att[3 * v + i, 3 * c + i] = 120.0
    port_J = sp.hstack([att, J]).tocsr()
    assert list(attachment_columns(port_J)) == list(range(6))
    assert compare_matrices(port_J, J, drop_columns="attachments").passed
    assert compare_matrices(port_J[:, 3:], J, drop_columns=[0, 1, 2]).passed
    wrong = port_J.tolil()
    wrong[3 * 5, 6 + 3 * 7] += 1.0  # one spring entry off
    result = compare_matrices(wrong.tocsr(), J, drop_columns="attachments")
    assert not result.passed and "FAIL" in result.summary()
