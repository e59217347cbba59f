"""An impulse on another disk: its radius read off which vertices the port pushed.

clothsim's ``impulse`` shares its total force F among the vertices initially within its
radius, in proportion to their mass (:class:`clothsim.effects.impulse.Impulse`). A port
whose disk is wider pushes more vertices, each less: a force that differs on a ring of
vertices and, less, on the whole disk, which neither a few parameters nor a force confined
to some vertices (:mod:`clothsim.ports.force_field`) reproduces; the step was left
UNDECIDED ("start-dependent: the port iterates otherwise").

The radius only matters through the set of vertices it selects, and those sets are few:
the vertices' initial distances from the disk's centre, sorted, bound them. Each set
nearest the scene's (:data:`SIDE` on each side, fewest vertices changed first) is
replayed, F shared among its vertices as the impulse shares it; the one that reproduces the
port's first two failing steps (a step at which the impulse acts) is named, with the range
of radii that selects it.
"""

from __future__ import annotations

import numpy as np

from .force_field import reproduced
from .replays import replay

__all__ = ["impulse_cause"]

#: Sets of vertices tried on each side of the scene's (a smaller and a larger disk).
SIDE = 6


def _share(effect, model, vertices) -> np.ndarray:
    """The force (n, 3) [N] the impulse puts on ``vertices``, F shared by mass."""
    f = np.zeros((model.vertex_count, 3))
    m = model.vertex_mass[vertices]
    if len(vertices) and m.sum() > 0:
        f[vertices] = (m / m.sum())[:, None] * effect.force
    return f


def _candidates(effect, model):
    """(radius range, vertices) of the disks nearest the scene's, nearest first."""
    d = np.linalg.norm(model.mesh.vertices - effect.center, axis=1)
    scale = max(float(d.max()), 1e-300)   # distances equal but for their rounding are one
    levels = np.unique(np.round(d / (1e-9 * scale))) * (1e-9 * scale)
    d = np.round(d / (1e-9 * scale)) * (1e-9 * scale)
    inside = int(np.searchsorted(levels, effect.radius * (1 + 1e-9), side="right"))
    out = []
    for j in range(max(1, inside - SIDE), min(len(levels), inside + SIDE) + 1):
        if j == inside:
            continue
        low = float(levels[j - 1])
        high = float(levels[j]) if j < len(levels) else np.inf
        out.append((abs(j - inside), (low, high), np.flatnonzero(d <= low)))
    return [(span, which) for _, span, which in sorted(out, key=lambda c: c[0])]


def impulse_cause(steps, reproduces, fitted: int = 2):
    """An impulse of another radius whose replays reproduce the fitted steps.

    Parameters
    ----------
    steps : list of StepData
        The failing steps (their :attr:`~clothsim.ports.hypotheses.StepData.effects` and
        ``time``): the first is fitted, the first ``fitted`` must be reproduced, the later
        ones are replayed and explained when reproduced.
    reproduces : callable
        ``reproduces(step, distance) -> bool``.
    fitted : int, default 2

    Returns
    -------
    (str, str, dict) or None
        The impulse in words, the hypothesis' name and step k → the replay's distance [m]
        of the steps it reproduces.
    """
    first = steps[0]
    impulses = [(i, e) for i, e in enumerate(first.effects) if e.kind == "impulse"
                and e.active(first.time)]
    for index, e in impulses:
        scene = _share(e, first.model, e.vertices)
        for (low, high), which in _candidates(e, first.model):
            change = _share(e, first.model, which) - scene
            if not reproduces(first, replay(first, "force field", change)):
                continue
            d = reproduced(steps, fitted, reproduces, lambda s, which=which, e=e: replay(
                s, "force field", _share(e, s.model, which) - _share(e, s.model, e.vertices))
                if e.active(s.time) else np.inf)
            if d is not None:
                bound = (f"between {low:.4g} and {high:.4g} m" if np.isfinite(high)
                         else f"of at least {low:.4g} m")
                return (f"an impulse (effects[{index}]) on a disk of radius {bound} instead "
                        f"of {e.radius:g} m ({len(which)} vertices pushed, not "
                        f"{len(e.vertices)}; look at effects[{index}].radius)",
                        "impulse", d)
    return None
