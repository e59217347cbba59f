"""The paper's timings as ratios measured on this machine.

- 81 × 81 cloth (the paper's Fig. 1 size, 6561 vertices, h = 1/30 s): one local/global
  iteration against one Newton iteration (paper: 10 iterations = 50 ms per frame, i.e.
  5 ms per iteration, against 13 s per frame for Newton's exact solution).
- 129 × 129 and 257 × 257: one local/global iteration against the C++/Eigen float32 port
  measured elsewhere (4.9 ms and 28 ms).

Each figure is the median of several iterations on a mid-motion step of the horizontal
sheet held at two corners (the paper's setup). The factorization is done once and not timed.
"""

from __future__ import annotations

import time
import warnings

import numpy as np

from clothsim.solvers import LocalGlobalSolver, NewtonSolver

from . import curtain, report

CPP_ITERATION_SECONDS = {129: 4.9e-3, 257: 28e-3}
PAPER_ITERATION_SECONDS_81 = 50e-3 / 10
PAPER_NEWTON_FRAME_SECONDS_81 = 13.0


def iteration_seconds(n: int, *, repeats: int = 20) -> tuple[float, float, object]:
    """Median wall time of one local/global iteration at n × n, and the factor time."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sim = curtain(n, plane="xz", iterations=5)
        sim.run(3)
        problem = sim.problem()
        lg = LocalGlobalSolver(sim.model, iterations=1, check_conditioning=False)
        t0 = time.perf_counter()
        lg.system(problem)
        factor_seconds = time.perf_counter() - t0
        x = problem.initial_guess()
        times = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            d = lg.local_step(x)
            lg.gradient(problem, x, d)
            x = lg.global_step(problem, d)
            times.append(time.perf_counter() - t0)
    return float(np.median(times)), factor_seconds, (sim, problem)


def main() -> None:
    it81, f81, (sim, problem) = iteration_seconds(81)
    newton = NewtonSolver(sim.model, iterations=1, tolerance=None)
    t_newton = []
    for _ in range(3):
        t0 = time.perf_counter()
        newton.solve(problem)
        t_newton.append(time.perf_counter() - t0)
    nt = float(np.median(t_newton))
    report("81x81: one local-global iteration [ms]", it81 * 1e3, ".2f")
    report("81x81: one Newton iteration [ms]", nt * 1e3, ".1f")
    report("81x81: Newton iteration / local-global iteration (wall-time ratio)", nt / it81)
    report("81x81: local-global iteration / paper's 5 ms (ratio)",
           it81 / PAPER_ITERATION_SECONDS_81)
    report("81x81: 10 iterations / one Newton iteration (paper: 50 ms vs 13 s per frame)",
           10 * it81 / nt)
    report("81x81: factorization / one iteration (ratio)", f81 / it81)
    for n, cpp in CPP_ITERATION_SECONDS.items():
        it, fs, _ = iteration_seconds(n, repeats=10)
        report(f"{n}x{n}: one local-global iteration [ms]", it * 1e3, ".1f")
        report(f"{n}x{n}: clothsim / C++ port iteration time ratio (C++ {cpp * 1e3:g} ms)",
               it / cpp)
        report(f"{n}x{n}: factorization [s]", fs, ".2f")
