"""The fault zoo: faults planted in the project's own coursework solution, each named.

The Python solution (examples/ports/mass_springs.py) and the C++ one
(examples/ports/cpp/mass_springs_solution.cpp, edited as a student would edit it, built
with g++ and Eigen when they are installed) run on the coursework cases clothsim writes
itself (no third-party file), and on the assignment's net when the shared data is there.
Each fault must be named in the first FAIL line by the model parameter it changes; the
correct solution passes with every step agreeing; a port no single parameter explains is
said to be so.
"""

from __future__ import annotations

import importlib.util
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

import clothsim as cs
from clothsim.ports.check import check_steps
from clothsim.ports.coursework import write_coursework
from clothsim.ports.export import export_port
from clothsim.scene.files import data_root

from .test_check_verdicts import trajectory as clothsim_trajectory

REPO = Path(__file__).resolve().parents[2]
CPP = REPO / "examples" / "ports" / "cpp"
EIGEN = Path("/usr/include/eigen3")
FRAMES = 6

spec = importlib.util.spec_from_file_location("mass_springs",
                                              REPO / "examples" / "ports" / "mass_springs.py")
mass_springs = importlib.util.module_from_spec(spec)
spec.loader.exec_module(mass_springs)

#: fault -> the words the first FAIL line must carry
NAMED = {
    "gravity-sign": "the external force (0, +9.8, 0) N per vertex instead of (0, -9.8, 0)",
    "rest-length": "rest lengths × 0.900 (all springs)",
    "stiffness": "springs twice as stiff (stiffness × 2.00, all springs)",
    "unnormalized": "no force (stiffness × 0.0",
    "unpinned": "pins that exert no force",
}


@pytest.fixture(scope="module")
def cases(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("coursework")
    write_coursework(out, frames=FRAMES, cases=["net", "sheet-voronoi", "chain"])
    return out


@pytest.fixture(scope="module")
def jacobson_net(tmp_path_factory) -> Path:
    if not (data_root() / "jacobson-a8" / "net.json").is_file():
        pytest.skip("the assignment's net is not in the data root (CLOTHSIM_DATA)")
    out = tmp_path_factory.mktemp("jacobson-net")
    export_port(cs.load_scene("jacobson-net"), out, frames=FRAMES, iterate_steps=0)
    return out


def trajectory(out: Path):
    x, v = np.loadtxt(out / "positions.txt"), np.loadtxt(out / "velocities.txt")
    return x.reshape(len(x), -1, 3), v.reshape(len(v), -1, 3)


def checked(scene, out: Path):
    x, v = trajectory(out)
    return check_steps(scene, x, v), x


def assert_named(report, x, fault, scene):
    first = report.first_failure
    summary = report.summary()
    assert first is not None and first.k == 0, summary
    assert summary.startswith("FAIL at step 0 -> 1: model differs"), summary
    assert NAMED[fault] in summary, summary
    assert "raise its iterations" not in summary and "iterations = 0" not in summary, summary
    # the vertex of largest error, a pin only when its own error exceeds the tolerance
    sim = scene.build_simulation(scene.build_model())
    sim.step()
    err = np.linalg.norm(sim.state.positions - x[1], axis=1)
    assert first.vertex == int(np.argmax(err)), summary
    if "pinned" in first.line():
        assert err[first.vertex] > first.tolerance, summary


@pytest.mark.parametrize("case", ["net", "sheet-voronoi", "chain"])
@pytest.mark.parametrize("fault", list(NAMED))
def test_python_solution_faults_are_named(cases, tmp_path, case, fault):
    d = cases / case
    out = mass_springs.run(d, tmp_path / "out", fault=fault)
    scene = cs.load_scene(d / "scene.toml")
    report, x = checked(scene, out)
    assert_named(report, x, fault, scene)
    if fault == "unpinned":
        assert "pinned by a 1e+10 N/m penalty" in report.first_failure.line()


def test_gravity_as_m_g_is_named_where_the_masses_are_not_1_kg(cases, tmp_path):
    d = cases / "sheet-voronoi"                        # libigl's Voronoi masses
    out = mass_springs.run(d, tmp_path / "out", fault="gravity-mass")
    scene = cs.load_scene(d / "scene.toml")
    report, x = checked(scene, out)
    NAMED["gravity-mass"] = ("the external force (0, -9.8, 0) m/s² × m on each vertex "
                             "instead of (0, -9.8, 0) N per vertex")
    assert_named(report, x, "gravity-mass", scene)
    # on the net every mass is 1 kg: the same program, and it passes
    d = cases / "net"
    assert checked(cs.load_scene(d / "scene.toml"),
                   mass_springs.run(d, tmp_path / "net", fault="gravity-mass"))[0].passed


@pytest.mark.parametrize("case", ["net", "sheet-voronoi", "chain"])
def test_python_solution_passes_with_every_step_agreeing(cases, tmp_path, case):
    d = cases / case
    report, _ = checked(cs.load_scene(d / "scene.toml"), mass_springs.run(d, tmp_path / "o"))
    assert report.passed and {s.status for s in report.steps} == {"agrees"}, report.summary()


@pytest.mark.parametrize("fault", ["gravity-sign", "rest-length", "stiffness", "unnormalized"])
def test_python_solution_faults_are_named_on_the_assignments_net(jacobson_net, tmp_path,
                                                                 fault):
    out = mass_springs.run(jacobson_net, tmp_path / "out", fault=fault)
    report, x = checked(cs.load_scene("jacobson-net"), out)
    assert_named(report, x, fault, cs.load_scene("jacobson-net"))


def test_a_port_no_parameter_explains_is_said_to_be_so(cases, tmp_path):
    d = cases / "net"
    x, v = trajectory(mass_springs.run(d, tmp_path / "o"))
    rng = np.random.default_rng(0)
    x[1:] += 1e-3 * rng.standard_normal(x[1:].shape)   # noise: no model makes it stationary
    report = check_steps(cs.load_scene(d / "scene.toml"), x, v, steps=2)
    first = report.first_failure
    assert first is not None and first.k == 0, report.summary()
    assert "no single model parameter explains" in first.note, first.line()
    assert "the port's steps" not in first.note, first.line()


def test_a_port_that_returns_its_start_is_not_told_to_take_zero_iterations(cases, tmp_path):
    d = cases / "net"
    x, v = trajectory(mass_springs.run(d, tmp_path / "o", frames=3))
    x[3], v[3] = x[2], 0.0                 # the last step returns x_n: nothing was solved
    report = check_steps(cs.load_scene(d / "scene.toml"), x, v)
    first = report.first_failure
    assert first is not None and first.k == 2, report.summary()
    assert "start point x_n itself" in first.note, first.line()
    assert "iterations = 0" not in report.summary() and not first.settings


def test_a_cloth_left_at_rest_minimizes_g_without_its_force(cases):
    """A port that never moves a cloth at rest (springs at rest length) solves g without
    the external force: that is the cause named, not an iteration count."""
    d = cases / "net"
    scene = cs.load_scene(d / "scene.toml")
    x0 = scene.build_model().mesh.vertices
    xs = np.stack([x0, x0, x0])
    summary = check_steps(scene, xs, np.zeros_like(xs)).summary()
    assert "minimize g with an external force (0, 0, 0) N per vertex" in summary or \
        "the external force (0, 0, 0) N per vertex instead of (0, -9.8, 0)" in summary, summary


# -- the C++ solution, edited as a student would ---------------------------------------------
#: fault -> (text of mass_springs_solution.cpp, its replacement)
CPP_FAULTS = {
    "gravity-sign": ("+ fext +", "- fext +"),
    "rest-length": ("r(e) = (V.row", "r(e) = 0.9 * (V.row"),
    "stiffness": ("k * A.transpose()", "2 * k * A.transpose()"),
    "unnormalized": ("r(e) * p.row(e).normalized()", "p.row(e)"),
}


@pytest.fixture(scope="module")
def cpp_drivers(tmp_path_factory) -> dict[str, Path]:
    """The assignment driver built with the correct solution and with each fault."""
    if shutil.which("g++") is None:
        pytest.skip("g++ is not installed (scripts/bootstrap.sh installs it as root)")
    if not (EIGEN / "Eigen" / "Sparse").is_file():
        pytest.skip(f"Eigen headers are absent ({EIGEN}; apt package libeigen3-dev)")
    build = tmp_path_factory.mktemp("cpp-faults")
    source = (CPP / "mass_springs_solution.cpp").read_text()
    jobs = {}
    for fault in [None, *CPP_FAULTS]:
        text = source
        if fault is not None:
            old, new = CPP_FAULTS[fault]
            assert old in text, old
            text = text.replace(old, new)
        name = fault or "correct"
        (build / f"{name}.cpp").write_text(text)
        jobs[name] = subprocess.Popen(
            ["g++", "-O1", "-std=c++17", f"-I{EIGEN}", f"-I{CPP}", f"-I{CPP / 'include'}",
             "-o", str(build / name),
             str(CPP / "assignment_driver.cpp"), str(build / f"{name}.cpp")],
            stderr=subprocess.PIPE, text=True)
        if len(jobs) % 2 == 0:   # two compilers at a time (a shared machine)
            for job in jobs.values():
                job.wait()
    for job in jobs.values():
        assert job.wait() == 0, job.stderr.read()[-2000:]
    return {name: build / name for name in jobs}


def run_cpp(driver: Path, model: Path, out: Path) -> Path:
    done = subprocess.run([str(driver), str(model), str(out), "--frames", str(FRAMES)],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    return out


@pytest.mark.slow  # five g++/Eigen builds (75 s on 2 cores): CI runs it, make test does not
@pytest.mark.parametrize("fault", [None, *CPP_FAULTS])
def test_cpp_solution_faults_are_named(cpp_drivers, cases, tmp_path, fault):
    d = cases / "net"
    scene = cs.load_scene(d / "scene.toml")
    report, x = checked(scene, run_cpp(cpp_drivers[fault or "correct"], d, tmp_path / "o"))
    if fault is None:
        assert report.passed and {s.status for s in report.steps} == {"agrees"}, \
            report.summary()
    else:
        assert_named(report, x, fault, scene)


# -- a subset: one spring family, some vertices (clothsim itself as the port) ---------------
def sheet(*, bending=10.0, forced=None, iterations=100, method="newton"):
    """A 6 × 6 hanging sheet, -9.8 N on every vertex (or only on ``forced``), converged."""
    mesh = cs.grid(6, 6, size=(1.0, 1.0), plane="xy")
    springs = cs.grid_springs(mesh, structural=200.0, shear=200.0, bending=bending)
    model = cs.Model.build(mesh, springs, total_mass=1.0)
    top = np.flatnonzero(mesh.vertices[:, 1] == mesh.vertices[:, 1].max())[[0, -1]]
    force = cs.Force([0.0, -9.8, 0.0], vertices=forced)
    return cs.Simulation(model, h=1 / 30, effects=[force, cs.Pin(top)], solver=method,
                         iterations=iterations, tolerance=1e-12 if method == "newton" else None)


def run_sim(sim, steps=3):
    return clothsim_trajectory(sim, steps)


def test_bending_springs_of_another_stiffness_are_named_by_family():
    x, v = run_sim(sheet(bending=5.0))
    summary = check_steps(sheet, x, v).summary()
    assert "stiffness × 0.500 (the bending springs only)" in summary, summary


def test_a_force_missing_on_some_vertices_is_named_with_them():
    x, v = run_sim(sheet(forced=np.arange(6, 36)))   # the bottom row feels no force
    summary = check_steps(sheet, x, v).summary()
    assert "no external force on 6 of 36 vertices (0, 1, 2, 3, 4, 5)" in summary, summary


def test_a_port_with_fewer_iterations_keeps_its_unconverged_verdict():
    """No model is fitted onto a port that only stops short: the iterations are named."""
    x, v = run_sim(sheet(method="local-global", iterations=5))
    report = check_steps(sheet, x, v)
    first = report.first_failure
    assert first is not None and first.status == "not converged", report.summary()
    assert "iterations" in first.note and "the port's steps" not in first.note, first.line()
