"""The paper's Fig. 1 claims, reproduced from the tool alone (``clothsim accuracy --paper``).

Liu et al. (2013), Fig. 1: a sheet held at two corners, h = 1/30 s; local/global beats
Newton's method for the first digit(s) of accuracy, Newton wins asymptotically, and 10
local/global iterations cost a fraction of one Newton iteration. :func:`paper_report` runs
the same setup (n × n instead of 81 × 81 so it finishes in minutes), on a step after
``frames`` converged steps (the sheet has fallen and buckles), and prints the time each
method needs to each error level, the crossover level and the cost ratio.

Nothing in the table depends on the machine's speed but the milliseconds: local/global's
error trace is cut at a fixed iteration count (:data:`LOCAL_GLOBAL_CAP`), not at a wall
time, and a level it has not reached there gets the count extrapolated from the trace's
tail contraction (:mod:`.extrapolate`). Its milliseconds are iterations × the median time
of one iteration (every local/global iteration does the same work: a local step and a
solve with the cached factor), timed over :data:`TIMED_ITERATIONS` iterations in each of
``repeats`` repeats, interleaved with Newton's timed traces (median per iterate).

With ``out``, the table (``paper.md``, as printed, and ``paper.csv``), the figure
(``paper.png``: error against time, both methods) and ``paper.json`` (machine, versions,
settings) are written there; each phase shows a progress bar on a terminal and log lines
otherwise (:mod:`.phases`).
"""

from __future__ import annotations

import csv
import math
import time
import warnings

import numpy as np

from ..gallery import curtain
from ..io.common import atomic_path, write_text
from ..io.outfolder import OutputFolder
from ..solvers import LocalGlobalSolver, NewtonSolver
from .extrapolate import TAIL, fit_tail
from .phases import Phases, advance
from .reference import certified_reference
from .timing import _limited_threads, machine_info
from .trace import ACCURACY_LEVELS, iterates, trace_solver

LOCAL_GLOBAL_CAP = 20_000
"""Local/global iterations traced (a count, so the table does not move with the machine)."""
TIMED_ITERATIONS = 200
"""Local/global iterations timed per repeat (their median gives ms per iteration)."""
MIN_ERROR = 1e-9


def _local_global_errors(model, problem, x_star, cap: int):
    """(iterations, errors) of local/global from y, to ``cap`` iterations or MIN_ERROR."""
    solver = LocalGlobalSolver(model, iterations=cap, check_conditioning=False)
    scale = float(np.linalg.norm(x_star - problem.x)) or 1.0
    errs = []
    for x in iterates(solver, problem):
        errs.append(float(np.linalg.norm(x - x_star)) / scale)
        advance()
        if len(errs) > cap or not math.isfinite(errs[-1]) or errs[-1] <= MIN_ERROR:
            break
    return np.arange(len(errs)), np.asarray(errs)


def _seconds_per_iteration(model, problem) -> float:
    solver = LocalGlobalSolver(model, check_conditioning=False)
    solver.system(problem)   # the cached factor: paid once per scene and h, not timed
    gen = iterates(solver, problem)
    next(gen)
    t0 = time.perf_counter()
    for _ in range(TIMED_ITERATIONS):
        next(gen)
    spent = time.perf_counter() - t0
    gen.close()
    return spent / TIMED_ITERATIONS


def paper_report(*, n: int = 41, k: float = 1000.0, frames: int = 15, repeats: int = 5,
                 cap: int = LOCAL_GLOBAL_CAP, threads: int = 1, out=None,
                 force: bool = False) -> str:
    """Crossover of local/global and Newton on the paper's Fig. 1 setup; returns the text.

    Parameters
    ----------
    n : int
        Vertices per side (the paper: 81).
    k : float
        Spring stiffness [N/m].
    frames : int
        Converged steps before the measured one.
    repeats : int
        Interleaved timing repeats (medians are reported).
    cap : int, default :data:`LOCAL_GLOBAL_CAP`
        Local/global iterations traced; levels beyond are extrapolated.
    threads : int
        BLAS threads during timing.
    out : path, optional
        Folder to write ``paper.md``, ``paper.csv``, ``paper.png`` and ``paper.json`` into
        (missing, empty or an earlier ``--paper`` output; see
        :func:`~clothsim.io.folders.claim_folder`).
    force : bool
        Write into ``out`` even when it holds other files.

    Returns
    -------
    str
        The report (plain text, Markdown tables).
    """
    if out is not None:
        with OutputFolder(out, "paper", force=force) as folder:
            folder.mark("writing", {"clothsim": machine_info(threads)["clothsim"],
                                    "paper": {"n": n}})
            return _paper(n, k, frames, repeats, cap, threads, folder)
    return _paper(n, k, frames, repeats, cap, threads, None)


def _paper(n, k, frames, repeats, cap, threads, out) -> str:
    phases = Phases()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sim = curtain(n, k=k, plane="xz", method="newton", iterations=100, tolerance=1e-10)
        with phases.phase("converged steps", frames, "step"):
            sim.run(frames, callback=lambda *_: advance())
        problem = sim.problem()
        with phases.phase("reference", 1, "step"):
            ref = certified_reference(sim.model, problem)
            advance()
        with phases.phase("local/global trace", cap + 1, "it"):
            lg_its, lg_err = _local_global_errors(sim.model, problem, ref.x, cap)
    per_it, nt_times = [], []
    nt_err = None
    with _limited_threads(threads), phases.phase("timing", repeats, "repeat"):
        for _ in range(repeats):
            per_it.append(_seconds_per_iteration(sim.model, problem))
            nt = trace_solver(NewtonSolver(sim.model), problem, ref.x, iterations=60)
            nt_times.append(nt.seconds)
            nt_err = nt.error
            advance()
    per_iteration = float(np.median(per_it))
    m = min(len(t) for t in nt_times)
    nt_sec = np.median(np.stack([t[:m] for t in nt_times]), axis=0)
    nt_err = nt_err[:m]
    a = int(round(lg_its[-1] * (1 - TAIL)))
    tail = fit_tail(lg_its[a:], lg_err[a:])
    rows = _rows(lg_err, per_iteration, nt_err, nt_sec, tail)
    text = _text(n, k, frames, ref, rows, per_iteration, nt_sec, lg_its[-1], repeats,
                 threads, tail)
    if out is not None:
        _write(out, text, rows, lg_its, lg_err, per_iteration, nt_err, nt_sec,
               dict(n=n, k=k, frames=frames, repeats=repeats, cap=cap, threads=threads,
                    seconds_per_local_global_iteration=per_iteration,
                    phase_seconds=phases.seconds))
    return text


def _rows(lg_err, per_iteration, nt_err, nt_sec, tail) -> list[dict]:
    """One dict per level: iterations and ms of each method, extrapolated or not."""
    out = []
    for level in ACCURACY_LEVELS:
        hit = np.flatnonzero(lg_err <= level)
        lg_it, extrapolated = (int(hit[0]), False) if len(hit) else (tail.count(level), True)
        nhit = np.flatnonzero(nt_err <= level)
        nt = (int(nhit[0]), float(nt_sec[nhit[0]])) if len(nhit) else (None, math.nan)
        lg_s = lg_it * per_iteration if math.isfinite(lg_it) else math.inf
        faster = ("local/global" if lg_s < (nt[1] if nt[0] is not None else math.inf)
                  else "Newton" if nt[0] is not None else "neither")
        out.append(dict(level=level, local_global_iterations=lg_it,
                        local_global_ms=1e3 * lg_s, local_global_extrapolated=extrapolated,
                        newton_iterations=nt[0], newton_ms=1e3 * nt[1], faster=faster))
    return out


def _text(n, k, frames, ref, rows, per_iteration, nt_sec, traced, repeats, threads,
          tail) -> str:
    lines = [f"# The paper's Fig. 1 setup: {n} x {n} sheet held at two corners, k = {k:g} N/m, "
             f"h = 1/30 s, step {frames + 1}",
             f"reference: Newton residual {ref.residual:.1e}, lambda_min(H)/m_min = "
             f"{ref.min_eigenvalue:.3g}, uncertainty {ref.uncertainty:.1e}"
             + (" (two minima!)" if ref.two_minima else ""), "",
             "| error | local/global: it, ms | Newton: it, ms | faster |", "|---|---|---|---|"]
    for r in rows:
        it, ms = r["local_global_iterations"], r["local_global_ms"]
        if not math.isfinite(it):
            lg = f"not reached in {traced} it (its error stops falling)"
        elif r["local_global_extrapolated"]:
            lg = (f"beyond the {traced} traced: ≈ {float(f'{it:.2g}'):.0f} it ≈ "
                  f"{ms:.2g} ms (extrapolated)")
        else:
            lg = f"{it}, {ms:.3g}"
        nt = ("not reached" if r["newton_iterations"] is None
              else f"{r['newton_iterations']}, {r['newton_ms']:.3g}")
        lines.append(f"| {r['level']:.0e} | {lg} | {nt} | {r['faster']} |")
    ahead = [r["level"] for r in rows if r["faster"] == "local/global"]
    crossover = next((r["level"] for r in rows if r["faster"] == "Newton"), None)
    newton_one = float(nt_sec[1]) if len(nt_sec) > 1 else math.nan
    lines += ["",
              (f"local/global is ahead of Newton down to error {min(ahead):.0e}" if ahead
               else "local/global is never ahead of Newton on this step"),
              (f"crossover: Newton is faster from error {crossover:.0e} on" if crossover
               else "no crossover within the measured levels"),
              f"10 local/global iterations cost {10 * per_iteration * 1e3:.3g} ms = "
              f"{10 * per_iteration / newton_one:.2f} of one Newton iteration "
              f"({newton_one * 1e3:.3g} ms, factorization included)",
              f"local/global traced for {traced} iterations (a count, not a time); its ms = "
              f"iterations x {per_iteration * 1e3:.3g} ms, the median time of one iteration "
              f"over {repeats} repeats of {TIMED_ITERATIONS}; beyond the trace, iterations "
              f"extrapolated from its tail contraction {tail.rate:.6f} per iteration "
              f"(iterations {int(round(traced * (1 - TAIL)))}–{traced})",
              f"Newton: medians of {repeats} interleaved repeats, {threads} BLAS thread(s)"]
    return "\n".join(lines)


def _write(folder: OutputFolder, text, rows, lg_its, lg_err, per_iteration, nt_err, nt_sec,
           settings) -> None:
    from .plots import plot_paper

    out = folder.path
    write_text(out / "paper.md", text + "\n")
    with atomic_path(out / "paper.csv") as tmp, tmp.open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    plot_paper(out / "paper.png", lg_its, lg_err, per_iteration, nt_err, nt_sec,
               [(r["level"], r["local_global_iterations"]) for r in rows
                if r["local_global_extrapolated"]])
    folder.mark("complete", machine_info(settings["threads"]) | {"paper": settings})
