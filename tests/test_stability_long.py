"""Long run: 10⁴ steps of the built-in "flag" scene stay finite, stay
inside the scene's bounding volume, and do not get slower step after step.

The full 31 × 21 flag takes ~10 ms a step (~105 s for 10⁴ steps), so the test runs the same
scene with a coarser cloth (``cloth.resolution = [7, 5]``, ~1.5 ms a step, 10⁴ steps) and
``benchmarks/stability_figures.py`` runs the full flag with the same :func:`measure_long_run`.

Bounding volume: the flag hangs from a pole, the segment through its pinned left edge.
Every vertex starts within W = 1.5 m of that segment (the flag's width); springs hold each
vertex to the pole through a chain of cloth, so it must stay within (1 + margin) W, margin
10 % (a capsule around the pole). A blow-up, or energy pumped in by the wind that the
solver failed to bound, leaves it at once.

Trend: the CPU time of each ``Simulation.step`` (``time.process_time``), median per chunk of
500 steps, divided by the median CPU time of 50 control steps interleaved in the same chunk
(a second simulation of the scene, put back to its first state each chunk: it sees the same
machine but never runs long), Theil–Sen slope of these ratios against the step number,
relative, per 1000 steps: must stay below 5 % (a growing cache, list or matrix in the
simulation would show as a steady rise). Without the control, CPU time on this shared
2-core machine wanders by ±30 % from one chunk to the next and by 60 % over minutes.
"""

from __future__ import annotations

import numpy as np
import pytest

from benchmarks.measure_long_run import (
    measure_long_run,
    relative_trend,
    segment_distance,
)

POLE_MARGIN = 0.10          # vertices stay within (1 + margin) W of the pole
TREND_LIMIT = 0.05          # relative slope of the per-step time per 1000 steps


@pytest.mark.slow
def test_flag_ten_thousand_steps_finite_bounded_no_slowdown():
    """Coarse flag, 10⁴ steps (333 s simulated): measured max distance 1.005 W (limit
    1.1 W), normalized step-time trend < 1 % per 1000 steps (limit 5 %), t drift 5e-11 s."""
    r = measure_long_run()
    assert r["finite"] and r["steps_done"] == 10_000
    assert r["width"] == pytest.approx(1.5, rel=1e-12)     # the flag's width from the pole
    assert r["max_pole_ratio"] <= 1.0 + POLE_MARGIN
    assert r["max_pole_ratio"] > 0.9                       # it did stream out in the wind
    assert r["time_drift"] <= 1e-9
    trend = r["normalized"]
    assert trend["relative_slope_per_1000"] < TREND_LIMIT, trend["chunk_medians"]


def test_trend_detector_sees_a_growing_step_time():
    """The trend check can fail. A step cost growing by 2 % of its start per 100 steps,
    under 30 % multiplicative noise and 50 spikes of 100×, measures 9.9 % per 1000 steps
    (flagged); the same noise without growth −0.2 %. A machine that slows down 3× midway
    (another job starts) gives a raw trend of 11.9 %, cancelled by the control steps to 0.4 %,
    while the growth is still seen through the control (11.3 %)."""
    rng = np.random.default_rng(9)
    n, chunk = 10_000, 500
    noise = rng.lognormal(0.0, 0.3, n)
    noise[rng.integers(0, n, 50)] *= 100.0                  # another process took the core
    flat = 1e-3 * noise
    growing = flat * (1.0 + 2e-4 * np.arange(n))
    assert abs(relative_trend(flat, chunk)["relative_slope_per_1000"]) < 0.01
    assert relative_trend(growing, chunk)["relative_slope_per_1000"] > TREND_LIMIT
    machine = np.where(np.arange(n) < n // 2, 1.0, 3.0)     # the machine's slowdown factor
    control = (1e-3 * machine[::10] * rng.lognormal(0.0, 0.3, n // 10)).reshape(n // chunk, -1)
    assert relative_trend(flat * machine, chunk)["relative_slope_per_1000"] > TREND_LIMIT
    assert abs(relative_trend(flat * machine, chunk, control)["relative_slope_per_1000"]) < 0.01
    assert relative_trend(growing * machine, chunk, control)["relative_slope_per_1000"] \
        > TREND_LIMIT


def test_bounding_volume_detects_a_vertex_leaving():
    """segment_distance: a point 2 m beyond the pole's end is 2 m away; beside it, its offset."""
    a, b = np.array([-0.75, 1.0, 0.0]), np.array([-0.75, 2.0, 0.0])
    x = np.array([[-0.75, 4.0, 0.0], [0.75, 1.5, 0.0], [-0.75, 1.2, 0.0], [-0.75, 0.0, 1.0]])
    np.testing.assert_allclose(segment_distance(x, a, b), [2.0, 1.5, 0.0, np.sqrt(2.0)],
                               rtol=0, atol=1e-15)
