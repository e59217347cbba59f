"""The full ``clothsim accuracy`` study (no ``--quick``) of the seed's demo at 41 × 41.

Runs the drop-on-square scene (a cloth dropped onto a box: free fall, then contact and
crumpling) at 41 × 41 vertices, in this process, exactly as
``clothsim accuracy drop-on-square --set cloth.resolution=[41,41] --jobs N --no-plots``
does (N: the cores this process may use; errors and trajectory runs go to N workers,
timing stays in this process on one thread), and
prints the wall and CPU seconds of each phase (from ``accuracy.json``'s
``phase_seconds``) and in total, the commit, the load average and the report's first line.
It writes the same as Markdown to ``docs/data/accuracy-full.md``, which
docs/performance.md includes. The machine is shared: the wall time includes waiting for a
core, the CPU time does not (CPU is this process's only: the workers' is not counted, so
the errors and trajectories phases show less CPU than wall time when they run in parallel).
The file is rewritten after each phase, so a run stopped early leaves the phases it
finished, marked incomplete. Run: ``python -m benchmarks accuracy_full`` (it takes
minutes).
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
import time
import warnings
from pathlib import Path

from .accuracy_quick import commit, scene

N = 41
JOBS = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
TARGET_SECONDS = 600.0
ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "docs" / "data" / "accuracy-full.md"


def table(phases: dict, *, sha: str, head: str, load: str, wall: float | None = None,
          cpu: float | None = None, running: str | None = None) -> list[str]:
    """The Markdown lines of docs/data/accuracy-full.md.

    Parameters
    ----------
    phases : dict
        Phase name → {"wall": s, "cpu": s}, the phases finished so far.
    sha : str
        The commit measured (HEAD when the run started).
    head : str
        The report's first line ("" while the study runs).
    load : str
        The load average at the start.
    wall, cpu : float, optional
        The whole study's seconds (None while it runs).
    running : str, optional
        What the run is doing now, when it has not finished (the file then says so).

    Returns
    -------
    list of str
    """
    from clothsim.accuracy.phases import PHASES

    lines = [f"Measured by `python -m benchmarks accuracy_full` at commit {sha} (one "
             f"BLAS/OpenMP thread; load average {load} at the start): `clothsim accuracy "
             f"drop-on-square --set cloth.resolution=[{N},{N}] --jobs {JOBS}`, the full "
             f"study.", ""]
    if head:
        lines += [f"Result: {head}.", ""]
    lines += ["| phase | wall [s] | CPU [s] |", "|---|---|---|"]
    for name in PHASES:
        if name in phases:
            lines.append(f"| {name} | {phases[name]['wall']:.1f} | {phases[name]['cpu']:.1f} |")
    if wall is not None:
        rest_wall = wall - sum(p["wall"] for p in phases.values())
        rest_cpu = cpu - sum(p["cpu"] for p in phases.values())
        lines += [f"| other (set-up, one-off costs, files) | {rest_wall:.1f} | {rest_cpu:.1f} |",
                  f"| **total** | **{wall:.1f}** | **{cpu:.1f}** |", "",
                  f"Target: ≤ {TARGET_SECONDS / 60:.0f} min of wall time — "
                  f"{'met' if wall <= TARGET_SECONDS else 'missed'} "
                  f"({wall / 60:.1f} min wall, {cpu / 60:.1f} min CPU)."]
    else:
        spent = sum(p["wall"] for p in phases.values())
        lines += ["", f"**Incomplete**: the run had not finished; it was in phase "
                      f"*{running}* after {spent / 60:.1f} min of wall time in the phases above "
                      f"(the file is rewritten after each phase)."]
    return lines


def main(argv: list[str] | None = None) -> None:
    import logging

    from clothsim.accuracy import run_accuracy
    from clothsim.accuracy.phases import PHASES

    load = Path("/proc/loadavg").read_text().split()[0]
    sha = commit()
    done: dict = {}

    class Progress(logging.Handler):  # rewrite the file after each phase
        def emit(self, record):
            if record.msg.startswith("phase "):
                name, w, c = record.args
                done[name] = {"wall": w, "cpu": c}
                later = [p for p in PHASES if p not in done]
                OUT.write_text("\n".join(table(done, sha=sha, head="", load=load,
                                               running=later[0] if later else "files")) + "\n")
                print(f"   {name}: {w:.1f} s wall, {c:.1f} s CPU", flush=True)

    logger = logging.getLogger("clothsim.accuracy.phases")
    handler, level = Progress(), logger.level
    logger.addHandler(handler)
    logger.setLevel(logging.INFO)
    try:
        with tempfile.TemporaryDirectory() as out, warnings.catch_warnings():
            warnings.simplefilter("ignore")
            t0, c0 = time.perf_counter(), time.process_time()
            text = run_accuracy(scene(N), Path(out), plots=False, jobs=JOBS)
            wall, cpu = time.perf_counter() - t0, time.process_time() - c0
            phases = json.loads((Path(out) / "accuracy.json").read_text())["phase_seconds"]
    finally:
        logger.removeHandler(handler)
        logger.setLevel(level)
    lines = table(phases, sha=sha, head=text.splitlines()[0].lstrip("# "), load=load, wall=wall,
                  cpu=cpu)
    for line in lines:
        print(f"   {line}")
    OUT.write_text("\n".join(lines) + "\n")
    print(f"   written to {OUT.relative_to(ROOT)}")


if __name__ == "__main__":
    main(sys.argv[1:])
