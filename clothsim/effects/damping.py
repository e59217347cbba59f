"""Extra damping, three models seen in the paper's lineage (implicit Euler already damps).

``model="velocity"``  (c ∈ [0, 1), default 0.01)
    After the step, v ← (1 − c) v: every velocity loses the fraction c per step
    (kinetic energy the fraction 1 − (1 − c)²). Also damps rigid motion (free fall too).
``model="inertial"``  (a ∈ (0, 1], default 0.993, sam007961/FastMassSpring)
    The inertial target becomes y = x_n + a h v_n (in code: y ← y − (1 − a) h v_n, so it
    composes with other target changes); a = 1 is no damping.
``model="rigid"``  (c ∈ [0, 1], default 0.01, the paper's code)
    After the step, velocities are blended toward the rigid-body motion of the whole
    mesh: v ← v + c (v_rigid − v), v_rigid,i = v_cm + ω × (x_i − x_cm), with x_cm, v_cm
    the centre of mass and its velocity, L = Σ m_i (x_i − x_cm) × v_i the angular momentum
    and ω = I⁻¹ L (I the inertia tensor about x_cm; a singular I, e.g. a straight strand,
    uses the pseudo-inverse). Σ m v_rigid = Σ m v and Σ m r × v_rigid = I ω = L, so linear
    and angular momentum are kept; only motion relative to the rigid motion is damped.

The strength key is ``coefficient`` for every model (c or a above). ``Damping(model=...)``
returns an instance of the subclass for that model, which overrides only the hook it
needs, so a declared damping costs one hook per step and an undeclared one nothing.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError, check_finite
from .base import Effect

DAMPING_MODELS = ("velocity", "inertial", "rigid")
DEFAULT_COEFFICIENT = {"velocity": 0.01, "inertial": 0.993, "rigid": 0.01}


class Damping(Effect):
    """Damping by one of :data:`DAMPING_MODELS` (see the module docstring).

    Parameters
    ----------
    model : {"velocity", "inertial", "rigid"}, default "velocity"
        Damping model (stored as ``damping_model``: ``self.model`` is the cloth model).
    coefficient : float, optional
        c for "velocity" (0 ≤ c < 1) and "rigid" (0 ≤ c ≤ 1), a for "inertial"
        (0 < a ≤ 1); defaults in :data:`DEFAULT_COEFFICIENT`.
    """

    kind = "damping"

    def __new__(cls, model: str = "velocity", coefficient: float | None = None):
        if cls is Damping:
            if model not in DAMPING_MODELS:
                raise InputError(f"damping.model: must be one of "
                                 f"{', '.join(map(repr, DAMPING_MODELS))}, got {model!r}")
            cls = _SUBCLASS[model]
        return super().__new__(cls)

    def __init__(self, model: str = "velocity", coefficient: float | None = None):
        if model not in DAMPING_MODELS or type(self) is not _SUBCLASS[model]:
            raise InputError(f"damping.model: {type(self).__name__} cannot take model {model!r}")
        self.damping_model = model
        if coefficient is None:
            coefficient = DEFAULT_COEFFICIENT[model]
        c = check_finite("damping.coefficient", coefficient)
        if c.ndim != 0:
            raise InputError(f"damping.coefficient: expected one number, got shape {c.shape}")
        c = float(c)
        ok = {"velocity": 0.0 <= c < 1.0, "inertial": 0.0 < c <= 1.0,
              "rigid": 0.0 <= c <= 1.0}[model]
        if not ok:
            interval = {"velocity": "[0, 1)", "inertial": "(0, 1]", "rigid": "[0, 1]"}[model]
            raise InputError(f"damping.coefficient: must be in {interval} for model "
                             f"{model!r}, got {c!r}")
        self.coefficient = c

    def describe(self):
        return {"kind": self.kind, "model": self.damping_model, "coefficient": self.coefficient}


class VelocityDamping(Damping):
    """v ← (1 − c) v after the step."""

    def correct_velocities(self, t, state, x, v):
        return (1.0 - self.coefficient) * v


class InertialDamping(Damping):
    """y = x_n + a h v_n."""

    def adjust_target(self, t, state, y):
        return y - ((1.0 - self.coefficient) * self.h) * state.velocities


def rigid_velocity(x: np.ndarray, v: np.ndarray, m: np.ndarray) -> np.ndarray:
    """Velocity field of the rigid motion with the same momenta as (x, v).

    Parameters
    ----------
    x, v : ndarray, shape (n, 3)
        Positions [m] and velocities [m/s].
    m : ndarray, shape (n,)
        Masses [kg].

    Returns
    -------
    ndarray, shape (n, 3)
        v_cm + ω × (x − x_cm), ω = I⁻¹ L (pseudo-inverse when I is singular).
    """
    total = m.sum()
    x_cm = m @ x / total
    v_cm = m @ v / total
    r = x - x_cm
    L = m @ np.cross(r, v)
    r2 = np.einsum("ij,ij->i", r, r)
    I = (m @ r2) * np.eye(3) - np.einsum("i,ij,ik->jk", m, r, r)  # noqa: E741 (inertia tensor)
    omega = np.linalg.lstsq(I, L, rcond=None)[0]
    return v_cm + np.cross(omega, r)


class RigidDamping(Damping):
    """v ← v + c (v_rigid − v) after the step."""

    def correct_velocities(self, t, state, x, v):
        c = self.coefficient
        if c == 0.0:
            return v
        return v + c * (rigid_velocity(x, v, self.model.vertex_mass) - v)


_SUBCLASS = {"velocity": VelocityDamping, "inertial": InertialDamping, "rigid": RigidDamping}
