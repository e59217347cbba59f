"""The effect protocol: how a declared effect takes part in a time step.

An effect overrides only the hooks it needs (:data:`HOOKS`);
:class:`~clothsim.simulation.Simulation` calls only overridden hooks, so an effect that a
scene does not declare costs nothing and the hooks of a declared one are the only extra
work. The simulation first calls :meth:`Effect.bind` once (it stores ``self.model`` and the
time step ``self.h``: hooks read h from there), then ``connect_pins`` on effects that
need to know which vertices are pinned. One step from t to t + h runs:

1. ``add_force(t, state, f)``                add external forces f (n, 3) [N]
2. ``adjust_target(t, state, y) -> y``       change the inertial target y (damping)
3. ``pins(t + h) -> PinSet``                  exact pins and penalty anchors for the step
4. the solver minimizes g(x)
5. ``correct_positions(t + h, state, x) -> x``    move x after the solve (collisions, …)
6. v = (x − x_n) / h, then ``correct_velocities(t + h, state, x, v) -> v``

An effect instance belongs to one simulation: binding it to a second one is an
:class:`~clothsim.errors.InputError` (it keeps per-run data such as contacts).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..problem import PinSet

#: Every hook an effect may override, in the order a step calls them (``connect_pins``
#: is called once, after :meth:`Effect.bind`).
HOOKS = ("add_force", "adjust_target", "pins", "correct_positions", "correct_velocities",
         "connect_pins")


class Effect:
    """Base class of effects. Subclasses set ``kind`` and override the hooks they need.

    Attributes
    ----------
    kind : str
        The scene's name of the effect.
    model : Model
        The model, set by :meth:`bind`.
    h : float
        The time step [s], set by :meth:`bind`; hooks read it from here.
    """

    kind = "effect"
    _simulation = None  # the Simulation this instance is bound to (one only)

    def bind(self, model, h: float) -> None:
        """Check the effect against ``model`` and precompute what it needs.

        Called once by the simulation before the first step. Subclasses call
        ``super().bind(model, h)`` first.

        Parameters
        ----------
        model : Model
        h : float
            Time step [s].
        """
        self.model = model
        self.h = h

    def add_force(self, t: float, state, f: np.ndarray) -> None:
        """Add this effect's external force to ``f`` in place.

        Parameters
        ----------
        t : float
            Time at the start of the step [s].
        state : State
            The state x_n, v_n at time t.
        f : ndarray, shape (n, 3)
            Force accumulator [N]; add to it, never replace it.
        """
        raise NotImplementedError

    def adjust_target(self, t: float, state, y: np.ndarray) -> np.ndarray:
        """Return a changed inertial target y (do not modify ``y`` in place).

        Parameters
        ----------
        t : float
            Time at the start of the step [s].
        state : State
            The state at time t.
        y : ndarray, shape (n, 3)
            Inertial target so far [m] (x_n + h v_n before any adjustment).

        Returns
        -------
        ndarray, shape (n, 3)
        """
        raise NotImplementedError

    def pins(self, t: float) -> PinSet:
        """The pins active in the step ending at time ``t`` [s].

        Returns
        -------
        PinSet
        """
        raise NotImplementedError

    def correct_positions(self, t: float, state, x: np.ndarray) -> np.ndarray:
        """Return corrected end-of-step positions (do not modify ``x`` in place).

        Parameters
        ----------
        t : float
            Time at the end of the step [s].
        state : State
            The state at the start of the step.
        x : ndarray, shape (n, 3)
            Positions after the solve (and earlier corrections) [m].

        Returns
        -------
        ndarray, shape (n, 3)
        """
        raise NotImplementedError

    def correct_velocities(self, t: float, state, x: np.ndarray,
                           v: np.ndarray) -> np.ndarray:
        """Return corrected end-of-step velocities (do not modify ``v`` in place).

        Parameters
        ----------
        t : float
            Time at the end of the step [s].
        state : State
            The state at the start of the step.
        x : ndarray, shape (n, 3)
            Final positions of the step [m].
        v : ndarray, shape (n, 3)
            Velocities (x − x_n) / h after earlier corrections [m/s].

        Returns
        -------
        ndarray, shape (n, 3)
        """
        raise NotImplementedError

    def connect_pins(self, pinned: Callable[[float], np.ndarray]) -> None:
        """Receive the simulation's pin query (for effects that must not move pins).

        Parameters
        ----------
        pinned : callable
            ``pinned(t)`` returns the sorted vertices held by any pin (exact or penalty)
            in the step ending at time t, shape (p,), int.
        """
        raise NotImplementedError

    def describe(self) -> dict:
        """JSON-ready description of the effect as built (for run.json)."""
        return {"kind": self.kind}


def overrides(effect: Effect, hook: str) -> bool:
    """True when ``effect`` implements ``hook`` (the simulation calls only those)."""
    return getattr(type(effect), hook) is not getattr(Effect, hook)


__all__ = ["HOOKS", "Effect", "PinSet", "overrides"]
