"""Memory of a long run: ``python -m benchmarks memory`` (or ``python -m benchmarks.memory
--n 257 --frames 500``).

Runs a hanging n × n cloth (default 257², 500 frames, 10 local/global iterations per frame)
through :func:`clothsim.runner.run_scene`, as ``clothsim run`` does, and reports:

- traced memory (:mod:`tracemalloc`: every Python and NumPy allocation) after the first
  frames and after the last one; their difference is the growth (acceptance: < 20 MB);
- the traced peak (working memory of a frame included) over the first frames and over the
  rest of the run;
- the process's peak resident set size (``resource.getrusage``).

The trajectory is streamed to disk, so the growth should not depend on the frame count
(before, every frame stayed in memory: 3 MiB per frame at 257², ~1.9 GB for 500 frames).
"""

from __future__ import annotations

import argparse
import resource
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

from clothsim.runner import run_scene
from clothsim.scene import Scene

FIRST = 10  # frames after which the run counts as started (caches, factorization, imports)
MB = 1e6


def scene(n: int, frames: int) -> Scene:
    """A hanging n × n cloth pinned at its two top corners."""
    return Scene.from_dict({
        "scene": {"name": f"memory-{n}", "frames": frames, "fps": 30},
        "cloth": {"resolution": [n, n], "center": [0, 1, 0], "plane": "xy"},
        "springs": {"structural": 1000.0, "shear": 1000.0, "bending": 100.0},
        "solver": {"iterations": 10},
        "effects": [{"kind": "gravity"},
                    {"kind": "pin", "vertices": [n * (n - 1), n * n - 1]}],
    })


def measure(n: int = 257, frames: int = 500) -> dict:
    """Run and measure; returns the figures (bytes, seconds)."""
    levels: dict[str, float] = {}

    def progress(k, total):
        current, peak = tracemalloc.get_traced_memory()
        if k == FIRST:
            levels.update(after_first=current, peak_first=peak)
            tracemalloc.reset_peak()
        if k > FIRST:
            levels["peak_after_first"] = peak
        levels["last"] = current

    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        tracemalloc.start()
        try:
            run_scene(scene(n, frames), Path(tmp) / "run", progress=progress, preview=False)
        finally:
            tracemalloc.stop()
        seconds = time.perf_counter() - start
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024  # kB on Linux
    levels.update(seconds=seconds, max_rss=rss, frame_bytes=2 * n * n * 3 * 8)
    levels["growth"] = levels["last"] - levels["after_first"]
    levels["peak_growth"] = levels["peak_after_first"] - levels["peak_first"]
    return levels


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.memory")
    parser.add_argument("--n", type=int, default=257, help="grid side (default 257)")
    parser.add_argument("--frames", type=int, default=500, help="frames (default 500)")
    args = parser.parse_args([] if argv is None else argv)
    if args.frames <= FIRST:
        parser.error(f"--frames: must be > {FIRST}")
    r = measure(args.n, args.frames)
    print(f"{args.n}² cloth, {args.frames} frames ({r['seconds']:.0f} s; one frame's positions "
          f"and velocities: {r['frame_bytes'] / MB:.2f} MB)")
    print(f"  traced memory after frame {FIRST}:    {r['after_first'] / MB:8.1f} MB")
    print(f"  traced memory after frame {args.frames}:   {r['last'] / MB:8.1f} MB")
    verdict = "ok" if r["growth"] < 20 * MB else "FAILS the 20 MB bound"
    print(f"  growth over frames {FIRST}..{args.frames}:    {r['growth'] / MB:8.1f} MB  "
          f"({verdict})")
    print(f"  traced peak, frames 0..{FIRST}:       {r['peak_first'] / MB:8.1f} MB")
    print(f"  traced peak, frames {FIRST}..{args.frames}:     "
          f"{r['peak_after_first'] / MB:8.1f} MB ({r['peak_growth'] / MB:+.1f} MB)")
    print(f"  peak resident set size:     {r['max_rss'] / MB:8.1f} MB")


if __name__ == "__main__":
    main(sys.argv[1:])
