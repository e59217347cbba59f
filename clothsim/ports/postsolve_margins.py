"""Post-solve contact decisions too close to call from a port's state: taken as the port took them.

In ``"post-solve"`` contact mode an obstacle moves the vertices that end a step inside it
onto its surface (:mod:`clothsim.effects.obstacles`). Whether a vertex is caught, and onto
which face of a box, is a comparison of its coordinates with the surface's: a vertex that
starts within the printed rounding of the surface (a grid vertex exactly on a box's edge)
can be caught by the port and missed by clothsim from the same printed start, or put on
the other face, a decision worth up to a step's whole motion.

When a step fails, a vertex is too close to call if its decision changes when the
surface is moved in or out by r, the larger of the printed rounding and the error of the
vertices neither answer has on an obstacle (how far the start's rounding moved the solve).
Its decisions are then clothsim's own and:

* **not projected**: the solver's answer, when some moved surface does not catch it;
* **on a face**: the seed's response (projection, friction) onto a face (the surface, for a
  sphere or a plane) some moved surface catches it on.

The check takes the one nearest the port's x_{k+1} (the port's decision, read off its
answer) and solves the step again. A vertex whose decision no such move changes keeps
clothsim's, so a port that ignores an obstacle, or puts a vertex elsewhere than any of
these decisions would, still fails; and a port whose answer leaves the vertices clothsim
projected elsewhere is ``contacts differ`` (:meth:`PortDecisions.unprojected`).
"""

from __future__ import annotations

from contextlib import contextmanager

import numpy as np

from ..simulation import State

__all__ = ["PortDecisions"]

_AXES = "xyz"


def _codes(ob, x0, x, r):
    """(3, n) int: each vertex's decision with the surface moved in by r, as is, moved out
    by r: -1 not caught, else the face caught on (a box's 6 faces: axis + 3 × (outward
    normal positive); 0: a sphere or a plane)."""
    margin = ob.margin
    codes = np.full((3, len(x)), -1)
    try:
        for row, d in enumerate((-r, 0.0, r)):
            ob.set_margin(margin + d)
            index, _, n = ob.contacts(x0, x)
            axis = np.argmax(np.abs(n), axis=1)
            face = axis + 3 * (n[np.arange(len(n)), axis] > 0)
            codes[row, index] = face if ob.kind == "box" else 0
    finally:
        ob.set_margin(margin)
    return codes


def _on_surface(ob, x, r):
    """Which points lie within r of the obstacle's surface."""
    margin = ob.margin
    try:
        ob.set_margin(margin + r)
        grown = ob.inside(x)
        ob.set_margin(margin - r)
        return grown & ~ob.inside(x)
    finally:
        ob.set_margin(margin)


def _normals(ob, x, v, r):
    """The outward normals of the faces points on the surface are on; of a box's faces a
    point is on (an edge, a corner), the one its velocity v runs into most."""
    if ob.kind != "box":
        return ob.closest(x)[1]
    best, normals = np.full(len(x), np.inf), ob.closest(x)[1]
    for face in range(6):
        a, upper = face % 3, face >= 3
        n = np.zeros(3)
        n[a] = 1.0 if upper else -1.0
        plane = ob._hi[a] if upper else ob._lo[a]
        along = np.delete(np.arange(3), a)
        on = ((np.abs(x[:, a] - plane) <= r)
              & np.all((x[:, along] >= ob._lo[along] - r) & (x[:, along] <= ob._hi[along] + r),
                       axis=1))
        into = v @ n
        take = on & (into < best)
        normals[take], best[take] = n, into[take]
    return normals


def _place(ob, x0, x, face):
    """The seed's response of the points onto ``face`` (:meth:`Obstacle.respond`)."""
    if ob.kind == "box":
        a, upper = face % 3, face >= 3
        p = x.copy()
        p[:, a] = ob._hi[a] if upper else ob._lo[a]
        n = np.zeros_like(x)
        n[:, a] = 1.0 if upper else -1.0
    else:
        p, n = ob.closest(x)
    return ob.respond(x0, x.copy(), p, np.array(n))


def _face_name(obstacle, f):
    if obstacle.kind != "box":
        return f"on the {obstacle.kind}"
    return f"on the box's {'+' if f >= 3 else '-'}{_AXES[f % 3]} face"


class PortDecisions:
    """The post-solve decisions of one step too close to call, taken as the port's.

    Parameters
    ----------
    sim : Simulation
        Its post-solve obstacles are the ones decided.

    Attributes
    ----------
    obstacles : list of Obstacle
        The scene's obstacles in ``"post-solve"`` mode.
    taken : list of (int, str)
        The decisions adopted since :meth:`adopted` began (the check's solve from the
        port's start first, then its replays): vertex, words ("not projected", "on the
        box's +y face").
    gap : float
        How far the surfaces are moved to find the decisions too close to call [m].
    """

    def __init__(self, sim):
        self.sim = sim
        self.obstacles = [e for e in sim.effects if e.kind in ("sphere", "plane", "box")
                          and getattr(e, "contact", None) == "post-solve"]
        self.taken = []
        self.gap = 0.0

    def __bool__(self):
        return bool(self.obstacles)

    @contextmanager
    def adopted(self, x_port, rounding, err):
        """Within the block, the obstacles take the port's decisions too close to call.

        Parameters
        ----------
        x_port : ndarray, shape (n, 3)
            The port's x_{k+1} [m].
        rounding : ndarray, shape (n,)
            How far the port's start may be from the values it computed, per vertex [m]
            (:func:`~clothsim.ports.held_margins.position_rounding`).
        err : ndarray, shape (n,)
            |x_clothsim − x_port| per vertex of clothsim's step [m]. The surfaces are moved
            by the largest of the rounding and the error of the vertices neither answer has
            on an obstacle (how far the start's rounding moved the solve).

        Yields
        ------
        PortDecisions
            Itself; :meth:`note` names the decisions its last solve took.
        """
        touched = np.zeros(len(x_port), bool)
        for ob in self.obstacles:
            touched[ob.contact_vertices] = True
            touched |= _on_surface(ob, x_port, float(np.max(rounding)))
        free = err[~touched]
        self.taken = []
        self.gap = max(float(np.max(rounding)), float(free.max()) if len(free) else 0.0)
        for ob in self.obstacles:
            ob.correct_positions = self._wrap(ob, ob.correct_positions, x_port, rounding)
        try:
            yield self
        finally:
            for ob in self.obstacles:
                del ob.correct_positions   # the class's method again

    def start(self, x, rounding) -> np.ndarray:
        """The port's x_k to restart from: a vertex its printing put inside an obstacle is
        put back on the surface.

        A right port's x_k is never strictly inside a solid (its projection leaves every
        vertex on or outside it), but a vertex it put on a sphere, printed, can read a
        rounding inside it; clothsim's step would then take it for a vertex that started
        inside and put it on the surface point nearest its answer instead of where its
        path entered (drape-sphere with Anderson 10 printed with ``%g``, step 6 → 7: 20
        vertices up to 4.7e-7 m inside, answers 6e-3 m apart).

        Parameters
        ----------
        x : ndarray, shape (n, 3)
            The port's x_k as read [m].
        rounding : ndarray, shape (n,)
            How far each vertex may be from the value the port computed [m].

        Returns
        -------
        ndarray, shape (n, 3)
            A copy, the vertices strictly inside an obstacle within ``rounding`` of its
            surface put on its nearest surface point.
        """
        x = np.array(x, np.float64)
        for ob in self.obstacles:
            i = np.flatnonzero(ob.inside(x))
            i = i[_on_surface(ob, x[i], float(np.max(rounding[i])))] if len(i) else i
            if len(i):
                x[i] = ob.closest(x[i])[0]
        return x

    def derived_velocities(self, xs, vs, rounding) -> np.ndarray:
        """Derived velocities (x_k − x_{k−1}) / h put through the step's velocity corrections.

        A step ends with the velocity corrections of the scene's effects, in order: the
        seed's projection removes the inward normal velocity of the vertices it caught
        (:meth:`Obstacle.correct_velocities`), a damping acts after it. A port's v_k is
        therefore not (x_k − x_{k−1}) / h. Which vertices it caught is read off the port's
        own frames, not off clothsim's decisions: those on an obstacle's surface at x_k
        (within ``rounding``), each with the normal of the face it is on (of a box's faces
        it is on, the one its motion x_{k−1} → x_k ran into most).

        Parameters
        ----------
        xs : ndarray, shape (frames, n, 3)
            The port's positions [m].
        vs : ndarray, shape (frames, n, 3)
            (x_k − x_{k−1}) / h, and 0 at frame 0 [m/s].
        rounding : float
            How far a printed vertex on a surface may be from it [m].

        Returns
        -------
        ndarray, shape (frames, n, 3)
            The velocities after the corrections.
        """
        sim = self.sim
        vs = np.array(vs, np.float64)
        saved = [(ob.contact_vertices, ob.contact_normals) for ob in self.obstacles]
        t = sim.state.time
        try:
            for k in range(1, len(xs)):
                for ob in self.obstacles:
                    i = np.flatnonzero(_on_surface(ob, xs[k], rounding))
                    ob.contact_vertices = i
                    ob.contact_normals = _normals(ob, xs[k][i], vs[k][i], rounding)
                start, v = State(xs[k - 1], vs[k - 1], t, k - 1), vs[k]
                t = t + sim.h
                for e in sim._hooks["correct_velocities"]:   # as Simulation.step
                    v = e.correct_velocities(t, start, xs[k], v)
                vs[k] = v
        finally:
            for ob, (cv, cn) in zip(self.obstacles, saved, strict=True):
                ob.contact_vertices, ob.contact_normals = cv, cn
        return vs

    def note(self) -> str:
        """The note of the last solve's adopted decisions.

        Returns
        -------
        str
            "" when no decision was changed.
        """
        if not self.taken:
            return ""
        v, words = self.taken[0]
        c = len(self.taken)
        return (f"{c} post-solve contact decision{'s' * (c != 1)} too close to call from "
                f"the port's state (caught or not by a surface moved "
                f"{self.gap:.2g} m) taken as the port's: vertex {v} {words}")

    def unprojected(self, err, tol) -> str:
        """The note of a step whose vertices clothsim's projection moved the port left off.

        The judge compares both answers with the minimizer of g, which knows no obstacle:
        a port without the post-solve projection would pass it.

        Parameters
        ----------
        err : ndarray, shape (n,)
            |x_clothsim − x_port| per vertex [m] of clothsim's last step.
        tol : float
            The step's tolerance [m].

        Returns
        -------
        str
            "" when every vertex the obstacles moved is within the tolerance.
        """
        for ob in self.obstacles:
            moved = ob.contact_vertices[err[ob.contact_vertices] > tol]
            if len(moved):
                v = int(moved[np.argmax(err[moved])])
                return (f"{len(moved)} vertices clothsim's post-solve {ob.kind} projection "
                        f"moved are off by up to {err[v]:.3e} m (vertex {v}): the port "
                        f"projects otherwise, or not at all")
        return ""

    def _wrap(self, ob, original, x_port, rounding):
        def correct(t, state, x):
            x_own = original(t, state, x)
            x_new, taken = self._decide(ob, state.positions, x, x_own, x_port, self.gap)
            if taken:
                self.taken += [(v, words) for v, words, _ in taken]
                self._contacts(ob, taken)
            return x_new
        return correct

    def _decide(self, ob, x0, x, x_own, x_port, r):
        """clothsim's corrected x with the port's decisions for the marginal vertices."""
        codes = _codes(ob, x0, x, r)
        i = np.flatnonzero((codes != codes[0]).any(axis=0))
        if not len(i):
            return x_own, []
        cands, normals, words = [x_own[i]], [None], [""]
        free = (codes[:, i] == -1).any(axis=0)
        cands.append(np.where(free[:, None], x[i], np.nan))
        normals.append(None)
        words.append("not projected")
        for f in range(6 if ob.kind == "box" else 1):
            placed, n = _place(ob, x0[i], x[i], f)
            cands.append(np.where((codes[:, i] == f).any(axis=0)[:, None], placed, np.nan))
            normals.append(n)
            words.append(_face_name(ob, f))
        dist = np.stack([np.linalg.norm(c - x_port[i], axis=1) for c in cands])
        dist = np.where(np.isfinite(dist), dist, np.inf)
        best = np.argmin(dist, axis=0)
        cols = np.arange(len(i))
        changed = np.flatnonzero((best > 0) & (dist[best, cols] < dist[0]) & (dist[0] > r))
        x_new = x_own.copy()
        x_new[i[changed]] = np.stack(cands)[best[changed], changed]
        return x_new, [(int(i[j]), words[best[j]],
                        None if normals[best[j]] is None else normals[best[j]][j])
                       for j in changed]

    @staticmethod
    def _contacts(ob, taken):
        """The obstacle's contacts (for its velocity correction) after the adoption."""
        vs = np.array([v for v, _, _ in taken])
        keep = ~np.isin(ob.contact_vertices, vs)
        on = [(v, n) for v, _, n in taken if n is not None]
        ob.contact_vertices = np.concatenate([ob.contact_vertices[keep],
                                              np.array([v for v, _ in on], np.int64)])
        ob.contact_normals = np.concatenate([ob.contact_normals[keep],
                                             np.array([n for _, n in on]).reshape(-1, 3)])
