"""Step problems shared by the solver tests (built from clothsim.gallery)."""

from __future__ import annotations

import warnings

from clothsim import gallery


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
