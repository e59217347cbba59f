"""Accelerated solvers against local/global, and the paper's crossover (interleaved repeats).

Two step problems at 41 × 41 (1681 vertices), each after a converged run:

- the paper's sheet held at two corners (horizontal, k = 1000 N/m, h = 1/30 s) after it has
  fallen and buckles: time to relative error 1e-3, local/global against chebyshev,
  anderson, lbfgs (the acceptance asks for ≥ 10× each);
- a stretched vertical curtain (k = 800 N/m) mid-swing: time to 1e-6 (≥ 4× for the best).

Each method's trace is repeated ``REPEATS`` times, interleaved (method A, B, C, D, then
again), and the median time is used; BLAS is limited to one thread; the cached factor and
Chebyshev's ρ are computed before timing (one-off costs, printed apart). Then the
``clothsim accuracy --paper`` report. Run: ``python -m benchmarks accuracy_bench``
(``python -m benchmarks.accuracy_bench --no-paper``: the two steps only, about a minute).
"""

from __future__ import annotations

import time
import warnings

import numpy as np

from clothsim import gallery
from clothsim.accuracy import certified_reference, paper_report, trace_solver
from clothsim.accuracy.timing import _limited_threads
from clothsim.solvers import estimate_spectral_radius, make_solver

N = 41
REPEATS = 5
METHODS = ("local-global", "chebyshev", "anderson", "lbfgs")


def _step(plane: str, k: float, frames: int):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sim = gallery.curtain(N, k=k, plane=plane, method="newton", iterations=100,
                              tolerance=1e-10)
        sim.run(frames)
    return sim.model, sim.problem()


def time_to(model, problem, level: float, *, max_seconds: float = 120.0) -> dict:
    """Median seconds (and iterations) of each method to relative error ``level``.

    A trace is cut at ``max_seconds``; a median beyond it is inf, and the printed speed-ups
    against it are lower bounds (marked ">").
    """
    ref = certified_reference(model, problem, second_start=False)
    t0 = time.perf_counter()
    rho = estimate_spectral_radius(model, problem)
    rho_s = time.perf_counter() - t0
    seconds = {m: [] for m in METHODS}
    iterations = {}
    with _limited_threads(1):
        for _ in range(REPEATS):
            for m in METHODS:
                opts = {"rho": rho} if m == "chebyshev" else {}
                solver = make_solver(m, model, **opts)
                solver.system(problem)  # the cached factor: one-off, not timed
                tr = trace_solver(solver, problem, ref.x, iterations=10 ** 6,
                                  max_seconds=max_seconds, min_error=level)
                hit = tr.first_below(level)
                seconds[m].append(np.inf if hit is None else hit[1])
                iterations[m] = None if hit is None else hit[0]
    med = {m: float(np.median(v)) for m, v in seconds.items()}
    return {"median": med, "iterations": iterations, "rho": rho, "rho_seconds": rho_s,
            "max_seconds": max_seconds,
            "min_eigenvalue": ref.min_eigenvalue}


def _print(title: str, level: float, res: dict) -> None:
    base = res["median"]["local-global"]
    capped = not np.isfinite(base)
    if capped:  # local/global did not get there within the cap: speed-ups are lower bounds
        base = res["max_seconds"]
    print(f"{title}: time to relative error {level:g} (median of {REPEATS} interleaved "
          f"repeats, 1 BLAS thread); rho = {res['rho']:.5f} (estimated in "
          f"{res['rho_seconds']:.2f} s, one-off), lambda_min(H)/m_min = "
          f"{res['min_eigenvalue']:.3g}")
    for m in METHODS:
        t, it = res["median"][m], res["iterations"][m]
        bound = ">" if capped and m != "local-global" else " "
        print(f"  {m:13s} {it!s:>6} it  {t * 1e3:9.1f} ms   speed-up {bound}x{base / t:6.1f}")


def main(paper: bool = True) -> None:
    """Print both steps' tables, then (``paper``) the ``--paper`` report."""
    from .iteration_cost import commit

    print(f"accelerated methods against local/global, commit {commit()}")
    model, problem = _step("xz", 1000.0, 15)
    _print(f"buckling sheet {N}x{N} (held at two corners)", 1e-3,
           time_to(model, problem, 1e-3))
    model, problem = _step("xy", 800.0, 8)
    _print(f"stretched curtain {N}x{N}", 1e-6, time_to(model, problem, 1e-6))
    if paper:
        print(paper_report(n=N, repeats=3))


if __name__ == "__main__":
    import sys

    main(paper="--no-paper" not in sys.argv[1:])
