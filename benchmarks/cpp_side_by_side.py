"""clothsim side by side with a C++ port: sam007961/FastMassSpring, time per iteration.

Run ``python -m benchmarks cpp_side_by_side`` (or ``python -m benchmarks.cpp_side_by_side
[--sizes 129,257] [--repeats 15] [--source PATH]``; a few minutes). It

- gets the port's solver (``ClothApp/MassSpringSolver.{h,cpp}``, MIT License, Samer Itani)
  at the pinned commit :data:`COMMIT` into clothsim's cache folder, downloaded with pooch
  and each file checked against its SHA-256 (``--source`` reads them from a folder or a git
  clone instead, checked the same way; nothing of the port is in this repository);
- compiles it with clothsim's driver ``examples/ports/fastmassspring/driver.cpp`` (g++,
  Eigen 3; skipped with one line where either is missing), without the port's viewer;
- builds the cloth of the performance page (n × n, 1 m, 1 kg, k = 800 N/m, bending springs
  at every other vertex, h = 1/30 s, 10 iterations, held at two corners) as clothsim
  :class:`~clothsim.simulation.Simulation` and hands the same vertices, springs, masses,
  forces and pins to the driver; both start each step's iterations from x_n (the port's
  start: ``initial_guess="x_n"``) with no extra damping (the port's a = 1);
- steps both 10 steps along an API user's path (``Simulation.run(3)``, then ``step()``) and
  checks that they agree on the positions (:data:`TOLERANCE`: the port computes in float);
- times, interleaved and repeated, one 10-iteration solve of each (clothsim: its
  simulation's own solver on the step after those, as the performance page's guard does;
  the port: ``MassSpringSolver::solve(10)`` going on stepping), thread CPU time, every
  thread pool limited to one thread, and also clothsim's bare CHOLMOD solve of its system;
- prints per size clothsim's and the port's ms per iteration and their ratio with its
  spread, and writes docs/data/cpp-side-by-side.md (commit and load average noted).
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

import clothsim as cs
from clothsim.gallery import GRAVITY, grid_cloth, top_corners
from clothsim.io.common import atomic_path

from . import ROOT
from .fastmassspring import (
    COMMIT,
    CXXFLAGS,
    ITERATIONS,
    Driver,
    Skip,
    build_driver,
    compiler_version,
    eigen_version,
    port_source,
    write_scene,
)
from .iteration_cost import commit
from .performance import MAX_STEPS, pending_switch, spread

PAGE = ROOT / "docs" / "data" / "cpp-side-by-side.md"
SIZES = (129, 257)
REPEATS = 31
WARM_STEPS = 10         # Simulation.run(3), then 7 steps: mid-motion, as the performance page
#: and more while the automatic CHOLMOD mode's ski-rental switch is pending (at most MAX_STEPS),
#: so both programs are timed in the factor the run keeps, as the performance page's guard
#: also checked, never timed: a size where the port's float arithmetic resolves one iteration
CHECK_SIZE = 17
F32 = float(np.finfo(np.float32).eps)


def side_by_side_sim(n: int) -> cs.Simulation:
    """The performance page's cloth, each step's iterations started from x_n (the port's)."""
    model = grid_cloth(n, k=800.0, plane="xz", center=(0.0, 1.0, 0.0),
                       bending_pattern="alternate")
    return cs.Simulation(model, h=1 / 30, iterations=ITERATIONS, initial_guess="x_n",
                         effects=[cs.Gravity(GRAVITY), cs.Pin(top_corners(n, "xz"))])


class Case:
    """One size: clothsim's simulation and the port's driver on the same scene, agreed."""

    def __init__(self, n: int, program: Path, folder: Path, timed: bool = True):
        from sksparse.cholmod import cholesky

        self.n, self.timed = n, timed
        sim = side_by_side_sim(n)
        x_start = sim.state.positions.copy()
        write_scene(sim, folder / f"scene-{n}.txt")
        self.driver = Driver(program, folder / f"scene-{n}.txt")
        sim.run(3)                          # the short-run API path, then stepping on
        for _ in range(WARM_STEPS - 3):
            sim.step()
        self.steps = WARM_STEPS
        while self.steps < MAX_STEPS and pending_switch(sim):
            sim.step()
            self.steps += 1
        self.driver.steps(self.steps)
        x, x_port = sim.state.positions, self.driver.positions(folder / f"positions-{n}.txt")
        self.drift = float(np.linalg.norm(x_port - x, axis=1).max())
        self.moved = float(np.linalg.norm(x - x_start, axis=1).max())
        self.springs = sim.model.spring_count
        self.problem, self.solver = sim.problem(), sim.solver
        # the same step started from y (clothsim's default): its cost, not compared
        self.problem_y = dataclasses.replace(self.problem, start="y")
        # one step from the same state: the port's float rounding of one step, not of ten
        self.distance, self.one_fewer = self._one_step(sim, folder)
        factor = self.solver.system(self.problem).A_FF_factor
        self.mode = factor.cholmod_mode
        # the forward error bound of a solve in float: what the port's rounding may leave
        self.tolerance = factor.condition_estimate * F32 * float(np.abs(x).max())
        self.bare = cholesky(factor.A, mode=self.mode)   # the same solve, bare
        self.rhs = np.asfortranarray(np.random.default_rng(n).normal(size=(factor.A.shape[0],
                                                                            3)))
        self.times = {"clothsim": [], "port": [], "bare": [], "port_wall": [],
                      "clothsim_y": []}

    def _one_step(self, sim: cs.Simulation, folder: Path) -> tuple[float, float]:
        """Largest distance between the port's step and clothsim's from clothsim's state,
        and (the scale of another computation) between clothsim's steps of 10 and 9
        iterations."""
        x, v = sim.state.positions, sim.state.velocities
        prev, now = folder / f"prev-{self.n}.txt", folder / f"now-{self.n}.txt"
        self.driver.set_state(x - sim.h * v, x, prev, now)
        self.driver.steps(1)
        x_port = self.driver.positions(folder / f"step-{self.n}.txt")
        x_10 = self.solver.solve(self.problem).x
        x_9 = None
        for it in self.solver.iterates(self.problem):
            if it.k == ITERATIONS - 1:
                x_9 = it.x.copy()
                break
        return (float(np.linalg.norm(x_port - x_10, axis=1).max()),
                float(np.linalg.norm(x_9 - x_10, axis=1).max()))

    def measure(self, what: str) -> None:
        """One sample of ``what``: thread CPU seconds per iteration."""
        if what == "port":
            cpu, wall = self.driver.steps(1)
            self.times["port"].append(cpu[0] / ITERATIONS)
            self.times["port_wall"].append(wall[0] / ITERATIONS)
            return
        c0 = time.thread_time()
        if what.startswith("clothsim"):
            self.solver.solve(self.problem if what == "clothsim" else self.problem_y)
        else:
            for _ in range(ITERATIONS):
                self.bare(self.rhs)
        self.times[what].append((time.thread_time() - c0) / ITERATIONS)

    def row(self) -> dict:
        t = {k: np.asarray(v) for k, v in self.times.items()}
        timed = {"clothsim": spread(t["clothsim"]), "port": spread(t["port"]),
                 "bare": spread(t["bare"]), "ratio": spread(t["clothsim"] / t["port"]),
                 "port_wall": spread(t["port_wall"]), "clothsim_y": spread(t["clothsim_y"]),
                 "ratio_y": spread(t["clothsim_y"] / t["port"])} if self.timed else {}
        return {"n": self.n, "springs": self.springs, "mode": self.mode, "timed": self.timed,
                "tolerance": self.tolerance, "agree": self.distance <= self.tolerance,
                "distance": self.distance, "one_fewer": self.one_fewer, "drift": self.drift,
                "moved": self.moved, "steps": self.steps,
                "port_setup_s": self.driver.setup_seconds, **timed}


def run(sizes=SIZES, *, repeats: int = REPEATS, source=None) -> dict:
    """Build, agree and time every size, interleaved; raises :class:`Skip` where it cannot."""
    program = build_driver(port_source(source))
    load, measured = os.getloadavg()[0], commit()   # the code as it was when measured
    with tempfile.TemporaryDirectory() as tmp, warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cases = []
        try:
            for n in sizes:
                cases.append(Case(n, program, Path(tmp)))
            if CHECK_SIZE not in sizes:
                cases.append(Case(CHECK_SIZE, program, Path(tmp), timed=False))
            order = ["clothsim", "port", "bare", "clothsim_y"]
            for r in range(repeats):
                for case in (c for c in cases if c.timed):   # interleaved, order rotated
                    for what in order[r % 4:] + order[:r % 4]:
                        case.measure(what)
            shares = {c.n: profile(c) for c in cases if c.timed}
            starts = {c.n: start_gradient(c) for c in cases if c.timed}
            setups = {c.n: step_setup(c) + gathers(c) for c in cases if c.timed}
        finally:
            for case in cases:
                case.driver.close()
    return {"rows": [c.row() for c in cases], "profile": shares, "start_gradient": starts,
            "setup": setups,
            "repeats": repeats, "load": (load, os.getloadavg()[0]), "commit": measured,
            "compiler": compiler_version(), "eigen": eigen_version()}


#: clothsim's solve by where its time goes: cProfile self time, functions grouped
PARTS = (("CHOLMOD solve", ("solve_columns",)),
         ("local step: spring vectors and projection", ("take", "directions.py", "einsum",
                                                        "spring_blocks.py")),
         ("right-hand side: h² J products", ("csr_matvec", "_right_hand_side")),
         ("per step: start, gradient at x_0", ("gradient ", "fused.py __init__", "_constant",
                                               "_free_difference", "free_product",
                                               "csc_matvecs")),
         ("other: update, norms, Python", ("",)))


def profile(case: Case, solves: int = 10) -> dict[str, float]:
    """Shares of clothsim's solve time by part (:data:`PARTS`), on ``case``'s step."""
    import cProfile
    import pstats

    prof = cProfile.Profile()
    prof.runcall(lambda: [case.solver.solve(case.problem) for _ in range(solves)])
    shares = dict.fromkeys(name for name, _ in PARTS)
    shares = {k: 0.0 for k in shares}
    for (path, _, func), (_, _, self_time, _, _) in pstats.Stats(prof).stats.items():
        where = f"{func} {Path(path).name} {func}"
        part = next(name for name, keys in PARTS if any(k in where for k in keys))
        shares[part] += self_time
    total = sum(shares.values())
    return {k: v / total for k, v in shares.items()}


def start_gradient(case: Case, repeats: int = 15) -> tuple[float, float]:
    """Thread CPU seconds of ∇g(x_0) from its definition (the full gradient) and of the
    one product A_FF δ_0 that gives it too (∇g(x_0)_F = A_FF δ_0 − rhs(x_0)) as a step
    started at x_n computes it (:meth:`~clothsim.solvers.system.SystemFactor.free_product`
    on the vertex-major δ_0), interleaved, medians."""
    sysf = case.solver.system(case.problem)
    x0 = case.problem.initial_guess()
    delta = np.ascontiguousarray(x0[sysf.free] - case.problem.y[sysf.free])
    d = case.solver._dirs.current().T
    times = {"gradient": [], "product": []}
    for _ in range(repeats):
        for what in times:
            c0 = time.thread_time()
            if what == "gradient":
                case.solver.gradient(case.problem, x0, d)
            else:
                sysf.free_product(delta)
            times[what].append(time.thread_time() - c0)
    return float(np.median(times["gradient"])), float(np.median(times["product"]))


def step_setup(case: Case, repeats: int = 15) -> tuple[float, float]:
    """Thread CPU seconds of a step's setup (:class:`~clothsim.solvers.fused.FusedStep`:
    y's spring vectors, c_F, the local step and right-hand side at x_0, A_FF δ_0) and of
    the whole 10-iteration solve it starts, interleaved, medians."""
    from clothsim.solvers.fused import FusedStep

    times = {"setup": [], "solve": []}
    for _ in range(repeats):
        for what in times:
            c0 = time.thread_time()
            if what == "setup":
                FusedStep(case.solver, case.problem)
            else:
                case.solver.solve(case.problem)
            times[what].append(time.thread_time() - c0)
    return float(np.median(times["setup"])), float(np.median(times["solve"]))


def gathers(case: Case, repeats: int = 15) -> tuple[float, float]:
    """Thread CPU seconds of all springs' vectors p(y) as the step gathers them (strided
    slices over the regular blocks, :mod:`clothsim.solvers.spring_blocks`) and by two takes
    per coordinate, interleaved, medians."""
    gather = case.solver._dirs._gather
    yT = np.ascontiguousarray(case.problem.y.T)
    out = np.empty((3, len(gather.a)))
    times = {"slices": [], "takes": []}
    for _ in range(repeats):
        for what in times:
            c0 = time.thread_time()
            (gather if what == "slices" else gather._takes)(yT, out)
            times[what].append(time.thread_time() - c0)
    return float(np.median(times["slices"])), float(np.median(times["takes"]))


def _ms(q) -> str:
    return f"{1e3 * q[0]:.2f} ({1e3 * q[1]:.2f}–{1e3 * q[2]:.2f})"


def table(result: dict) -> list[str]:
    """The timings, then the agreement, as Markdown tables (the page's and the terminal's)."""
    lines = ["| grid | springs | clothsim ms/iteration | of which its bare solve | "
             "port ms/iteration | clothsim/port | clothsim from y (its default) | "
             "from y/port |", "|---|---|---|---|---|---|---|---|"]
    for r in (r for r in result["rows"] if r["timed"]):
        lines.append(f"| {r['n']}² | {r['springs']} | {_ms(r['clothsim'])} {r['mode']} | "
                     f"{1e3 * r['bare'][0]:.2f} | {_ms(r['port'])} | **{r['ratio'][0]:.2f}** "
                     f"({r['ratio'][1]:.2f}–{r['ratio'][2]:.2f}) | {_ms(r['clothsim_y'])} | "
                     f"{r['ratio_y'][0]:.2f} ({r['ratio_y'][1]:.2f}–{r['ratio_y'][2]:.2f}) |")
    lines += ["", "| grid | one step apart | float bound κ·ε·max‖x‖ | agree | one iteration "
              "fewer moves clothsim's by | apart after the warm-up's steps from rest |",
              "|---|---|---|---|---|---|"]
    for r in result["rows"]:
        lines.append(f"| {r['n']}²{'' if r['timed'] else ' (check only)'} | "
                     f"{r['distance']:.1e} m | {r['tolerance']:.1e} m | "
                     f"{'yes' if r['agree'] else '**no**'} | {r['one_fewer']:.1e} m | "
                     f"{r['drift']:.1e} m after {r['steps']} steps "
                     f"(cloth moved {r['moved']:.2f} m) |")
    sizes = list(result["profile"])
    lines += ["", "| clothsim's solve, share of its time | " + " | ".join(f"{n}²" for n in sizes)
              + " |", "|---|" + "---|" * len(sizes)]
    for name, _ in PARTS:
        lines.append(f"| {name} | " + " | ".join(f"{100 * result['profile'][n][name]:.0f} %"
                                                 for n in sizes) + " |")
    for i, what in enumerate(("∇g(x_0) from its definition (spring gather), ms",
                              "∇g(x_0) as A_FF δ_0 − rhs(x_0) (FusedStep's), ms")):
        lines.append(f"| {what} | " + " | ".join(
            f"{1e3 * result['start_gradient'][n][i]:.2f}" for n in sizes) + " |")
    setups = [result["setup"][n] for n in sizes]
    lines.append("| a step's setup (y's spring vectors, c_F, local step and rhs at x_0, "
                 "A_FF δ_0), ms (share of the step's solve) | "
                 + " | ".join(f"{1e3 * t[0]:.2f} ({100 * t[0] / t[1]:.0f} %)" for t in setups)
                 + " |")
    lines.append("| all springs' vectors p(y): by strided slices (the step's) / by two takes "
                 "a coordinate, ms | "
                 + " | ".join(f"{1e3 * t[2]:.2f} / {1e3 * t[3]:.2f}" for t in setups) + " |")
    return lines


def write_page(result: dict, sizes, repeats: int) -> None:
    """docs/data/cpp-side-by-side.md, written whole or not at all."""
    lo, hi = result["load"]
    head = (f"Measured by `python -m benchmarks.cpp_side_by_side --sizes "
            f"{','.join(map(str, sizes))} --repeats {repeats}` at commit {result['commit']} "
            f"against sam007961/FastMassSpring at {COMMIT[:7]} ({result['compiler']}, "
            f"{' '.join(CXXFLAGS)}, Eigen {result['eigen']}): thread CPU time per "
            f"local/global iteration, median and interquartile range of {repeats} "
            f"interleaved samples, every thread pool on one thread; load average {lo:.2f} at "
            f"the start, {hi:.2f} at the end (2 cores, shared). Agreement: the largest "
            f"distance between the two programs' vertices after one step from the same state "
            f"(the warm-up's last step: `Simulation.run(3)`, {WARM_STEPS - 3} steps, and more "
            f"while the automatic mode's switch is pending), against the forward error bound "
            f"of a solve in float "
            f"(κ from CHOLMOD's condition estimate, ε = {F32:.2g}).")
    PAGE.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(PAGE) as tmp:
        tmp.write_text("\n".join([head, "", *table(result)]) + "\n")


def main(argv: list[str] | None = None) -> dict | None:
    """Run, print and write the page; ``argv`` as on the command line (default none)."""
    parser = argparse.ArgumentParser(prog="python -m benchmarks.cpp_side_by_side")
    parser.add_argument("--sizes", default=",".join(map(str, SIZES)))
    parser.add_argument("--repeats", type=int, default=REPEATS)
    parser.add_argument("--source", help="a folder or git clone holding the port's files")
    parser.add_argument("--no-page", action="store_true", help="print only")
    args = parser.parse_args([] if argv is None else argv)
    sizes = tuple(int(s) for s in args.sizes.split(","))
    import sksparse.cholmod  # noqa: F401  (load CHOLMOD's OpenMP and BLAS: limited too)

    try:
        with threadpool_limits(1):
            result = run(sizes, repeats=args.repeats, source=args.source)
    except Skip as exc:
        print(f"cpp_side_by_side skipped: {exc}")
        return None
    print("\n".join(table(result)))
    bad = [r["n"] for r in result["rows"] if not r["agree"]]
    if bad:
        print(f"the programs disagree at {bad} beyond the float bound: they do not compute "
              f"the same step; page not written")
    elif not args.no_page:
        write_page(result, sizes, args.repeats)
    return result


if __name__ == "__main__":
    main(sys.argv[1:])
