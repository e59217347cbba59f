"""Gravity: a uniform acceleration field, f_i = m_i g."""

from __future__ import annotations

from ..errors import InputError, check_finite
from .base import Effect


class Gravity(Effect):
    """Uniform gravity.

    Parameters
    ----------
    acceleration : (3,) array_like, default (0, −9.81, 0)
        g [m/s²].
    """

    kind = "gravity"

    def __init__(self, acceleration=(0.0, -9.81, 0.0)):
        g = check_finite("gravity.acceleration", acceleration)
        if g.shape != (3,):
            raise InputError(f"gravity.acceleration: expected 3 numbers, got shape {g.shape}")
        self.acceleration = g

    def bind(self, model, h):
        super().bind(model, h)
        self._force = model.vertex_mass[:, None] * self.acceleration[None, :]

    def add_force(self, t, state, f):
        f += self._force

    def describe(self):
        return {"kind": self.kind, "acceleration": self.acceleration.tolist()}
