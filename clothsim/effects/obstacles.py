"""Static obstacles: a half-space (plane), a sphere and an axis-aligned box.

As in the paper and the student report, collisions are not part of the optimization: after the
solve, vertices that end a step inside an obstacle are moved out (the ``correct_positions``
hook), and the simulation then derives v = (x − x_n)/h, which is the collision response.

Contact model (one vectorized pass per obstacle and step)
---------------------------------------------------------
For every vertex the segment from x_n (start of the step) to x (the solver's answer) is
tested against the solid:

1. **Detection, continuous.** If x_n is outside and the segment enters the solid (sign
   change for the plane, ray/sphere roots for the sphere, slab test for the box), the
   contact point p is the *entry point* and n the outward normal there. So a vertex that
   would cross a thin box or a small sphere within one step is caught on the side it came
   from (no tunnelling). If x_n is already inside (only an initial overlap can do that),
   p is the surface point nearest to x.
2. **Normal response.** x is projected onto the supporting plane at p:
   x ← x + δ n with penetration δ = max(0, (p − x)·n). The obstacles are convex, so a
   point on that plane is never inside.
3. **Friction (Coulomb-like, position based).** The tangential displacement of the step,
   Δ_t = (I − n nᵀ)(x − x_n), is shortened by μ δ: Δ_t ← Δ_t max(0, 1 − μ δ / |Δ_t|).
   δ m / h is the normal impulse that stopped the vertex, so the tangential impulse
   removed is at most μ times it (Coulomb's bound); when |Δ_t| ≤ μ δ the vertex sticks
   (static friction). μ = 0 is frictionless sliding.
4. **Sphere only.** The point is moved radially onto the sphere, so a vertex sliding over
   the sphere stays on it, on the hemisphere centred at the entry point.
5. **Velocity** (``correct_velocities``). The inward normal part of v of the vertices in
   contact is removed: v ← v − min(0, v·n) n (perfectly inelastic contact; resting
   vertices keep v·n = 0 instead of carrying the approach speed into the next step).

Thickness: each obstacle tests the surface moved out by its contact thickness δ
(``thickness``; :mod:`clothsim.effects.thickness`). Only vertices are tested, so with δ = 0
a triangle between a vertex on a box's top face and one on its side cuts the box's edge,
and a chord over a sphere dips inside it; the default ``"auto"`` δ of a box and a sphere
is the least margin that keeps every obstacle point out of every triangle at the cloth's
rest shape.

Limitations: obstacles are static and rigid; a sphere smaller than the mesh spacing
between vertices can pass between them; several obstacles are applied one after another,
so a vertex squeezed between two overlapping ones may end inside the first. Pinned vertices
are moved like any other vertex if they lie inside an obstacle, except a vertex of mass 0
(pinned exactly): one that starts inside an obstacle is an
:class:`~clothsim.errors.InputError` when the obstacle
is bound.
"""

from __future__ import annotations

import numpy as np

from ..contacts import ContactSet
from ..errors import InputError, check_finite
from .base import Effect
from .holding import CONTACT_MODES, Holding, friction_force, hold_step
from .thickness import STRETCH_ALLOWANCE, auto_thickness, check_thickness, covering_radius


def _vector3(name: str, value) -> np.ndarray:
    a = check_finite(name, value)
    if a.shape != (3,):
        raise InputError(f"{name}: expected 3 numbers, got shape {a.shape}")
    return a


def _non_negative(name: str, value) -> float:
    a = check_finite(name, value)
    if a.ndim != 0:
        raise InputError(f"{name}: expected one number, got shape {a.shape}")
    if a < 0:
        raise InputError(f"{name}: must be non-negative, got {float(a)!r}")
    return float(a)


def _rowdot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.einsum("ij,ij->i", a, b)


class Obstacle(Effect):
    """Base of the static obstacles: the shared contact response (see module docstring).

    A subclass implements :meth:`contacts` (detection), :meth:`inside` and
    :meth:`closest` (for the final safety projection) and may override :meth:`settle`.

    Attributes
    ----------
    friction : float
        Coulomb coefficient μ (dimensionless, >= 0).
    thickness : float or "auto"
        The contact thickness as given [m] (:mod:`clothsim.effects.thickness`).
    margin : float
        The thickness in use, δ [m]: ``"auto"`` is resolved when the obstacle is bound to a
        model (0 before, and 0 in ``"post-solve"`` mode, which reproduces the seed).
    contact_vertices : ndarray, shape (c,), int
        Vertices in contact during the last step.
    contact_normals : ndarray, shape (c, 3)
        Their outward unit normals at the end of the step.
    """

    kind = "obstacle"

    def __init__(self, friction: float = 0.0, contact: str = "hold", thickness=0.0):
        self.friction = _non_negative(f"{self.kind}.friction", friction)
        self.thickness = check_thickness(f"{self.kind}.thickness", thickness)
        self.margin = 0.0 if thickness == "auto" else self.thickness
        if contact not in CONTACT_MODES:
            raise InputError(f"{self.kind}.contact: must be one of "
                             f"{', '.join(map(repr, CONTACT_MODES))}, got {contact!r}")
        self.contact = contact
        self.unused_hooks = (("hold_contacts", "add_force") if contact != "hold"
                             else ("add_force",) if self.friction == 0.0 else ())
        self.contact_vertices = np.zeros(0, np.int64)
        self.contact_normals = np.zeros((0, 3))
        self._holding = Holding()

    # -- geometry, implemented by each shape ---------------------------------------------
    def set_margin(self, margin: float) -> None:
        """Use the contact thickness ``margin`` in the geometry below.

        Parameters
        ----------
        margin : float
            δ >= 0 [m].
        """
        self.margin = float(margin)

    def auto_margin(self, r: float) -> float:
        """The ``"auto"`` thickness for cells of covering radius ``r`` [m].

        Parameters
        ----------
        r : float
            The covering radius to cover [m]: :data:`~clothsim.effects.thickness.
            STRETCH_ALLOWANCE` × :func:`~clothsim.effects.thickness.covering_radius` of the
            cloth at rest.

        Returns
        -------
        float
            δ [m] (:func:`~clothsim.effects.thickness.auto_thickness`).
        """
        return auto_thickness(self.kind, r)

    def contacts(self, x0: np.ndarray, x: np.ndarray):
        """Vertices whose step segment x0 → x touches the solid.

        Parameters
        ----------
        x0, x : ndarray, shape (n, 3), positions at the step's start and after the solve [m]

        Returns
        -------
        index : ndarray, shape (c,), int
        point : ndarray, shape (c, 3)
            Contact point p on the surface [m] (entry point, or nearest point to x).
        normal : ndarray, shape (c, 3)
            Outward unit normal at p.
        """
        raise NotImplementedError

    def inside(self, x: np.ndarray) -> np.ndarray:
        """Which points are strictly inside the solid.

        Parameters
        ----------
        x : ndarray, shape (k, 3)
            Points [m].

        Returns
        -------
        ndarray of bool, shape (k,)
        """
        raise NotImplementedError

    def closest(self, x: np.ndarray):
        """The nearest surface points and the outward unit normals there.

        Parameters
        ----------
        x : ndarray, shape (k, 3)
            Points [m].

        Returns
        -------
        points : ndarray, shape (k, 3)
            Nearest points on the surface [m].
        normals : ndarray, shape (k, 3)
            Outward unit normals at those points.
        """
        raise NotImplementedError

    def settle(self, x: np.ndarray, normal: np.ndarray):
        """Final placement of contact points after friction (default: keep them).

        Parameters
        ----------
        x : ndarray, shape (k, 3)
            Contact points after the friction step [m] (may be modified in place).
        normal : ndarray, shape (k, 3)
            Outward unit normals at the contacts.

        Returns
        -------
        x : ndarray, shape (k, 3)
            The points placed exactly on the surface [m].
        normal : ndarray, shape (k, 3)
            The normals there.
        """
        return x, normal

    def on_face(self, x: np.ndarray, normal: np.ndarray) -> np.ndarray:
        """Which held contact points still lie on the face of their normal (default: all).

        Parameters
        ----------
        x : ndarray, shape (k, 3)
            Contact points [m].
        normal : ndarray, shape (k, 3)
            Their held normals.

        Returns
        -------
        ndarray of bool, shape (k,)
        """
        return np.ones(len(x), bool)

    def respond(self, x0: np.ndarray, x: np.ndarray, p: np.ndarray, n: np.ndarray):
        """The seed's response of vertices that reached the solid in this step.

        Projection onto the plane at the contact point, position-based Coulomb friction,
        placement on the surface (steps 2–4 of the module docstring).

        Parameters
        ----------
        x0, x : ndarray, shape (c, 3)
            Their positions at the start of the step and after the solve [m].
        p, n : ndarray, shape (c, 3)
            Contact points [m] and outward unit normals (:meth:`contacts`).

        Returns
        -------
        x : ndarray, shape (c, 3)
            The corrected positions [m].
        n : ndarray, shape (c, 3)
            The normals there.
        """
        depth = np.maximum(_rowdot(p - x, n), 0.0)
        xc = x + depth[:, None] * n
        if self.friction > 0.0:
            step = xc - x0
            tangential = step - _rowdot(step, n)[:, None] * n
            length = np.linalg.norm(tangential, axis=1)
            keep = np.zeros_like(length)
            moving = length > 0
            keep[moving] = np.maximum(0.0, 1.0 - self.friction * depth[moving] / length[moving])
            xc = xc - (1.0 - keep)[:, None] * tangential
        return self.settle(xc, n)

    # -- the hooks ---------------------------------------------------------------------
    def hold_contacts(self, t):
        return self._holding.planes if self.contact == "hold" else ContactSet()

    def add_force(self, t, state, f):
        if self.contact == "hold":
            friction_force(self, state, f)

    def correct_positions(self, t, state, x):
        if self.contact == "hold" and hasattr(self, "model"):   # bound to a simulation
            return hold_step(self, state, x)
        x0 = state.positions
        index, p, n = self.contacts(x0, x)
        if len(index) == 0:
            self.contact_vertices = index
            self.contact_normals = n
            return x
        x = x.copy()
        x[index], n = self.respond(x0[index], x[index], p, n)
        # safety net against rounding: nothing may stay strictly inside
        still = np.flatnonzero(self.inside(x))
        if len(still):
            q, nq = self.closest(x[still])
            x[still] = q
            index = np.concatenate([index, still])
            n = np.concatenate([n, nq])
        self.contact_vertices = index
        self.contact_normals = n
        return x

    def correct_velocities(self, t, state, x, v):
        if len(self.contact_vertices) == 0:
            return v
        i, n = self.contact_vertices, self.contact_normals
        vn = _rowdot(v[i], n)
        inward = vn < 0
        if not inward.any():
            return v
        v = v.copy()
        v[i[inward]] -= vn[inward, None] * n[inward]
        return v

    def bind(self, model, h):
        super().bind(model, h)
        if self.thickness == "auto":
            mesh = model.mesh
            r = STRETCH_ALLOWANCE * covering_radius(mesh.vertices, mesh.triangles, mesh.strands)
            self.set_margin(0.0 if self.contact == "post-solve" else self.auto_margin(r))
        self.contact_vertices = np.zeros(0, np.int64)
        self.contact_normals = np.zeros((0, 3))
        massless = model.massless_vertices
        inside = massless[self.inside(model.mesh.vertices[massless])] if len(massless) else []
        if len(inside):  # mass 0 means exactly pinned: the contact response would move it
            key = {"sphere": "center", "box": "min", "plane": "point"}.get(self.kind, "kind")
            within = f" (within its thickness {self.margin:.3g} m)" if self.margin else ""
            raise InputError(f"{self.kind}.{key}: vertex {inside[0]} has mass 0, which pins it "
                             f"exactly at its initial position, but it starts inside the "
                             f"{self.kind}{within}, whose contact response would move it; "
                             f"move the obstacle or give the vertex a mass",
                             field=f"{self.kind}.{key}")
        self._holding = Holding()

    def get_state(self) -> dict[str, np.ndarray]:
        """The contacts this obstacle hands the next step (``"hold"`` mode; none in
        ``"post-solve"`` mode, which carries nothing from one step to the next).

        Returns
        -------
        dict of str to ndarray
            :meth:`Holding.arrays <clothsim.effects.holding.Holding.arrays>` (copies).
        """
        return self._holding.arrays() if self.contact == "hold" else {}

    def state_bytes(self, vertex_count: int) -> int:
        """Bytes of :meth:`get_state` at most (:meth:`Holding.max_bytes
        <clothsim.effects.holding.Holding.max_bytes>`; none in ``"post-solve"`` mode).

        Parameters
        ----------
        vertex_count : int

        Returns
        -------
        int
        """
        return Holding.max_bytes(vertex_count) if self.contact == "hold" else 0

    def set_state(self, state, name: str | None = None) -> None:
        """Restore what :meth:`get_state` returned (after :meth:`bind`).

        Parameters
        ----------
        state : mapping of str to ndarray
        name : str, optional
            Names the source in an error (default: the obstacle's kind).

        Raises
        ------
        InputError
            An array missing or of the wrong shape or range.
        """
        if self.contact == "hold":
            self._holding = Holding.from_arrays(state, self.model.vertex_count,
                                                name or self.kind)

    def describe(self):
        return {"kind": self.kind, **self._shape(), "friction": self.friction,
                "thickness": self.thickness, "margin": self.margin, "contact": self.contact}

    def _shape(self) -> dict:
        raise NotImplementedError
