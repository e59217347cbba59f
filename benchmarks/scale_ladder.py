"""Large cloths: the scale ladder 129², 257², 513², 1025² (issue 23's figures).

``python -m benchmarks.scale_ladder [--sizes 129,257,513,1025] [--run-sizes 513]`` measures
(``python -m benchmarks scale_ladder`` runs it with these defaults),
each size in a fresh process (so the peak resident set is that size's alone), with BLAS
and OpenMP on one thread (as the solver runs them: CHOLMOD's factorization of 100 000 rows
or more on two, :func:`clothsim.factorization.cholmod_threads`):

- through the API (the ``hanging`` cloth at that resolution: two pinned corners, gravity):
  setup (model and simulation), the factorization (the mode clothsim chose, and why), the
  first step (factor + 10 iterations), the median of the next 3 steps, peak RSS, bytes per
  vertex;
- through ``clothsim run`` (``--run-sizes``, 5 frames): wall and CPU time (user + system:
  on a busy machine the wall time counts the other processes too; the picture process
  of a large cloth, :mod:`clothsim.pictures`, is counted), and the pictures' share
  (``preview.gif`` + ``final.png``, from a second run with ``--no-preview``), and the
  time of each phase of a third run (:mod:`benchmarks.run_phases`).

It prints a Markdown table with the commit and writes it to ``docs/data/scale-ladder.md``,
which docs/performance.md includes.

``--mode-sizes 65,129,193,257,385,513`` measures instead CHOLMOD's two modes on the same
matrices (M + h²L over the free vertices, each size in a fresh process, one thread, the
large factorizations too: the cost model is of one thread's CPU seconds): the
fastest of 3 factorizations and of 15 three-column solves (the modes interleaved), in CPU
seconds (so that other processes on the machine count less), fits each as a power law
t = c · n^p of the free vertices n, and writes the table, the fits and the mode that cost
model chooses at each size for a few solve counts and for an unknown count (the ski-rental
rule of :mod:`clothsim.factor_mode`) to ``docs/data/cholmod-modes.md``. The
constants of :data:`clothsim.factor_mode.MODE_COSTS` are that file's fits.
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from . import run_phases

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "docs" / "data" / "scale-ladder.md"
MODES_OUT = ROOT / "docs" / "data" / "cholmod-modes.md"
MIB = 1024 ** 2

CHILD = r"""
import json, resource, sys, time
import numpy as np
import clothsim as cs
from clothsim.factorization import single_threaded
n = int(sys.argv[1])
t0 = time.perf_counter()
scene = cs.load_scene("hanging", [f"cloth.resolution=[{n}, {n}]"])
sim = scene.build_simulation()
setup = time.perf_counter() - t0
with single_threaded():
    t0 = time.perf_counter()
    sim.solver.system(sim.problem())
    factor = time.perf_counter() - t0
    sim.solver.invalidate()
    t0 = time.perf_counter()
    sim.step()
    first = time.perf_counter() - t0
    steps = []
    for _ in range(3):
        t0 = time.perf_counter()
        sim.step()
        steps.append(time.perf_counter() - t0)
rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
import os, tempfile
from clothsim.io.frames import FrameWriter
write = {}
with tempfile.TemporaryDirectory() as tmp:   # one frame as `clothsim run` writes it
    for comp in ("zlib", "none"):
        fw = FrameWriter(os.path.join(tmp, comp), sim.model.mesh, springs=sim.model.springs,
                         pinned=np.zeros(sim.model.vertex_count, bool), compression=comp)
        t0 = time.process_time()   # CPU: the disk's own time is not counted
        path = fw.write(0, 0.0, sim.state.positions, sim.state.velocities)
        write[comp] = [time.process_time() - t0, os.path.getsize(path)]
print(json.dumps({"n": n, "vertices": sim.model.vertex_count, "setup": setup,
                  "factor": factor, "first": first, "step": float(np.median(steps)),
                  "rss": rss, "mode": sim.solver.factorization, "write": write}))
"""


MODES_CHILD = r"""
import json, sys, time
import numpy as np
import clothsim as cs
from clothsim import matrices
from clothsim import factorization
from clothsim.factorization import Factor, single_threaded
factorization.CHOLMOD_THREADS = {"factor": 1, "solve": 1}   # the cost model: one thread
n = int(sys.argv[1])
sim = cs.load_scene("hanging", [f"cloth.resolution=[{n}, {n}]"]).build_simulation()
problem = sim.problem()
A = matrices.system_matrix(sim.model, problem.h, anchor_vertices=problem.anchor_vertices,
                           anchor_stiffness=problem.anchor_stiffness).tocsr()
free = np.flatnonzero(problem.free_mask(sim.model.vertex_count))
A_FF = A[free][:, free]
bT = np.random.default_rng(0).standard_normal((3, len(free)))
out = {"n": n, "free": len(free)}
with single_threaded():
    factors, times = {}, {"simplicial": [], "supernodal": []}
    for _ in range(3):   # interleaved, the fastest of 3: a factorization is one long sample
        for mode in times:
            t0 = time.process_time()
            factors[mode] = Factor(A_FF, backend="cholmod", check_conditioning=False,
                                   cholmod_mode=mode)
            times[mode].append(time.process_time() - t0)
    for mode in times:
        out[mode + "_factor"] = min(times[mode])
    solves = {mode: [] for mode in factors}
    for _ in range(15):   # interleaved: both modes see the same machine
        for mode, f in factors.items():
            t0 = time.process_time()
            f.solve_columns(bT)
            solves[mode].append(time.process_time() - t0)
    for mode in factors:
        out[mode + "_solve"] = min(solves[mode])
print(json.dumps(out))
"""


def modes(n: int) -> dict:
    out = subprocess.run([sys.executable, "-c", MODES_CHILD, str(n)], check=True,
                         capture_output=True, text=True, cwd=ROOT)
    return json.loads(out.stdout.strip().splitlines()[-1])


def fit(ns, ts) -> tuple[float, float]:
    """(c, p) of the least-squares line log t = log c + p log n."""
    p, logc = np.polyfit(np.log(ns), np.log(ts), 1)
    return float(np.exp(logc)), float(p)


def mode_table(sizes: list[int]) -> list[str]:
    """Measure both CHOLMOD modes at each size; the table, the fits and the choices."""
    from clothsim.factor_mode import choose_cholmod_mode
    lines = [f"Measured by `python -m benchmarks.scale_ladder --mode-sizes "
             f"{','.join(map(str, sizes))}` at commit {commit()} (CPU seconds, one "
             f"BLAS/OpenMP thread; load average {Path('/proc/loadavg').read_text().split()[0]} "
             f"at the start; each factorization the fastest of 3, each solve of 15, three "
             f"right-hand sides).", "",
             "| grid | free vertices | simplicial factor | simplicial solve | "
             "supernodal factor | supernodal solve |", "|---|---|---|---|---|---|"]
    rows = []
    for n in sizes:
        r = modes(n)
        rows.append(r)
        lines.append(f"| {n}² | {r['free']:,} | {r['simplicial_factor']:.3f} s | "
                     f"{1e3 * r['simplicial_solve']:.2f} ms | {r['supernodal_factor']:.3f} s | "
                     f"{1e3 * r['supernodal_solve']:.2f} ms |")
        print(lines[-1], flush=True)
    ns = [r["free"] for r in rows]
    lines += ["", "Fits t = c · n^p over the free vertices n (the constants of "
              "`clothsim.factor_mode.MODE_COSTS`):", "",
              "| quantity | c [s] | p |", "|---|---|---|"]
    costs = {}
    for mode in ("simplicial", "supernodal"):
        pair = []
        for what in ("factor", "solve"):
            c, p = fit(ns, [r[f"{mode}_{what}"] for r in rows])
            pair.append((float(f"{c:.3e}"), float(f"{p:.3f}")))
            lines.append(f"| {mode} {what} | {c:.3e} | {p:.3f} |")
        costs[mode] = tuple(pair)
    lines += ["", "The mode `choose_cholmod_mode` picks with these fits, by the run's expected "
              "solves (factor + solves, predicted), and for an unknown count (the ski-rental "
              "rule: the mode cheaper to factor, then the faster solves after as many solves "
              "as cost the other mode's factorization):", "",
              "| free vertices | 50 solves | 600 solves | 6 000 solves | 60 000 solves | "
              "unknown count |", "|---|---|---|---|---|---|"]
    for n in (33 ** 2, 129 ** 2, 257 ** 2, 385 ** 2, 513 ** 2, 1025 ** 2):
        picks = [choose_cholmod_mode(n, "auto", s, costs).mode for s in (50, 600, 6000, 60000)]
        ski = choose_cholmod_mode(n, "auto", None, costs, final=False)
        picks.append(ski.mode + ("" if ski.switch_after is None else
                                 f", {ski.switch_to} after {ski.switch_after} solves"))
        lines.append(f"| {n:,} | " + " | ".join(picks) + " |")
    return lines


def api(n: int) -> dict:
    out = subprocess.run([sys.executable, "-c", CHILD, str(n)], check=True,
                         capture_output=True, text=True, cwd=ROOT)
    return json.loads(out.stdout.strip().splitlines()[-1])


def cli(n: int, frames: int = 5) -> dict:
    """Wall and CPU seconds (user + system) of `clothsim run`, with and without pictures."""
    times = {}
    with tempfile.TemporaryDirectory() as tmp:
        for label, extra in (("with", []), ("without", ["--no-preview"])):
            r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
            t0 = time.perf_counter()
            subprocess.run([sys.executable, "-m", "clothsim", "run", "hanging", "--set",
                            f"cloth.resolution=[{n}, {n}]", "--frames", str(frames), "--out",
                            str(Path(tmp) / label), *extra], check=True, cwd=ROOT,
                           capture_output=True)
            times[label] = time.perf_counter() - t0
            r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
            times[label + "_cpu"] = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
    return times


def commit(tree: Path = ROOT) -> str:
    """The short commit the source tree ``tree`` has checked out ("unknown" outside git)."""
    try:
        return subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                              text=True, cwd=tree, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.scale_ladder")
    parser.add_argument("--sizes", default="129,257,513,1025")
    parser.add_argument("--run-sizes", default="513")
    parser.add_argument("--mode-sizes", default="",
                        help="measure the two CHOLMOD modes instead (docs/data/cholmod-modes.md)")
    args = parser.parse_args([] if argv is None else argv)
    if args.mode_sizes:
        lines = mode_table([int(s) for s in args.mode_sizes.split(",") if s])
        MODES_OUT.write_text("\n".join(lines) + "\n")
        print(f"written to {MODES_OUT.relative_to(ROOT)}")
        return
    lines = [f"Measured by `python -m benchmarks.scale_ladder --sizes {args.sizes} --run-sizes "
             f"{args.run_sizes}` at commit {commit()} "
             f"(one BLAS/OpenMP thread, CHOLMOD's factorization from 100 000 rows on two; "
             f"load average {Path('/proc/loadavg').read_text().split()[0]}"
             f" at the start).", "",
             "| grid | vertices | setup | factor | first step | next step | peak RSS | "
             "bytes per vertex | factorization |", "|---|---|---|---|---|---|---|---|---|"]
    writes = ["", "Frame write (CPU seconds of one frame as `clothsim run` writes it after 4 "
              "steps, its colour fields included; `[output] frame_compression`):", "",
              "| grid | zlib | none | zlib per vertex | zlib bytes per vertex | "
              "none bytes per vertex |", "|---|---|---|---|---|---|"]
    for n in (int(s) for s in args.sizes.split(",") if s):
        r = api(n)
        (tz, bz), (tn, bn) = r["write"]["zlib"], r["write"]["none"]
        writes.append(f"| {n}² | {tz:.3f} s | {tn:.3f} s | {1e6 * tz / r['vertices']:.1f} µs | "
                      f"{bz / r['vertices']:.0f} | {bn / r['vertices']:.0f} |")
        lines.append(f"| {n}² | {r['vertices']:,} | {r['setup']:.2f} s | {r['factor']:.2f} s | "
                     f"{r['first']:.2f} s | {r['step']:.3f} s | {r['rss'] / MIB:,.0f} MiB | "
                     f"{r['rss'] / r['vertices']:,.0f} | {r['mode'].split(':')[0]} |")
        print(lines[-1], flush=True)
    lines += writes
    runs = [int(s) for s in args.run_sizes.split(",") if s]
    if runs:
        lines += ["", "| `clothsim run`, 5 frames | wall | CPU | without pictures: wall | "
                  "CPU | pictures' share of CPU |", "|---|---|---|---|---|---|"]
        for n in runs:
            t = cli(n)
            share = 1 - t["without_cpu"] / t["with_cpu"]
            lines.append(f"| {n}² | {t['with']:.1f} s | {t['with_cpu']:.1f} s | "
                         f"{t['without']:.1f} s | {t['without_cpu']:.1f} s | "
                         f"{max(share, 0.0):.0%} |")
            print(lines[-1], flush=True)
        for n in runs:   # where the time goes (benchmarks.run_phases, a third run)
            r = run_phases.phases(n)
            lines += ["", f"Where a {n}² `clothsim run` of 5 frames spends its time "
                      "(`python -m benchmarks.run_phases`: wall and the CPU of the thread "
                      "that ran each phase; the frame files are written by a second process, "
                      "the pictures by a third, whose CPU overlaps the steps'; "
                      "`trajectory.npz` is built once, while the last frame's file is "
                      "written):", "",
                      *run_phases.table(r)]
    OUT.write_text("\n".join(lines) + "\n")
    print(f"written to {OUT.relative_to(ROOT)}")


if __name__ == "__main__":
    main(sys.argv[1:])
