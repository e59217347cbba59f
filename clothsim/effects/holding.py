"""The obstacles' default contact mode, ``"hold"``: contact planes kept inside the solve.

The seed resolves collisions after the solve, each vertex on its own
(``"post-solve"``, :mod:`clothsim.effects.obstacles`). Over a box edge this tears the
cloth: a vertex that enters through a side face is put on it while its neighbour stays on
the top, the next solve knows nothing of the contact and pulls the pair into the box, and
the projection separates them again (springs at several times their rest length, more on
finer cloths: the contact table of docs/effects.md, ``benchmarks contact``). In
``"hold"`` mode an obstacle instead tells the next step which vertices it pushes, and the
step's solve keeps them on their contact planes while the rest of the cloth moves with
them (:mod:`clothsim.contacts`, :mod:`clothsim.solvers.held`).

One step of an obstacle in ``"hold"`` mode:

1. **Held vertices** (the planes of ``hold_contacts``): the solve kept them on their
   planes; the simulation then set each plane's normal force F [N]. F < 0 means the
   cloth pulls the vertex away: it is released where the solve put it (on the plane, so
   outside the convex obstacle) and leaves the surface. F ≥ 0: friction shortens the
   tangential displacement of the step by μ δ with δ = F h² / m (the seed's Coulomb rule,
   with the plane's impulse in place of the projection depth), and the vertex is placed
   on the surface (a sphere: radially; a box: exactly on its face). A box vertex that slid
   off its face (beyond an edge) is released. Static friction (:func:`_sticking`): a
   sticking vertex is held in all three directions while its tangential force stays in
   the cone |F_t| ≤ μ F_n (+ the forces' noise); a sliding one feels kinetic friction
   μ F_n against its velocity, or against the cloth's pull when it starts from rest, and
   sticks again once friction has stopped it, not merely once it is slow.
2. **Other vertices**: the seed's response (continuous detection along x_n → x,
   projection onto the entry face's plane, friction, placement), for the vertices that
   reached the obstacle in this step.
3. **Next step**: the vertices of 1 still pushed and those of 2 are held, each on the
   plane through its position with the contact normal. A sphere contact keeps its normal
   while it stays within :data:`NORMAL_TOLERANCE` of the current one, so the held-contact
   factor stays cached while the cloth rests.
"""

from __future__ import annotations

import numpy as np

from ..contacts import ContactSet
from ..errors import InputError

#: How far (|n_kept − n_now|) a held contact's normal may turn before it is renewed.
NORMAL_TOLERANCE = 1e-2

#: A sticking vertex slides once |F_t| > μ F_n + this × the solve's unbalanced force per
#: vertex (:attr:`ContactSet.noise`): forces estimated from a truncated iteration are not
#: better than that, and switching on noise refactors the held-contact system every step.
NOISE_MARGIN = 3.0

#: The obstacles' contact modes: contact planes held in the solve, or the seed's projection.
CONTACT_MODES = ("hold", "post-solve")


def _rowdot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.einsum("ij,ij->i", a, b)


def tangent_frame(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors completing each normal to an orthonormal frame (deterministic).

    Parameters
    ----------
    n : ndarray, shape (c, 3), unit normals

    Returns
    -------
    t1, t2 : ndarray, shape (c, 3)
    """
    axis = np.zeros_like(n)
    axis[np.arange(len(n)), np.argmin(np.abs(n), axis=1)] = 1.0
    t1 = np.cross(n, axis)
    t1 /= np.linalg.norm(t1, axis=1)[:, None]
    return t1, np.cross(n, t1)


class Holding:
    """What an obstacle in ``"hold"`` mode carries from one step to the next.

    Attributes
    ----------
    vertices : ndarray, shape (c,), int
        Held vertices.
    normals : ndarray, shape (c, 3)
        Their contact normals.
    stick : ndarray of bool, shape (c,)
        Held in all three directions (static friction) rather than only along the normal.
    normal_force : ndarray, shape (c,)
        The normal force of the last step [N] (kinetic friction of sliding vertices).
    pull : ndarray, shape (c, 3)
        Unit direction of the tangential force the cloth exerted on the vertex in the last
        step (−R_t/|R_t|, R_t the tangential reaction; zero when none): the direction a
        vertex that starts sliding from rest moves in, so the one kinetic friction opposes
        before the vertex has a velocity of its own.
    planes : ContactSet
        The planes handed to the step: one per held vertex, two more per sticking one.
        Their offsets are n · x at ``x`` (the positions ``hold_step`` placed), or
        ``offsets`` when given (a state restored by :meth:`from_arrays`).
    """

    #: The arrays :meth:`arrays` returns and :meth:`from_arrays` takes.
    ARRAYS = ("vertices", "normals", "stick", "normal_force", "pull", "offsets")

    def __init__(self, x=None, vertices=None, normals=None, stick=None, normal_force=None,
                 pull=None, *, offsets=None):
        self.vertices = np.zeros(0, np.int64) if vertices is None else vertices
        self.normals = np.zeros((0, 3)) if normals is None else normals
        c = len(self.vertices)
        self.stick = np.zeros(c, bool) if stick is None else stick
        self.normal_force = np.zeros(c) if normal_force is None else normal_force
        self.pull = np.zeros((c, 3)) if pull is None else pull
        v, n = self.vertices, self.normals
        if len(v) == 0:
            self.planes = ContactSet()
            return
        t1, t2 = tangent_frame(n[self.stick])
        vs = v[self.stick]
        rows_v = np.concatenate([v, vs, vs])
        rows_n = np.concatenate([n, t1, t2])
        self.planes = ContactSet(rows_v, rows_n,
                                 _rowdot(x[rows_v], rows_n) if offsets is None else offsets)

    def arrays(self) -> dict[str, np.ndarray]:
        """Everything the next step reads, as copies: what ``--resume`` saves per frame.

        Returns
        -------
        dict of str to ndarray
            :data:`ARRAYS`: the attributes of the class docstring and ``offsets``, the
            planes' offsets o = n · x [m], shape (c + 2 s,) (s sticking vertices). The
            planes' vertices and normals follow from the others (:func:`tangent_frame` is
            deterministic); their forces are set by the next solve.
        """
        return {"vertices": self.vertices.copy(), "normals": self.normals.copy(),
                "stick": self.stick.copy(), "normal_force": self.normal_force.copy(),
                "pull": self.pull.copy(), "offsets": self.planes.offsets.copy()}

    @staticmethod
    def max_bytes(vertex_count: int) -> int:
        """Bytes of :meth:`arrays` at most: every vertex held and sticking (three planes).

        Parameters
        ----------
        vertex_count : int
            n.

        Returns
        -------
        int
            n × (8 + 24 + 1 + 8 + 24 + 3 × 8) bytes, and 1 kB of archive headers.
        """
        return 89 * int(vertex_count) + 1024

    @classmethod
    def from_arrays(cls, arrays, vertex_count: int, name: str = "holding") -> Holding:
        """The holding :meth:`arrays` returned, checked (it is read from a file).

        Parameters
        ----------
        arrays : mapping of str to ndarray
            :data:`ARRAYS`.
        vertex_count : int
            n: held vertices must be in 0..n−1.
        name : str
            Names the source in an error (e.g. the file and the obstacle).

        Returns
        -------
        Holding

        Raises
        ------
        InputError
            A missing array, or one of the wrong shape, type or range (naming it).
        """
        missing = [k for k in cls.ARRAYS if k not in arrays]
        if missing:
            raise InputError(f"{name}: no array {missing[0]!r}", field=name)
        a = {k: np.asarray(arrays[k]) for k in cls.ARRAYS}
        c = len(a["vertices"])
        s = int(a["stick"].sum()) if a["stick"].dtype == bool else -1
        shapes = {"vertices": ((c,), "i"), "normals": ((c, 3), "f"), "stick": ((c,), "b"),
                  "normal_force": ((c,), "f"), "pull": ((c, 3), "f"),
                  "offsets": ((c + 2 * s,), "f")}
        for k, (shape, kind) in shapes.items():
            if a[k].shape != shape or a[k].dtype.kind != kind:
                raise InputError(f"{name}: {k!r} has shape {a[k].shape} and type {a[k].dtype}, "
                                 f"expected {shape} of kind {kind!r}", field=name)
        v = a["vertices"]
        if c and (v.min() < 0 or v.max() >= vertex_count):
            raise InputError(f"{name}: a held vertex is out of range 0..{vertex_count - 1}",
                             field=name)
        return cls(None, v.astype(np.int64), a["normals"].astype(np.float64), a["stick"],
                   a["normal_force"].astype(np.float64), a["pull"].astype(np.float64),
                   offsets=a["offsets"].astype(np.float64))

    def reaction(self) -> np.ndarray:
        """The force each held vertex's planes exerted in the last solve.

        Returns
        -------
        ndarray, shape (c, 3)
            Σ F_plane n_plane over the vertex's planes [N] (zero before the solve).
        """
        c, f = len(self.vertices), self.planes.forces
        if f is None:
            return np.zeros((c, 3))
        R = f[:c, None] * self.normals
        s = np.flatnonzero(self.stick)
        rows = self.planes.normals[c:]
        k = len(s)
        R[s] += f[c:c + k, None] * rows[:k] + f[c + k:, None] * rows[k:]
        return R


def friction_force(obstacle, state, f: np.ndarray) -> None:
    """Kinetic friction on sliding held vertices, added to ``f`` [N] (``add_force``).

    −μ F_n t̂, with F_n the normal force of the last step and t̂ the direction of the
    vertex's tangential velocity v_n (a sliding vertex; a sticking one is held in place).
    A vertex that starts sliding from rest (v_n = 0: it stuck until the cloth's pull
    exceeded μ F_n) has no velocity yet: friction opposes the pull (:attr:`Holding.pull`),
    the direction it will move in. Without this the first step of every slip had no
    friction at all, the vertex overshot, stuck, and slipped again (stick-slip chatter
    that changed the contact set, and refactored, in nearly every step).

    Parameters
    ----------
    obstacle : Obstacle
        In ``"hold"`` mode; its ``_holding`` says which vertices slide.
    state : State
        The start of the step.
    f : ndarray, shape (n, 3)
        The force accumulator [N], added to in place.

    Returns
    -------
    None
    """
    held = obstacle._holding
    slide = ~held.stick
    if obstacle.friction == 0.0 or not slide.any():
        return
    v, n, fn = held.vertices[slide], held.normals[slide], held.normal_force[slide]
    vel = state.velocities[v]
    vt = vel - _rowdot(vel, n)[:, None] * n
    speed = np.linalg.norm(vt, axis=1)
    on = speed > 0
    vt[on] /= speed[on, None]
    vt[~on] = held.pull[slide][~on]
    f[v] -= (obstacle.friction * np.maximum(fn, 0.0))[:, None] * vt


def _sticking(obstacle, state, x, hv, hn, fn, ft, was_stuck, pull, noise) -> np.ndarray:
    """Which held vertices stick in the next step (static friction), with hysteresis.

    A sticking vertex keeps sticking while the cloth's tangential pull stays inside the
    friction cone, |F_t| <= μ F_n + ``noise`` (the forces' uncertainty). A sliding one
    sticks once friction has stopped it: its tangential velocity at the end of the step
    no longer points the way friction opposed (v_t · t̂ <= 0, t̂ the direction
    :func:`friction_force` used). A slide that is still under way, however slowly, thus
    goes on, rather than sticking at once and slipping again in the next step (measured:
    sticking also below the velocity the solve's unbalanced force makes in a step doubled
    the switches on drape-sphere at 25², 45 against 18 a frame with 100 iterations).
    """
    x0, h, mu = state.positions, obstacle.h, obstacle.friction
    step = x[hv] - x0[hv]
    vt = (step - _rowdot(step, hn)[:, None] * hn) / h
    v0 = state.velocities[hv]
    direction = v0 - _rowdot(v0, hn)[:, None] * hn
    length = np.linalg.norm(direction, axis=1)
    direction = np.where(length[:, None] > 0, direction / np.maximum(length, 1e-300)[:, None],
                         pull)
    stopped = _rowdot(vt, direction) <= 0.0
    return np.where(was_stuck, ft <= mu * fn + noise, stopped) & (mu > 0)


def hold_step(obstacle, state, x: np.ndarray) -> np.ndarray:
    """The ``correct_positions`` of an obstacle in ``"hold"`` mode (module docstring).

    Parameters
    ----------
    obstacle : Obstacle
        Bound; its ``_holding`` is the state its ``hold_contacts`` handed this step.
    state : State
        The start of the step.
    x : ndarray, shape (n, 3)
        Positions after the solve [m].

    Returns
    -------
    ndarray, shape (n, 3)
        Corrected positions [m]. Sets ``obstacle.contact_vertices``/``contact_normals``
        (every vertex in contact at the end) and ``obstacle._holding`` (the next step's).
    """
    x0, held, h, mu = state.positions, obstacle._holding, obstacle.h, obstacle.friction
    mass = obstacle.model.vertex_mass
    x = x.copy()
    R = held.reaction()
    fn = _rowdot(R, held.normals)
    Rt = R - fn[:, None] * held.normals
    ft = np.linalg.norm(Rt, axis=1)
    noise = NOISE_MARGIN * held.planes.noise
    pull = -np.divide(Rt, ft[:, None], out=np.zeros_like(Rt), where=ft[:, None] > 0)
    # released when pulled away at all: a margin of the force noise here (hysteresis) kept
    # 51 vertices clinging to the sphere below its equator in drape-sphere at 25²
    push = fn >= 0.0
    hv, hn, fn, ft, was_stuck, pull = (held.vertices[push], held.normals[push], fn[push],
                                       ft[push], held.stick[push], pull[push])
    xk = x[hv]
    on = obstacle.on_face(xk, hn)
    hv, hn, fn, ft, was_stuck, pull, xk = (hv[on], hn[on], fn[on], ft[on], was_stuck[on],
                                           pull[on], xk[on])
    xk, now = obstacle.settle(xk, hn.copy())
    x[hv] = xk
    turned = np.linalg.norm(now - hn, axis=1) > NORMAL_TOLERANCE
    hn = np.where(turned[:, None], now, hn)
    stick = _sticking(obstacle, state, x, hv, hn, fn, ft, was_stuck, pull, noise)
    # the vertices that reached the obstacle in this step: the seed's response
    others = np.setdiff1d(np.arange(len(x)), held.vertices)
    index, p, n = obstacle.contacts(x0[others], x[others])
    index = others[index]
    new_stick, depth = np.zeros(len(index), bool), np.zeros(len(index))
    if len(index):
        solved = x[index]
        x[index], n = obstacle.respond(x0[index], solved, p, n)
        after, moved = x[index] - x0[index], solved - x0[index]
        depth = _rowdot(after - moved, n)
        slid = np.linalg.norm(after - _rowdot(after, n)[:, None] * n, axis=1)
        new_stick = (mu > 0) & (slid <= 1e-3 * np.linalg.norm(moved, axis=1))
    vertices, normals = np.concatenate([hv, index]), np.concatenate([hn, n])
    stick = np.concatenate([stick, new_stick])
    force = np.concatenate([fn, mass[index] * depth / h ** 2])   # the projection's impulse
    pull = np.concatenate([pull, np.zeros((len(index), 3))])
    still = np.flatnonzero(obstacle.inside(x))
    if len(still):   # safety net against rounding: nothing may stay strictly inside
        x[still], nq = obstacle.closest(x[still])
        new = ~np.isin(still, vertices)
        vertices = np.concatenate([vertices, still[new]])
        normals = np.concatenate([normals, nq[new]])
        stick = np.concatenate([stick, np.zeros(int(new.sum()), bool)])
        force = np.concatenate([force, np.zeros(int(new.sum()))])
        pull = np.concatenate([pull, np.zeros((int(new.sum()), 3))])
    obstacle.contact_vertices, obstacle.contact_normals = vertices, normals
    obstacle._holding = Holding(x, vertices, normals, stick, force, pull)
    return x


__all__ = ["CONTACT_MODES", "NORMAL_TOLERANCE", "Holding", "friction_force", "hold_step",
           "tangent_frame"]
