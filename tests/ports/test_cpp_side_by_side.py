"""The side by side with sam007961/FastMassSpring: the driver builds and agrees with clothsim.

The port's solver is compiled with clothsim's driver (examples/ports/fastmassspring) and
stepped on clothsim's scenes; the answers must agree within the float bound the benchmark
states, a changed computation must not, and the benchmark's table must be complete. No
timing is asserted. Skipped without g++, Eigen or the port's files (downloaded into the cache
on first use; offline, ``$CLOTHSIM_FASTMASSSPRING`` may name a folder or git clone holding
them).
"""

from __future__ import annotations

import subprocess
import warnings

import numpy as np
import pytest

import clothsim as cs
from benchmarks import cpp_side_by_side as side
from benchmarks import fastmassspring as port
from clothsim.factorization import cholmod_available
from clothsim.gallery import GRAVITY, grid_cloth, top_corners

pytestmark = pytest.mark.skipif(not cholmod_available(), reason="the benchmark times CHOLMOD")
# compiling the port with Eigen takes about 20 s on one core: CI runs those tests, make test
# runs only the ones that need no build
slow = pytest.mark.slow


@pytest.fixture(scope="module")
def program():
    try:
        return port.build_driver(port.port_source())
    except port.Skip as exc:
        pytest.skip(str(exc))


def _agree(program, tmp_path, sim, steps, *, damping=1.0, iterations=port.ITERATIONS):
    """Largest vertex distance after one step of each from clothsim's state after ``steps``
    steps, and the float bound the benchmark holds it to."""
    port.write_scene(sim, tmp_path / "scene.txt", damping=damping)
    driver = port.Driver(program, tmp_path / "scene.txt", iterations)
    try:
        sim.run(steps)
        x, v = sim.state.positions, sim.state.velocities
        driver.set_state(x - sim.h * v, x, tmp_path / "prev.txt", tmp_path / "now.txt")
        driver.steps(1)
        x_port = driver.positions(tmp_path / "x.txt")
    finally:
        driver.close()
    sim.step()
    kappa = sim.solver.system(sim.problem()).A_FF_factor.condition_estimate
    bound = kappa * side.F32 * np.abs(sim.state.positions).max()
    return float(np.linalg.norm(x_port - sim.state.positions, axis=1).max()), bound


@slow
def test_benchmark_builds_agrees_and_reports(program, capsys, monkeypatch):
    """The benchmark on a tiny grid: every size agrees, the check size discriminates one
    iteration, the table holds every figure (the timings are printed, never asserted)."""
    monkeypatch.setattr(side, "PAGE", None)   # never written here
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = side.main(["--sizes", "9", "--repeats", "2", "--no-page"])
    assert result is not None
    rows = {r["n"]: r for r in result["rows"]}
    assert set(rows) == {9, side.CHECK_SIZE} and not rows[side.CHECK_SIZE]["timed"]
    for r in rows.values():
        assert r["agree"] and r["distance"] <= r["tolerance"]
        assert r["moved"] > 0.05                  # the cloth fell: agreement is not trivial
        assert r["steps"] >= side.WARM_STEPS      # the warm-up, and past a pending switch
    check = rows[side.CHECK_SIZE]
    assert check["tolerance"] < check["one_fewer"] / 4   # one iteration less would show
    timed = rows[9]
    assert all(q[1] <= q[0] <= q[2] for q in (timed["clothsim"], timed["port"],
                                               timed["ratio"]))
    assert timed["ratio_y"][1] <= timed["ratio_y"][0] <= timed["ratio_y"][2]
    shares = result["profile"][9]
    assert set(shares) == {name for name, _ in side.PARTS}
    assert sum(shares.values()) == pytest.approx(1.0) and shares["CHOLMOD solve"] > 0
    assert shares["per step: start, gradient at x_0"] > 0   # the x_n start's gradient
    full, product = result["start_gradient"][9]
    assert full > 0 and product > 0
    setup, solve, slices, takes = result["setup"][9]
    assert 0 < setup < solve                  # a step's setup is part of its solve
    assert slices > 0 and takes > 0
    out = capsys.readouterr().out
    assert "| 9² |" in out and f"| {side.CHECK_SIZE}² (check only) |" in out


@slow
@pytest.mark.parametrize("case", ["inertial-damping", "free-fall", "one-pin-stiff"])
def test_driver_agrees_on_scenes_it_was_not_built_for(program, tmp_path, case):
    """The port's damping a = 0.993 against clothsim's Damping("inertial"); no pins (free
    fall, the springs at rest); one pin and stiffer springs, mass per vertex uniform."""
    n = 11
    if case == "one-pin-stiff":
        model = grid_cloth(n, k=5000.0, plane="xz", vertex_mass=0.01,
                           bending_pattern="alternate")
        effects = [cs.Gravity(GRAVITY), cs.Pin([0])]
    else:
        model = grid_cloth(n, k=800.0, plane="xz", center=(0.0, 1.0, 0.0),
                           bending_pattern="alternate")
        effects = [cs.Gravity(GRAVITY)]
        if case == "inertial-damping":
            effects += [cs.Pin(top_corners(n, "xz")), cs.Damping("inertial", 0.993)]
    sim = cs.Simulation(model, h=1 / 30, iterations=port.ITERATIONS, initial_guess="x_n",
                        effects=effects)
    damping = 0.993 if case == "inertial-damping" else 1.0
    distance, bound = _agree(program, tmp_path, sim, 8, damping=damping)
    assert distance <= bound
    if case == "free-fall":     # 9 steps of implicit Euler free fall: x drops g h² Σ k
        drop = 9.81 * (1 / 30) ** 2 * sum(range(1, 10))
        assert sim.state.positions[:, 1].mean() == pytest.approx(1.0 - drop, rel=1e-6)


@slow
def test_another_computation_is_told_apart(program, tmp_path):
    """The port at 9 iterations against clothsim's 10: beyond the bound (the check can fail)."""
    sim = side.side_by_side_sim(side.CHECK_SIZE)
    distance, bound = _agree(program, tmp_path, sim, 3, iterations=port.ITERATIONS - 1)
    assert distance > 3 * bound


def test_source_with_other_contents_is_refused(tmp_path, monkeypatch):
    """A --source whose file is not the pinned one, or that holds none: one line, named."""
    monkeypatch.setenv("CLOTHSIM_CACHE", str(tmp_path / "cache"))
    src = tmp_path / "src"
    for name in port.PORT.files:
        (src / name).parent.mkdir(parents=True, exist_ok=True)
        (src / name).write_text("not the port\n")
    with pytest.raises(port.Skip, match="MassSpringSolver.cpp does not match its pinned"):
        port.port_source(src)
    assert not (tmp_path / "cache" / port.PORT.name / "ClothApp").exists()
    with pytest.raises(port.Skip, match="neither holds .* nor is a git repository"):
        port.port_source(tmp_path / "empty")


@slow
def test_driver_names_a_bad_scene(program, tmp_path):
    """A scene file that ends early stops the driver with one line saying so."""
    bad = tmp_path / "scene.txt"
    bad.write_text("clothsim-fastmassspring-scene 1\n4 1 0\n0.03 1\n0 0 0 1 0 0 0\n")
    with pytest.raises(RuntimeError, match="ends early or holds a non-number"):
        port.Driver(program, bad)
    done = subprocess.run([str(program)], capture_output=True, text=True)
    assert done.returncode == 2 and "usage" in done.stderr


def test_no_compiler_or_offline_is_one_line(tmp_path, monkeypatch, capsys):
    """Without a compiler, or offline without the port's files, the benchmark says so in
    one line and writes nothing."""
    monkeypatch.setenv("CXX", "no-such-compiler-here")
    with pytest.raises(port.Skip, match="no C.. compiler"):
        port.build_driver(tmp_path)
    monkeypatch.setenv("CLOTHSIM_CACHE", str(tmp_path / "cache"))
    monkeypatch.setenv("CLOTHSIM_OFFLINE", "1")
    monkeypatch.delenv("CLOTHSIM_FASTMASSSPRING", raising=False)
    monkeypatch.setattr(side, "PAGE", tmp_path / "page.md")
    assert side.main(["--sizes", "9"]) is None
    out = capsys.readouterr().out.strip()
    assert out.startswith("cpp_side_by_side skipped: ") and "CLOTHSIM_OFFLINE" in out
    assert "\n" not in out and not (tmp_path / "page.md").exists()


def test_failed_download_leaves_no_folder(tmp_path, monkeypatch):
    """A download that fails (here: nothing listens) is one line and leaves no empty folders
    in the cache."""
    import dataclasses

    monkeypatch.setenv("CLOTHSIM_CACHE", str(tmp_path))
    monkeypatch.delenv("CLOTHSIM_OFFLINE", raising=False)
    monkeypatch.delenv("CLOTHSIM_FASTMASSSPRING", raising=False)
    monkeypatch.setattr(port, "PORT", dataclasses.replace(port.PORT, url="http://127.0.0.1:9/"))
    with pytest.raises(port.Skip, match="could not download .*CLOTHSIM_FASTMASSSPRING"):
        port.port_source()
    assert list(tmp_path.iterdir()) == []
