"""Wind: quadratic pressure drag on every triangle.

For triangle t with vertices (i, j, k) at the current positions x_n, velocities v_n:

    v_rel = w − (v_i + v_j + v_k) / 3          relative air velocity [m/s]
    n     = unit normal, A = area               (from the cross product of two edges)
    F_t   = ½ ρ C_d A (v_rel · n) |v_rel · n| n     [N]

F_t points along the wind's normal component (the sign of v_rel · n times n) whichever way
the triangle faces, vanishes for a triangle edge-on to the relative flow, and scales with
|v_rel|². Each vertex of the triangle gets F_t / 3 (summed with ``np.bincount``). The force
uses the state at the start of the step and is held constant over it (explicit in the
wind, like every external force here).

Limitations: only the normal (pressure) part of the drag; no tangential skin friction, no
shielding of one part of the cloth by another, uniform wind in space and time.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError, check_finite
from .base import Effect


def _non_negative(name: str, value) -> float:
    a = check_finite(name, value)
    if a.ndim != 0 or a < 0:
        raise InputError(f"{name}: must be one non-negative number, got {value!r}")
    return float(a)


class Wind(Effect):
    """Uniform wind acting on the cloth's triangles.

    Parameters
    ----------
    velocity : (3,) array_like
        Wind velocity w [m/s].
    drag : float, default 1.0
        Drag coefficient C_d (dimensionless, >= 0; a flat plate normal to the flow ≈ 1.2).
    density : float, default 1.2
        Air density ρ [kg/m³] (>= 0).
    """

    kind = "wind"

    def __init__(self, velocity, *, drag: float = 1.0, density: float = 1.2):
        w = check_finite("wind.velocity", velocity)
        if w.shape != (3,):
            raise InputError(f"wind.velocity: expected 3 numbers, got shape {w.shape}")
        self.velocity = w
        self.drag = _non_negative("wind.drag", drag)
        self.density = _non_negative("wind.density", density)

    def bind(self, model, h):
        super().bind(model, h)
        if model.mesh.triangle_count == 0:
            raise InputError("wind: the cloth mesh has no triangles (wind acts on triangle "
                             "faces)")
        self._triangles = model.mesh.triangles
        self._n = model.vertex_count

    def triangle_force(self, x: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Drag force of every triangle, F_t = ½ ρ C_d A_t (v_rel·n_t) |v_rel·n_t| n_t.

        v_rel is the wind velocity minus the mean velocity of the triangle's vertices, A_t
        its area and n_t its unit normal; degenerate triangles get no force.

        Parameters
        ----------
        x : ndarray, shape (n, 3)
            Positions [m].
        v : ndarray, shape (n, 3)
            Velocities [m/s].

        Returns
        -------
        ndarray, shape (m, 3)
            Force on each of the m triangles [N].
        """
        T = self._triangles
        cross = np.cross(x[T[:, 1]] - x[T[:, 0]], x[T[:, 2]] - x[T[:, 0]])   # 2 A n
        twice_area = np.linalg.norm(cross, axis=1)
        v_rel = self.velocity - (v[T[:, 0]] + v[T[:, 1]] + v[T[:, 2]]) / 3.0
        vn = np.divide(np.einsum("ij,ij->i", v_rel, cross), twice_area,
                       out=np.zeros_like(twice_area), where=twice_area > 0)   # v_rel · n
        # ½ ρ C_d A (v·n)|v·n| n  with  A n = cross / 2
        return (0.25 * self.density * self.drag * vn * np.abs(vn))[:, None] * cross

    def vertex_force(self, x: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Wind force on every vertex: a third of each adjacent triangle's F_t.

        Parameters
        ----------
        x : ndarray, shape (n, 3)
            Positions [m].
        v : ndarray, shape (n, 3)
            Velocities [m/s].

        Returns
        -------
        ndarray, shape (n, 3)
            Force on each vertex [N].
        """
        F = self.triangle_force(x, v) / 3.0
        T = self._triangles.ravel()
        return np.stack([np.bincount(T, weights=np.repeat(F[:, k], 3), minlength=self._n)
                         for k in range(3)], axis=1)

    def add_force(self, t, state, f):
        f += self.vertex_force(state.positions, state.velocities)

    def describe(self):
        return {"kind": self.kind, "velocity": self.velocity.tolist(), "drag": self.drag,
                "density": self.density}
