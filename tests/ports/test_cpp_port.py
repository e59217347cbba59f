"""A real compiled port in the tests: examples/ports/cpp, built with g++ and Eigen.

The port (``clothsim_port``) and the assignment driver with the project's solution
(``assignment_driver``) are built once per session, run on folders ``clothsim export``
writes, and judged by ``clothsim check``: their right configurations pass, a missing or
softer pin, a float32 run checked as float32, another start point and two injected faults
each give the verdict they should. Skipped without g++, Eigen or the assignment data.
"""

from __future__ import annotations

import os
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import clothsim as cs
from clothsim.cli import main as cli_main
from clothsim.errors import InputError
from clothsim.ports.check import check_steps
from clothsim.ports.export import export_port

REPO = Path(__file__).resolve().parents[2]
CPP = REPO / "examples" / "ports" / "cpp"
SCENES = REPO / "clothsim" / "scenes"
EIGEN = Path("/usr/include/eigen3")


@pytest.fixture(scope="session")
def programs(tmp_path_factory) -> dict[str, Path]:
    """Both programs, built once into a temporary folder."""
    if shutil.which("g++") is None or shutil.which("make") is None:
        pytest.skip("g++ or make is not installed (scripts/bootstrap.sh installs them as root)")
    if not (EIGEN / "Eigen" / "Sparse").is_file():
        pytest.skip(f"Eigen headers are absent ({EIGEN}; apt package libeigen3-dev)")
    build = tmp_path_factory.mktemp("cpp-build")
    done = subprocess.run(["make", "-s", "-j2", "-C", str(CPP), f"BUILD={build}"],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-3000:]
    return {"port": build / "clothsim_port", "driver": driver_path(build)}


def driver_path(build: Path, *make_args: str) -> Path:
    """Where the Makefile builds the assignment driver for this solution (its own folder)."""
    done = subprocess.run(["make", "-s", "-C", str(CPP), f"BUILD={build}", *make_args,
                           "driver-path"], capture_output=True, text=True, check=True)
    return Path(done.stdout.strip())


def prebuilt(programs: dict[str, Path], build: Path) -> None:
    """Copy the session's programs where make looks for them in ``build`` (up to date)."""
    driver_path(build).parent.mkdir(parents=True, exist_ok=True)
    shutil.copy2(programs["port"], build / "clothsim_port")
    shutil.copy2(programs["driver"], driver_path(build))


def _scene(name_or_path):
    scene = cs.load_scene(name_or_path)
    try:
        scene.build_model()
    except InputError as exc:  # the assignment's files live in the shared data root
        pytest.skip(f"scene data absent: {exc}")
    return scene


def _export(tmp_path_factory, name: str, frames: int) -> Path:
    out = tmp_path_factory.mktemp(f"export-{name}")
    export_port(_scene(name), out, frames=frames, iterate_steps=0)
    return out


@pytest.fixture(scope="module")
def net(tmp_path_factory) -> Path:
    return _export(tmp_path_factory, "jacobson-net", 30)


@pytest.fixture(scope="module")
def hanging(tmp_path_factory) -> Path:
    return _export(tmp_path_factory, "hanging", 60)


@pytest.fixture(scope="module")
def flag(tmp_path_factory) -> Path:
    return _export(tmp_path_factory, "jacobson-flag", 10)


def run(program: Path, model: Path, out: Path, *args: str) -> Path:
    done = subprocess.run([str(program), str(model), str(out), *args], capture_output=True,
                          text=True)
    assert done.returncode == 0, done.stderr
    return out


def trajectory(out: Path) -> tuple[np.ndarray, np.ndarray]:
    x, v = np.loadtxt(out / "positions.txt"), np.loadtxt(out / "velocities.txt")
    return x.reshape(len(x), -1, 3), v.reshape(len(v), -1, 3)


def check(scene, out: Path, **kw):
    x, v = trajectory(out)
    return check_steps(_scene(scene), x, v, **kw)


def scene_variant(tmp_path: Path, name: str, **replace: str) -> Path:
    """The built-in scene ``name`` with lines replaced (``key = value`` by key) or added
    under ``[cloth]`` / ``[solver]``; its ``data:`` paths still resolve from anywhere."""
    lines = (SCENES / f"{name}.toml").read_text(encoding="utf-8").splitlines()
    for key, line in replace.items():
        hits = [i for i, s in enumerate(lines) if s.split("=")[0].strip() == key]
        if hits:
            lines[hits[0]] = line
        else:
            lines.insert(lines.index("[cloth]") + 1, line)
    path = tmp_path / f"{name}-variant.toml"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def pinned(model: Path) -> set[int]:
    return {int(r[0]) for r in np.loadtxt(model / "pins.txt", ndmin=2)}


# -- the port in the assignment's configuration ---------------------------------------------
def test_port_passes_check_in_the_assignments_configuration(programs, net, tmp_path, capsys):
    out = run(programs["port"], net, tmp_path / "port")
    status = cli_main(["check", "jacobson-net", str(out), "--steps", "30"])  # 30 of its 90
    text = capsys.readouterr().out
    assert status == 0 and "PASS" in text, text
    report = check("jacobson-net", out)
    assert len(report.steps) == 30
    assert {s.status for s in report.steps} == {"agrees"}
    # the port is the same computation: per step within ~1e-12 m, not just the tolerance
    assert max(s.error for s in report.steps) < 1e-12, report.summary()
    reference, _ = trajectory(net)
    assert np.abs(trajectory(out)[0] - reference).max() < 1e-10


def test_port_without_pins_fails_at_the_first_step_naming_a_pinned_vertex(programs, net,
                                                                         tmp_path):
    report = check("jacobson-net", run(programs["port"], net, tmp_path / "o", "--pins", "off"))
    first = report.first_failure
    assert first is not None and first.k == 0, report.summary()
    assert "pinned" in first.line() and first.vertex in pinned(net), first.line()


def test_softer_pins_fail_and_pass_the_scene_with_those_pins(programs, net, tmp_path):
    out = run(programs["port"], net, tmp_path / "o", "--pin-stiffness", "1e7")
    report = check("jacobson-net", out)
    first = report.first_failure
    assert first is not None and first.k == 0, report.summary()
    assert first.vertex in pinned(net) and "pinned" in first.line(), first.line()
    soft = scene_variant(tmp_path, "jacobson-net", pin_stiffness="pin_stiffness = 1e7")
    passed = check(soft, out)
    assert passed.passed and max(s.error for s in passed.steps) < 1e-12, passed.summary()


def test_settings_flags_match_a_scene_with_those_settings(programs, net, tmp_path):
    out = run(programs["port"], net, tmp_path / "o", "--start", "y", "--iterations", "10",
              "--h", "0.02", "--frames", "5")
    assert len(trajectory(out)[0]) == 6
    variant = scene_variant(tmp_path, "jacobson-net", initial_guess='initial_guess = "y"',
                            iterations="iterations = 10", fps="h = 0.02",
                            substeps="")
    report = check(variant, out)
    assert report.passed and max(s.error for s in report.steps) < 1e-12, report.summary()
    assert not check("jacobson-net", out).passed


@pytest.mark.parametrize("fault", ["unnormalized", "sign"])
def test_injected_faults_fail_at_the_first_step(programs, net, tmp_path, fault):
    report = check("jacobson-net", run(programs["port"], net, tmp_path / "o", "--fault", fault),
                   steps=3)
    first = report.first_failure
    assert first is not None and first.k == 0 and not first.passed, report.summary()
    assert first.status not in ("float32 rounding", "start-dependent"), first.line()


def test_initial_velocities_from_v0_txt_are_used(programs, net, tmp_path):
    model = tmp_path / "model"
    shutil.copytree(net, model, ignore=shutil.ignore_patterns("*.mtx", "*.npz", "*.f64"))
    v0 = np.zeros((61, 3))
    v0[:, 2] = 0.1  # 0.1 m/s out of the net's plane
    np.savetxt(model / "v0.txt", v0, fmt="%.17g")
    out = run(programs["port"], model, tmp_path / "o", "--frames", "3")
    x, v = trajectory(out)
    assert np.array_equal(v[0], v0)
    report = check_steps(_scene("jacobson-net"), x, v)
    assert report.passed and max(s.error for s in report.steps) < 1e-12, report.summary()
    # the same frames claiming v_0 = 0: step 0 -> 1 is then wrong
    v[0] = 0
    assert check_steps(_scene("jacobson-net"), x, v).first_failure.k == 0


def test_exact_pins_in_double_agree_to_rounding(programs, hanging, tmp_path):
    report = check("hanging", run(programs["port"], hanging, tmp_path / "d"))
    assert report.passed and max(s.error for s in report.steps) < 1e-12, report.summary()


# -- float32 ----------------------------------------------------------------------------------
def test_float_build_passes_as_float32_on_hanging(programs, hanging, tmp_path):
    out = run(programs["port"], hanging, tmp_path / "f", "--precision", "float")
    x, _ = trajectory(out)
    assert np.array_equal(x.astype(np.float32).astype(np.float64), x)  # float values written
    report = check("hanging", out, precision="float32")
    assert len(report.steps) == 60 and report.passed, report.summary()
    worst = max(report.steps, key=lambda s: s.error / s.tolerance)
    print(f"hanging float32: max error {worst.error:.3e} m vs tolerance {worst.tolerance:.3e} m "
          f"(step {worst.k})")
    # float32 for real: well above float64 rounding, as the float64 run is not
    assert max(s.error for s in report.steps) > 1e-8
    assert not check("hanging", out, steps=5).passed


def test_float_build_without_pins_fails_at_the_first_step(programs, hanging, tmp_path):
    out = run(programs["port"], hanging, tmp_path / "f", "--precision", "float",
              "--pins", "off")
    first = check("hanging", out, precision="float32", steps=3).first_failure
    assert first is not None and first.k == 0 and first.status == "pinned vertex moved"
    assert first.vertex in pinned(hanging), first.line()


# -- the flag: another start point ------------------------------------------------------------
@pytest.fixture(scope="module")
def flag_run(programs, flag, tmp_path_factory) -> Path:
    return run(programs["port"], flag, tmp_path_factory.mktemp("flag-run"))


def test_flag_run_passes(flag_run):
    report = check("jacobson-flag", flag_run)
    assert report.passed and len(report.steps) == 10, report.summary()


def test_flag_run_against_a_y_start_scene_is_start_dependent(flag_run, tmp_path):
    scene = scene_variant(tmp_path, "jacobson-flag", initial_guess='initial_guess = "y"')
    report = check(scene, flag_run, steps=3)  # step 0 -> 1 agrees: v_0 = 0, so y = x_n
    assert report.summary().startswith("UNDECIDED"), report.summary()
    failing = [s for s in report.steps if not s.passed]
    assert failing and all(s.status == "start-dependent" for s in failing)
    assert all('initial_guess = "x_n"' in s.settings for s in failing), failing[0].line()


def test_flag_run_against_a_y_start_scene_is_undecided_over_all_steps(flag_run, tmp_path):
    scene = scene_variant(tmp_path, "jacobson-flag", initial_guess='initial_guess = "y"')
    report = check(scene, flag_run)
    assert report.summary().startswith("UNDECIDED"), report.summary()


# -- the assignment driver with the project's solution -----------------------------------------
def test_assignment_driver_with_our_solution_passes(programs, net, tmp_path, capsys):
    out = run(programs["driver"], net, tmp_path / "a")
    status = cli_main(["check", "jacobson-net", str(out), "--steps", "30"])  # 30 of its 90
    text = capsys.readouterr().out
    assert status == 0 and "PASS" in text, text
    assert max(s.error for s in check("jacobson-net", out).steps) < 1e-12


def test_assignment_driver_refuses_a_model_it_cannot_express(programs, hanging, tmp_path):
    done = subprocess.run([str(programs["driver"]), str(hanging), str(tmp_path / "o")],
                          capture_output=True, text=True)
    assert done.returncode == 2 and "one stiffness" in done.stderr, done.stderr


# -- bad input ----------------------------------------------------------------------------------
@pytest.mark.parametrize("file, line, text, message", [
    ("springs.txt", 3, "0 1 300", "springs.txt:3: expected 4 or 5 numbers"),
    ("springs.txt", 2, "0 1 300 0.25 0.5", "springs.txt:2: damping 0.5"),
    ("masses.txt", 4, "1 kg", "masses.txt:4: expected one mass"),
    ("pins.txt", 2, "0 1 1e10 nan 0 1", "pins.txt:2: x: not a finite number"),
    ("springs.txt", 2, "0 999 300 0.25", "springs.txt:2: b: vertex index"),
])
def test_a_bad_line_is_a_one_line_error_naming_file_and_line(programs, net, tmp_path, file, line,
                                                             text, message):
    model = tmp_path / "model"
    shutil.copytree(net, model, ignore=shutil.ignore_patterns("*.mtx", "*.npz", "*.f64"))
    rows = (model / file).read_text().splitlines()
    rows[line - 1] = text
    (model / file).write_text("\n".join(rows) + "\n")
    done = subprocess.run([str(programs["port"]), str(model), str(tmp_path / "o")],
                          capture_output=True, text=True)
    assert done.returncode == 2 and message in done.stderr, done.stderr
    assert len(done.stderr.strip().splitlines()) == 1


@pytest.mark.parametrize("args, message", [
    (["--precision", "half"], "--precision: float or double"),
    (["--iterations", "0"], "--iterations: must be an integer >= 1"),
    (["--fault", "typo"], "--fault: none, unnormalized or sign"),
    (["--bogus", "1"], "unknown option --bogus"),
])
def test_bad_flags_exit_2(programs, net, tmp_path, args, message):
    done = subprocess.run([str(programs["port"]), str(net), str(tmp_path / "o"), *args],
                          capture_output=True, text=True)
    assert done.returncode == 2 and message in done.stderr, done.stderr


# -- docs/ports.md's section runs as written ----------------------------------------------------
def test_the_docs_commands_run_and_give_the_verdicts_they_state(programs, tmp_path):
    text = (REPO / "docs" / "ports.md").read_text(encoding="utf-8")
    section = text.split("## A compiled port: examples/ports/cpp", 1)[1]
    block = section.split("```sh\n", 1)[1].split("```", 1)[0].splitlines()
    build = tmp_path / "b"
    build.mkdir()
    prebuilt(programs, build)          # already built: make finds them up to date
    _scene("jacobson-net")
    clothsim = f"{shlex.quote(sys.executable)} -m clothsim"  # the repository's .venv may lack
    env = dict(os.environ, PYTHONPATH=str(REPO))
    results = []
    for line in block:
        argv = [a.replace("/tmp/clothsim-cpp", str(build)) for a in shlex.split(line)]
        assert argv[:3] == ["make", "-C", "examples/ports/cpp"], line
        done = subprocess.run(argv + [f"CLOTHSIM={clothsim}"], cwd=REPO, env=env,
                              capture_output=True, text=True)
        results.append((done.returncode, done.stdout))
    assert results[0][0] == 0, results[0]
    status = [code for code, _ in results[1:]]
    assert status[0] == 0 and status[1] != 0 and status[2] != 0 and status[3] == 0, results
    out = [o for _, o in results[1:]]
    assert "PASS" in out[0] and "PASS" in out[3], out
    assert "FAIL at step 0 -> 1" in out[1] and "pinned" in out[1], out[1]
    assert "FAIL at step 0 -> 1" in out[2], out[2]


# -- the coursework profile, through the assignment driver ------------------------------------
def test_every_coursework_case_runs_through_the_assignment_driver_and_passes(programs,
                                                                             tmp_path):
    from clothsim.ports.coursework import CASES, write_coursework

    write_coursework(tmp_path / "profile", frames=10)
    for name in CASES:
        case = tmp_path / "profile" / name
        out = run(programs["driver"], case, tmp_path / "out" / name)
        report = check(case / "scene.toml", out)
        assert report.passed, f"{name}: {report.summary()}"
        assert all(s.status == "agrees" for s in report.steps), f"{name}: {report.summary()}"


def test_the_coursework_section_runs_as_written(programs, tmp_path):
    text = (REPO / "docs" / "ports.md").read_text(encoding="utf-8")
    section = text.split("## Checking a coursework solution", 1)[1]
    block = section.split("```sh\n", 1)[1].split("```", 1)[0].splitlines()
    build = tmp_path / "b"
    build.mkdir()
    prebuilt(programs, build)
    clothsim = f"{shlex.quote(sys.executable)} -m clothsim"
    env = dict(os.environ, PYTHONPATH=str(REPO))
    outputs = []
    for line in block:
        line = line.replace("$PWD", str(tmp_path)).replace("/tmp/clothsim-cpp", str(build))
        argv = shlex.split(line)
        if argv[0] == ".venv/bin/clothsim":
            argv = [sys.executable, "-m", "clothsim", *argv[1:]]
            cwd = tmp_path
        else:
            assert argv[:3] == ["make", "-C", "examples/ports/cpp"], line
            argv += [f"CLOTHSIM={clothsim}", f"RUN={tmp_path / 'run'}"]
            cwd = REPO
        done = subprocess.run(argv, cwd=cwd, env=env, capture_output=True, text=True)
        assert done.returncode == 0, (line, done.stdout, done.stderr)
        outputs.append(done.stdout)
    assert "6 coursework conformance cases written" in outputs[0]
    assert "PASS: 30 steps agree" in outputs[1], outputs[1]


def test_too_few_iterations_are_not_converged_with_the_settings_named(programs, tmp_path):
    from clothsim.ports.coursework import write_coursework

    write_coursework(tmp_path / "profile", frames=3, cases=["net"])
    case = tmp_path / "profile" / "net"
    out = run(programs["port"], case, tmp_path / "out", "--start", "y", "--iterations", "5")
    first = check(case / "scene.toml", out).first_failure
    assert first is not None and first.k == 0 and first.status == "not converged", first
    assert first.settings == '[solver] initial_guess = "y" and iterations = 5', first.line()


# -- a student's solution: several files, its own include folder, one build per solution ------
def split_solution(folder: Path, *, start_from_unext: bool = False,
                   fault: str | None = None) -> list[Path]:
    """The project's solution as a real one is laid out: three files in src/, each including
    its header by the assignment's name from the solution's own include/ folder (the
    assignment's headers plus one of its own). ``start_from_unext``: the step iterates from
    Unext as it finds it (as main.cpp passes it, a copy of the current positions), like two
    of the published solutions. ``fault="unnormalized"``: the local step forgets to normalize."""
    src, include = folder / "src", folder / "include"
    src.mkdir(parents=True, exist_ok=True)
    include.mkdir(exist_ok=True)
    for header in (CPP / "include").glob("*.h"):
        shutil.copy2(header, include / header.name)
    (include / "penalty.h").write_text("#pragma once\ninline double pin_penalty() "
                                       "{ return 1e10; }\n")
    text = (CPP / "mass_springs_solution.cpp").read_text(encoding="utf-8")
    text = text.replace("const double w = 1e10;", "const double w = pin_penalty();")
    if start_from_unext:
        assert "  Unext = Ucur;\n" in text
        text = text.replace("  Unext = Ucur;\n", "")
    if fault == "unnormalized":
        text = text.replace("r(e) * p.row(e).normalized()", "r(e) * p.row(e)")
    bodies = {}
    for chunk in ("\n" + text).split("\n\n"):
        for name in ("signed_incidence_matrix_sparse", "fast_mass_springs_precomputation_sparse",
                     "fast_mass_springs_step_sparse"):
            if chunk.lstrip().startswith(("void " + name, "bool " + name)):
                bodies[name] = chunk.strip() + "\n"
    assert len(bodies) == 3, list(bodies)
    files = []
    for name, body in bodies.items():
        path = src / f"{name}.cpp"
        uses = "#include \"signed_incidence_matrix_sparse.h\"\n" if "precomputation" in name else ""
        path.write_text(f"#include \"{name}.h\"\n{uses}#include \"penalty.h\"\n"
                        f"#include <vector>\n\n{body}")
        files.append(path)
    return files


def test_a_three_file_solution_checked_as_the_howto_says_and_a_changed_one_rebuilt(programs,
                                                                                   tmp_path):
    """docs/howto/check-a-cpp-solution.md as written, on a solution in three files with its
    own include folder that starts its iterations from Unext (an empty Unext aborts it):
    PASS. The same files then changed to a wrong local step and dated before that build:
    make builds them afresh in a folder of their own and the check fails; the first
    build's PASS is never reprinted."""
    text = (REPO / "docs" / "howto" / "check-a-cpp-solution.md").read_text(encoding="utf-8")
    block = text.split("```sh\n", 1)[1].split("```", 1)[0].splitlines()
    build = tmp_path / "b"
    files = split_solution(tmp_path / "student", start_from_unext=True)
    clothsim = f"{shlex.quote(sys.executable)} -m clothsim"
    env = dict(os.environ, PYTHONPATH=str(REPO))

    def run_line(line: str) -> subprocess.CompletedProcess:
        argv = shlex.split(line.replace("$PWD", str(tmp_path))
                           .replace("/tmp/clothsim-cpp", str(build)))
        if argv[0] == ".venv/bin/clothsim":
            return subprocess.run([sys.executable, "-m", "clothsim", *argv[1:]], cwd=tmp_path,
                                  env=env, capture_output=True, text=True)
        assert argv[:4] == ["make", "check", "-C", "examples/ports/cpp"], line
        return subprocess.run(argv + [f"CLOTHSIM={clothsim}"], cwd=REPO, env=env,
                              capture_output=True, text=True)

    assert [run_line(line).returncode for line in block[:-1]] == [0] * (len(block) - 1)
    done = run_line(block[-1])
    assert done.returncode == 0, (done.stdout[-2000:], done.stderr[-2000:])
    assert "PASS: 30 steps agree" in done.stdout, done.stdout
    assert len(list(build.glob("assignment-*/assignment_driver"))) == 1
    # the student's files changed (a local step that forgets to normalize), dated 2000-01-01
    split_solution(tmp_path / "student", start_from_unext=True, fault="unnormalized")
    for f in files:
        os.utime(f, (946684800, 946684800))
    done = run_line(block[-1])
    assert done.returncode != 0 and "PASS" not in done.stdout, done.stdout
    assert "FAIL at step 0 -> 1" in done.stdout, done.stdout
    assert len(list(build.glob("assignment-*/assignment_driver"))) == 2


def test_a_missing_solution_file_is_a_one_line_make_error(tmp_path):
    if shutil.which("make") is None:
        pytest.skip("make is not installed")
    done = subprocess.run(["make", "-s", "-C", str(CPP), f"BUILD={tmp_path}",
                           f"SOLUTION={tmp_path / 'nope.cpp'}", "driver-path"],
                          capture_output=True, text=True)
    assert done.returncode != 0
    assert f"SOLUTION: no file {tmp_path / 'nope.cpp'}" in done.stderr, done.stderr
