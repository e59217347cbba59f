"""Every trajectory format round-trips: written, read back, compared with itself."""

import numpy as np
import pytest

from clothsim import io
from clothsim.cli import main
from clothsim.errors import InputError
from clothsim.gallery import curtain
from clothsim.ports.compare import compare_trajectories
from clothsim.ports.formats import read_trajectory, write_trajectory


@pytest.fixture(scope="module")
def run():
    sim = curtain(5)
    xs, vs = [sim.state.positions.copy()], [sim.state.velocities.copy()]
    for _ in range(4):
        sim.step()
        xs.append(sim.state.positions.copy())
        vs.append(sim.state.velocities.copy())
    return sim, np.stack(xs), np.stack(vs)


@pytest.mark.parametrize("name, options", [
    ("t.npz", {}), ("t.npy", {}), ("t.txt", {}), ("t.csv", {}), ("frames", {}),
    ("t.f64", {}), ("t.bin", {"dtype": "float64"}),
])
def test_float64_formats_round_trip_exactly(run, tmp_path, name, options):
    _, x, _ = run
    path = write_trajectory(tmp_path / name, x, **options)
    back = read_trajectory(path, dtype=options.get("dtype"), vertex_count=x.shape[1])
    np.testing.assert_array_equal(back, x)
    np.savez(tmp_path / "ref.npz", positions=x)
    result = compare_trajectories(path, tmp_path / "ref.npz", rtol=0, atol=0,
                                  dtype=options.get("dtype"), vertex_count=x.shape[1])
    assert result.passed and result.max_error.max() == 0


def test_other_layouts_are_read(run, tmp_path):
    _, x, v = run
    np.savez(tmp_path / "port.npz", X=x.reshape(len(x), -1))  # flat (frames, 3n), other key
    np.testing.assert_array_equal(read_trajectory(tmp_path / "port.npz", key="X"), x)
    with pytest.raises(InputError, match="has no array 'positions'.*--key"):
        read_trajectory(tmp_path / "port.npz")
    write_trajectory(tmp_path / "t.f32", x, dtype="float32")
    x32 = read_trajectory(tmp_path / "t.f32", vertex_count=x.shape[1])
    np.testing.assert_array_equal(x32, x.astype(np.float32))
    with pytest.raises(InputError, match="--vertices"):
        read_trajectory(tmp_path / "t.f32")
    with pytest.raises(InputError, match="whole number of frames"):
        read_trajectory(tmp_path / "t.f32", vertex_count=7)
    d = tmp_path / "port"
    d.mkdir()
    write_trajectory(d / "positions.txt", x)
    write_trajectory(d / "velocities.txt", v)
    np.testing.assert_array_equal(read_trajectory(d, key="velocities"), v)
    (tmp_path / "bad.txt").write_text("1 2 3\n4 5\n")
    with pytest.raises(InputError, match="different counts"):
        read_trajectory(tmp_path / "bad.txt")


def test_pvd_frames_round_trip(run, tmp_path):
    sim, x, v = run
    writer = io.FrameWriter(tmp_path / "run", sim.model.mesh)
    for i in range(len(x)):
        writer.write(i, i * sim.h, x[i], v[i])
    np.testing.assert_array_equal(read_trajectory(tmp_path / "run"), x)
    np.testing.assert_array_equal(read_trajectory(tmp_path / "run", key="velocities"), v)


def test_export_compares_with_itself_in_every_format(tmp_path, capsys):
    out = tmp_path / "ref"
    assert main(["export", "hanging", "--out", str(out), "--frames", "3",
                 "--iterate-steps", "1"]) == 0
    n = len(np.loadtxt(out / "vertices.txt"))
    for args in ([str(out), str(out)], [str(out / "trajectory.npz"), str(out)],
                 [str(out / "positions.txt"), str(out)],
                 [str(out / "positions.f64"), str(out), "--vertices", str(n)],
                 [str(out / "velocities.f64"), str(out), "--vertices", str(n),
                  "--key", "velocities"]):
        assert main(["compare", *args, "--rtol", "0", "--atol", "0"]) == 0, args
    assert "PASS" in capsys.readouterr().out


def test_export_iterates_follow_the_solver_stop_rule(tmp_path):
    import clothsim as cs
    from clothsim.ports.export import export_port

    def converged():
        model, effects = cs.gallery.hanging_cloth(5)
        return cs.Simulation(model, h=1 / 30, effects=effects, iterations=500, tolerance=1e-8)

    manifest = export_port(converged, tmp_path, frames=2, iterate_steps=2)
    assert manifest["solver"]["tolerance"] == 1e-8
    x = np.load(tmp_path / "trajectory.npz")["positions"]
    for k in range(2):
        it = np.load(tmp_path / "iterates" / f"step_{k:04d}.npz")
        assert 1 < len(it["x"]) < 501
        np.testing.assert_array_equal(it["x"][-1], x[k + 1])
        assert it["gradient_norm"][-1] <= 1e-8 * it["gradient_norm"][0]
