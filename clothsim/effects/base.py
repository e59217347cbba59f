"""The effect protocol: how a declared effect takes part in a time step.

An effect overrides only the hooks it needs; :class:`~clothsim.simulation.Simulation`
calls only overridden hooks, so an effect that a scene does not declare costs nothing and
the hooks of a declared one are the only extra work. One step from t to t + h runs:

1. ``add_force(t, state, f)``        add external forces f (n, 3) [N] (gravity, wind, …)
2. ``adjust_target(t, state, y, h)``  change the inertial target y (inertial damping)
3. ``pins(t + h)``                    exact pins and penalty anchors for the step
4. the solver minimizes g(x)
5. ``correct_positions(t + h, state, x, h)``  move x after the solve (collisions, strain)
6. velocities v = (x − x_n) / h, then ``correct_velocities(t + h, state, x, v, h)``
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

_EMPTY_I = np.zeros(0, np.int64)
_EMPTY_X = np.zeros((0, 3))


@dataclass
class PinSet:
    """Pins active during one step (see :class:`~clothsim.solvers.StepProblem`)."""

    fixed_vertices: np.ndarray = field(default_factory=lambda: _EMPTY_I)
    fixed_positions: np.ndarray = field(default_factory=lambda: _EMPTY_X)
    anchor_vertices: np.ndarray = field(default_factory=lambda: _EMPTY_I)
    anchor_positions: np.ndarray = field(default_factory=lambda: _EMPTY_X)
    anchor_stiffness: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @staticmethod
    def merge(parts: list[PinSet]) -> PinSet:
        if len(parts) == 1:
            return parts[0]
        cat = np.concatenate
        return PinSet(
            cat([p.fixed_vertices for p in parts]), cat([p.fixed_positions for p in parts]),
            cat([p.anchor_vertices for p in parts]), cat([p.anchor_positions for p in parts]),
            cat([p.anchor_stiffness for p in parts]))


class Effect:
    """Base class of effects. Subclasses set ``kind`` and override hooks.

    ``bind(model, h)`` is called once by the simulation before the first step, to check
    the effect against the model and precompute what it needs.
    """

    kind = "effect"

    def bind(self, model, h: float) -> None:
        self.model = model
        self.h = h

    def add_force(self, t: float, state, f: np.ndarray) -> None:
        raise NotImplementedError

    def adjust_target(self, t: float, state, y: np.ndarray, h: float) -> np.ndarray:
        raise NotImplementedError

    def pins(self, t: float) -> PinSet:
        raise NotImplementedError

    def correct_positions(self, t: float, state, x: np.ndarray, h: float) -> np.ndarray:
        raise NotImplementedError

    def correct_velocities(self, t: float, state, x: np.ndarray, v: np.ndarray,
                           h: float) -> np.ndarray:
        raise NotImplementedError

    def describe(self) -> dict:
        """JSON-ready description of the effect as built (for run.json)."""
        return {"kind": self.kind}


HOOKS = ("add_force", "adjust_target", "pins", "correct_positions", "correct_velocities")


def overrides(effect: Effect, hook: str) -> bool:
    """True when ``effect`` implements ``hook`` (the simulation calls only those)."""
    return getattr(type(effect), hook) is not getattr(Effect, hook)
