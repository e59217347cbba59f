"""Naming a blow-up: which effect's force, or which vertices of the new state, stopped being
finite in a step (the messages of :class:`~clothsim.errors.NonFiniteStateError` that
:meth:`clothsim.simulation.Simulation.step` raises; the solver names a gradient that
overflows from the step's start, :func:`clothsim.solvers.base.overflow_cause`)."""

from __future__ import annotations

import numpy as np

from .state import State


def force_cause(force_effects, s: State) -> str:
    """Which effect's force is not finite in the step from ``s``, and the state's size.

    Parameters
    ----------
    force_effects : sequence of Effect
        The effects with an ``add_force`` hook, in the order the step calls them.
    s : State
        Start of the step.

    Returns
    -------
    str
        E.g. "the external forces became non-finite in the step from t = 0.1 s: wind's
        force on vertex 0 is [nan, nan, nan] (|x| up to ... m, |v| up to ... m/s)".
    """
    with np.errstate(all="ignore"):
        size = (f"|x| up to {float(np.abs(s.positions).max()):.3g} m, |v| up to "
                f"{float(np.abs(s.velocities).max()):.3g} m/s")
        for e in force_effects:
            f = np.zeros_like(s.positions)
            e.add_force(s.time, s, f)
            if not np.isfinite(f).all():
                i = int(np.flatnonzero(~np.isfinite(f).all(axis=1))[0])
                return (f"the external forces became non-finite in the step from t = "
                        f"{s.time:.6g} s: {e.kind}'s force on vertex {i} is "
                        f"{f[i].tolist()} ({size})")
    return f"the external forces became non-finite in the step from t = {s.time:.6g} s"


def state_cause(x: np.ndarray, v: np.ndarray, t: float) -> str | None:
    """How many vertices of the new state (positions ``x``, velocities ``v``) are not
    finite, and the first; None when every one is.

    Parameters
    ----------
    x, v : ndarray, shape (n, 3)
        The step's new positions [m] and velocities [m/s].
    t : float
        Time at the start of the step [s].

    Returns
    -------
    str or None
    """
    bad = ~(np.isfinite(x).all(axis=1) & np.isfinite(v).all(axis=1))
    if not bad.any():
        return None
    return (f"the state became non-finite at {int(bad.sum())} of {len(bad)} vertices "
            f"(first: {int(np.flatnonzero(bad)[0])}) in the step from t = {t:.6g} s")
