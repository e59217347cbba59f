"""A static half-space obstacle (see :mod:`clothsim.effects.obstacles`)."""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from .obstacles import Obstacle, _vector3


class Plane(Obstacle):
    """A static half-space: the solid lies behind a plane, ``normal`` points to free space.

    Parameters
    ----------
    point : (3,) array_like
        A point on the plane [m].
    normal : (3,) array_like
        Direction of free space (normalized here; must not be zero).
    friction : float, default 0
        Coulomb coefficient μ.
    thickness : float or "auto", default 0
        Contact thickness δ [m]: vertices are kept at least this far in front of the plane
        (the contact surface is the plane moved by δ along the normal). ``"auto"`` is 0: a
        triangle whose corners are in front of a plane lies wholly in front of it.

    Notes
    -----
    The whole solid lies behind the plane, so the end-of-step signed distance
    φ(x) = (x − point)·n − δ already detects every crossing (a sign change of φ
    along the step): no tunnelling is possible and the contact point is x − φ n.
    """

    kind = "plane"

    def __init__(self, point, normal, *, friction: float = 0.0, thickness=0.0,
                 contact: str = "hold"):
        super().__init__(friction, contact, thickness)
        self.point = _vector3("plane.point", point)
        normal = _vector3("plane.normal", normal)
        scale = float(np.abs(normal).max())
        if scale == 0.0:
            raise InputError("plane.normal: must not be the zero vector")
        normal = normal / scale          # largest entry ±1: the norm cannot overflow
        self.normal = normal / float(np.linalg.norm(normal))
        self.set_margin(self.margin)

    def set_margin(self, margin):
        super().set_margin(margin)
        self._offset = float(self.point @ self.normal) + self.margin

    def signed_distance(self, x: np.ndarray) -> np.ndarray:
        """φ(x) = n·x − n·point − δ, negative inside (δ the thickness in use).

        Parameters
        ----------
        x : ndarray, shape (k, 3), points [m]

        Returns
        -------
        ndarray, shape (k,), signed distances [m]
        """
        return x @ self.normal - self._offset

    def contacts(self, x0, x):
        phi = self.signed_distance(x)
        index = np.flatnonzero(phi < 0)
        n = np.broadcast_to(self.normal, (len(index), 3))
        return index, x[index] - phi[index, None] * n, n

    def inside(self, x):
        return self.signed_distance(x) < 0

    def closest(self, x):
        n = np.broadcast_to(self.normal, x.shape)
        return x - self.signed_distance(x)[:, None] * n, n

    def _shape(self):
        return {"point": self.point.tolist(), "normal": self.normal.tolist()}
