"""A push on a disk of cloth: the student report's second demo (an upward force on a circle).

The total force F [N] is shared by the selected vertices in proportion to their mass,

    f_i = F m_i / m_disk,   m_disk = Σ_{i in disk} m_i,

so every selected vertex gets the same acceleration F / m_disk and, without springs, the
disk's centre of mass accelerates by exactly F / m_disk. The selection is made once, from
the *initial* positions: the vertices within ``radius`` of ``center`` (a ball, so for a
flat cloth through ``center`` it is a disk). The force is constant while
start ≤ t < start + duration, t being the time at the start of a step (implicit Euler
holds f constant over the step).
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import InputError, check_finite
from .base import Effect


class Impulse(Effect):
    """Constant external force on the vertices initially within a ball.

    Parameters
    ----------
    center : (3,) array_like
        Centre of the selection ball [m].
    radius : float
        Its radius [m], > 0.
    force : (3,) array_like
        Total force F on the selected vertices [N], shared in proportion to mass.
    start : float, default 0
        Time the force switches on [s], >= 0.
    duration : float, default inf
        How long it acts [s], > 0 (inf: for ever).

    Attributes
    ----------
    vertices : ndarray, shape (k,), int
        Selected vertices (after :meth:`bind`).
    vertex_force : ndarray, shape (k, 3)
        f_i [N] of each selected vertex.
    """

    kind = "impulse"

    def __init__(self, center, radius, force, *, start: float = 0.0,
                 duration: float = math.inf):
        c = check_finite("impulse.center", center)
        if c.shape != (3,):
            raise InputError(f"impulse.center: expected 3 numbers, got shape {c.shape}")
        r = check_finite("impulse.radius", radius)
        if r.ndim != 0 or r <= 0:
            raise InputError(f"impulse.radius: must be one positive number, got "
                             f"{np.asarray(radius).tolist()!r}")
        f = check_finite("impulse.force", force)
        if f.shape != (3,):
            raise InputError(f"impulse.force: expected 3 numbers, got shape {f.shape}")
        t0 = check_finite("impulse.start", start)
        if t0.ndim != 0 or t0 < 0:
            raise InputError(f"impulse.start: must be one non-negative number, "
                             f"got {np.asarray(start).tolist()!r}")
        try:
            dt = float(duration)
        except (TypeError, ValueError):
            raise InputError(f"impulse.duration: must be a number, got {duration!r}") from None
        if not dt > 0:
            raise InputError(f"impulse.duration: must be positive (inf allowed), got {dt!r}")
        self.center, self.radius, self.force = c, float(r), f
        self.start, self.duration = float(t0), dt
        self.vertices = np.zeros(0, np.int64)
        self.vertex_force = np.zeros((0, 3))

    def bind(self, model, h):
        super().bind(model, h)
        q = model.mesh.vertices - self.center
        self.vertices = np.flatnonzero(np.einsum("ij,ij->i", q, q) <= self.radius ** 2)
        if len(self.vertices) == 0:
            raise InputError(f"impulse.radius: no vertex lies within {self.radius!r} m of "
                             f"impulse.center {self.center.tolist()}")
        m = model.vertex_mass[self.vertices]
        if not m.sum() > 0:  # shared in proportion to mass: 0/0 would be NaN forces
            raise InputError(f"impulse.radius: every vertex within {self.radius!r} m of "
                             f"impulse.center {self.center.tolist()} has mass 0 (pinned "
                             f"exactly), so the force, shared in proportion to mass, has no "
                             f"vertex to act on", field="impulse.radius")
        self.vertex_force = (m / m.sum())[:, None] * self.force

    def active(self, t: float) -> bool:
        """Whether the push acts at time t: start ≤ t < start + duration.

        Parameters
        ----------
        t : float
            Time at the start of the step [s].

        Returns
        -------
        bool
        """
        return self.start <= t < self.start + self.duration

    def add_force(self, t, state, f):
        if self.active(t):
            f[self.vertices] += self.vertex_force

    def describe(self):
        return {"kind": self.kind, "center": self.center.tolist(), "radius": self.radius,
                "force": self.force.tolist(), "start": self.start,
                "duration": None if math.isinf(self.duration) else self.duration,
                "vertex_count": int(len(self.vertices))}
