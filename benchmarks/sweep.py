"""Trajectory accuracy against wall time on the swinging sheet, and the energy figure.

Scene (``benchmarks.swing``): 11 × 11, 1 m × 1 m, 1 kg horizontal sheet hinged along one
edge (k = 800 N/m structural and shear, 80 N/m bending), released from rest; it swings
down like a pendulum for 6 frames (0.2 s at 30 fps), its free edge falling about 0.2 m
(over 0.5 s, as it folds, the converged error's slope against h drops to 0.8: pre-asymptotic).
Configurations: h ∈ {1/30, 1/60, 1/120, 1/240} × local/global and Chebyshev at 1 … 100
iterations per step, Newton at 1 … 10, plus symplectic Euler at its stable step.
Reference: Newton to a relative residual of 1e-10 at h = 1/3840 and 1/1920,
Richardson-extrapolated (``clothsim.accuracy.reference_trajectory``). Error: positions at
every frame against the reference, ‖X − X_ref‖ / ‖X_ref − X_0‖.

Writes docs/data/accuracy.csv, docs/img/frontier.png, convergence.png, damping.png and
prints the cheapest configuration per accuracy level, the log-log slopes against h and
the energy figures (ratios).
"""

from __future__ import annotations

import math
import platform
import time

from clothsim.accuracy import (
    ACCURACY_LEVELS,
    TRAJECTORY_LEVELS,
    cheapest,
    convergence_slope,
    energy_curves,
    plot_convergence,
    plot_damping,
    plot_frontier,
    reference_trajectory,
    run_sweep,
    write_csv,
)

from . import DOCS_IMG, ROOT, report, swing_factory

GRID = 11
STIFFNESS = 800.0
FRAME = 1 / 30
FRAMES = 6
TIME_STEPS = (FRAME, FRAME / 2, FRAME / 4, FRAME / 8)
REFERENCE_H = FRAME / 128
DOCS_DATA = ROOT / "docs" / "data"


def main() -> None:
    factory = swing_factory(GRID, stiffness=STIFFNESS, bending=STIFFNESS / 10)
    t0 = time.perf_counter()
    reference, ref_err = reference_trajectory(factory, h=REFERENCE_H, frames=FRAMES,
                                              frame_time=FRAME)
    print(f"  scene: {GRID}x{GRID} swinging sheet, k={STIFFNESS:g} N/m, {FRAMES} frames; "
          f"{platform.node()} {platform.processor() or platform.machine()}")
    report("reference h=1/3840: relative error estimate before extrapolation", ref_err, ".2e")
    report("reference time [s]", time.perf_counter() - t0, ".1f")
    rows = run_sweep(factory, time_steps=TIME_STEPS, frame_time=FRAME, frames=FRAMES,
                     iterations=(1, 2, 5, 10, 20, 50, 100),
                     newton_iterations=(1, 2, 3, 5, 10), reference=reference, progress=True)
    DOCS_DATA.mkdir(parents=True, exist_ok=True)
    DOCS_IMG.mkdir(parents=True, exist_ok=True)
    write_csv(rows, DOCS_DATA / "accuracy.csv")
    title = f"{GRID}×{GRID} swinging sheet, {FRAMES * FRAME:.2g} s"
    plot_frontier(rows, DOCS_IMG / "frontier.png",
                  title=f"{title}: accuracy against wall time per frame")
    plot_convergence(rows, DOCS_IMG / "convergence.png",
                     title=f"{title}: trajectory error against h")
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
    for method, its in (("newton", 10), ("newton", 3), ("chebyshev", 100), ("chebyshev", 20),
                        ("local-global", 100), ("local-global", 10), ("local-global", 1)):
        report(f"log-log slope of trajectory error vs h, {method} {its} it (implicit Euler: 1)",
               convergence_slope(rows, method=method, iterations=its), ".2f")
    by = {(r.method, round(1 / r.h) if math.isfinite(r.h) else 0, r.iterations): r
          for r in rows}
    conv = [by["newton", round(1 / h), 10].trajectory_error for h in TIME_STEPS]
    print("  newton 10 it trajectory error at h=1/30..1/240: "
          + ", ".join(f"{e:.3e}" for e in conv))
    report("trajectory error ratio h=1/30 / h=1/240 (Newton 10 it; first order: 8)",
           conv[0] / conv[-1])
    for its in (1, 2, 5, 10, 20):
        report(f"h=1/30 trajectory error ratio local-global {its} it / Newton 10 it",
               by["local-global", 30, its].trajectory_error / conv[0])
    se = [r for r in rows if r.method == "symplectic-euler"][0]
    report(f"symplectic Euler (h=1/{round(1 / se.h)}) trajectory error", se.trajectory_error,
           ".3e")
    report("symplectic Euler / local-global 10 it h=1/30 cost-per-frame ratio",
           se.seconds_per_frame / by["local-global", 30, 10].seconds_per_frame)
    # energy: what truncated iterations do to the motion (implicit Euler's damping shown)
    ref_sim = factory("newton", REFERENCE_H, 50, 1e-10)
    from clothsim.accuracy import run_trajectory
    ref_energy = run_trajectory(ref_sim, frames=FRAMES, frame_time=FRAME,
                                record_energy=True).energy
    curves = energy_curves(factory, h=FRAME, frames=FRAMES, frame_time=FRAME,
                           settings=[("local-global", 1, None), ("local-global", 3, None),
                                     ("local-global", 10, None), ("newton", 50, 1e-10)],
                           reference=ref_energy)
    plot_damping(DOCS_IMG / "damping.png", cloth_curves=curves, frame_time=FRAME,
                 cloth_title=f"{GRID}×{GRID} swinging sheet, h = 1/30 s: total energy")
    e0 = curves["newton, tol 1e-10"][0]
    ref_loss = e0 - ref_energy[-1]
    for label, e in curves.items():
        report(f"energy lost in {FRAMES * FRAME:.2g} s, {label} [J]", e0 - e[-1], ".4f")
        report(f"energy lost in {FRAMES * FRAME:.2g} s, {label} / reference",
               (e0 - e[-1]) / ref_loss, ".3g")
    print(f"  wrote {DOCS_DATA / 'accuracy.csv'}, {DOCS_IMG}/frontier.png, convergence.png, "
          "damping.png")
