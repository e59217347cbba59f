"""Damping and energy curves: one run per setting, labelled, equal to a direct run."""

from __future__ import annotations

import numpy as np

from clothsim import accuracy as acc
from clothsim.gallery import curtain


def factory(method, h, iterations, tolerance):
    return curtain(5, method=method, h=h, iterations=iterations, tolerance=tolerance)


SETTINGS = [("local-global", 3, None), ("newton", 50, 1e-10)]


def test_damping_curves_are_the_runs_heights():
    curves = acc.damping_curves(factory, h=1 / 30, frames=6, frame_time=1 / 30,
                                settings=SETTINGS, vertex=0)
    assert list(curves) == ["local-global, 3 it", "newton, tol 1e-10"]
    direct = acc.run_trajectory(factory("local-global", 1 / 30, 3, None), frames=6,
                                frame_time=1 / 30)
    np.testing.assert_array_equal(curves["local-global, 3 it"], direct.frames[:, 0, 1])
    assert all(c.shape == (7,) for c in curves.values())
    assert curves["newton, tol 1e-10"][-1] < curves["newton, tol 1e-10"][0]  # the corner falls


def test_energy_curves_lose_energy_and_keep_the_reference():
    ref = np.linspace(1.0, 0.5, 7)
    curves = acc.energy_curves(factory, h=1 / 30, frames=6, frame_time=1 / 30,
                               settings=SETTINGS, reference=ref)
    assert list(curves) == ["local-global, 3 it", "newton, tol 1e-10",
                            "reference (small h, converged)"]
    np.testing.assert_array_equal(curves["reference (small h, converged)"], ref)
    for label in ("local-global, 3 it", "newton, tol 1e-10"):
        e = curves[label]
        assert e.shape == (7,) and e[-1] < e[0]   # implicit Euler only removes energy
