"""A static solid axis-aligned box obstacle (see :mod:`clothsim.effects.obstacles`)."""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from .obstacles import Obstacle, _vector3


class Box(Obstacle):
    """A static solid axis-aligned box.

    Parameters
    ----------
    min, max : (3,) array_like
        Opposite corners [m], ``min < max`` on every axis.
    friction : float, default 0
        Coulomb coefficient μ.
    thickness : float or "auto", default "auto"
        Contact thickness δ [m]: the cloth's vertices are held on the box grown by δ on
        every side (``min − δ``, ``max + δ``), so the triangles between them clear the
        box's edges and corners. ``"auto"``: the covering radius r of the cloth's
        triangles at rest × 1.1 (a grid of spacing ℓ: 0.78 ℓ), the least δ that provably keeps
        every box point out of every triangle (:func:`~clothsim.effects.thickness.
        auto_thickness`); 0 in ``"post-solve"`` mode (the seed's).

    Notes
    -----
    Slab test: on each axis k the step x_n + s d is strictly between the faces for s in
    the open interval between (min_k − x_n,k)/d_k and (max_k − x_n,k)/d_k (all s, or none,
    when d_k = 0). The step enters the box at s_in = max_k (near ends) when
    s_in < s_out = min_k (far ends), s_in ≤ 1 and s_out > 0; the entry face is the one of
    the axis attaining s_in. A vertex starting inside goes to the nearest face.
    """

    kind = "box"

    def __init__(self, min, max, *, friction: float = 0.0,  # noqa: A002 (TOML keys)
                 thickness="auto", contact: str = "hold"):
        super().__init__(friction, contact, thickness)
        lo = _vector3("box.min", min)
        hi = _vector3("box.max", max)
        bad = np.flatnonzero(lo >= hi)
        if len(bad):
            k = int(bad[0])
            raise InputError(f"box.min[{k}]: must be less than box.max[{k}], got "
                             f"{float(lo[k])!r} >= {float(hi[k])!r}")
        self.min, self.max = lo, hi
        self.set_margin(self.margin)

    def set_margin(self, margin):
        super().set_margin(margin)
        self._lo, self._hi = self.min - self.margin, self.max + self.margin

    def inside(self, x):
        return np.all((x > self._lo) & (x < self._hi), axis=1)

    def closest(self, x):
        gaps = np.concatenate([x - self._lo, self._hi - x], axis=1)   # (k, 6)
        face = np.argmin(gaps, axis=1)
        axis, upper = face % 3, face >= 3
        rows = np.arange(len(x))
        p = x.copy()
        p[rows, axis] = np.where(upper, self._hi[axis], self._lo[axis])
        n = np.zeros_like(x)
        n[rows, axis] = np.where(upper, 1.0, -1.0)
        return p, n

    def contacts(self, x0, x):
        start_in = self.inside(x0)
        d = x - x0
        with np.errstate(divide="ignore", invalid="ignore"):
            a = (self._lo - x0) / d
            b = (self._hi - x0) / d
        near, far = np.minimum(a, b), np.maximum(a, b)
        still = d == 0
        between = (x0 > self._lo) & (x0 < self._hi)
        near[still] = np.where(between[still], -np.inf, np.inf)
        far[still] = np.where(between[still], np.inf, -np.inf)
        axis = np.argmax(near, axis=1)
        rows = np.arange(len(x0))
        s_in = near[rows, axis]
        s_out = far.min(axis=1)
        enters = ~start_in & (s_in < s_out) & (s_in <= 1.0) & (s_out > 0)
        i = np.flatnonzero(enters)
        k = axis[i]
        p = x0[i] + np.clip(s_in[i], 0.0, 1.0)[:, None] * d[i]
        up = d[i, k] < 0                      # moving down the axis: entered by the max face
        rr = np.arange(len(i))
        p[rr, k] = np.where(up, self._hi[k], self._lo[k])
        n = np.zeros((len(i), 3))
        n[rr, k] = np.where(up, 1.0, -1.0)
        j = np.flatnonzero(start_in & self.inside(x))
        pj, nj = self.closest(x[j])
        return np.concatenate([i, j]), np.concatenate([p, pj]), np.concatenate([n, nj])

    def settle(self, x, normal):
        # put the contact coordinate exactly on its face (x + δ n can be an ulp off)
        rows = np.arange(len(x))
        axis = np.argmax(np.abs(normal), axis=1)
        x[rows, axis] = np.where(normal[rows, axis] > 0, self._hi[axis], self._lo[axis])
        return x, normal

    def on_face(self, x, normal):
        # the two coordinates along the face within the box (its closed rectangle)
        along = np.abs(normal) < 0.5
        inside = (x >= self._lo) & (x <= self._hi)
        return np.all(inside | ~along, axis=1)

    def _shape(self):
        return {"min": self.min.tolist(), "max": self.max.tolist()}
