"""Step problems shared by the solver tests (built from clothsim.gallery)."""

from __future__ import annotations

import warnings

import numpy as np

import clothsim as cs
from clothsim import gallery
from clothsim.simulation import State


def convex_step(n: int = 6):
    """A mid-swing step of a stretched curtain at h = 1/120: H ≻ 0 everywhere relevant."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sim = gallery.curtain(n, k=800.0, h=1 / 120, method="newton", tolerance=1e-10,
                              iterations=100)
        sim.run(6)
    return sim.model, sim.problem()


def buckling_step(n: int = 9, frames: int = 12):
    """The paper's sheet held at two corners (horizontal, h = 1/30) after it has fallen."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sim = gallery.curtain(n, k=1000.0, plane="xz", method="newton", tolerance=1e-10,
                              iterations=100)
        sim.run(frames)
    return sim.model, sim.problem()


def two_minima_simulation(n: int = 7, seed: int = 1, amplitude: float = 1e-2):
    """A vertical 7 × 7 flag pinned along its left edge with a small random out-of-plane
    velocity: its second step has two minima (Newton from y and converged local/global end
    5.6e-7 J·s² apart in g, both with H ≻ 0)."""
    model = gallery.grid_cloth(n, k=800.0, bending=20.0, plane="xy", center=(0.0, 1.5, 0.0))
    left = [i for i in range(n * n) if i % n == 0]
    v = np.zeros((n * n, 3))
    v[:, 2] = amplitude * np.random.default_rng(seed).standard_normal(n * n)
    return cs.Simulation(model, h=1 / 30, solver="newton", tolerance=1e-10, iterations=100,
                         effects=[cs.Gravity(gallery.GRAVITY), cs.Pin(left)],
                         state=State(model.mesh.vertices.copy(), v))
