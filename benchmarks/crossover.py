"""The paper's comparison, error against iterations and against wall time, on one step.

Two steps WITH REAL MOTION (‖∇g(y)‖ many orders above its rounding floor
``gradient_noise_floor``, so every digit of error down to 1e-8 is resolved):

- **curtain** (documented crossover): 41 × 41 curtain (1 kg, 1 m, k = 3000 N/m structural
  and shear, 300 N/m bending) hanging from its two top corners, h = 1/30 s, the first step
  after release from its flat rest shape: gravity pulls every free vertex, the springs
  are stretched, not compressed.
- **falling sheet**: 21 × 21 horizontal sheet held at two corners (the paper's Fig. 1
  setup), the 4th step after release: it buckles, compressed springs make E non-convex,
  and local/global converges sublinearly there.

Methods: local/global (the paper), Chebyshev-accelerated local/global (Wang 2015, ρ
estimated on this step), Newton (exact Hessian when definite, line search). x* = Newton to
1e-12. Each method is traced ``REPEATS`` times and the fastest time to each iterate is
kept (the machine is shared).

Printed: wall time of each method to reach each relative error 1e-1 … 1e-8, the ratios
that state the crossover, and the Chebyshev/local-global ratio at 1e-6. Writes
docs/img/solver_accuracy.png and docs/img/solver_accuracy_buckling.png.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from clothsim.accuracy import (
    ACCURACY_LEVELS,
    converged_solution,
    plot_solver_accuracy,
    solver_accuracy,
)
from clothsim.solvers import estimate_spectral_radius, objective_gradient
from clothsim.solvers.base import gradient_noise_floor

from . import DOCS_IMG, curtain, report

STIFFNESS = 3000.0
REPEATS = 3
SCENES = {  # name: (grid, plane, steps before the measured one, traced iterations)
    "curtain": (41, "xy", 0, 400),
    "falling sheet": (21, "xz", 3, 3000),
}


def run(name: str, *, newton_iterations: int = 40, repeats: int = REPEATS):
    """Trace the three methods on the scene's step; returns (sim, problem, traces, rho)."""
    n, plane, warmup, iterations = SCENES[name]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sim = curtain(n, stiffness=STIFFNESS, bending=STIFFNESS / 10, plane=plane,
                      method="newton", iterations=50, tolerance=1e-12)
        sim.run(warmup)
        problem = sim.problem()
        x_star = converged_solution(sim.model, problem)
        rho = estimate_spectral_radius(sim.model, problem, iterations=200, fit_last=50)
        best = None
        for _ in range(repeats):
            traces = solver_accuracy(sim.model, problem, iterations=iterations,
                                     newton_iterations=newton_iterations, x_star=x_star,
                                     max_seconds=20.0,
                                     solver_options={"chebyshev": {"rho": rho}})
            if best is None:
                best = traces
            else:
                for m, tr in traces.items():
                    k = min(len(tr.seconds), len(best[m].seconds))
                    best[m].seconds[:k] = np.minimum(best[m].seconds[:k], tr.seconds[:k])
    return sim, problem, best, rho


def _times(traces) -> dict:
    out = {}
    for level in ACCURACY_LEVELS:
        for name, tr in traces.items():
            hit = tr.first_below(level)
            out[name, level] = hit[1] if hit else math.inf
    return out


def main() -> None:
    for name, (n, _plane, warmup, _) in SCENES.items():
        sim, problem, traces, rho = run(name)
        g0 = float(np.linalg.norm(objective_gradient(sim.model, problem,
                                                     problem.initial_guess())))
        floor = gradient_noise_floor(sim.model, problem, problem.initial_guess())
        x_star_move = float(np.linalg.norm(converged_solution(sim.model, problem) - problem.x))
        print(f"  == {name}: {n}x{n}, k={STIFFNESS:g} N/m, step {warmup + 1}, h=1/30 s, "
              f"estimated rho={rho:.4f}")
        report(f"{name}: |grad g(y)| / rounding floor", g0 / floor, ".2e")
        report(f"{name}: |x* - x_n| [m]", x_star_move, ".3g")
        for level in ACCURACY_LEVELS:
            row = []
            for m, tr in traces.items():
                hit = tr.first_below(level)
                row.append(f"{m} {hit[1] * 1e3:.1f} ms ({hit[0]} it)" if hit
                           else f"{m} not reached")
            print(f"  error {level:.0e}: " + "; ".join(row))
        for m, tr in traces.items():
            print(f"  {m}: final error {tr.error[-1]:.2e} after {tr.iterations[-1]} it, "
                  f"{tr.seconds[-1] * 1e3:.0f} ms")
        times = _times(traces)
        for level in ACCURACY_LEVELS:
            best = min(traces, key=lambda m: times[m, level])
            if math.isfinite(times[best, level]):
                report(f"{name}: local-global/newton wall-time ratio to {level:.0e} "
                       f"(fastest: {best})", times["local-global", level]
                       / times["newton", level])
        report(f"{name}: chebyshev/local-global wall-time ratio to 1e-6",
               times["chebyshev", 1e-6] / times["local-global", 1e-6])
        lg, nw = traces["local-global"], traces["newton"]
        report(f"{name}: one Newton iteration / one local-global iteration (wall time)",
               nw.seconds[1] / (lg.seconds[-1] / lg.iterations[-1]))
        DOCS_IMG.mkdir(parents=True, exist_ok=True)
        path = DOCS_IMG / ("solver_accuracy.png" if name == "curtain"
                           else "solver_accuracy_buckling.png")
        plot_solver_accuracy(traces, path, title=f"{n}×{n} {name}, step {warmup + 1} after "
                             f"release, h = 1/30 s, k = {STIFFNESS:g} N/m")
        print(f"  wrote {path}")
