"""The paper's comparison, error against iterations and against wall time, on one step.

Scene: a 41 × 41 curtain (1 kg, 1 m, k = 3000 N/m structural and shear, 300 N/m bending)
hanging from its two top corners, h = 1/30 s; the step measured is the 21st (mid-swing).
Methods: local/global (the paper), Chebyshev-accelerated local/global (Wang 2015, ρ
estimated on this step), Newton (exact Hessian, line search). x* = Newton to 1e-12.

Printed: wall time of each method to reach each relative error 1e-1 … 1e-8, the ratios
that state the crossover, and the Chebyshev/local-global ratio at 1e-6. Writes
docs/img/solver_accuracy.png.
"""

from __future__ import annotations

import math
import warnings

from clothsim.accuracy import (ACCURACY_LEVELS, converged_solution, plot_solver_accuracy,
                               solver_accuracy)
from clothsim.solvers import estimate_spectral_radius

from . import DOCS_IMG, curtain, report

GRID = 41
STIFFNESS = 3000.0
WARMUP_STEPS = 20


def run(n: int = GRID, *, iterations: int = 3000, newton_iterations: int = 30):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sim = curtain(n, stiffness=STIFFNESS, bending=STIFFNESS / 10, method="newton",
                      iterations=50, tolerance=1e-12)
        sim.run(WARMUP_STEPS)
        problem = sim.problem()
        x_star = converged_solution(sim.model, problem)
        rho = estimate_spectral_radius(sim.model, problem, iterations=200, fit_last=50)
        traces = solver_accuracy(sim.model, problem, iterations=iterations,
                                 newton_iterations=newton_iterations, x_star=x_star,
                                 max_seconds=30.0, solver_options={"chebyshev": {"rho": rho}})
    return sim, traces, rho


def main() -> None:
    sim, traces, rho = run()
    print(f"  scene: {GRID}x{GRID} curtain, k={STIFFNESS:g} N/m, step {WARMUP_STEPS + 1}, "
          f"h=1/30 s, estimated rho={rho:.4f}")
    times = {}
    for level in ACCURACY_LEVELS:
        row = []
        for name, tr in traces.items():
            hit = tr.first_below(level)
            times[name, level] = hit[1] if hit else math.inf
            row.append(f"{name} {hit[1] * 1e3:.1f} ms ({hit[0]} it)" if hit
                       else f"{name} not reached")
        print(f"  error {level:.0e}: " + "; ".join(row))
    for level in ACCURACY_LEVELS:
        best = min(traces, key=lambda m: times[m, level])
        report(f"local-global/newton wall-time ratio to {level:.0e} (fastest: {best})",
               times["local-global", level] / times["newton", level])
    report("chebyshev/local-global wall-time ratio to 1e-6",
           times["chebyshev", 1e-6] / times["local-global", 1e-6])
    lg, nw = traces["local-global"], traces["newton"]
    report("one Newton iteration / one local-global iteration (wall time)",
           (nw.seconds[1] / 1) / (lg.seconds[-1] / lg.iterations[-1]))
    DOCS_IMG.mkdir(parents=True, exist_ok=True)
    plot_solver_accuracy(traces, DOCS_IMG / "solver_accuracy.png",
                         title=f"{GRID}×{GRID} curtain, one step at h = 1/30 s")
    print(f"  wrote {DOCS_IMG / 'solver_accuracy.png'}")
