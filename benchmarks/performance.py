"""Per-iteration cost of local/global against the floor of its sparse solve.

Run ``python -m benchmarks performance`` (about 3 minutes; ``--quick`` skips 257²). On a
grid with structural, shear and bending springs started at every other vertex (the C++
ports' pattern), mid-motion (the horizontal sheet held at two corners, after 10 steps of
falling), it measures in one process, with the sizes and the measurements interleaved in
every repeat (the machine is shared, so only figures measured side by side are compared):

- the time of one iteration as an API user's simulation runs it: ``Simulation.run(3)`` (a
  short call, which tells the solver only that at least 30 solves follow), then stepping
  on to mid-motion and past the automatic mode's ski-rental switch, if one is pending
  (:mod:`clothsim.factor_mode`: the factor it settles in; the steps taken are reported),
  then its own solver's :meth:`LocalGlobalSolver.solve` (a 10-iteration solve, divided by
  10) with the factor that path left (its mode is reported);
- the fastest bare CHOLMOD solve of the same n × n system with three right-hand sides,
  simplicial and supernodal, and the ratio of the two;
- setup (assembly + factorization; the condition estimate timed apart) and its growth
  exponent fitted over the sizes;
- the paper's 81 × 81 frame at 10 iterations, CPU time (``time.process_time``), next to
  the paper's 50 ms.

Every thread pool — BLAS, and the OpenMP runtime CHOLMOD loads — is limited to one thread
(threadpoolctl) for every measurement, so a CPU time is one thread's work (OpenMP workers
left spinning by an earlier call otherwise add their CPU time to whatever is measured next;
the solver itself limits BLAS, see docs/performance.md). Results go to
docs/data/performance.csv (with the commit, the load average at the start and the end, and
the 81 × 81 frame), the table docs/data/performance.md written from it
(:mod:`benchmarks.performance_page`; docs/performance.md includes it and explains it) and
docs/img/performance.png. ``python -m benchmarks.performance --from-csv [PATH]`` rewrites
only the table from a CSV (default docs/data/performance.csv), measuring nothing.
"""

from __future__ import annotations

import csv
import os
import sys
import time
import warnings
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

import clothsim as cs
from clothsim.errors import InputError
from clothsim.factorization import spmv_add
from clothsim.gallery import GRAVITY, grid_cloth, top_corners
from clothsim.io.common import atomic_path
from clothsim.solvers import LocalGlobalSolver

from . import DOCS_IMG
from .performance_page import CSV_PATH, PAPER_FRAME_SECONDS_81, RUN_COLUMNS
from .performance_page import write as write_page
from .scale_ladder import commit

SIZES = (33, 65, 129, 257)
ITERATIONS = 10
#: steps after ``Simulation.run(3)`` before measuring: mid-motion, 10 steps in all (more
#: while the automatic mode's switch to the faster solves is pending, at most MAX_STEPS)
STEP_ON = 7
MAX_STEPS = 300


def falling_sheet(n: int, *, iterations: int = ITERATIONS) -> cs.Simulation:
    """The benchmark cloth: n × n, 1 m, 1 kg, k = 800 N/m, held at two corners."""
    model = grid_cloth(n, k=800.0, plane="xz", center=(0.0, 1.0, 0.0),
                       bending_pattern="alternate")
    return cs.Simulation(model, h=1 / 30, iterations=iterations,
                         effects=[cs.Gravity(GRAVITY), cs.Pin(top_corners(n, "xz"))])


def pending_switch(sim: cs.Simulation) -> bool:
    """Whether the solver's factor will still be replaced by the automatic mode's switch."""
    mode = sim.solver.system(sim.problem()).mode
    return mode is not None and mode.switch_after is not None


class Case:
    """One size: a mid-motion problem, its solver and the bare factors of its system."""

    def __init__(self, n: int):
        from sksparse.cholmod import cholesky

        self.n = n
        sim = falling_sheet(n)
        sim.run(3)                  # the short-run API path (issue 33), then stepping on
        for _ in range(STEP_ON):
            sim.step()
        self.steps = 3 + STEP_ON
        while self.steps < MAX_STEPS and pending_switch(sim):
            sim.step()
            self.steps += 1
        self.problem = sim.problem()
        self.model = sim.model
        self.solver = sim.solver    # the factor that path chose (and kept, or switched)
        sysf = self.solver.system(self.problem)
        self.mode = sysf.A_FF_factor.cholmod_mode
        A_FF = sysf.A_FF_factor.A
        self.factors = {mode: cholesky(A_FF, mode=mode) for mode in ("simplicial",
                                                                      "supernodal")}
        rng = np.random.default_rng(n)
        self.rhs = np.asfortranarray(rng.normal(size=(A_FF.shape[0], 3)))
        self.inner = max(1, int(40_000 / n ** 2))   # repeat tiny solves to time them
        self.parts_solver = None
        self.times = {k: [] for k in ("iteration", "simplicial", "supernodal", "setup",
                                      "condition", "iteration_cpu", "simplicial_cpu",
                                      "supernodal_cpu", "parts")}

    def _timed(self, key: str, fn, count: int) -> None:
        """Wall and CPU time of ``fn`` per unit (``count`` units per call)."""
        t0, c0 = time.perf_counter(), time.process_time()
        fn()
        c1, t1 = time.process_time(), time.perf_counter()
        self.times[key].append((t1 - t0) / count)
        self.times[key + "_cpu"].append((c1 - c0) / count)

    def measure_iteration(self) -> None:
        self._timed("iteration", lambda: self.solver.solve(self.problem), ITERATIONS)

    def measure_bare(self, mode: str) -> None:
        F, b = self.factors[mode], self.rhs

        def solves():
            for _ in range(self.inner):
                F(b)

        self._timed(mode, solves, self.inner)

    def measure_parts(self, repeats: int = 5) -> None:
        """The iteration's NumPy work, each part timed alone and repeated (its data in cache).

        Their sum is what an iteration costs besides its solve when nothing else competes
        for the cache and no per-step work is shared out: a floor for the ratio."""
        if self.parts_solver is None:   # its own buffers (the measured solver's stay as they are)
            self.parts_solver = LocalGlobalSolver(self.model, check_conditioning=False)
        solver = self.parts_solver
        sysf, dirs = solver.system(self.problem), solver._dirs
        xT = np.ascontiguousarray(self.problem.y.T)
        pyT, eT = solver._pyT, solver._eT
        rhsT, rhs_nextT, cT = sysf.work
        runs = sysf.free_runs
        dirs.vectors_into(xT, pyT)
        dirs.vectors_into(xT, eT)

        def update():    # x = y + δ over the free runs, then the residual and its norm
            for start, stop, offset in runs:
                np.add(xT[:, start:stop], rhsT[:, offset:offset + stop - start],
                       out=xT[:, start:stop])
            np.subtract(rhsT, rhs_nextT, out=rhs_nextT)
            float(np.dot(rhs_nextT.reshape(-1), rhs_nextT.reshape(-1)))

        def rhs():
            np.copyto(rhs_nextT, cT)
            for c in range(3):
                spmv_add(sysf.h2J_F, eT[c], rhs_nextT[c])

        def local():     # spring vectors, then e = d − p(y) in place
            dirs.vectors_into(xT, eT)
            dirs.e_into(xT, eT, pyT)

        rhsT.fill(0.0)                  # δ = 0: x stays y, so every repeat does the same work
        total = 0.0
        for fn in (update, rhs, local):
            fn()                        # warm: this part's data in cache
            times = []
            for _ in range(repeats):
                t0 = time.process_time()
                fn()
                times.append(time.process_time() - t0)
            total += float(np.median(times))
        self.times["parts"].append(total)

    def measure_setup(self) -> None:
        t0 = time.perf_counter()
        solver = LocalGlobalSolver(self.model, check_conditioning=False)
        sysf = solver.system(self.problem)
        self.times["setup"].append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        sysf.A_FF_factor.condition_estimate   # noqa: B018 (timed apart)
        self.times["condition"].append(time.perf_counter() - t0)


def frame_cpu_seconds(repeats: int) -> list[float]:
    """CPU time of one 81 × 81 frame (one step, 10 iterations, gravity and two pins)."""
    sim = falling_sheet(81)
    sim.run(3)                                      # factor once, reach mid-motion
    out = []
    for _ in range(repeats):
        t0 = time.process_time()
        sim.step()
        out.append(time.process_time() - t0)
    return out


def spread(values) -> tuple[float, float, float]:
    """Median and the 25th and 75th percentiles."""
    q = np.percentile(np.asarray(values), [50, 25, 75])
    return float(q[0]), float(q[1]), float(q[2])


def run(sizes=SIZES, *, repeats: int = 15, setup_repeats: int = 3) -> dict:
    """Measure everything, interleaved; returns the rows of the table and the frame."""
    measured, load = commit(), os.getloadavg()[0]     # the code as it was when measured
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cases = [Case(n) for n in sizes]
        for r in range(repeats):
            for case in cases:                      # interleaved: sizes and methods
                order = ["iteration", "simplicial", "supernodal"]
                for what in order[r % 3:] + order[:r % 3]:
                    if what == "iteration":
                        case.measure_iteration()
                    else:
                        case.measure_bare(what)
                if r < setup_repeats:
                    case.measure_setup()
                    case.measure_parts()
        frame = frame_cpu_seconds(repeats)
    rows = []
    for case in cases:
        med = {k: spread(v) for k, v in case.times.items() if v}
        fastest = min(med["simplicial"][0], med["supernodal"][0])
        fastest_cpu = min(med["simplicial_cpu"][0], med["supernodal_cpu"][0])
        rows.append({"n": case.n, "vertices": case.n ** 2, "mode": case.mode,
                     "steps": case.steps,
                     "springs": case.model.spring_count,
                     "iteration_ms": med["iteration"], "simplicial_ms": med["simplicial"],
                     "supernodal_ms": med["supernodal"],
                     "ratio": med["iteration"][0] / fastest,
                     "iteration_cpu_ms": med["iteration_cpu"],
                     "simplicial_cpu_ms": med["simplicial_cpu"],
                     "supernodal_cpu_ms": med["supernodal_cpu"],
                     "ratio_cpu": med["iteration_cpu"][0] / fastest_cpu,
                     "setup_s": med["setup"], "condition_s": med["condition"],
                     "parts_ms": med["parts"],
                     "floor": 1 + med["parts"][0] / fastest_cpu})
    verts = np.array([r["vertices"] for r in rows], float)
    setup = np.array([r["setup_s"][0] for r in rows])
    exponent = float(np.polyfit(np.log(verts), np.log(setup), 1)[0]) if len(rows) > 1 else 0.0
    return {"rows": rows, "setup_exponent": exponent, "frame_s": spread(frame),
            "commit": measured, "load": (load, os.getloadavg()[0]), "cores": os.cpu_count() or 0,
            "repeats": repeats}


def write_csv(result: dict, path=CSV_PATH) -> None:
    """The rows, and the run's commit, load, cores, repeats and 81 × 81 frame on each row
    (atomically: a reader never sees half a CSV)."""
    frame = [f"{1e3 * v:.3f}" for v in result["frame_s"]]
    run_cells = [result["commit"], f"{result['load'][0]:.2f}", f"{result['load'][1]:.2f}",
                 result["cores"], result["repeats"], *frame]
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp, open(tmp, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["grid", "vertices", "springs", "factor_mode", "steps", "iteration_ms",
                    "iteration_q25_ms",
                    "iteration_q75_ms", "simplicial_ms", "supernodal_ms", "ratio",
                    "iteration_cpu_ms", "simplicial_cpu_ms", "supernodal_cpu_ms",
                    "ratio_cpu", "numpy_parts_cpu_ms", "floor", "setup_s", "condition_s",
                    *RUN_COLUMNS])
        for r in result["rows"]:
            w.writerow([f"{r['n']}x{r['n']}", r["vertices"], r["springs"], r["mode"], r["steps"],
                        *(f"{1e3 * v:.4f}" for v in r["iteration_ms"]),
                        f"{1e3 * r['simplicial_ms'][0]:.4f}",
                        f"{1e3 * r['supernodal_ms'][0]:.4f}", f"{r['ratio']:.3f}",
                        f"{1e3 * r['iteration_cpu_ms'][0]:.4f}",
                        f"{1e3 * r['simplicial_cpu_ms'][0]:.4f}",
                        f"{1e3 * r['supernodal_cpu_ms'][0]:.4f}", f"{r['ratio_cpu']:.3f}",
                        f"{1e3 * r['parts_ms'][0]:.4f}", f"{r['floor']:.3f}",
                        f"{r['setup_s'][0]:.6f}", f"{r['condition_s'][0]:.6f}", *run_cells])


def plot(result: dict) -> None:
    from matplotlib.figure import Figure

    rows = result["rows"]
    v = [r["vertices"] for r in rows]
    fig = Figure(figsize=(9, 3.6))
    ax, bx = fig.subplots(1, 2)
    for key, label in (("iteration_ms", "one iteration, solve()"),
                       ("simplicial_ms", "bare CHOLMOD solve, simplicial"),
                       ("supernodal_ms", "bare CHOLMOD solve, supernodal")):
        med = np.array([1e3 * r[key][0] for r in rows])
        lo = med - np.array([1e3 * r[key][1] for r in rows])
        hi = np.array([1e3 * r[key][2] for r in rows]) - med
        ax.errorbar(v, med, yerr=[lo, hi], marker="o", capsize=3, label=label)
    ax.set(xscale="log", yscale="log", xlabel="vertices", ylabel="ms",
           title="per iteration vs. the sparse solve")
    ax.legend(fontsize=8)
    bx.plot(v, [r["ratio"] for r in rows], marker="o")
    bx.axhline(1.0, color="gray", lw=0.8)
    bx.set(xscale="log", ylim=(0, None), xlabel="vertices",
           ylabel="iteration / fastest bare solve", title="overhead around the solve")
    fig.tight_layout()
    DOCS_IMG.mkdir(parents=True, exist_ok=True)
    fig.savefig(DOCS_IMG / "performance.png", dpi=110)


def report(result: dict) -> None:
    print("wall time (CPU time in brackets), ms; ratio = iteration / fastest bare solve; the "
          "iteration after Simulation.run(3) and stepping on, in the mode it chose")
    print(f"{'grid':>8} {'mode':>5} {'steps':>5} {'springs':>8} {'iteration (IQR)':>26} "
          f"{'simplicial':>16} {'supernodal':>16} {'ratio':>11} {'floor':>6} {'setup s':>8} "
          f"{'cond s':>7}")
    for r in result["rows"]:
        it = r["iteration_ms"]
        print(f"{r['n']:>4}x{r['n']:<3} {r['mode'][:5]:>5} {r['steps']:>5} {r['springs']:>8} "
              f"{1e3 * it[0]:>7.3f} ({1e3 * it[1]:.3f}-{1e3 * it[2]:.3f}) "
              f"[{1e3 * r['iteration_cpu_ms'][0]:.3f}] "
              f"{1e3 * r['simplicial_ms'][0]:>7.3f} [{1e3 * r['simplicial_cpu_ms'][0]:.3f}] "
              f"{1e3 * r['supernodal_ms'][0]:>7.3f} [{1e3 * r['supernodal_cpu_ms'][0]:.3f}] "
              f"{r['ratio']:>5.2f} [{r['ratio_cpu']:.2f}] {r['floor']:>6.2f} "
              f"{r['setup_s'][0]:>8.3f} {r['condition_s'][0]:>7.3f}")
    print(f"setup grows as vertices^{result['setup_exponent']:.2f}")
    f = result["frame_s"]
    print(f"81x81 frame, 10 iterations, CPU: {1e3 * f[0]:.1f} ms (IQR {1e3 * f[1]:.1f}-"
          f"{1e3 * f[2]:.1f}); the paper: {1e3 * PAPER_FRAME_SECONDS_81:.0f} ms")


def main(argv: list[str] | None = None) -> None:
    argv = sys.argv[1:] if argv is None else argv
    if "--from-csv" in argv:                        # rewrite the table only, measure nothing
        rest = argv[argv.index("--from-csv") + 1:]
        source = rest[0] if rest and not rest[0].startswith("-") else CSV_PATH
        try:
            print(f"written to {write_page(source)} from {source}")
        except InputError as error:
            raise SystemExit(f"benchmarks.performance: {error}") from None
        return None
    sizes = SIZES[:-1] if "--quick" in argv else SIZES
    import sksparse.cholmod  # noqa: F401  (load CHOLMOD's OpenMP and BLAS: limited too)

    with threadpool_limits(1):                      # BLAS and OpenMP
        result = run(sizes)
    report(result)
    write_csv(result)
    write_page(CSV_PATH)
    plot(result)
    return result


if __name__ == "__main__":
    main()
