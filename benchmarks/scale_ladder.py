"""Large cloths: the scale ladder 129², 257², 513², 1025² (issue 23's figures).

``python -m benchmarks scale_ladder [--sizes 129,257,513,1025] [--run-sizes 513]`` measures,
each size in a fresh process (so the peak resident set is that size's alone), with BLAS
and OpenMP on one thread:

- through the API (the ``hanging`` cloth at that resolution: two pinned corners, gravity):
  setup (model and simulation), the factorization (the mode clothsim chose, and why), the
  first step (factor + 10 iterations), the median of the next 3 steps, peak RSS, bytes per
  vertex;
- through ``clothsim run`` (``--run-sizes``, 5 frames): wall time, and the share of the
  pictures (``preview.gif`` + ``final.png``, from a second run with ``--no-preview``).

It prints a Markdown table with the commit and writes it to ``docs/data/scale-ladder.md``,
which docs/performance.md includes.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "docs" / "data" / "scale-ladder.md"
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
print(json.dumps({"n": n, "vertices": sim.model.vertex_count, "setup": setup,
                  "factor": factor, "first": first, "step": float(np.median(steps)),
                  "rss": rss, "mode": sim.solver.factorization}))
"""


def api(n: int) -> dict:
    out = subprocess.run([sys.executable, "-c", CHILD, str(n)], check=True,
                         capture_output=True, text=True, cwd=ROOT)
    return json.loads(out.stdout.strip().splitlines()[-1])


def cli(n: int, frames: int = 5) -> dict:
    times = {}
    with tempfile.TemporaryDirectory() as tmp:
        for label, extra in (("with", []), ("without", ["--no-preview"])):
            t0 = time.perf_counter()
            subprocess.run([sys.executable, "-m", "clothsim", "run", "hanging", "--set",
                            f"cloth.resolution=[{n}, {n}]", "--frames", str(frames), "--out",
                            str(Path(tmp) / label), *extra], check=True, cwd=ROOT,
                           capture_output=True)
            times[label] = time.perf_counter() - t0
    return times


def commit() -> str:
    try:
        return subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                              text=True, cwd=ROOT, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.scale_ladder")
    parser.add_argument("--sizes", default="129,257,513,1025")
    parser.add_argument("--run-sizes", default="513")
    args = parser.parse_args([] if argv is None else argv)
    lines = [f"Measured by `python -m benchmarks scale_ladder` at commit {commit()} "
             f"(one BLAS/OpenMP thread; load average {Path('/proc/loadavg').read_text().split()[0]}"
             f" at the start).", "",
             "| grid | vertices | setup | factor | first step | next step | peak RSS | "
             "bytes per vertex | factorization |", "|---|---|---|---|---|---|---|---|---|"]
    for n in (int(s) for s in args.sizes.split(",") if s):
        r = api(n)
        lines.append(f"| {n}² | {r['vertices']:,} | {r['setup']:.2f} s | {r['factor']:.2f} s | "
                     f"{r['first']:.2f} s | {r['step']:.3f} s | {r['rss'] / MIB:,.0f} MiB | "
                     f"{r['rss'] / r['vertices']:,.0f} | {r['mode'].split(':')[0]} |")
        print(lines[-1], flush=True)
    runs = [int(s) for s in args.run_sizes.split(",") if s]
    if runs:
        lines += ["", "| `clothsim run`, 5 frames | wall | without pictures | pictures' share |",
                  "|---|---|---|---|"]
        for n in runs:
            t = cli(n)
            share = 1 - t["without"] / t["with"]
            lines.append(f"| {n}² | {t['with']:.1f} s | {t['without']:.1f} s | "
                         f"{max(share, 0.0):.0%} |")
            print(lines[-1], flush=True)
    OUT.write_text("\n".join(lines) + "\n")
    print(f"written to {OUT.relative_to(ROOT)}")


if __name__ == "__main__":
    main(sys.argv[1:])
