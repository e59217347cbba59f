"""The large-cloth limits of issue 33, this commit against another, interleaved.

``python -m benchmarks.large_vs OLD_TREE [--repeats 2] [--runs-only]`` runs, alternately
with the clothsim source tree at OLD_TREE (e.g. ``git archive main | tar -x -C /tmp/old``)
and this one, each in a fresh process: the ``hanging`` cloth at 1025² stepped by hand
(setup, and the first step: factorization and 10 iterations, wall and CPU seconds, one BLAS
thread; left out with ``--runs-only``), and ``clothsim run`` of it at 513² for 5 frames
(wall and CPU, pictures included). On a shared machine the wall times carry the other
processes' load; the ratios of interleaved runs are what compares the two trees. Prints a
Markdown table of the medians, then each pair's ratios of the 513² run with the load
average before it.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from benchmarks.scale_ladder import commit

ROOT = Path(__file__).resolve().parents[1]

FIRST_STEP = r"""
import json, sys, time
import clothsim as cs
from clothsim.factorization import single_threaded
n = int(sys.argv[1])
t0, c0 = time.perf_counter(), time.process_time()
sim = cs.load_scene("hanging", [f"cloth.resolution=[{n}, {n}]"]).build_simulation()
setup, setup_cpu = time.perf_counter() - t0, time.process_time() - c0
with single_threaded():
    t0, c0 = time.perf_counter(), time.process_time()
    sim.step()
    first, first_cpu = time.perf_counter() - t0, time.process_time() - c0
print(json.dumps({"setup": setup, "setup_cpu": setup_cpu, "first": first,
                  "first_cpu": first_cpu, "mode": sim.solver.factorization.split(":")[0]}))
"""


def env_for(tree: Path) -> dict:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(tree)
    return env


def first_step(tree: Path, n: int) -> dict:
    out = subprocess.run([sys.executable, "-c", FIRST_STEP, str(n)], check=True, cwd=tree,
                         capture_output=True, text=True, env=env_for(tree))
    return json.loads(out.stdout.strip().splitlines()[-1])


def cli_run(tree: Path, n: int, frames: int = 5) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-m", "clothsim", "run", "hanging", "--set",
                        f"cloth.resolution=[{n}, {n}]", "--frames", str(frames), "--out",
                        str(Path(tmp) / "r")], check=True, cwd=tree, capture_output=True,
                       env=env_for(tree))
        wall = time.perf_counter() - t0
        r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    return {"wall": wall, "cpu": (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.large_vs")
    parser.add_argument("old", type=Path)
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--runs-only", action="store_true",
                        help="only the 513² clothsim run (not the 1025² first step)")
    parser.add_argument("--write", type=Path, metavar="PAGE",
                        help="also write the tables, with the command and both commits, to "
                             "PAGE (docs/data/large-vs.md)")
    args = parser.parse_args(sys.argv[1:] if argv is None else argv)
    trees = {"old": args.old.resolve(), "new": ROOT}
    res = {k: {"first": [], "run": []} for k in trees}
    load = Path("/proc/loadavg").read_text().split()[0]
    for r in range(args.repeats):
        for name in (("old", "new") if r % 2 == 0 else ("new", "old")):
            if not args.runs_only:
                res[name]["first"].append(first_step(trees[name], 1025))
                print(name, "1025² first step", res[name]["first"][-1], flush=True)
            before = Path("/proc/loadavg").read_text().split()[0]
            res[name]["run"].append(dict(cli_run(trees[name], 513), load=float(before)))
            print(name, "513² clothsim run", res[name]["run"][-1], flush=True)

    print(f"\n{args.repeats} interleaved repeats; load average {load} at the start\n")
    print("\n".join(table(res) + [""] + pairs(res)))
    if args.write is not None:
        end = Path("/proc/loadavg").read_text().split()[0]
        command = " ".join(["python -m benchmarks.large_vs OLD_TREE", f"--repeats {args.repeats}"]
                           + (["--runs-only"] if args.runs_only else [])
                           + [f"--write {args.write}"])
        head = (f"Measured by `{command}` at commit {commit()} with OLD_TREE at commit "
                f"{commit(trees['old'])}: {args.repeats} interleaved repeats, each run in a "
                f"fresh process, load average {load} at the start and {end} at the end "
                f"(2 cores, shared).")
        args.write.write_text("\n".join([head, ""] + table(res) + [""] + pairs(res)) + "\n")
        print(f"written to {args.write}")


def table(res: dict) -> list[str]:
    """The Markdown lines: medians of each tree's runs, wall and CPU, and new / old."""
    lines = ["| quantity | old wall | new wall | new / old | old CPU | new CPU | new / old |",
             "|---|---|---|---|---|---|---|"]
    for label, key, w, c in (("1025² setup", "first", "setup", "setup_cpu"),
                             ("1025² first step", "first", "first", "first_cpu"),
                             ("513² clothsim run, 5 frames", "run", "wall", "cpu")):
        if not all(res[k][key] for k in ("old", "new")):   # --runs-only
            continue
        ow, nw = (statistics.median([x[w] for x in res[k][key]]) for k in ("old", "new"))
        oc, nc = (statistics.median([x[c] for x in res[k][key]]) for k in ("old", "new"))
        lines.append(f"| {label} | {ow:.1f} s | {nw:.1f} s | {nw / ow:.2f} | {oc:.1f} s | "
                     f"{nc:.1f} s | {nc / oc:.2f} |")
    return lines


def pairs(res: dict) -> list[str]:
    """The Markdown lines of each interleaved pair of 513² runs: new / old wall and CPU, and
    the load average before each run (the noise a ratio carries on a shared machine)."""
    lines = ["| pair | load (old, new) | new / old wall | new / old CPU |", "|---|---|---|---|"]
    for i, (o, n) in enumerate(zip(res["old"]["run"], res["new"]["run"])):
        lines.append(f"| {i + 1} | {o.get('load', float('nan')):.1f}, "
                     f"{n.get('load', float('nan')):.1f} | {n['wall'] / o['wall']:.2f} | "
                     f"{n['cpu'] / o['cpu']:.2f} |")
    return lines


if __name__ == "__main__":
    main()
