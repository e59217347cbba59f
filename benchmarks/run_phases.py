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

``python -m benchmarks.run_phases --beside 3`` asks whether the processes beside the steps
slow them (:func:`beside`): interleaved runs with the frame files and pictures and without
either, each step's thread CPU.

``python -m benchmarks.run_phases --step-parts [--size 513] [--write]`` splits one step of
that run instead (:func:`step_parts`): the thread CPU of the step and of each part of its
iteration (the CHOLMOD solve, the local step's passes, the right-hand side, the residual)
and of its per-step setup, each the best of 5; ``--write`` also writes
``docs/data/step-parts.md``.
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
        (runner, "digest_model", "scene hash (a thread, beside the simulation build)"),
        (runner, "input_hashes", "input hashes"),
        (runfolder.RunFolder, "begin", "folder begin"),
        (simulation.Simulation, "prepare", "first factorization (before frame 0)"),
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
import resource
steps_ru = []
_step = simulation.Simulation.step

def step_rusage(*args, **kwargs):   # the step's system time and page faults (its thread)
    r0 = resource.getrusage(resource.RUSAGE_THREAD)
    try:
        return _step(*args, **kwargs)
    finally:
        r1 = resource.getrusage(resource.RUSAGE_THREAD)
        steps_ru.append((r1.ru_stime - r0.ru_stime, r1.ru_minflt - r0.ru_minflt))
simulation.Simulation.step = step_rusage
n, nframes, extra = int(sys.argv[1]), sys.argv[2], json.loads(sys.argv[3])
if sys.argv[4] in ("off", "bare"):   # frames written on the run's own thread (A/B baseline)
    frameproc.PROCESS_FROM = 10 ** 12
if sys.argv[4] == "bare":            # ... and not written: an empty file for each
    frames.FrameWriter.write_file = lambda self, path, x, v, mask: open(path, "wb").close()
with tempfile.TemporaryDirectory() as tmp:
    W, C = time.perf_counter(), time.process_time()
    rc = clothsim.cli.main(["run", "hanging", "--set", f"cloth.resolution=[{n}, {n}]",
                            "--frames", nframes, "--out", tmp, *extra])
    run = (time.perf_counter() - W, time.process_time() - C)
children = os.times()
print(json.dumps({"rc": rc, "imports": imports, "run": run, "spans": spans, "steps_ru": steps_ru,
                  "total": (time.perf_counter() - T0, time.process_time()),
                  "children_cpu": children.children_user + children.children_system}))
"""


STEP = r"""
import json, sys, time
import numpy as np
import clothsim as cs
from clothsim.factorization import single_threaded
from clothsim.solvers.fused import FusedStep
n, repeats = int(sys.argv[1]), int(sys.argv[2])
sim = cs.load_scene("hanging", [f"cloth.resolution=[{n}, {n}]"]).build_simulation()
sim.expect_steps(5)      # clothsim run's 5 frames: the factor that run keeps
for _ in range(2):
    sim.step()
out = {"iterations": sim.solver.iterations, "mode": sim.solver.factorization.split(":")[0]}

def best(name, fn, before=None):
    t = []
    for _ in range(repeats):
        if before is not None:
            before()
        c = time.thread_time()
        fn()
        t.append(time.thread_time() - c)
    out[name] = min(t)

best("step", sim.step)
with single_threaded():
    best("setup", lambda: FusedStep(sim.solver, sim.problem()))
    st = FusedStep(sim.solver, sim.problem())
    delta = st.solve()
    dirs, eT, xT = st.dirs, st.eT, st._place(delta)
    spare = np.empty_like(eT)
    best("solve", st.solve)
    best("place", lambda: st._place(delta))
    best("vectors", lambda: dirs.vectors_into(xT, eT))
    best("scale", lambda: dirs._scale(eT), lambda: dirs.vectors_into(xT, eT))
    best("difference", lambda: np.subtract(eT, st.pyT, out=spare))
    best("rhs", lambda: st._right_hand_side(eT, st.rhs_previous))
    best("norm", lambda: st.gradient_norm(st.rhs_previous))
print(json.dumps(out))
"""

#: The parts of one step (:func:`step_parts`): key, what it is, calls per step ("k": one
#: per iteration).
PARTS = [("setup", "per step: y's spring vectors, c_F, x_0's local step and rhs "
          "(`FusedStep`)", 1),
         ("solve", "global step: CHOLMOD's solve of the three columns", "k"),
         ("place", "x = y + δ over the free runs", "k"),
         ("vectors", "local step: spring vectors p(x) (strided slices)", "k"),
         ("scale", "local step: ‖p‖ (einsum, sqrt), d = (r / ‖p‖) p", "k"),
         ("difference", "local step: e = d − p(y)", "k"),
         ("rhs", "right-hand side c_F + h² J_F e (three sparse products)", "k"),
         ("norm", "‖∇g‖ from the two right-hand sides", "k")]


def step_parts(size: int = 513, repeats: int = 5) -> dict:
    """Thread CPU seconds of one step of ``clothsim run hanging`` at ``size``² (its factor:
    5 frames expected) and of each part of it, each the best of ``repeats``, in a fresh
    process: the JSON of :data:`STEP` (keys of :data:`PARTS`, ``step``, ``iterations``)."""
    out = subprocess.run([sys.executable, "-c", STEP, str(size), str(repeats)], check=True,
                         capture_output=True, text=True, cwd=ROOT)
    return json.loads(out.stdout.strip().splitlines()[-1])


def parts_table(r: dict) -> list[str]:
    """:func:`step_parts` as Markdown rows: per call, per step, share of the step; "other"
    is the step less its parts (the problem, velocities, checks, the loop itself)."""
    k, step = r["iterations"], r["step"]
    lines = ["| part | per call | calls per step | per step | share of the step |",
             "|---|---|---|---|---|"]
    total = 0.0
    for key, label, calls in PARTS:
        calls = k if calls == "k" else calls
        total += r[key] * calls
        lines.append(f"| {label} | {r[key] * 1e3:.1f} ms | {calls} | {r[key] * calls:.3f} s "
                     f"| {r[key] * calls / step:.0%} |")
    lines.append(f"| other: the problem, velocities, checks, the loop | | | "
                 f"{step - total:.3f} s | {(step - total) / step:.0%} |")
    lines.append(f"| whole step (`Simulation.step`, {r['mode']} factor) | | 1 | {step:.3f} s "
                 f"| 100% |")
    return lines


def phases(size: int = 513, frames: int = 5, extra: list[str] | None = None,
           frame_process: bool = True, bare: bool = False) -> dict:
    """One instrumented run in a fresh process: its JSON (see the module docstring; with
    ``steps_ru``, each step's system time [s] and minor page faults, of its thread);
    ``frame_process`` False writes the frames on the run's thread
    (:mod:`clothsim.io.frameproc` off); ``bare`` writes an empty file for each frame
    instead (nothing beside the steps but the run's own thread; give ``--no-preview`` in
    ``extra`` to leave out the pictures too)."""
    mode = "bare" if bare else "on" if frame_process else "off"
    out = subprocess.run([sys.executable, "-c", CHILD, str(size), str(frames),
                          json.dumps(list(extra or [])), mode],
                         check=True, capture_output=True, text=True, cwd=ROOT)
    return json.loads(out.stdout.strip().splitlines()[-1])


def beside_rows(pair: int, load: str, what: str, r: dict) -> str:
    """One Markdown row of :func:`beside`: each step's thread CPU, the first step's system
    time and page faults."""
    steps = [s for s in r["spans"] if s[0] == "step"]
    cpu = " ".join(f"{s[4]:.2f}" for s in steps)
    sys_time, faults = r["steps_ru"][0] if r["steps_ru"] else (0.0, 0)
    later = sum(f for _, f in r["steps_ru"][1:])
    return (f"| {pair} | {load} | {what} | {cpu} | {sys_time:.2f} s, {faults} | {later} | "
            f"{r['children_cpu']:.2f} s |")


def beside(size: int = 513, frames: int = 5, pairs: int = 3) -> list[str]:
    """Does what runs beside the steps slow them? ``pairs`` interleaved runs with the frame
    files (second process) and the pictures (third) as a run writes them, and without
    either (:func:`phases` with ``bare`` and ``--no-preview``): each step's thread CPU
    (which memory or cache shared with those processes would raise; sharing cores would
    not), the first step's system time and minor page faults, the later steps' faults, and
    the child processes' CPU. Returns the Markdown lines."""
    lines = ["| pair | load | beside the steps | each step's thread CPU [s] | step 1: system "
             "time, page faults | later steps' page faults | children's CPU |",
             "|---|---|---|---|---|---|---|"]
    for i in range(pairs):
        for full in (True, False) if i % 2 == 0 else (False, True):
            load = Path("/proc/loadavg").read_text().split()[0]
            r = phases(size, frames, [] if full else ["--no-preview"], bare=not full)
            lines.append(beside_rows(i + 1, load, "frame files and pictures" if full
                                     else "neither", r))
            print(lines[-1], flush=True)
    return lines


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
    parser.add_argument("--step-parts", action="store_true",
                        help="instead, the thread CPU of one step's parts (best of 5)")
    parser.add_argument("--write", action="store_true",
                        help="with --step-parts: also write docs/data/step-parts.md")
    parser.add_argument("--beside", type=int, default=0, metavar="PAIRS",
                        help="instead, PAIRS interleaved runs with the frame files and "
                             "pictures and without: each step's thread CPU")
    parser.add_argument("--ab", type=int, default=0, metavar="PAIRS",
                        help="instead, PAIRS interleaved runs with and without the frame "
                             "process: wall, this process's CPU, its children's CPU")
    args = parser.parse_args([] if argv is None else argv)
    extra = [a for s in args.set for a in ("--set", s)]
    extra += ["--no-preview"] if args.no_preview else []
    if args.step_parts:
        from benchmarks.scale_ladder import commit
        load = Path("/proc/loadavg").read_text().split()[0]
        text = "\n".join([
            f"Measured by `python -m benchmarks.run_phases --step-parts --size {args.size} "
            f"--write` at commit {commit()} (thread CPU seconds, each part the best of 5, "
            f"one BLAS/OpenMP thread; load average {load} at the start).", "",
            *parts_table(step_parts(args.size))]) + "\n"
        print(text)
        if args.write:
            (ROOT / "docs" / "data" / "step-parts.md").write_text(text, encoding="utf-8")
        return
    if args.beside:
        beside(args.size, args.frames, args.beside)
        return
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
