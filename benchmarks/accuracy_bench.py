"""Accelerated solvers against local/global, Chebyshev's ρ sensitivity, the paper's crossover.

Two step problems at 41 × 41 (1681 vertices), each after a converged run (:func:`step`):

- ``buckling``: the paper's sheet held at two corners (horizontal, k = 1000 N/m,
  h = 1/30 s) after it has fallen and buckles: time to relative error 1e-3, local/global
  against chebyshev, anderson, lbfgs (issue 20 asks for ≥ 10× from the best);
- ``curtain``: a stretched vertical curtain (k = 800 N/m) mid-swing: time to 1e-6 (≥ 4×).

Each method's trace is repeated ``REPEATS`` times, interleaved (method A, B, C, D, then
again), and the median time is used; BLAS is limited to one thread; the cached factor and
Chebyshev's ρ are computed before timing (one-off costs, printed apart). Then Chebyshev's
iterations on the buckling step with ρ scaled around its estimate, and the
``clothsim accuracy --paper`` report on the same step.

Run ``python -m benchmarks accuracy_bench``. It prints everything with the commit and
writes what the docs show to ``docs/data/``: ``accelerated.md`` (the two steps),
``rho-sensitivity.md`` and ``paper.md``. The iteration counts in them are
hardware-independent; ``tests/test_documented_counts.py`` recomputes every one with
:func:`iteration_counts`, :func:`rho_sensitivity` and :func:`paper_counts` and fails when
one no longer reproduces (then re-run this benchmark).
``python -m benchmarks.accuracy_bench --no-paper`` stops after the two steps and the ρ table
(about a minute; ``paper.md`` is left as it was).
"""

from __future__ import annotations

import time
import warnings
from pathlib import Path

import numpy as np

from clothsim import gallery
from clothsim.accuracy import certified_reference, paper_report, trace_solver
from clothsim.accuracy.timing import _limited_threads
from clothsim.solvers import NewtonSolver, estimate_spectral_radius, make_solver

N = 41
REPEATS = 5
PAPER_REPEATS = 3
METHODS = ("local-global", "chebyshev", "anderson", "lbfgs")
#: (plane, stiffness [N/m], converged frames before the step, target relative error)
STEPS = {"buckling": ("xz", 1000.0, 15, 1e-3), "curtain": ("xy", 800.0, 8, 1e-6)}
TITLES = {"buckling": f"buckling sheet {N}x{N} (held at two corners)",
          "curtain": f"stretched curtain {N}x{N}"}
#: multiples of the estimated ρ in the sensitivity table
RHO_FACTORS = (0.90, 0.95, 0.98, 1.0, 1.01, 1.02, 1.05)
DATA = Path(__file__).resolve().parents[1] / "docs" / "data"


def step(name: str, n: int = N):
    """The model and step problem of :data:`STEPS` ``name``, after its converged run.

    Parameters
    ----------
    name : {"buckling", "curtain"}
        Which step.
    n : int
        Vertices per side.

    Returns
    -------
    (Model, StepProblem)
    """
    plane, k, frames, _ = STEPS[name]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sim = gallery.curtain(n, k=k, plane=plane, method="newton", iterations=100,
                              tolerance=1e-10)
        sim.run(frames)
    return sim.model, sim.problem()


def _firsts(solver, problem, x_ref, levels, *, iterations=10 ** 6) -> dict:
    """level → the first k whose iterate is within ``level`` of x_ref (None: not within
    ``iterations``), counted as :meth:`IterateTrace.first_below` counts, in one pass and
    without the trace's timing and objective."""
    scale = float(np.linalg.norm(x_ref - problem.x)) or 1.0
    out = dict.fromkeys(levels)
    left = sorted(levels, reverse=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        for k, it in zip(range(iterations + 1), solver.iterates(problem)):
            err = float(np.linalg.norm(it.x - x_ref)) / scale
            if not np.isfinite(err):
                break
            while left and err <= left[0]:
                out[left.pop(0)] = k
            if not left:
                break
    return out


def _first(solver, problem, x_ref, level, *, iterations=10 ** 6):
    k = _firsts(solver, problem, x_ref, [level], iterations=iterations)[level]
    return None if k is None else (k, None)


def iteration_counts(model, problem, x_ref, level: float, rho: float,
                     methods=METHODS) -> dict:
    """Iterations each of :data:`METHODS` needs to relative error ``level`` (no timing).

    Parameters
    ----------
    model, problem
        The step (:func:`step`).
    x_ref : ndarray, shape (n, 3)
        The certified reference [m].
    level : float
        Relative error ‖x − x*‖ / ‖x* − x_n‖ to reach.
    rho : float
        Chebyshev's ρ.
    methods : sequence of str
        Which of :data:`METHODS`.

    Returns
    -------
    dict
        method → iterations, or None when not reached within 10⁶ iterations.
    """
    out = {}
    for m in methods:
        opts = {"rho": rho} if m == "chebyshev" else {}
        hit = _first(make_solver(m, model, **opts), problem, x_ref, level)
        out[m] = None if hit is None else hit[0]
    return out


def rho_sensitivity(model, problem, x_ref, level: float, rho: float,
                    factors=RHO_FACTORS) -> list[tuple[float, float, int | None]]:
    """Chebyshev's iterations to ``level`` with ρ scaled by each factor.

    Parameters
    ----------
    model, problem, x_ref, level
        As :func:`iteration_counts`.
    rho : float
        The estimated ρ.
    factors : sequence of float
        Multiples of ``rho`` (the product is capped at 0.9999).

    Returns
    -------
    list of (float, float, int or None)
        (factor, ρ used, iterations or None when not reached).
    """
    out = []
    for f in factors:
        used = min(rho * f, 0.9999)
        hit = _first(make_solver("chebyshev", model, rho=used), problem, x_ref, level)
        out.append((f, used, None if hit is None else hit[0]))
    return out


def paper_counts(model, problem, x_ref, levels, *, local_global_cap: int) -> dict:
    """Iterations of local/global and Newton to each level of the paper's table.

    Parameters
    ----------
    model, problem, x_ref
        The buckling step (:func:`step`) and its reference.
    levels : sequence of float
        Relative errors.
    local_global_cap : int
        Local/global iterations to trace at most.

    Returns
    -------
    dict
        ``{"local-global": {level: it or None}, "newton": {level: it or None}}``.
    """
    out = {}
    for name, solver, cap in (
            ("local-global", make_solver("local-global", model, check_conditioning=False),
             local_global_cap),
            ("newton", NewtonSolver(model), 60)):
        out[name] = _firsts(solver, problem, x_ref, levels, iterations=cap)
    return out


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
            "max_seconds": max_seconds, "reference": ref,
            "min_eigenvalue": ref.min_eigenvalue}


def _lines(title: str, level: float, res: dict) -> list[str]:
    base = res["median"]["local-global"]
    capped = not np.isfinite(base)
    if capped:  # local/global did not get there within the cap: speed-ups are lower bounds
        base = res["max_seconds"]
    ref = res["reference"]
    out = [f"{title}: time to relative error {level:g} (median of {REPEATS} interleaved "
           f"repeats, 1 BLAS thread); rho = {res['rho']:.5f} (estimated in "
           f"{res['rho_seconds']:.2f} s, one-off); reference "
           f"{'certified minimum' if ref.certified else 'NOT certified'}, "
           f"lambda_min(H)/m_min = {res['min_eigenvalue']:.3g}"]
    for m in METHODS:
        t, it = res["median"][m], res["iterations"][m]
        bound = ">" if capped and m != "local-global" else " "
        out.append(f"  {m:13s} {it!s:>6} it  {t * 1e3:9.1f} ms   speed-up {bound}x"
                   f"{base / t:6.1f}")
    return out


def _write(name: str, header: str, body: str) -> None:
    DATA.mkdir(parents=True, exist_ok=True)
    (DATA / name).write_text(f"{header}\n\n{body}\n", encoding="utf-8")


def main(paper: bool = True) -> None:
    """Print and write both steps' tables and the ρ table, then (``paper``) the paper's."""
    from .iteration_cost import commit

    head = commit()
    lines = [f"accelerated methods against local/global, commit {head}"]
    results = {}
    for name, (_, _, _, level) in STEPS.items():
        model, problem = step(name)
        res = time_to(model, problem, level)
        results[name] = (model, problem, res)
        lines += _lines(TITLES[name], level, res)
    print("\n".join(lines), flush=True)
    _write("accelerated.md", f"Printed by `.venv/bin/python -m benchmarks accuracy_bench` at "
           f"commit {head} (iteration counts are checked by tests/test_documented_counts.py):",
           "```text\n" + "\n".join(lines) + "\n```")

    model, problem, res = results["buckling"]
    level = STEPS["buckling"][3]
    rows = rho_sensitivity(model, problem, res["reference"].x, level, res["rho"])
    table = ["| rho used | " + " | ".join(
        (f"**{u:.4f}**" if f == 1.0 else f"{u:.4f} (×{f:.2f})") for f, u, _ in rows) + " |",
             "|---|" + "---|" * len(rows),
             "| iterations | " + " | ".join(
                 ("not reached" if it is None else (f"**{it}**" if f == 1.0 else str(it)))
                 for f, _, it in rows) + " |"]
    print("\n".join(table), flush=True)
    _write("rho-sensitivity.md",
           f"Chebyshev on the {TITLES['buckling']} step, iterations to relative error "
           f"{level:g} (local/global: {res['iterations']['local-global']}; estimated "
           f"rho = {res['rho']:.4f}); printed by `.venv/bin/python -m benchmarks "
           f"accuracy_bench` at commit {head}:", "\n".join(table))

    if not paper:
        return
    paper = paper_report(n=N, repeats=PAPER_REPEATS)
    print(paper, flush=True)
    _write("paper.md", f"Printed by `.venv/bin/python -m benchmarks accuracy_bench` at commit "
           f"{head}, as `.venv/bin/clothsim accuracy --paper --paper-size {N} --repeats "
           f"{PAPER_REPEATS}` prints it (timings from a shared machine: read the ratios; "
           f"iteration counts are checked by tests/test_documented_counts.py):",
           "```text\n" + paper + "\n```")


if __name__ == "__main__":
    import sys

    main(paper="--no-paper" not in sys.argv[1:])
