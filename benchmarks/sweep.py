"""The full accuracy/time sweep on a 21 × 21 curtain, and the damping figure.

Scene: 21 × 21 curtain (1 kg, 1 m, k = 3000 N/m, bending 300 N/m) hanging from its two
top corners, 30 frames (1 s) at 30 fps. Configurations: h ∈ {1/30, 1/60, 1/120, 1/240} ×
local/global and Chebyshev at 1 … 100 iterations, Newton at 1 … 5 iterations, plus
symplectic Euler at its stable step. Reference: h = 1/3840 s, local/global to a relative
residual of 1e-10. Writes docs/img/accuracy.csv, frontier.png and damping.png and prints
the cheapest configuration per accuracy level and the ratios that summarize it.
"""

from __future__ import annotations

import math

import numpy as np

from clothsim.accuracy import (ACCURACY_LEVELS, TRAJECTORY_LEVELS, cheapest, damping_curves,
                               plot_damping, plot_frontier, run_sweep, write_csv)

from . import DOCS_IMG, curtain_factory, report

GRID = 21
STIFFNESS = 3000.0
FRAME = 1 / 30
FRAMES = 30


def main() -> None:
    factory = curtain_factory(GRID, stiffness=STIFFNESS, bending=STIFFNESS / 10)
    rows = run_sweep(factory, time_steps=(FRAME, FRAME / 2, FRAME / 4, FRAME / 8),
                     frame_time=FRAME, frames=FRAMES, iterations=(1, 2, 5, 10, 20, 50, 100),
                     newton_iterations=(1, 2, 3, 5), progress=True)
    DOCS_IMG.mkdir(parents=True, exist_ok=True)
    write_csv(rows, DOCS_IMG / "accuracy.csv")
    plot_frontier(rows, DOCS_IMG / "frontier.png",
                  title=f"{GRID}×{GRID} curtain, 1 s: accuracy against wall time per frame")
    for col, levels in (("trajectory_error", TRAJECTORY_LEVELS),
                        ("solver_error", ACCURACY_LEVELS)):
        print(f"  cheapest per {col} level:")
        for level, r in cheapest(rows, error=col, levels=levels):
            if r is None:
                print(f"    <= {level:.0e}: not reached")
            else:
                print(f"    <= {level:.0e}: {r.method} h=1/{round(1 / r.h)} "
                      f"it={r.iterations}: {r.seconds_per_frame * 1e3:.2f} ms/frame "
                      f"(error {getattr(r, col):.2e})")
    by = {(r.method, round(1 / r.h) if math.isfinite(r.h) else 0, r.iterations): r
          for r in rows}
    conv = [by["newton", k, 5].trajectory_error for k in (30, 60, 120, 240)]
    slope = np.polyfit(np.log([1 / 30, 1 / 60, 1 / 120, 1 / 240]), np.log(conv), 1)[0]
    report("trajectory error vs h, Newton 5 it: log-log slope (implicit Euler: 1)", slope, ".2f")
    report("trajectory error ratio h=1/30 / h=1/240 (Newton 5 it)", conv[0] / conv[-1])
    for its in (1, 2, 5, 10):
        report(f"h=1/30 trajectory error ratio local-global {its} it / Newton 5 it",
               by["local-global", 30, its].trajectory_error / conv[0])
    se = [r for r in rows if r.method == "symplectic-euler"][0]
    report(f"symplectic Euler (h=1/{round(1 / se.h)}) / implicit Euler h=1/240 trajectory "
           f"error ratio", se.trajectory_error / conv[-1])
    report("symplectic Euler / local-global 10 it h=1/30 cost-per-frame ratio",
           se.seconds_per_frame / by["local-global", 30, 10].seconds_per_frame)
    corner = 0  # bottom-left corner, free
    curves = damping_curves(factory, h=FRAME, frames=60, frame_time=FRAME, vertex=corner,
                            settings=[("local-global", 1, None), ("local-global", 3, None),
                                      ("local-global", 10, None), ("newton", 30, 1e-10)])
    plot_damping(DOCS_IMG / "damping.png", cloth_curves=curves)
    late = {k: float(np.ptp(v[30:])) for k, v in curves.items()}
    ref = late["newton, tol 1e-10"]
    for k, v in late.items():
        report(f"corner swing amplitude in the 2nd second, {k} / converged", v / ref)
    print(f"  wrote {DOCS_IMG}/accuracy.csv, frontier.png, damping.png")
