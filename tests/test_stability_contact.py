"""Tunnelling through a small sphere inside a running simulation.

tests/test_effects.py checks the obstacles' continuous detection directly (a thin slab and a
small sphere, 5 thicknesses per step) and a cloth falling onto the thin slab. This adds the
small sphere in a simulation: a 6 × 6 cloth (spacing 0.01 m) falls at 3 m/s, i.e. 0.1 m per
step of h = 1/30 s, onto a sphere of radius R = 0.01 m (5 diameters per step). The step that
crosses the sphere ends 0.04 m below its centre, past it, so an end-point test sees nothing;
the vertices whose paths cross it must stop on the upper side, and no vertex may end any step
inside.
"""

from __future__ import annotations

import numpy as np
import pytest

from benchmarks.measure_stability import SPHERE_RADIUS as R
from benchmarks.measure_stability import measure_sphere_tunnelling


@pytest.mark.parametrize("friction", [0.0, 1.0])
def test_small_sphere_no_tunnelling_in_simulation(friction):
    """Measured: the 4 centre vertices are caught on step 1 and end on the surface (gap
    ~1e-17 m) where the free cloth ends at y = −0.051 m, 5 radii below the centre; with
    μ = 1 they stick at the entry point y = R/√2; max depth over 8 steps −7e-18 m."""
    r = measure_sphere_tunnelling(friction)
    assert r["max_depth"] <= 1e-9
    assert sorted(r["caught"].tolist()) == [14, 15, 20, 21]     # the 4 centre vertices
    assert r["contacts"][0] == 4                                # caught on the first step
    assert r["would_end"] < -R                # without the sphere they end below it
    assert np.all(r["caught_gap"] >= 0) and np.all(r["caught_gap"] <= 1e-12)   # held on it
    if friction >= 1.0:                       # sticking: exactly at the entry point
        assert r["caught_height"] == pytest.approx(R / np.sqrt(2), abs=1e-12)
