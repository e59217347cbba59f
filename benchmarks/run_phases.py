"""Where a large ``clothsim run`` spends its time, phase by phase.

``python -m benchmarks.run_phases [--size 513] [--frames 5] [--set key=value ...]`` runs
``clothsim run hanging`` at that resolution in a fresh process (through the command line's
own ``main``) with the run's phases wrapped in timers, and prints one line per phase: how
often it ran, its wall time and the CPU time of the thread that ran it (the frame writer
runs on a background thread, the frame files in a second process and the pictures in a
third: their CPU overlaps the steps'; ``trajectory.npz`` is built once, beside the last
frame, and moved into place by the final files), and the process's wall and CPU time in
total. On a shared machine the wall time
counts the other processes too: compare CPU seconds, or two variants interleaved
(:func:`phases`, used by ``benchmarks.scale_ladder``).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CHILD = r"""
import json, os, sys, tempfile, threading, time
T0, C0 = time.perf_counter(), time.process_time()
import clothsim.cli
imports = (time.perf_counter() - T0, time.process_time() - C0)
from clothsim import pictures, runner
from clothsim.io import frames, runfolder, runfiles, effectstate
from clothsim.scene import Scene
from clothsim.io import frameproc
from clothsim.solvers import local_global
from clothsim import factorization, simulation
spans = []

def wrap(owner, name, label):
    fn = getattr(owner, name)
    def timed(*args, **kwargs):
        w, c = time.perf_counter(), time.thread_time()
        try:
            return fn(*args, **kwargs)
        finally:
            spans.append((label, threading.current_thread().name, w - T0,
                          time.perf_counter() - w, time.thread_time() - c))
    setattr(owner, name, timed)

for owner, name, label in [
        (Scene, "build_model", "model build"), (Scene, "build_simulation", "simulation build"),
        (runner, "scene_hash", "scene hash"), (runner, "input_hashes", "input hashes"),
        (runfolder.RunFolder, "begin", "folder begin"),
        (local_global, "factor_system", "assembly + factorization"),
        (factorization.Factor, "__init__", "factorization (CHOLMOD)"),
        (simulation.Simulation, "step", "step"),
        (runfolder.RunFolder, "wait", "waiting for the frame writer"),
        (runfolder.RunFolder, "_write_frame", "frame write (all)"),
        (effectstate, "write_state", "  state file"),
        (frames.FrameWriter, "write", "  frame .vtu + .pvd"),
        (frames.FrameWriter, "write_file", "    .vtu file (this process)"),
        (frameproc.FrameProcess, "write", "    .vtu file (frame process, waited for)"),
        (runfiles.TrajectoryStore, "append", "trajectory store (run's thread)"),
        (runfolder.RunFolder, "_save_npz", "  trajectory.npz"),
        (runfolder.RunFolder, "wait_last", "last frame: npz built, then waited for"),
        (runfiles.TrajectoryStore, "write_npz_beside", "  trajectory.npz beside the last frame"),
        (runfolder.RunFolder, "_mark", "  run.json"),
        (pictures.PictureProcess, "start", "pictures: start"),
        (pictures.PictureProcess, "request", "pictures: hand-off"),
        (pictures.PictureProcess, "answer", "pictures: wait for answer"),
        (runner, "write_run_pictures", "pictures: write files"),
        (runfolder.RunFolder, "end", "final files (npz, run.json)")]:
    wrap(owner, name, label)
runfolder.write_state = effectstate.write_state
n, nframes, extra = int(sys.argv[1]), sys.argv[2], json.loads(sys.argv[3])
if sys.argv[4] == "off":   # frames written on the run's own thread (the A/B baseline)
    frameproc.PROCESS_FROM = 10 ** 12
with tempfile.TemporaryDirectory() as tmp:
    W, C = time.perf_counter(), time.process_time()
    rc = clothsim.cli.main(["run", "hanging", "--set", f"cloth.resolution=[{n}, {n}]",
                            "--frames", nframes, "--out", tmp, *extra])
    run = (time.perf_counter() - W, time.process_time() - C)
children = os.times()
print(json.dumps({"rc": rc, "imports": imports, "run": run, "spans": spans,
                  "total": (time.perf_counter() - T0, time.process_time()),
                  "children_cpu": children.children_user + children.children_system}))
"""


def phases(size: int = 513, frames: int = 5, extra: list[str] | None = None,
           frame_process: bool = True) -> dict:
    """One instrumented run in a fresh process: its JSON (see the module docstring);
    ``frame_process`` False writes the frames on the run's thread
    (:mod:`clothsim.io.frameproc` off)."""
    out = subprocess.run([sys.executable, "-c", CHILD, str(size), str(frames),
                          json.dumps(list(extra or [])), "on" if frame_process else "off"],
                         check=True, capture_output=True, text=True, cwd=ROOT)
    return json.loads(out.stdout.strip().splitlines()[-1])


def summary(r: dict) -> list[tuple[str, int, float, float]]:
    """(phase, calls, wall [s], thread CPU [s]) per phase, in the order they first start
    (a phase before the phases inside it)."""
    rows: dict[str, list] = {"imports": [1, *r["imports"]]}
    for label, _thread, _at, wall, cpu in sorted(r["spans"], key=lambda s: s[2]):  # by start
        row = rows.setdefault(label, [0, 0.0, 0.0])
        row[0] += 1
        row[1] += wall
        row[2] += cpu
    steps = [s for s in r["spans"] if s[0] == "step"]
    for i, s in enumerate(steps[:2]):
        rows[f"  step {i + 1}"] = [1, s[3], s[4]]
    return [(k, *v) for k, v in rows.items()]


def table(r: dict) -> list[str]:
    """The phases as Markdown rows."""
    lines = ["| phase | calls | wall | thread CPU |", "|---|---|---|---|"]
    lines += [f"| {k} | {c} | {w:.2f} s | {cpu:.2f} s |" for k, c, w, cpu in summary(r)]
    lines.append(f"| whole process | 1 | {r['total'][0]:.2f} s | {r['total'][1]:.2f} s "
                 f"(+ {r['children_cpu']:.2f} s in child processes) |")
    return lines


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.run_phases")
    parser.add_argument("--size", type=int, default=513)
    parser.add_argument("--frames", type=int, default=5)
    parser.add_argument("--set", action="append", default=[], help="a scene override")
    parser.add_argument("--no-preview", action="store_true")
    parser.add_argument("--ab", type=int, default=0, metavar="PAIRS",
                        help="instead, PAIRS interleaved runs with and without the frame "
                             "process: wall, this process's CPU, its children's CPU")
    args = parser.parse_args([] if argv is None else argv)
    extra = [a for s in args.set for a in ("--set", s)]
    extra += ["--no-preview"] if args.no_preview else []
    if args.ab:
        print("| pair | load | frames written by | wall | run's CPU | children's CPU | "
              "wall ratio (process / thread) |\n|---|---|---|---|---|---|---|")
        for i in range(args.ab):
            pair = {}
            for on in (True, False) if i % 2 == 0 else (False, True):
                load = Path("/proc/loadavg").read_text().split()[0]
                r = pair[on] = phases(args.size, args.frames, extra, frame_process=on)
                print(f"| {i + 1} | {load} | {'process' if on else 'thread'} | "
                      f"{r['total'][0]:.2f} s | {r['total'][1]:.2f} s | "
                      f"{r['children_cpu']:.2f} s | |", flush=True)
            print(f"| {i + 1} | | | | | | {pair[True]['total'][0] / pair[False]['total'][0]:.3f} |",
                  flush=True)
        return
    r = phases(args.size, args.frames, extra)
    print(f"load average {Path('/proc/loadavg').read_text().split()[0]}")
    print("\n".join(table(r)))


if __name__ == "__main__":
    main(sys.argv[1:])
