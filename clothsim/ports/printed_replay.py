"""A printed start's effect on a step, measured by replaying the step.

:mod:`clothsim.ports.precision` bounds the effect of a port's printed x_k and v_k on the
step's answer by the rounding itself, which holds for a step that contracts its start
(local/global iterations, a converged minimizer). An accelerated solver stopped after a
fixed number of iterations (Anderson, L-BFGS, Chebyshev) is a nonlinear function of its
start and can move its answer more: :func:`replayed_tolerance` replays clothsim's step
from the start moved by the printed rounding and takes the spread of the answers
(docs/ports.md, "Printed precision").
"""

from __future__ import annotations

import numpy as np

#: Sign patterns of the printed rounding a failing step is replayed from (seeds 0, 1, ...).
PATTERNS = 4
#: Safety factor over the replayed spread: the printed rounding is one pattern among many,
#: and a few sign patterns sample the directions the step amplifies, not the worst one
#: (benchmarks/replay_spread.py prints the spread of 4 and of 32 patterns, and of uniform
#: draws in the rounding's range, beside the port's error).
SPREAD_MARGIN = 2.0

def moved_starts(x, v, unit_x: float, unit_v: float, h: float, x_before=None, *,
                 patterns: int = PATTERNS, signs: bool = True, solids=()) -> list:
    """The port's start moved by its printed rounding, in ``patterns`` patterns.

    Each coordinate c of x_k (and of v_k) is moved by ± u |c| (seeds 0, 1, ...), or by a
    uniform draw in [−u |c|, u |c|]. A right port's start is never strictly inside a solid
    (contact leaves every vertex on or outside it): a vertex the move puts inside one of
    ``solids`` that was not inside as read is moved the other way (a vertex on a box's top
    face, printed exactly as 0.5, rounds upwards), or not at all if that is inside too.

    Parameters
    ----------
    x, v : ndarray, shape (n, 3)
        The port's x_k [m] and v_k [m/s] as read.
    unit_x, unit_v : float
        Relative rounding of the positions and of the velocities.
    h : float
        Time step [s].
    x_before : ndarray, shape (n, 3), optional
        x_{k−1} [m] when the velocities are derived, v_k = (x_k − x_{k−1}) / h.
    patterns : int, default :data:`PATTERNS`
    signs : bool, default True
    solids : sequence of Obstacle
        Their :meth:`inside` keeps the moved starts out of them.

    Returns
    -------
    list of (ndarray, ndarray)
        The moved (x_k, v_k), one per pattern.
    """
    x, v = np.asarray(x, np.float64), np.asarray(v, np.float64)
    inside = [ob.inside(x) for ob in solids]
    out = []
    for seed in range(patterns):
        rng = np.random.default_rng(seed)

        def draw(shape, rng=rng):
            return rng.choice((-1.0, 1.0), shape) if signs else rng.uniform(-1.0, 1.0, shape)

        dx = unit_x * np.abs(x) * draw(x.shape)
        for ob, was in zip(solids, inside):
            for flip in (-1.0, 0.0):   # the other way; else not moved
                into = ob.inside(x + dx) & ~was
                dx[into] *= flip
        if x_before is None:
            dv = unit_v * np.abs(v) * draw(v.shape)
        else:
            dv = (dx - unit_x * np.abs(x_before) * draw(x.shape)) / h
        out.append((x + dx, v + dv))
    return out


def spread_tolerance(restart, starts, x_answer, x_port, unit_x: float) -> float:
    """:data:`SPREAD_MARGIN` × the largest distance of a replayed answer from ``x_answer``,
    plus the answer's own rounding √3 u max|x_{k+1}| [m] (:func:`replayed_tolerance`).

    Parameters
    ----------
    restart : callable
        (x, v) -> clothsim's x_{k+1} from that start.
    starts : list of (ndarray, ndarray)
        The moved starts (:func:`moved_starts`).
    x_answer, x_port : ndarray, shape (n, 3)
        clothsim's x_{k+1} from the start as read, and the port's [m].
    unit_x : float
        Relative rounding of the positions.

    Returns
    -------
    float
        Tolerance [m].
    """
    spread = 0.0
    for xm, vm in starts:
        moved = np.linalg.norm(restart(xm, vm) - x_answer, axis=1)
        spread = max(spread, float(np.nan_to_num(moved, nan=np.inf).max()))
    return (SPREAD_MARGIN * spread
            + np.sqrt(3.0) * unit_x * float(np.abs(np.asarray(x_port)).max()))


def replayed_tolerance(restart, x, v, x_answer, x_port, unit_x: float, unit_v: float,
                       h: float, x_before=None, *, patterns: int = PATTERNS,
                       signs: bool = True, solids=()) -> float:
    """The printed-precision tolerance [m] of one step, its start term measured by replay.

    The port's start (x_k, v_k) is known to within its printed rounding, u |c| per
    coordinate. clothsim's step is replayed from the start moved by ± u |c| in each
    coordinate (:data:`PATTERNS` sign patterns drawn from seeds 0, 1, ...;
    :func:`moved_starts`); the largest distance of a replayed answer from ``x_answer``
    (the step from the start as read), times :data:`SPREAD_MARGIN`, bounds the start's
    effect for whatever the solver is. The answer's own rounding, √3 u max|x_{k+1}|, is
    added.

    Parameters
    ----------
    restart : callable
        (x, v) -> clothsim's x_{k+1} from that start, the step's settings and contact planes
        unchanged.
    x, v : ndarray, shape (n, 3)
        The port's x_k [m] and v_k [m/s] as read.
    x_answer : ndarray, shape (n, 3)
        clothsim's x_{k+1} from (x, v) [m].
    x_port : ndarray, shape (n, 3)
        The port's x_{k+1} [m].
    unit_x, unit_v : float
        Relative rounding of the positions and of the velocities (:func:`unit`).
    h : float
        Time step [s].
    x_before : ndarray, shape (n, 3), optional
        x_{k−1} [m] when the velocities are derived, v_k = (x_k − x_{k−1}) / h (its
        rounding then moves v_k); None for stored velocities, or v_k = 0 at frame 0.
    patterns : int, default :data:`PATTERNS`
        Perturbations replayed (seeds 0 to ``patterns`` − 1).
    signs : bool, default True
        Each coordinate moved by ± u |c|; False: by a uniform draw in [−u |c|, u |c|], as
        rounding is (benchmarks/replay_spread.py compares the two).
    solids : sequence of Obstacle
        The moved starts are kept out of them (:func:`moved_starts`).

    Returns
    -------
    float
        Tolerance [m].
    """
    starts = moved_starts(x, v, unit_x, unit_v, h, x_before, patterns=patterns, signs=signs,
                          solids=solids)
    return spread_tolerance(restart, starts, x_answer, x_port, unit_x)
