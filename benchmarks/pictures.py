"""What the pictures of a run cost beside the run: ``preview.gif`` + ``final.png`` of a large
grid (257², 513²), drawn decimated (the default, ``clothsim.plotting.MAX_TRIANGLES``) and in
full (the budget lifted), against the 5-frame run that writes them.

``python -m benchmarks.pictures [N ...]`` (default 257 513). BLAS on one thread; each time
is the best of ``REPEATS`` runs, the variants interleaved. Prints one row per size:
run without pictures [s], pictures decimated [s], their share of the whole run, pictures
in full [s], and the triangles drawn per picture.
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPEATS = 2
FRAMES = 5


def scene(n: int):
    """A hanging n × n grid, two pinned top corners, gravity (the README's example)."""
    from clothsim.scene import Scene

    return Scene.from_dict({
        "scene": {"name": f"hanging-{n}", "frames": FRAMES},
        "cloth": {"shape": "grid", "resolution": [n, n], "plane": "xy",
                  "center": [0.0, 1.0, 0.0]},
        "springs": {"structural": 800.0, "shear": 800.0, "bending": 80.0},
        "effects": [{"kind": "gravity"},
                    {"kind": "pin", "vertices": [n * (n - 1), n * n - 1]}],
    })


def pictures(out: Path, sim, budget: int) -> float:
    """Seconds to draw the run's preview.gif and final.png (the runner's calls)."""
    import clothsim.plotting as plotting

    z = np.load(out / "trajectory.npz")
    saved = plotting.MAX_TRIANGLES
    plotting.MAX_TRIANGLES = budget
    try:
        t0 = time.perf_counter()
        times = z["time"]
        plotting.write_preview(out / "preview.gif", z["positions"], sim.model.mesh,
                               times=times, effects=sim.effects)
        plotting.write_final_image(out / "final.png", z["positions"][-1], sim.model.mesh,
                                   title="bench", effects=sim.effects, t=float(times[-1]))
        return time.perf_counter() - t0
    finally:
        plotting.MAX_TRIANGLES = saved


def measure(n: int) -> dict:
    from clothsim.plotting import MAX_TRIANGLES
    from clothsim.runner import run_scene

    best = {"run": np.inf, "decimated": np.inf, "full": np.inf}
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "run"
        for _ in range(REPEATS):
            sc = scene(n)
            t0 = time.perf_counter()
            run_scene(sc, out, preview=False)
            best["run"] = min(best["run"], time.perf_counter() - t0)
            sim = sc.build_simulation()
            best["decimated"] = min(best["decimated"], pictures(out, sim, MAX_TRIANGLES))
            best["full"] = min(best["full"], pictures(out, sim, 10**9))
    best["triangles"] = 2 * (n - 1) ** 2
    return best


def main(argv=None) -> None:
    from threadpoolctl import threadpool_limits

    from clothsim.display import decimate
    from clothsim.mesh import grid

    sizes = [int(a) for a in (argv if argv is not None else sys.argv[1:])] or [257, 513]
    print(f"{'grid':>6} {'run [s]':>8} {'pictures [s]':>13} {'share':>6} "
          f"{'in full [s]':>12} {'drawn':>8} {'of':>8}")
    with threadpool_limits(1):
        for n in sizes:
            r = measure(n)
            from clothsim.plotting import MAX_TRIANGLES

            drawn = decimate(grid(n, n), MAX_TRIANGLES)[0].triangle_count
            share = r["decimated"] / (r["run"] + r["decimated"])
            print(f"{n:>5}² {r['run']:8.2f} {r['decimated']:13.2f} {share:6.1%} "
                  f"{r['full']:12.2f} {drawn:8d} {r['triangles']:8d}", flush=True)


if __name__ == "__main__":
    main()
