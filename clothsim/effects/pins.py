"""Pinned vertices, two ways (Liu et al. 2013 and its code).

``method="constraint"`` (default, exact)
    The pinned vertices are removed from the unknowns: they sit exactly at their targets
    (the initial position, optionally moved by a prescribed motion) and never move
    otherwise. Their coupling to free vertices moves to the right-hand side.
``method="penalty"`` (the paper's code)
    Each pinned vertex is tied to its target q by a zero-rest-length spring of stiffness
    k: k enters L's diagonal and h² k q the right-hand side. As k → ∞ it approaches the
    exact pin; for finite k the vertex sags by about m g / k.

A pin may be released at a time (it is then dropped and the system refactored) and may
follow a prescribed motion (constant ``velocity`` or a callable ``motion(t)``).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..errors import InputError, check_finite
from .base import Effect, PinSet

PIN_METHODS = ("constraint", "penalty")


def _box(region, name: str) -> tuple[np.ndarray, np.ndarray]:
    """(min, max) [m] of one region box ``{"min": [x, y, z], "max": [x, y, z]}``."""
    if not isinstance(region, dict) or set(region) != {"min", "max"}:
        raise InputError(f"{name}: expected a table with keys 'min' and 'max'")
    lo = check_finite(f"{name}.min", region["min"]).reshape(-1)
    hi = check_finite(f"{name}.max", region["max"]).reshape(-1)
    if lo.shape != (3,) or hi.shape != (3,):
        raise InputError(f"{name}: 'min' and 'max' need 3 numbers each")
    return lo, hi


class Pin(Effect):
    """Pin vertices to their initial positions (or to a prescribed motion).

    Parameters
    ----------
    vertices : array_like of int, optional
        Indices of the pinned vertices (0-based).
    region : dict or list of dict, optional
        ``{"min": [x, y, z], "max": [x, y, z]}``: pin every vertex whose initial position
        lies in this box (inclusive); a list of such boxes pins the vertices of any of them
        (e.g. two tiny boxes for two corners, which stay the corners at any resolution), and
        each box must hold a vertex. Give ``vertices`` or ``region``, not both.
    method : {"constraint", "penalty"}
    stiffness : float, default 1e5
        Penalty spring stiffness k [N/m] (``method="penalty"`` only).
    release : float, optional
        Time [s] after which the pin no longer acts.
    velocity : (3,) array_like, optional
        Pinned vertices move with this constant velocity [m/s].
    motion : callable, optional
        ``motion(t)`` → displacement [m] from the initial positions, shape (3,) or (p, 3).
    """

    kind = "pin"

    def __init__(self, vertices=None, *, region: dict | None = None, method: str = "constraint",
                 stiffness: float = 1e5, release: float | None = None,
                 velocity=None, motion: Callable[[float], np.ndarray] | None = None):
        if (vertices is None) == (region is None):
            raise InputError("pin: give exactly one of 'vertices' or 'region'")
        self.region = None
        if region is not None:
            many = isinstance(region, (list, tuple))
            if many and not region:
                raise InputError("pin.region: an empty array of boxes pins nothing")
            self.region = [_box(b, f"pin.region[{i}]" if many else "pin.region")
                           for i, b in enumerate(region if many else [region])]
            self._many = many
            vertices = []
        v = np.asarray(vertices)
        if v.size and not np.issubdtype(v.dtype, np.integer):
            if v.dtype.kind not in "fiu" or not np.all(np.mod(v, 1) == 0):  # text, None
                raise InputError("pin.vertices: must be integer vertex indices")
        self.vertices = v.astype(np.int64).reshape(-1)
        if method not in PIN_METHODS:
            raise InputError(f"pin.method: must be one of {', '.join(map(repr, PIN_METHODS))}, "
                             f"got {method!r}")
        self.method = method
        k = float(check_finite("pin.stiffness", stiffness))
        if k <= 0:
            raise InputError(f"pin.stiffness: must be positive, got {k!r}")
        self.stiffness = k
        self.release = None if release is None else float(check_finite("pin.release", release))
        if self.release is not None and self.release < 0:
            raise InputError(f"pin.release: must be a time >= 0 [s], got {self.release!r}")
        self.velocity = None if velocity is None else check_finite("pin.velocity", velocity)
        if self.velocity is not None and self.velocity.shape != (3,):
            raise InputError(f"pin.velocity: expected 3 numbers, got shape {self.velocity.shape}")
        self.motion = motion

    def bind(self, model, h):
        super().bind(model, h)
        n = model.vertex_count
        if self.region is not None:
            x0 = model.mesh.vertices
            inside = np.zeros(len(x0), bool)
            for i, (lo, hi) in enumerate(self.region):
                box = np.all((x0 >= lo) & (x0 <= hi), axis=1)
                if not box.any():  # every box must hold a vertex (else a corner hangs free)
                    name = f"pin.region[{i}]" if self._many else "pin.region"
                    raise InputError(f"{name}: no vertex lies in the box min={lo.tolist()} "
                                     f"max={hi.tolist()}", field=name)
                inside |= box
            self.vertices = np.flatnonzero(inside)
        bad = np.flatnonzero((self.vertices < 0) | (self.vertices >= n))
        if len(bad):
            raise InputError(f"pin.vertices[{bad[0]}]: vertex {self.vertices[bad[0]]} out of "
                             f"range 0..{n - 1}")
        uniq, counts = np.unique(self.vertices, return_counts=True)
        if np.any(counts > 1):
            raise InputError(f"pin.vertices: vertex {uniq[counts > 1][0]} is listed twice")
        if self.method == "penalty":  # mass 0 means exactly pinned: a spring would let it move
            massless = self.vertices[model.vertex_mass[self.vertices] == 0]
            if len(massless):
                raise InputError(f"pin.method: vertex {massless[0]} has mass 0, which pins it "
                                 f"exactly at its initial position, but this penalty pin "
                                 f"would let it move by its spring's stretch; use method "
                                 f"'constraint' (cloth.pin_method for the pins a cloth's files "
                                 f"declare) or give the vertex a mass", field="pin.method")
        if self.method == "penalty" and len(self.vertices):  # lost in M + h²L's rounding?
            m = model.vertex_mass[self.vertices]
            held = h * h * self.stiffness / m
            if held.min() <= np.finfo(np.float64).eps:
                i = int(np.argmin(held))
                raise InputError(f"pin.stiffness: {self.stiffness!r} N/m is lost in the rounding "
                                 f"of vertex {self.vertices[i]}'s mass {m[i]:.3g} kg with h = "
                                 f"{h:.3g} s (h²k/m = {held[i]:.3g}, below ε = 2.2e-16): the pin "
                                 f"would hold nothing", field="pin.stiffness")
        self._rest = model.mesh.vertices[self.vertices].copy()
        self._empty = PinSet()

    def targets(self, t: float) -> np.ndarray:
        """Prescribed positions of the pinned vertices at time t.

        q(t) = q_0 + t v + motion(t), with q_0 the rest positions, v the constant
        ``velocity`` and ``motion`` the optional prescribed displacement.

        Parameters
        ----------
        t : float
            Time [s].

        Returns
        -------
        ndarray, shape (p, 3)
            Target positions [m].
        """
        x = self._rest
        if self.velocity is not None:
            x = x + t * self.velocity
        if self.motion is not None:
            x = x + np.broadcast_to(check_finite("pin.motion", self.motion(t)), x.shape)
        return x

    def active(self, t: float) -> bool:
        """Whether the pins hold at time t (until ``release``, if set).

        Parameters
        ----------
        t : float
            Time [s].

        Returns
        -------
        bool
        """
        return self.release is None or t <= self.release + 1e-12 * max(1.0, abs(self.release))

    def pins(self, t):
        if not self.active(t) or len(self.vertices) == 0:
            return self._empty
        q = self.targets(t)
        if self.method == "constraint":
            return PinSet(fixed_vertices=self.vertices, fixed_positions=q)
        return PinSet(anchor_vertices=self.vertices, anchor_positions=q,
                      anchor_stiffness=np.full(len(self.vertices), self.stiffness))

    def describe(self):
        out = {"kind": self.kind, "method": self.method, "vertex_count": int(len(self.vertices))}
        if self.method == "penalty":
            out["stiffness"] = self.stiffness
        if self.release is not None:
            out["release"] = self.release
        if self.velocity is not None:
            out["velocity"] = self.velocity.tolist()
        return out
