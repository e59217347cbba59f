"""Acceptance on the paper authors' own C++ run (the data set liu13-port, shipped with
clothsim)."""

import numpy as np
import pytest

from clothsim.ports.check import check_steps
from clothsim.ports.compare import compare_arrays, compare_trajectories
from clothsim.ports.diff import diff_models
from clothsim.ports.export import export_port
from clothsim.ports.matrices import compare_matrices

from .conftest import liu13_simulation, liu13_trajectory, port_dir


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    port_dir()
    out = tmp_path_factory.mktemp("liu13-export")
    export_port(liu13_simulation, out, frames=60, iterate_steps=2)
    return out


def test_matrices_compare_equal(exported):
    d = port_dir()
    assert compare_matrices(d / "M.mtx", exported / "M.mtx", rtol=0).passed
    for name in ("L", "A"):  # penalty pins included on both sides
        result = compare_matrices(d / f"{name}.mtx", exported / f"{name}.mtx", rtol=1e-12)
        assert result.passed, result.summary()
    # without the pins L differs: the export's L_springs is what the old export wrote
    assert not compare_matrices(d / "L.mtx", exported / "L_springs.mtx").passed
    j = compare_matrices(d / "J.mtx", exported / "J.mtx", drop_columns="attachments")
    assert j.passed and j.dropped == 6, j.summary()
    with pytest.raises(Exception, match="shapes differ"):
        compare_matrices(d / "J.mtx", exported / "J.mtx")


def test_trajectory_compares_over_60_frames(exported):
    result = compare_trajectories(port_dir(), exported)
    assert result.passed and result.frames == 61, result.summary()
    assert result.max_error.max() < 1e-10
    v = compare_trajectories(port_dir(), exported, key="velocities")
    assert v.passed, v.summary()


def test_export_iterates_reproduce_the_step(exported):
    it = np.load(exported / "iterates" / "step_0000.npz")
    assert it["x"].shape == (11, 441, 3) and it["d"].shape == (11, 2038, 3)
    x1 = np.load(exported / "trajectory.npz")["positions"][1]
    np.testing.assert_array_equal(it["x"][-1], x1)
    from clothsim.solvers.base import augmented_objective, objective

    sim = liu13_simulation()
    p = sim.problem()
    np.testing.assert_array_equal(it["y"], p.y)
    # every half step is non-increasing in ĝ(x, d) (the paper's block coordinate descent)
    values = []
    for k in range(10):
        values += [augmented_objective(sim.model, p, it["x"][k], it["d"][k]),
                   augmented_objective(sim.model, p, it["x"][k + 1], it["d"][k])]
    assert np.all(np.diff(values) <= 1e-12 * abs(values[0]))
    assert objective(sim.model, p, it["x"][-1]) < objective(sim.model, p, it["x"][0])
    x, _ = liu13_trajectory()
    assert np.abs(it["x"][-1] - x[1]).max() < 1e-10


def test_per_step_check_passes_every_step():
    x, v = liu13_trajectory()
    report = check_steps(liu13_simulation, x, v, tolerance=1e-10)
    assert report.passed and len(report.steps) == 60, report.summary()
    assert max(s.error for s in report.steps) < 1e-10
    assert report.summary().startswith("PASS")


def test_moved_vertex_fails_at_step_20_naming_it():
    x, v = liu13_trajectory()
    x = x.copy()
    x[21:, 137] += np.array([0.0, 1e-3, 0.0])
    report = check_steps(liu13_simulation, x, v, steps=23)
    first = report.first_failure
    assert (first.k, first.vertex) == (20, 137), report.summary()
    assert first.status == "not a minimizer"
    assert all(s.passed for s in report.steps[:20])
    assert "step 20 -> 21" in report.summary() and "vertex 137" in report.summary()


def test_attachments_left_out_are_named():
    diff = diff_models(lambda: liu13_simulation(attachments=False), port_dir())
    assert not diff.identical
    assert "vertices 0 and 420" in diff.cause and "only in B" in diff.cause
    assert diff_models(liu13_simulation, port_dir()).identical
    x, v = liu13_trajectory()
    report = check_steps(lambda: liu13_simulation(attachments=False), x, v, steps=2)
    assert report.first_failure.k == 0 and report.first_failure.status == "model differs"


def test_float32_rounded_run_passes_float32_only():
    x, v = liu13_trajectory()
    x32, v32 = (a.astype(np.float32).astype(np.float64) for a in (x, v))
    assert check_steps(liu13_simulation, x32, v32, precision="float32").passed
    report = check_steps(liu13_simulation, x32, v32, precision="float64", steps=3)
    assert not report.passed and report.first_failure.k == 0
    from clothsim.ports.compare import condition_number

    sim = liu13_simulation()
    p = sim.problem()
    kappa = condition_number(sim.model, sim.h, anchor_vertices=p.anchor_vertices,
                             anchor_stiffness=p.anchor_stiffness)
    assert kappa == pytest.approx(418, rel=0.01)  # the value the float32 build was measured at
    assert compare_arrays(x32, x, precision="float32", kappa=kappa).passed
    assert not compare_arrays(x32, x).passed
