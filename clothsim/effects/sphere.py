"""A static solid ball obstacle (see :mod:`clothsim.effects.obstacles`)."""

from __future__ import annotations

import numpy as np

from ..errors import InputError, check_finite
from .obstacles import Obstacle, _rowdot, _vector3
from .thickness import auto_thickness

#: Largest sphere radius [m]: R² and the contact quadratic stay far inside float range.
MAX_RADIUS = 1e100


class Sphere(Obstacle):
    """A static solid ball.

    Parameters
    ----------
    center : (3,) array_like
        Centre c [m].
    radius : float
        R [m], > 0.
    friction : float, default 0
        Coulomb coefficient μ.
    thickness : float or "auto", default "auto"
        Contact thickness δ [m]: the cloth's vertices are held on the sphere of radius
        R + δ. ``"auto"``: √(R² + r²) − R ≈ r²/(2R), r the covering radius of the cloth's
        triangles at rest × 1.1, the least δ that provably keeps the ball out of every triangle
        (the sagitta of a chord; :func:`~clothsim.effects.thickness.auto_thickness`); 0
        in ``"post-solve"`` mode (the seed's).

    Notes
    -----
    Entry along the step x(s) = x_n + s d, s ∈ [0, 1], d = x − x_n: the smaller root of
    |x_n + s d − c|² = R², computed without cancellation as
    s = (|x_n − c|² − R²) / (−d·(x_n − c) + √disc), disc = (d·(x_n − c))² − |d|²(|x_n − c|² − R²).
    """

    kind = "sphere"

    def __init__(self, center, radius, *, friction: float = 0.0, thickness="auto",
                 contact: str = "hold"):
        super().__init__(friction, contact, thickness)
        self.center = _vector3("sphere.center", center)
        r = check_finite("sphere.radius", radius)
        if r.ndim != 0 or r <= 0:
            raise InputError(f"sphere.radius: must be one positive number, got "
                             f"{np.asarray(radius).tolist()!r}")
        if r > MAX_RADIUS:
            raise InputError(f"sphere.radius: must be at most {MAX_RADIUS:g} m (its square "
                             f"must stay far from overflow), got {float(r)!r}")
        self.radius = float(r)
        self.set_margin(self.margin)

    def set_margin(self, margin):
        super().set_margin(margin)
        self._r = self.radius + self.margin       # the contact surface's radius

    def auto_margin(self, r):
        return auto_thickness(self.kind, r, radius=self.radius)

    def inside(self, x):
        q = x - self.center
        return _rowdot(q, q) < self._r ** 2

    def closest(self, x):
        q = x - self.center
        length = np.linalg.norm(q, axis=1)
        n = np.empty_like(q)
        ok = length > 0
        n[ok] = q[ok] / length[ok, None]
        n[~ok] = (0.0, 1.0, 0.0)  # the centre itself: any direction is nearest
        # a few ulps outside, so that rounding never leaves a placed point inside
        return self.center + (self._r * (1.0 + 4 * np.finfo(float).eps)) * n, n

    def contacts(self, x0, x):
        R2 = self._r ** 2
        q0 = x0 - self.center
        c0 = _rowdot(q0, q0) - R2                       # > = 0: x_n outside or on
        d = x - x0
        bh = _rowdot(d, q0)                             # half the linear coefficient
        disc = bh * bh - _rowdot(d, d) * c0
        start_out = c0 >= 0
        enters = start_out & (bh < 0) & (disc > 0)
        i = np.flatnonzero(enters)
        s = c0[i] / (-bh[i] + np.sqrt(disc[i]))
        hit = s <= 1.0
        i, s = i[hit], s[hit]
        p = x0[i] + s[:, None] * d[i]
        n = p - self.center
        n /= np.linalg.norm(n, axis=1)[:, None]
        p = self.center + self._r * n
        # started inside (initial overlap): nearest surface point of x
        j = np.flatnonzero(~start_out & self.inside(x))
        pj, nj = self.closest(x[j])
        return np.concatenate([i, j]), np.concatenate([p, pj]), np.concatenate([n, nj])

    def settle(self, x, normal):
        return self.closest(x)

    def _shape(self):
        return {"center": self.center.tolist(), "radius": self.radius}
