"""What a simulation advances and what each step reports: :class:`State` (positions,
velocities, time) and :class:`StepRecord` (iterations, residual, seconds)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .errors import InputError, check_finite

__all__ = ["State", "StepRecord"]


@dataclass
class State:
    """Positions and velocities at one time.

    Attributes
    ----------
    positions : ndarray, shape (n, 3)  [m]
    velocities : ndarray, shape (n, 3)  [m/s]
    time : float  [s]
    step : int
        Steps taken since the start.
    """

    positions: np.ndarray
    velocities: np.ndarray
    time: float = 0.0
    step: int = 0

    def __post_init__(self):
        x = check_finite("state.positions", self.positions)
        if x.ndim != 2 or x.shape[1] != 3:
            raise InputError(f"state.positions: expected shape (n, 3), got {x.shape}")
        v = check_finite("state.velocities", self.velocities)
        if v.shape != x.shape:
            raise InputError(f"state.velocities: expected shape {x.shape} like the positions, "
                             f"got {v.shape}")
        self.positions, self.velocities = x, v
        self.time = float(check_finite("state.time", self.time))

    def copy(self) -> State:
        """An independent copy (positions and velocities copied).

        Returns
        -------
        State
        """
        return State(self.positions.copy(), self.velocities.copy(), self.time, self.step)


@dataclass
class StepRecord:
    """What one step did: solver iterations, final relative residual, wall seconds.

    Attributes
    ----------
    iterations : int
        Solver iterations done.
    residual : float
        Final relative residual ‖∇g(x_k)‖ / ‖∇g(x_0)‖ (dimensionless).
    seconds : float
        Wall time of the whole step [s].
    converged : bool or None
        True or False when the solver had a tolerance (met or missed), None ("not
        checked") for a fixed iteration count.
    residual_history : list of float
        Relative residual at each iterate, from k = 0 (the initial guess: 1, or 0 when it
        is already the solution).
    """

    iterations: int
    residual: float
    seconds: float
    converged: bool | None = None
    residual_history: list[float] = field(default_factory=list)
