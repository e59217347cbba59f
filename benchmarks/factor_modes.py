"""The automatic CHOLMOD mode against both modes, after a short and a long run (issue 33).

``python -m benchmarks factor_modes [--sizes 129,257] [--long 60]`` runs, for each size of
the performance benchmark's cloth (:func:`benchmarks.performance.falling_sheet`), three
simulations side by side -- ``cholmod_mode`` "auto", "simplicial" and "supernodal" -- along
an API user's path: ``Simulation.run(3)`` (the short run: the solver is told only that at
least 30 solves follow), then stepping on to ``--long`` steps (the long run). It reports
the CPU time (one BLAS/OpenMP thread) of the short run and of the whole long run in each
mode, the mode "auto" is in after each, and its factorizations. The three simulations
advance interleaved, a step each in a rotating order, so that they share the machine's
load. Writes ``docs/data/factor-modes.md`` (docs/performance.md includes it).
"""

from __future__ import annotations

import argparse
import time
import warnings
from pathlib import Path

from threadpoolctl import threadpool_limits

from .performance import falling_sheet
from .scale_ladder import commit

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "docs" / "data" / "factor-modes.md"
MODES = ("auto", "simplicial", "supernodal")
SHORT = 3


def measure(n: int, long: int) -> dict:
    """CPU seconds of the short and the long run in each mode, and what "auto" did."""
    sims = {}
    for mode in MODES:
        sims[mode] = falling_sheet(n)
        sims[mode].solver.cholmod_mode = mode
    cpu = dict.fromkeys(MODES, 0.0)

    def timed(mode: str, advance) -> None:
        t0 = time.process_time()
        advance(sims[mode])
        cpu[mode] += time.process_time() - t0

    for mode in MODES:                         # the short run: Simulation.run(3) each
        timed(mode, lambda sim: sim.run(SHORT))
    auto = sims["auto"].solver
    out = {"short": dict(cpu), "short_mode": auto.factorization.split(":")[0]}
    for k in range(SHORT, long):               # stepping on, a step each, rotating order
        for mode in MODES[k % 3:] + MODES[:k % 3]:
            timed(mode, lambda sim: sim.step())
    out.update(long=dict(cpu), long_mode=auto.factorization.split(":")[0],
               factor_count=auto.factor_count, reason=auto.factorization)
    return out


def table(sizes: list[int], long: int) -> list[str]:
    """Measure every size; the Markdown lines."""
    load = Path("/proc/loadavg").read_text().split()[0]
    lines = [f"Measured by `python -m benchmarks.factor_modes --sizes "
             f"{','.join(map(str, sizes))} --long {long}` at commit {commit()} (CPU seconds, "
             f"one BLAS/OpenMP thread, the three simulations interleaved step by step; load "
             f"average {load} at the start). The cloth of the table at the top of this page; "
             f"\"auto\" is the mode clothsim chooses along the API path "
             f"`Simulation.run({SHORT})`, then `step()` to {long} steps.", "",
             "| grid | run | auto | simplicial | supernodal | auto / the better | "
             "auto's mode after it |", "|---|---|---|---|---|---|---|"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for n in sizes:
            r = measure(n, long)
            for key, label in (("short", f"`run({SHORT})`: {SHORT * 10} solves"),
                               ("long", f"then {long - SHORT} steps: {long * 10} solves")):
                t = r[key]
                mode = r[key + "_mode"] + (f", {r['factor_count']} factorizations"
                                           if key == "long" and r["factor_count"] > 1 else "")
                better = min(t["simplicial"], t["supernodal"])
                lines.append(f"| {n}² | {label} | {t['auto']:.2f} s | {t['simplicial']:.2f} s "
                             f"| {t['supernodal']:.2f} s | {t['auto'] / better:.2f} | {mode} |")
                print(lines[-1], flush=True)
            lines.append(f"|  | auto's reason | {r['reason']} | | | | |")
    return lines


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.factor_modes")
    parser.add_argument("--sizes", default="129,257")
    parser.add_argument("--long", type=int, default=60)
    args = parser.parse_args([] if argv is None else argv)
    import sksparse.cholmod  # noqa: F401  (load CHOLMOD's OpenMP and BLAS: limited too)

    with threadpool_limits(1):
        lines = table([int(s) for s in args.sizes.split(",")], args.long)
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text("\n".join(lines) + "\n", encoding="utf-8")


if __name__ == "__main__":
    import sys

    main(sys.argv[1:])
