"""Hostile input, round 3: the magnitudes round 2 left to the Python API, the Makefile's
paths with spaces, and the earlier rounds' fixes re-checked on variants they were not built
for.

Each case is a reproducer of a finding (it failed before its fix): one line naming the key
or argument, or a run that stays finite and moves.
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
from clothsim.cli import main
from clothsim.errors import InputError


def _one_line(capsys, code, expected_code=2) -> str:
    err = capsys.readouterr().err
    assert code == expected_code and err.count("\n") == 1, (code, err)
    assert "Error:" not in err and "Traceback" not in err, err
    return err.strip().removeprefix("clothsim: error: ")


def _model(k=800.0, mass=1.0):
    mesh = cs.grid(11, 11, size=(1.0, 1.0), center=(0.0, 1.0, 0.0), plane="xy")
    return cs.Model.build(mesh, cs.grid_springs(mesh, structural=k, shear=k, bending=k / 10),
                          total_mass=mass)


def _effects(g=-9.81):
    return [cs.Gravity((0.0, g, 0.0)), cs.Pin([110, 120])]


# ------------------------------------------------------------------ the Python API's magnitudes
# (Simulation(...) arguments, the field the error names, a piece of the condition it states);
# before: FactorizationError or OverflowError from CHOLMOD / Python, NonFiniteStateError at
# the first step, or a cloth that silently never moved (residual 0, 10 iterations)
API_REFUSED = {
    "h=1e300": (dict(h=1e300), "h", "h² = inf s² overflows float64"),  # was FactorizationError
    "h=1e300 newton": (dict(h=1e300, solver="newton"), "h", "overflows float64"),  # OverflowError
    "h=1e300 symplectic": (dict(h=1e300, solver="symplectic-euler"), "h", "overflows float64"),
    "h=1e-300": (dict(h=1e-300), "h", "h² = 0 s² underflows float64"),  # was: frozen
    "h=5e-324": (dict(h=5e-324), "h", "underflows float64"),
    "h=1e7": (dict(h=1e7), "h", "the mass is lost in M + h²L"),  # was: frozen (residual 0)
    "h=1e-12": (dict(h=1e-12), "effects[0].acceleration",
                "the motion is lost every step and the cloth would never move"),  # was: frozen
    "mass=1e300": (dict(mass=1e300), "model.vertex_mass", "makes the energy overflow"),
    "mass=1e-300": (dict(mass=1e-300), "h", "h²L_ii/m_i = 9.03e+302"),  # was: frozen
    "mass=1e-20": (dict(mass=1e-20), "h", "the mass is lost in M + h²L"),  # was: frozen
    "k=1e300": (dict(k=1e300), "h", "the mass is lost in M + h²L"),  # was: frozen
    "k=1e20": (dict(k=1e20), "h", "use h < 0.00021 s"),  # was: frozen
    "gravity 1e300": (dict(g=-1e300), "effects[0].acceleration", "h²|f|·√n"),
    "gravity 1e-30": (dict(g=-1e-30), "effects[0].acceleration", "a step longer than 1.8e+07 s"),
    "k=-1": (dict(k=-1.0), "springs.structural", "must be non-negative"),
    "h=nan": (dict(h=float("nan")), "h", "must be a finite number"),
}


@pytest.mark.parametrize("case", list(API_REFUSED))
def test_the_python_api_refuses_magnitudes_float64_cannot_step(case):
    args, field, says = API_REFUSED[case]
    args = dict(args)
    k, mass, g = args.pop("k", 800.0), args.pop("mass", 1.0), args.pop("g", -9.81)
    with pytest.raises(InputError) as info:
        model = _model(k=k, mass=mass)
        args.setdefault("h", 1 / 30)
        cs.Simulation(model, effects=_effects(g), **args)
    message = str(info.value)
    assert "\n" not in message and message.startswith(f"{field}: "), message
    assert says in message, message
    assert getattr(info.value, "field", None) in (field, None), info.value.field


@pytest.mark.parametrize("k, mass, g, h", [
    (0.0, 1.0, -9.81, 1 / 30),       # no springs: free fall
    (1e-300, 1.0, -9.81, 1 / 30),    # springs too soft to matter
    (800.0, 1e100, -9.81, 1 / 30),   # heavy: falls freely
    (800.0, 1.0, -1e100, 1 / 30),    # a huge gravity within the bounds: moves, finite
    (800.0, 1.0, -1e9, 1 / 30),
    (800.0, 1.0, -9.81, 1e-8),       # the shortest step that resolves gravity here
    (800.0, 1.0, -9.81, 1e4),        # long: M + h²L still factors in float64
])
def test_magnitudes_within_the_bounds_run_finite_and_move(k, mass, g, h):
    sim = cs.Simulation(_model(k=k, mass=mass), h=h, effects=_effects(g))
    x0 = sim.state.positions.copy()
    sim.run(3)
    x = sim.state.positions
    assert np.isfinite(x).all() and np.isfinite(sim.state.velocities).all()
    assert np.abs(x - x0).max() > 0, "the cloth froze"  # gravity moves the free vertices


def test_the_bound_on_a_short_step_is_where_the_motion_is_lost():
    """1e-8 s runs (gravity moves the cloth by 1e-15 m a step, above ε·1.5 m = 3.3e-16 m);
    1e-9 s is refused: x + h²g rounds back to x there and the velocity stays 0 for ever;
    2e-9 s too: only the lowest row would fall (its coordinates round more finely), the
    cloth torn by rounding."""
    mesh = cs.grid(11, 11, size=(1.0, 1.0), center=(0.0, 1.0, 0.0), plane="xy")
    model = cs.Model.build(mesh, cs.grid_springs(mesh, structural=0.0), total_mass=1.0)
    x0 = mesh.vertices
    for h, moving in ((1e-9, 0), (2e-9, 11)):  # what a step would move: nothing, one row
        moved = (x0 + h * h * np.array([0.0, -9.81, 0.0]) != x0).any(axis=1)
        assert np.count_nonzero(moved) == moving
        with pytest.raises(InputError, match="would never move"):
            cs.Simulation(model, h=h, effects=[cs.Gravity()])
    sim = cs.Simulation(model, h=1e-8, effects=[cs.Gravity()])
    sim.run(2)
    assert (sim.state.velocities[:, 1] < 0).all()


@pytest.mark.parametrize("change, key, says", [
    ("scene.fps=1e9", "effects[0].acceleration", "a step of h = 1e-09 s"),
    ("effects[0].acceleration=[0, -1e-30, 0]", "effects[0].acceleration", "never move"),
    ("effects[0].acceleration=[0, -1e300, 0]", "effects[0].acceleration", "h²|f|·√n"),
    ("springs.structural=1e20", "springs.structural", "the mass is lost in M + h²L"),
    ("cloth.mass=1e-300", "springs.structural", "the mass is lost in M + h²L"),
    ("cloth.mass=1e300", "cloth.mass", "makes the energy overflow"),
    ("scene.fps=1e-300", "scene.fps", "must be between"),
    ("scene.h=inf", "scene.h", "must be a finite number, got inf"),
])
def test_scene_magnitudes_exit_2_naming_the_key(tmp_path, capsys, change, key, says):
    out = tmp_path / "o"
    code = main(["run", "hanging", "--frames", "2", "--no-preview", "--out", str(out),
                 "--set", change])
    line = _one_line(capsys, code)
    assert line.startswith(f"--set {change}: {key}: ") and says in line, line
    assert not out.exists()


@pytest.mark.parametrize("h, says", [("1e300", "must be between"), ("1e-300", "must be between"),
                                     ("inf", "must be a finite number"),
                                     ("nan", "must be a finite number")])
def test_a_scene_files_h_out_of_float64s_reach_is_one_line(tmp_path, capsys, h, says):
    p = tmp_path / "s.toml"
    p.write_text(f"[scene]\nh = {h}\n")
    line = _one_line(capsys, main(["validate", str(p)]))
    assert line.startswith(f"{p}: scene.h: {says}"), line


def test_an_effect_after_the_cloth_files_pins_is_named_by_its_own_index(tmp_path, capsys):
    """A spring table's attachment is a pin that comes before the declared effects: the
    Simulation's effects[1] is the scene's effects[0]."""
    (tmp_path / "t.txt").write_text("0 -1 1000 0\n")
    p = tmp_path / "s.toml"
    p.write_text('[cloth]\nresolution = [5, 5]\n[springs]\ntable = "t.txt"\n'
                 '[[effects]]\nkind = "gravity"\nacceleration = [0, -1e-30, 0]\n')
    line = _one_line(capsys, main(["validate", str(p)]))
    assert line.startswith(f"{p}: effects[0].acceleration: gravity's largest"), line



def test_a_warning_after_the_cloth_files_pins_is_named_by_its_own_index(tmp_path):
    """The wind's drag warning comes from Simulation, whose effects[1] is the scene's
    effects[0] when a spring table's attachment pin comes first: the warning names the
    scene's key, as an error does."""
    from clothsim.solvers.symplectic import StabilityWarning

    (tmp_path / "t.txt").write_text("0 -1 1000 0\n")
    p = tmp_path / "s.toml"
    p.write_text('[cloth]\nresolution = [5, 5]\n[springs]\ntable = "t.txt"\n'
                 '[[effects]]\nkind = "wind"\nvelocity = [0, 0, 1e6]\n')
    scene = cs.load_scene(str(p))
    with pytest.warns(StabilityWarning) as record:
        scene.build_simulation()
    lines = [str(w.message) for w in record if issubclass(w.category, StabilityWarning)]
    assert lines and all(m.startswith("effects[0].velocity: the wind's drag") for m in lines), lines

# ------------------------------------------------------------------ make check with spaces
CPP = Path(__file__).resolve().parents[1] / "examples" / "ports" / "cpp"


def _make(*args: str) -> subprocess.CompletedProcess:
    if shutil.which("make") is None:
        pytest.skip("make is not installed")
    return subprocess.run(["make", "-s", "-C", str(CPP), *args], capture_output=True,
                          text=True)


def _student(root: Path) -> tuple[Path, Path]:
    """A solution in a folder whose name holds a space and a non-ASCII letter."""
    src, include = root / "sp ace é" / "src", root / "sp ace é" / "include"
    src.mkdir(parents=True)
    include.mkdir()
    shutil.copy2(CPP / "mass_springs_solution.cpp", src / "my solution.cpp")
    (include / "own header.h").write_text("#pragma once\n")
    return src, include


def test_make_takes_a_solution_whose_path_holds_spaces(tmp_path):
    """SOLUTION="$PWD/…/*.cpp" under a folder with a space: make split it into words and
    said 'SOLUTION: no file /…/sp' (docs/howto/check-a-cpp-solution.md)."""
    src, include = _student(tmp_path)
    build = tmp_path / "b ü"
    done = _make(f"BUILD={build}", f"SOLUTION={src}/*.cpp", f"SOLUTION_INCLUDE={include}",
                 "driver-path")
    assert done.returncode == 0, done.stderr
    driver = Path(done.stdout.strip())
    assert driver.parent.parent == build and driver.name == "assignment_driver", driver
    # the same files by their full name: the same build; another file: another build
    same = _make(f"BUILD={build}", f"SOLUTION={src / 'my solution.cpp'}",
                 f"SOLUTION_INCLUDE={include}", "driver-path")
    assert Path(same.stdout.strip()) == driver, same.stderr
    (src / "my solution.cpp").write_text("// changed\n", encoding="utf-8")
    other = _make(f"BUILD={build}", f"SOLUTION={src}/*.cpp", f"SOLUTION_INCLUDE={include}",
                  "driver-path")
    assert other.returncode == 0 and Path(other.stdout.strip()) != driver
    # several files separated by spaces still work, and a missing one is named whole
    a, b = tmp_path / "a.cpp", tmp_path / "b.cpp"
    a.write_text("\n")
    b.write_text("\n")
    assert _make(f"BUILD={build}", f"SOLUTION={a} {b}", "driver-path").returncode == 0
    missing = _make(f"BUILD={build}", f"SOLUTION={src}/nope file.cpp", "driver-path")
    assert missing.returncode != 0
    assert f"SOLUTION: no file {src}/nope file.cpp (relative paths" in missing.stderr, \
        missing.stderr
    nofolder = _make(f"BUILD={build}", f"SOLUTION={a}", f"SOLUTION_INCLUDE={tmp_path}/no pe",
                     "driver-path")
    assert f"SOLUTION_INCLUDE: no folder {tmp_path}/no pe" in nofolder.stderr


@pytest.mark.slow
def test_make_check_runs_the_howto_line_in_folders_with_spaces(tmp_path):
    """The howto's two lines, in a folder with a space and a non-ASCII letter: the driver
    built with the student's file, run on the coursework case and checked: PASS."""
    if shutil.which("g++") is None or not Path("/usr/include/eigen3/Eigen/Sparse").is_file():
        pytest.skip("g++ or Eigen is not installed")
    src, include = _student(tmp_path)
    work = src.parent
    clothsim = f"{shlex.quote(sys.executable)} -m clothsim"
    env = dict(os.environ, PYTHONPATH=str(CPP.parents[2]))
    conf = subprocess.run([sys.executable, "-m", "clothsim", "conformance", "--profile",
                           "coursework", "--out", str(work / "out" / "coursework")],
                          capture_output=True, text=True, env=env)
    assert conf.returncode == 0, conf.stderr
    net = work / "out" / "coursework" / "net"
    done = subprocess.run(["make", "check", "-C", str(CPP), f"BUILD={work / 'b ü'}",
                           "PROGRAM=assignment_driver", f"SOLUTION={src}/*.cpp",
                           f"SOLUTION_INCLUDE={include}", f"MODEL={net}",
                           f"SCENE={net / 'scene.toml'}", f"CLOTHSIM={clothsim}"],
                          capture_output=True, text=True, env=env)
    assert done.returncode == 0, (done.stdout[-2000:], done.stderr[-2000:])
    assert "PASS: 30 steps agree" in done.stdout, done.stdout


# ------------------------------------------------------------------ symbolic links
OUT_COMMANDS = [["run", "hanging", "--frames", "1", "--no-preview"],
                ["export", "hanging", "--frames", "1"],
                ["accuracy", "hanging", "--quick"],
                ["conformance"]]


@pytest.mark.parametrize("command", OUT_COMMANDS)
def test_a_dangling_link_as_out_is_bad_input_naming_the_link(tmp_path, capsys, command):
    """--out (or a folder above it) a link to nowhere: was exit 1, 'File exists; nothing
    was written'. clothsim makes no folder through it (its target stays absent)."""
    link, target = tmp_path / "out", tmp_path / "nowhere"
    link.symlink_to(target)
    line = _one_line(capsys, main(command + ["--out", str(link)]))
    assert line == (f"{link}: is a symbolic link to {target}, which does not exist; clothsim "
                    f"makes no folder through a dangling link (create its target, or choose "
                    f"another --out)"), line
    line = _one_line(capsys, main(command + ["--out", str(link / "sub")]))
    assert line.startswith(f"{link / 'sub'}: {link} is a symbolic link to {target}"), line
    assert not target.exists() and not os.path.lexists(target)


def _mine(folder: Path, names) -> dict[Path, bytes]:
    folder.mkdir(exist_ok=True)
    for name in names:
        (folder / name).write_bytes(b"mine\n")
    return {p: p.read_bytes() for p in folder.iterdir()}


def test_a_linked_folder_inside_a_run_folder_is_refused_and_its_target_untouched(tmp_path,
                                                                               capsys):
    """A run's state/ linked to a user's folder: a fresh run deleted the user's
    frame_*.npz there and wrote its own state files in their place."""
    out = tmp_path / "r"
    args = ["run", "drop-on-square", "--frames", "2", "--no-preview", "--out", str(out)]
    assert main(args) == 0
    assert (out / "state" / "frame_000001.npz").is_file()
    shutil.rmtree(out / "state")
    theirs = tmp_path / "theirs"
    before = _mine(theirs, ["frame_000000.npz", "frame_000001.npz", "notes.txt"])
    (out / "state").symlink_to(theirs)
    capsys.readouterr()
    for extra in ([], ["--force"], ["--resume", "--frames", "3"]):
        line = _one_line(capsys, main(args + extra))
        assert line == (f"{out / 'state'}: is a symbolic link to a folder ({theirs}); clothsim "
                        f"never writes through one (remove it, or choose another --out)"), line
        assert {p: p.read_bytes() for p in theirs.iterdir()} == before


def test_a_linked_case_folder_inside_a_conformance_set_is_refused(tmp_path, capsys):
    """A conformance case linked to a user's folder: its scene.toml was overwritten."""
    out = tmp_path / "c"
    assert main(["conformance", "--out", str(out)]) == 0
    case = sorted(p for p in out.iterdir() if p.is_dir())[0]
    shutil.rmtree(case)
    theirs = tmp_path / "theirs"
    before = _mine(theirs, ["scene.toml", "README.md"])
    case.symlink_to(theirs)
    capsys.readouterr()
    line = _one_line(capsys, main(["conformance", "--out", str(out)]))
    assert line.startswith(f"{case}: is a symbolic link to a folder"), line
    assert {p: p.read_bytes() for p in theirs.iterdir()} == before


def test_linked_result_files_are_replaced_never_written_through(tmp_path):
    """A link to a file in a run folder is legitimate to replace: the run renames its new
    file onto the name, which replaces the link; the linked file never changes (fresh run
    and --resume). A link as the --out folder itself is followed (a folder on another
    disk)."""
    names = ["trajectory.npz", "frame_000001.vtu", "trajectory.pvd", "preview.gif",
             "final.png"]
    user = tmp_path / "user.txt"
    user.write_text("precious\n")
    real = tmp_path / "disk"
    real.mkdir()
    out = tmp_path / "r"
    out.symlink_to(real)
    args = ["run", "hanging", "--frames", "2", "--out", str(out)]
    assert main(args) == 0
    for extra in ([], ["--resume", "--frames", "3"]):
        for name in names:
            (real / name).unlink()
            (real / name).symlink_to(user)
        assert main(args + extra) == 0
        assert user.read_text() == "precious\n"
        for name in names:
            assert (real / name).is_file() and not (real / name).is_symlink(), name
    assert len(list(real.glob("frame_*.vtu"))) == 4


@pytest.mark.parametrize("target", ["user.txt", "nowhere"])
def test_a_linked_lock_file_is_refused_and_never_created_or_written(tmp_path, capsys, target):
    out = tmp_path / "r"
    out.mkdir()
    user = tmp_path / "user.txt"
    user.write_text("precious\n")
    (out / ".clothsim.lock").symlink_to(tmp_path / target)
    line = _one_line(capsys, main(["run", "hanging", "--frames", "1", "--no-preview",
                                   "--out", str(out)]))
    assert line.startswith(f"{out / '.clothsim.lock'}: is a symbolic link;"), line
    assert user.read_text() == "precious\n" and not (tmp_path / "nowhere").exists()


# ------------------------------------------------------------------ accuracy --scheduler
def _refusal_within(address: str, seconds: float = 60) -> str:
    """check_scheduler(address)'s one-line refusal, run under a timeout (a hang fails)."""
    pytest.importorskip("dask.distributed", reason="dask.distributed is not installed")
    import threading

    from clothsim.accuracy.parallel import check_scheduler

    result = {}

    def check():
        try:
            check_scheduler(address)
        except InputError as exc:
            result["error"] = str(exc)

    thread = threading.Thread(target=check, daemon=True)
    thread.start()
    thread.join(seconds)
    assert not thread.is_alive(), f"check_scheduler({address!r}) hung"
    text = result["error"]
    assert "\n" not in text and text.startswith(f"accuracy.scheduler: cannot use {address!r}: ")
    return text.removeprefix(f"accuracy.scheduler: cannot use {address!r}: ")


@pytest.mark.parametrize("address, why", [
    ("", "empty; give a running scheduler's address, e.g. tcp://10.0.0.5:8786"),
    (" ", "empty; give a running scheduler's address"),  # was: missing port number in ''
    ("tcp://127.0.0.1:99999", "port 99999 is out of range (1 to 65535)"),  # was: refused
    ("tcp://127.0.0.1:0", "port 0 is out of range (1 to 65535)"),
    ("inproc://x", "an inproc:// address names a scheduler inside this process"),  # was:
    # 'not enough values to unpack (expected 3, got 1)'
    ("udp://127.0.0.1:1", "unknown address scheme 'udp'"),
])
def test_a_scheduler_address_that_names_no_scheduler_is_one_line_within_seconds(address, why):
    assert _refusal_within(address).startswith(why)


def test_a_listener_that_never_accepts_is_named_within_the_timeout(monkeypatch):
    """A port whose server listens but never accepts (the kernel completes the connection
    from its backlog): the probe waits for the handshake, not for ever."""
    import socket

    from clothsim.accuracy import parallel

    monkeypatch.setattr(parallel, "CONNECT_TIMEOUT", 1)
    with socket.socket() as srv:
        srv.bind(("127.0.0.1", 0))
        srv.listen(1)
        address = f"tcp://127.0.0.1:{srv.getsockname()[1]}"
        assert _refusal_within(address).startswith(
            "not a Dask scheduler: it accepted the connection but sent no Dask handshake "
            "within 1 s")


def test_the_command_refuses_a_closed_port_in_one_line_under_a_timeout(tmp_path):
    """The command line as a user runs it, in a process of its own under a timeout."""
    pytest.importorskip("dask.distributed", reason="dask.distributed is not installed")
    done = subprocess.run([sys.executable, "-m", "clothsim", "accuracy", "hanging", "--quick",
                           "--scheduler", "tcp://127.0.0.1:1", "--out", str(tmp_path / "acc")],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 2, done.stderr
    assert done.stderr == ("clothsim: error: accuracy.scheduler: cannot use "
                           "'tcp://127.0.0.1:1': Connection refused\n"), done.stderr
    assert not (tmp_path / "acc").exists()


# ------------------------------------------------------------------ huge forces
@pytest.mark.parametrize("method", ["local-global", "newton", "chebyshev"])
def test_a_pin_flung_beyond_float64_stops_in_one_line(tmp_path, capsys, method):
    """flag's pins moved at 1e75 m/s: the run stops at frame 3 naming the cause, exit 1;
    it also printed 'WARNING: RuntimeWarning (once): overflow encountered in dot' (the
    gradient's norm, whose inf the solver itself explains), and with Newton two more lines
    (the wind's force on the flung cloth), with Chebyshev one (its noise floor)."""
    out = tmp_path / "o"
    code = main(["run", "flag", "--frames", "3", "--no-preview", "--out", str(out),
                 "--set", "effects[1].velocity=[1e75, 0, 0]", "--set",
                 f"solver.method={method}"])
    line = _one_line(capsys, code, 1)
    assert line.startswith("frame 3: the state became non-finite (the step's gradient |grad g| "
                           "overflows float64 from its start: h²|f_ext|"), line
    assert "frame 2 is the last one kept" in line


@pytest.mark.parametrize("change", ["effects[1].velocity=[0, 3e7, 0]",   # pins 1e6 m a frame
                                    "effects[0].acceleration=[0, -1e9, 0]",
                                    "effects[2].velocity=[1e12, 0, 0]"])  # edge-on: no drag
def test_huge_forces_within_the_bounds_run_finite_and_move(tmp_path, change):
    out = tmp_path / "o"
    assert main(["run", "flag", "--frames", "3", "--no-preview", "--out", str(out),
                 "--set", change]) == 0
    x = np.load(out / "trajectory.npz")["positions"]
    assert np.isfinite(x).all()
    assert all(np.abs(x[k] - x[k - 1]).max() > 0 for k in range(1, 4))  # never frozen


def test_a_wind_whose_explicit_drag_overshoots_is_named_in_a_warning(tmp_path, capsys):
    """flag in a 1e12 m/s wind facing it: 3 frames ended 2e115 m away with exit 0 and no
    word (the drag, held over each step, overshot and grew every step). Now a
    StabilityWarning names the wind, h·ρ·C_d·|w|·A/M and the longest stable step; the
    flag's own 5 m/s wind (0.63) says nothing."""
    from clothsim.solvers.symplectic import StabilityWarning

    mesh = cs.grid(11, 11, size=(1.0, 1.0), center=(0.0, 1.0, 0.0), plane="xy")
    model = cs.Model.build(mesh, cs.grid_springs(mesh, structural=800.0), total_mass=1.0)
    with pytest.warns(StabilityWarning, match=r"^effects\[1\]\.velocity: the wind's drag is "
                                              r"explicit .*A/M = 40 for the cloth "):
        cs.Simulation(model, h=1 / 30, effects=[cs.Pin([110]), cs.Wind((0.0, 0.0, 1e3))])
    cs.Simulation(model, h=1 / 30, effects=[cs.Pin([110]), cs.Wind((0.0, 0.0, 5.0))])
    out = tmp_path / "o"
    assert main(["run", "flag", "--frames", "1", "--no-preview", "--out", str(out), "--set",
                 "effects[2].velocity=[0, 0, 1e12]"]) == 0
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "StabilityWarning" in err, err
    assert "effects[2].velocity: the wind's drag is explicit" in err
    assert "a step shorter than 5.6e-13 s" in err, err


def test_every_pwd_in_the_pages_commands_is_quoted():
    """A clone whose path holds a space (`~/My Files/clothsim`): an unquoted $PWD in a
    pasted command splits into two words (`MODEL=$PWD/out/…` in docs/ports.md and the
    check-a-cpp-solution howto)."""
    import re

    from .test_docs_pages import PAGES, blocks, commands, is_shell

    bare = [f"{b.name}: {c}" for page in PAGES for b in blocks(page) if is_shell(b)
            for c in commands(b) if "$PWD" in re.sub(r'"[^"]*"', "", c)]
    assert not bare, "\n".join(bare)


def test_a_force_that_turns_non_finite_is_a_blow_up_naming_the_effect(tmp_path, capsys):
    """flag in a 1e40 m/s wind: at frame 3 the wind's force on a cloth 1e151 m away is NaN;
    the run stopped with 'external_force[0, 0]: must be a finite number, got nan', a key no
    scene or argument has. Now it is the blow-up it is, naming the wind and the state."""
    from clothsim.errors import NonFiniteStateError
    from clothsim.state import State

    mesh = cs.grid(5, 5, plane="xy")
    model = cs.Model.build(mesh, cs.grid_springs(mesh, structural=10.0), total_mass=1.0)
    v = np.zeros((25, 3))
    v[:, 2] = 1e200
    sim = cs.Simulation(model, h=1 / 30, effects=[cs.Wind((0.0, 0.0, 1.0))],
                        state=State(mesh.vertices.copy(), v))
    with np.errstate(all="ignore"), pytest.raises(NonFiniteStateError) as info:
        sim.step()
    assert str(info.value).startswith("the external forces became non-finite in the step "
                                      "from t = 0 s: wind's force on vertex 0 is"), info.value
    assert "|v| up to 1e+200 m/s" in str(info.value)
    out = tmp_path / "o"
    code = main(["run", "flag", "--frames", "3", "--no-preview", "--out", str(out),
                 "--set", "effects[2].velocity=[1e40, 0, 1e40]"])
    err = capsys.readouterr().err
    assert code == 1, err
    assert "frame 3: the state became non-finite (the external forces became non-finite in " \
           "the step from t = 0.0666667 s: wind's force on vertex 0 is [nan, nan, nan]" in err
    assert "external_force" not in err
