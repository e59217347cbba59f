"""The C++ port sam007961/FastMassSpring for clothsim's side by side benchmark.

Its solver files (``ClothApp/MassSpringSolver.{h,cpp}``, MIT License, Samer Itani) are got
at the pinned commit :data:`COMMIT` into clothsim's cache folder: downloaded with pooch, or
copied from a folder or git clone the user names, each file checked against its SHA-256;
nothing of the port is in this repository. They are compiled with clothsim's driver
(``examples/ports/fastmassspring/driver.cpp``), never with the port's OpenGL viewer, and
the driver runs as a child process answering commands on a pipe (:class:`Driver`).
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np

import clothsim as cs
from clothsim.datasets import cache_dir, offline
from clothsim.datasets.download import fetch_files
from clothsim.datasets.registry import Dataset
from clothsim.datasets.store import DataUnavailableError, changed
from clothsim.io.common import atomic_path

from . import ROOT

#: sam007961/FastMassSpring's last commit (2020-04-10); its solver files are unchanged since
COMMIT = "b873efc23a41247a97a56058b9509bfe6ce6a3dd"
PORT = Dataset(
    name=f"sam007961-fastmassspring-{COMMIT[:7]}",
    title="the solver of sam007961/FastMassSpring (C++, Eigen; MIT License, Samer Itani)",
    source=f"github.com/sam007961/FastMassSpring, commit {COMMIT[:7]} (third party)",
    url=f"https://raw.githubusercontent.com/sam007961/FastMassSpring/{COMMIT}/",
    files={
        "ClothApp/MassSpringSolver.cpp":
            "0e1864d3bf2b66112ce0e7791e6a273f28e269eca9ecbcd17cba0d6a56fc4273",
        "ClothApp/MassSpringSolver.h":
            "98a0f42beb7d68e0742fc9a74ef7c2a45495a1d28b60b05a20827af4e9b0f78c",
        "LICENSE": "bf6a9223fe93c109fa35700b47ed5c6633ddc86122d872a6a69e01b719bbe3b7",
    },
)
DRIVER = ROOT / "examples" / "ports" / "fastmassspring" / "driver.cpp"
EIGEN = Path(os.environ.get("EIGEN", "/usr/include/eigen3"))
#: the iterations of one step
ITERATIONS = 10
#: CMake's Release flags (the port's CMakeLists sets none, which would mean -O0)
CXXFLAGS = ("-O3", "-DNDEBUG", "-std=c++17")


class Skip(Exception):
    """The side by side cannot run here (no compiler, no Eigen, no port source): one line."""


def port_source(source: str | Path | None = None) -> Path:
    """The folder holding the port's solver files at :data:`COMMIT`, each checked.

    Parameters
    ----------
    source : path, optional
        A folder holding the files, or a git repository holding the commit, to copy them
        from instead of downloading them; default ``$CLOTHSIM_FASTMASSSPRING`` if set.

    Returns
    -------
    Path
        ``<cache>/sam007961-fastmassspring-<commit>/``.

    Raises
    ------
    Skip
        When the files cannot be got (offline, no connection, a file that does not match
        its SHA-256), saying how to get them.
    """
    folder = cache_dir() / PORT.name
    source = source or os.environ.get("CLOTHSIM_FASTMASSSPRING") or None
    if source is not None:
        _copy_from(Path(source), folder)
    if not changed(PORT, folder):
        return folder
    how = (f"give --source (or $CLOTHSIM_FASTMASSSPRING) a folder or git clone of "
           f"github.com/sam007961/FastMassSpring at {COMMIT[:7]}")
    if offline():
        raise Skip(f"the port's source is not in {folder} and CLOTHSIM_OFFLINE is set; {how}")
    try:
        fetch_files(PORT, folder, None, how)
    except DataUnavailableError as exc:
        for sub in sorted(folder.rglob("*"), reverse=True):   # the empty folders it made
            if sub.is_dir() and not any(sub.iterdir()):
                sub.rmdir()
        if folder.is_dir() and not any(folder.iterdir()):
            folder.rmdir()
        raise Skip(str(exc)) from None
    return folder


def _copy_from(source: Path, folder: Path) -> None:
    """Copy the pinned files from a folder or a git repository; refuse any other content."""
    for name, sha in PORT.files.items():
        if (source / name).is_file():
            data = (source / name).read_bytes()
        else:
            done = subprocess.run(["git", "-C", str(source), "show", f"{COMMIT}:{name}"],
                                  capture_output=True)
            if done.returncode != 0:
                raise Skip(f"--source {source}: neither holds {name} nor is a git repository "
                           f"with commit {COMMIT[:7]}")
            data = done.stdout
        if hashlib.sha256(data).hexdigest() != sha:
            raise Skip(f"--source {source}: {name} does not match its pinned SHA-256 "
                       f"(another version of the port)")
        (folder / name).parent.mkdir(parents=True, exist_ok=True)
        with atomic_path(folder / name) as tmp:
            tmp.write_bytes(data)


def build_driver(source: Path) -> Path:
    """The driver compiled with the port's solver (built once per driver, port and flags).

    Raises
    ------
    Skip
        Without g++ or the Eigen headers; a failed build raises ``RuntimeError``.
    """
    cxx = shutil.which(os.environ.get("CXX", "g++"))
    if cxx is None:
        raise Skip("no C++ compiler (g++; apt package g++)")
    if not (EIGEN / "Eigen" / "Sparse").is_file():
        raise Skip(f"no Eigen headers in {EIGEN} (apt package libeigen3-dev; or set EIGEN)")
    key = hashlib.sha256(DRIVER.read_bytes() + " ".join((cxx, str(EIGEN), *CXXFLAGS)).encode()
                         + (source / "ClothApp" / "MassSpringSolver.cpp").read_bytes()
                         ).hexdigest()[:12]
    program = source / "build" / f"driver-{key}"
    if program.is_file():
        return program
    program.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(program) as tmp:
        done = subprocess.run([cxx, *CXXFLAGS, f"-I{EIGEN}", f"-I{source / 'ClothApp'}",
                               "-o", str(tmp), str(DRIVER),
                               str(source / "ClothApp" / "MassSpringSolver.cpp")],
                              capture_output=True, text=True)
        if done.returncode != 0:
            raise RuntimeError(f"building {DRIVER.name} failed:\n{done.stderr[-3000:]}")
    return program


def write_scene(sim: cs.Simulation, path: Path, damping: float = 1.0) -> None:
    """The driver's scene file (``driver.cpp``, scene_format 1) of ``sim`` at its state."""
    problem, springs = sim.problem(), sim.model.springs
    n = sim.model.vertex_count
    f = np.zeros((n, 3)) if problem.f_ext is None else problem.f_ext
    with atomic_path(path) as tmp, open(tmp, "w") as fh:
        fh.write(f"clothsim-fastmassspring-scene 1\n{n} {sim.model.spring_count} "
                 f"{len(problem.fixed_vertices)}\n{sim.h!r} {damping!r}\n")
        np.savetxt(fh, np.column_stack([sim.state.positions, sim.model.vertex_mass, f]),
                   fmt="%.17g")
        np.savetxt(fh, np.column_stack([springs.spring_vertices, springs.spring_rest_length,
                                        springs.spring_stiffness]),
                   fmt=["%d", "%d", "%.17g", "%.17g"])
        np.savetxt(fh, problem.fixed_vertices, fmt="%d")


class Driver:
    """The compiled driver stepping one scene, answering commands on a pipe (driver.cpp)."""

    def __init__(self, program: Path, scene: Path, iterations: int = ITERATIONS):
        self.proc = subprocess.Popen([str(program), str(scene), str(iterations)],
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, text=True,
                                     env=dict(os.environ, OMP_NUM_THREADS="1"))
        self.setup_seconds = float(self._ask(None, "ready")[0])

    def _ask(self, command: str | None, answer: str) -> list[str]:
        try:
            if command is not None:
                self.proc.stdin.write(command + "\n")
                self.proc.stdin.flush()
            words = self.proc.stdout.readline().split()
        except BrokenPipeError:     # it had stopped already: its stderr says why
            words = []
        if not words or words[0] != answer:
            self.proc.kill()
            _, err = self.proc.communicate()
            raise RuntimeError(f"the driver stopped: {' '.join(err.split())[-500:] or words}")
        return words[1:]

    def steps(self, count: int) -> tuple[np.ndarray, np.ndarray]:
        """Thread CPU and wall seconds of each of ``count`` steps' solve calls."""
        t = np.array(self._ask(f"steps {int(count)}", "times"), float).reshape(-1, 2)
        return t[:, 0], t[:, 1]

    def positions(self, path: Path) -> np.ndarray:
        """The port's positions now, (n, 3) [m] (written to ``path`` and read back)."""
        self._ask(f"write {path}", "written")
        return np.loadtxt(path, ndmin=2)

    def set_state(self, x_prev: np.ndarray, x: np.ndarray, prev: Path, now: Path) -> None:
        """Set the port's state to x_{n-1} = ``x_prev`` and x_n = ``x`` (through two files)."""
        np.savetxt(prev, x_prev, fmt="%.17g")
        np.savetxt(now, x, fmt="%.17g")
        self._ask(f"state {prev} {now}", "set")

    def close(self) -> None:
        """Ask the driver to quit; end it if it does not within 30 s."""
        if self.proc.poll() is None:
            try:
                self.proc.communicate("quit\n", timeout=30)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.communicate()


def compiler_version() -> str:
    cxx = shutil.which(os.environ.get("CXX", "g++")) or "g++"
    done = subprocess.run([cxx, "-dumpfullversion"], capture_output=True, text=True)
    return f"{Path(cxx).name} {done.stdout.strip()}"


def eigen_version() -> str:
    text = (EIGEN / "Eigen" / "src" / "Core" / "util" / "Macros.h").read_text()
    parts = [next((ln.split()[2] for ln in text.splitlines()
                   if ln.startswith(f"#define EIGEN_{w}_VERSION ")), "?")
             for w in ("WORLD", "MAJOR", "MINOR")]
    return ".".join(parts)


