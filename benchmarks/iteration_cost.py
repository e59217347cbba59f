"""Per-iteration cost of the accelerated solvers against local/global (interleaved ratios).

Run ``python -m benchmarks iteration_cost``. On the performance benchmark's cloth (n × n,
held at two corners, mid-fall after 10 steps; :func:`benchmarks.performance.falling_sheet`)
at 21² and 41², each method runs ``ITERATIONS`` iterations of its ``iterates`` on the same
step problem, with the factor (and Chebyshev's ρ) computed before timing. The methods are
interleaved in every repeat (order rotated), each repeat gives a ratio to the local/global
run of the same repeat, and the median ratio over ``REPEATS`` is printed, of wall time and
(in brackets) of CPU time (``time.process_time``: less moved by other jobs on a shared
machine); every thread pool is limited to one thread (threadpoolctl). Targets (issue 20):
Chebyshev ≤ 1.15, Anderson and L-BFGS ≤ 2. A last line gives each method's extra
microseconds per iteration over local/global's at :data:`TINY`² too, where every array is
tiny: the share of the extra that is the NumPy and Python calls' fixed cost.
"""

from __future__ import annotations

import subprocess
import time
import warnings
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from clothsim.solvers import estimate_spectral_radius, make_solver

from . import ROOT
from .performance import falling_sheet

SIZES = (21, 41)
TINY = 5
"""A cloth so small that an iteration's cost is its calls' fixed cost, not arithmetic."""
ITERATIONS = 100
REPEATS = 21
METHODS = ("local-global", "chebyshev", "anderson", "lbfgs")


def commit() -> str:
    """The repository's commit (short hash, ``+dirty`` when tracked files have changes)."""
    try:
        head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                              capture_output=True, text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"],
                               cwd=ROOT, capture_output=True, text=True).stdout.strip()
        return head + ("+dirty" if dirty else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def per_iteration(solver, problem, iterations: int = ITERATIONS) -> tuple[float, float]:
    """Wall and CPU seconds per iteration of ``solver.iterates`` over ``iterations``."""
    t0, c0 = time.perf_counter(), time.process_time()
    k = 0
    for it in solver.iterates(problem):
        k = it.k
        if k >= iterations:
            break
    c1, t1 = time.process_time(), time.perf_counter()
    return (t1 - t0) / max(k, 1), (c1 - c0) / max(k, 1)


def measure(n: int, repeats: int = REPEATS) -> dict:
    """Median per-iteration ratios to local/global (and local/global's own time) at n × n."""
    sim = falling_sheet(n)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sim.run(10)
    problem, model = sim.problem(), sim.model
    rho = estimate_spectral_radius(model, problem)
    solvers = {m: make_solver(m, model, **({"rho": rho} if m == "chebyshev" else {}))
               for m in METHODS}
    for s in solvers.values():
        per_iteration(s, problem, 5)               # factor, buffers, caches: not timed
    times = {m: [] for m in METHODS}
    for r in range(repeats):
        order = METHODS[r % len(METHODS):] + METHODS[:r % len(METHODS)]
        for m in order:
            times[m].append(per_iteration(solvers[m], problem))
    t = {m: np.array(v) for m, v in times.items()}     # (repeats, 2): wall, CPU
    base = t["local-global"]
    return {"n": n, "rho": rho, "local-global_s": float(np.median(base[:, 0])),
            "ratios": {m: float(np.median(t[m][:, 0] / base[:, 0])) for m in METHODS},
            "cpu_ratios": {m: float(np.median(t[m][:, 1] / base[:, 1])) for m in METHODS}}


TARGETS = {"chebyshev": 1.15, "anderson": 2.0, "lbfgs": 2.0}
"""Issue 20's per-iteration targets (ratio to local/global)."""
OUT = ROOT / "docs" / "data" / "iteration-cost.md"


def main() -> list[dict]:
    import sksparse.cholmod  # noqa: F401  (load CHOLMOD's OpenMP and BLAS: limited too)

    load = Path("/proc/loadavg").read_text().split()[0] if Path("/proc/loadavg").exists() \
        else "unknown"
    head = (f"per-iteration cost / local/global's, wall [CPU] (median of {REPEATS} "
            f"interleaved repeats of {ITERATIONS} iterations, 1 thread), commit {commit()}, "
            f"load average {load} at the start")
    print(head)
    lines, verdicts, results = [head], [], []
    with threadpool_limits(1):
        for n in SIZES:
            res = measure(n)
            results.append(res)
            ratios = "  ".join(f"{m} {res['ratios'][m]:.2f} [{res['cpu_ratios'][m]:.2f}]"
                               for m in METHODS[1:])
            line = (f"  {n}x{n}: local/global {1e6 * res['local-global_s']:.0f} us/iteration; "
                    f"{ratios}")
            print(line, flush=True)
            lines.append(line)
            for m, target in TARGETS.items():
                wall = res["ratios"][m]
                verdicts.append(f"  {n}x{n} {m} <= {target:g}: "
                                f"{'met' if wall <= target else 'missed'} ({wall:.2f})")
        tiny = measure(TINY)   # every array tiny: what is left is the calls' fixed cost
    extra = "; ".join(f"{r['n']}x{r['n']}: " + ", ".join(
        f"{m} +{1e6 * (r['ratios'][m] - 1.0) * r['local-global_s']:.0f}" for m in TARGETS)
        for r in (tiny, *results))
    line = f"extra us/iteration over local/global ({TINY}x{TINY}: fixed per-call cost) -- {extra}"
    print(line)
    lines += [line, "targets (issue 20), on the wall-time ratio:", *verdicts]
    for v in verdicts:
        print(v)
    OUT.write_text("Printed by `.venv/bin/python -m benchmarks iteration_cost`:\n\n```text\n"
                   + "\n".join(lines) + "\n```\n", encoding="utf-8")
    print(f"   written to {OUT.relative_to(ROOT)}")
    return results


if __name__ == "__main__":
    main()
