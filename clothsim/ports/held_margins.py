"""Contact decisions too close to call from a port's state: taken as the port took them.

Which vertices a step holds is decided by thresholds (:mod:`clothsim.effects.holding`): a
held vertex is released when its contact force turns negative, a new contact is one the
solve put inside the obstacle (its force m · depth / h²), a vertex sticks while its
tangential force stays inside the friction cone. ``check`` takes those decisions from
the port's state, and the port's state carries its rounding (printed digits, float32):
a position off by δ changes a vertex's force by up to about (m_v + h² Σ k) δ / h² (the
Hessian's diagonal over h²; at 25² with springs of 800 N/m, 6 printed digits move it by
0.2 N, ten times a vertex's weight). A decision whose deciding force lies within that of
its threshold is **marginal**: either outcome is right, and the port's is adopted
(:func:`adopt`), the step solved again with it. Every other difference stays a
``contacts differ``.

A vertex's first contact step decides its friction state geometrically (the seed's
response: it sticks when friction stops its tangential step, μ × depth >= |Δ_t|), with no
force of a step before to weigh: :func:`first_contact_flips` takes the step before again
from the port's state and hands the obstacle's own ``correct_positions`` the solve's answer
and the start moved by the rounding towards sliding and towards sticking; a new contact
whose friction state differs between the two is marginal too.

The port's outcome comes from its planes when it wrote them (``kind`` of
:func:`clothsim.ports.plane_diff.plane_differences`), otherwise from its answer
(:func:`inferred`): a marginally held vertex that the port's answer leaves off its plane,
outwards, was released; a marginally released one the port's answer keeps on it was held.
"""

from __future__ import annotations

import numpy as np

from ..effects.holding import NOISE_MARGIN, Holding
from .held_first import first_contact_flips
from .judge import hessian_diagonal
from .plane_diff import port_face

#: The kinds of plane difference a marginal decision explains.
MARGINAL_KINDS = ("clothsim", "port", "stick", "slide")


def position_rounding(x: np.ndarray, digits: int, float32: bool, floor: float) -> np.ndarray:
    """How far the port's numbers may be from the values it computed, per vertex [m].

    Parameters
    ----------
    x : ndarray, shape (n, 3)
        The port's positions [m].
    digits : int
        Significant digits printed (17: in full).
    float32 : bool
        The values are float32 numbers.
    floor : float
        At least this [m] (the float64 tolerance: two solves' own differences).

    Returns
    -------
    ndarray, shape (n,)
        √3 × the largest coordinate's rounding: half a unit in the last printed digit, or
        half a float32 ulp.
    """
    big = np.abs(np.asarray(x, np.float64)).max(axis=1)
    r = np.zeros(len(big))
    if digits < 15:
        exponent = np.floor(np.log10(np.maximum(big, 1e-300)))
        r = 0.5 * 10.0 ** (exponent + 1 - digits)
    if float32:
        r = np.maximum(r, 0.5 * np.spacing(big.astype(np.float32)).astype(np.float64))
    return np.maximum(np.sqrt(3.0) * r, floor)


class Margins:
    """The forces behind one step's contact decisions, and how far rounding moves them.

    Parameters
    ----------
    held : HeldSteps
        Anchored at the step (its decision) with the step before known.
    model : Model
        The step's model.
    problem : StepProblem
        The step.
    rounding : ndarray, shape (n,)
        How far each vertex of the port's state may be from what it computed [m]
        (:func:`position_rounding`).

    Attributes
    ----------
    force : ndarray, shape (n,)
        How far that moves a solved contact force [N]: (m_v / h² + 2 Σ k) × rounding.
    entry : ndarray, shape (n,)
        The same for a new contact's m · depth / h²: m_v × rounding / h² [N].
    """

    def __init__(self, held, model, problem, rounding):
        self.held = held
        h2 = problem.h ** 2
        mass = model.vertex_mass
        self.force = (2 * hessian_diagonal(model, problem) - mass) * rounding / h2
        self.entry = mass * rounding / h2
        self.tol = rounding
        self.previous = held.previous_planes()
        self._first: set | None = None

    def _was(self, v):
        """(obstacle, holding, row) of v in the step before, or None."""
        for e, h in self.previous:
            i = np.flatnonzero(h.vertices == v)
            if len(i):
                return e, h, int(i[0])
        return None

    def marginal(self, v: int, kind: str) -> bool:
        """Whether clothsim's decision for vertex v, of the given kind, was too close to call.

        Parameters
        ----------
        v : int
        kind : {"clothsim", "port", "stick", "slide"}
            What differs (:func:`~clothsim.ports.plane_diff.plane_differences`).

        Returns
        -------
        bool
        """
        F = float(self.force[v])
        was = self._was(v)
        forces = None if was is None else was[1].planes.forces
        if kind == "clothsim":     # clothsim holds it: kept by a small push, or a shallow entry
            limit = F if forces is not None else float(self.entry[v])
            for _, h in self.held.planes():
                i = np.flatnonzero(h.vertices == v)
                if len(i) and abs(float(h.normal_force[i[0]])) <= limit:
                    return True
            return False
        if kind == "port":         # clothsim released it (a small pull), or never touched it
            if forces is not None:
                return abs(float(forces[was[2]])) <= F
            x = self.held.x()[v]
            return any(float(np.linalg.norm(e.closest(x[None])[0][0] - x)) <= self.tol[v]
                       for e in self.held.obstacles)
        if forces is None:         # stick / slide of a new contact: a geometric decision
            if self._first is None:
                self._first = first_contact_flips(self.held, self.tol)
            return v in self._first
        e, h, i = was
        if not h.stick[i]:         # a sliding vertex sticks once it stopped: v_t . t <= 0
            along = self._along(v, h.normals[i], h.pull[i])
            return along is not None and abs(along) <= 2 * self.tol[v] / self.held.sim.h
        R = h.reaction()[i]
        fn = float(R @ h.normals[i])
        ft = float(np.linalg.norm(R - fn * h.normals[i]))
        cone = e.friction * fn + NOISE_MARGIN * h.planes.noise
        return abs(ft - cone) <= (1 + e.friction) * F


    def first_contact(self, v: int, kind: str) -> bool:
        """Whether v's decision of the given kind is a first contact's friction state.

        Parameters
        ----------
        v : int
        kind : str

        Returns
        -------
        bool
            True for "stick" / "slide" of a vertex not held in the step before.
        """
        return kind in ("stick", "slide") and self._was(v) is None

    def _along(self, v: int, n: np.ndarray, pull: np.ndarray) -> float | None:
        """v_t · t̂ of the port's step before at vertex v [m/s], t̂ the direction kinetic
        friction opposed (its tangential velocity at the step's start, else the pull): what
        decides that a sliding vertex stopped. None at the first step."""
        state = self.held.previous_state()
        if state is None:
            return None
        d = (self.held.x()[v] - state.positions[v]) / self.held.sim.h
        t = state.velocities[v] - (state.velocities[v] @ n) * n
        length = float(np.linalg.norm(t))
        t = t / length if length > 0 else pull
        return float((d - (d @ n) * n) @ t)

    def friction_flip(self, v: int, x_port, x_cs) -> str:
        """Whether the port's answer took a marginal friction decision the other way.

        Parameters
        ----------
        v : int
            A held vertex.
        x_port, x_cs : ndarray, shape (n, 3)
            The port's and clothsim's x_{k+1} [m].

        Returns
        -------
        str
            "stick" (clothsim's sticks, the port's moved), "slide" (clothsim's slid, the
            port's stayed), or "".
        """
        x = self.held.x()
        moved_p = float(np.linalg.norm(x_port[v] - x[v]))
        moved_c = float(np.linalg.norm(x_cs[v] - x[v]))
        for _, h in self.held.planes():
            i = np.flatnonzero(h.vertices == v)
            if not len(i):
                continue
            stuck = bool(h.stick[i[0]])
            kind = "stick" if stuck else "slide"
            if stuck and moved_p > self.tol[v] >= moved_c and self.marginal(v, kind):
                return kind
            if not stuck and moved_p <= self.tol[v] < moved_c and self.marginal(v, kind):
                return kind
        return ""


def inferred(held, margins, x_port, x_cs) -> list[tuple[int, str]]:
    """Marginal decisions the port's answer shows it took the other way, as plane kinds.

    Parameters
    ----------
    held : HeldSteps
    margins : Margins
    x_port, x_cs : ndarray, shape (n, 3)
        The port's and clothsim's x_{k+1} [m].

    Returns
    -------
    list of (int, str)
        (vertex, kind) with kind "clothsim" (the port released it), "port" (held it),
        "stick" (it slid where clothsim's stuck) or "slide" (it stuck where clothsim's
        slid).
    """
    tol, out = margins.tol, []
    for _, h in held.planes():
        c = len(h.vertices)
        v, n, o = h.vertices, h.normals, h.planes.offsets[:c]
        out_port = np.einsum("ij,ij->i", x_port[v], n) - o
        out += [(int(u), "clothsim") for u, gap in zip(v, out_port, strict=True)
                if gap > tol[u] and margins.marginal(int(u), "clothsim")]
    now = {int(u) for _, h in held.planes() for u in h.vertices}
    flipped = {u for u, _ in out}
    for u in sorted(now - flipped):
        kind = margins.friction_flip(u, x_port, x_cs)
        if kind:
            out.append((u, kind))
    for _, h in margins.previous:
        c = len(h.vertices)
        for u, n, o in zip(h.vertices, h.normals, h.planes.offsets[:c], strict=True):
            u = int(u)
            if u in now or not margins.marginal(u, "port"):
                continue
            on_port = abs(float(x_port[u] @ n) - o) <= tol[u]
            off_cs = abs(float(x_cs[u] @ n) - o) > tol[u]
            if on_port and off_cs:
                out.append((u, "port"))
    return out


def unsure(held, margins, x_port, changes) -> list[tuple[int, str]]:
    """Marginal decisions the port's answer cannot show: held or not, it is on the surface.

    A vertex clothsim holds by a decision too close to call (a new contact caught at a
    depth within the rounding, a push within it of 0) and that the port's answer has on
    its plane or on the obstacle's surface may have been free in the port's step: caught
    at its end and placed there, it lands on the surface too. Which it was shows only in
    the rest of the cloth, through the solve (:func:`clothsim.ports.held_verdicts.settle`
    solves the step both ways).

    Parameters
    ----------
    held : HeldSteps
    margins : Margins
    x_port : ndarray, shape (n, 3)
        The port's x_{k+1} [m].
    changes : list of (int, str)
        The decisions :func:`inferred` already takes as the port's (left out).

    Returns
    -------
    list of (int, str)
        (vertex, "clothsim"): release it.
    """
    tol, taken, out = margins.tol, {u for u, _ in changes}, []
    for e, h in held.planes():
        c = len(h.vertices)
        v, n, o = h.vertices, h.normals, h.planes.offsets[:c]
        gap = np.abs(np.einsum("ij,ij->i", x_port[v], n) - o)
        surface = np.linalg.norm(e.closest(x_port[v])[0] - x_port[v], axis=1)
        out += [(int(u), "clothsim") for u, a, b in zip(v, gap, surface, strict=True)
                if int(u) not in taken and min(a, b) <= tol[u]
                and margins.marginal(int(u), "clothsim")]
    return out


def adopt(held, changes, port_planes=None) -> None:
    """Change the step's decision to the port's, vertex by vertex.

    Parameters
    ----------
    held : HeldSteps
        Anchored at the step; its obstacles' holdings are replaced.
    changes : list of (int, str)
        (vertex, kind): "clothsim" releases it, "port" holds it (on the port's plane when
        given, else on its plane of the step before), "stick" lets it slide, "slide" makes
        it stick, "plane" holds it on the port's plane instead of clothsim's (sticking when
        the port holds it in three directions).
    port_planes : tuple of ndarray, optional
        The port's (vertices, normals, offsets) of the step.
    """
    kinds = dict(changes)
    x = held.x()
    new = []
    for e, h in held.planes():
        c = len(h.vertices)
        keep = np.array([kinds.get(int(v)) not in ("clothsim", "plane") for v in h.vertices],
                        bool)
        stick = h.stick.copy()
        for i, v in enumerate(h.vertices):
            kind = kinds.get(int(v))
            stick[i] = False if kind == "stick" else True if kind == "slide" else stick[i]
        parts = [h.vertices[keep], h.normals[keep], stick[keep], h.normal_force[keep],
                 h.pull[keep], h.planes.offsets[:c][keep]]
        new.append((e, parts))
    for v, kind in changes:
        if kind not in ("port", "plane"):
            continue
        e, n, o = _port_plane(held, v, port_planes, x)
        sticks = port_planes is not None and int(np.sum(port_planes[0] == v)) >= 3
        for f, parts in new:
            if f is e:
                for j, item in enumerate((v, n, sticks, 0.0, np.zeros(3), o)):
                    parts[j] = np.concatenate([parts[j], np.asarray(item)[None]])
    held.replace([(e, _holding(x, *parts)) for e, parts in new])


def _port_plane(held, v, port_planes, x):
    """The obstacle, outward normal and offset of the plane the port holds vertex v on."""
    if port_planes is not None:
        vs, ns, os_ = port_planes
        i = int(np.flatnonzero(vs == v)[0])
        e, outward = port_face(held.obstacles, ns[i], x[v])
        sign = 1.0 if float(ns[i] @ outward) >= 0 else -1.0
        return e, sign * ns[i], sign * float(os_[i])
    for e, h in held.previous_planes():
        i = np.flatnonzero(h.vertices == v)
        if len(i):
            return e, h.normals[i[0]], float(h.planes.offsets[i[0]])
    e, n = port_face(held.obstacles, np.zeros(3), x[v])
    return e, n, float(n @ x[v])


def _holding(x, vertices, normals, stick, force, pull, offsets) -> Holding:
    out = Holding(x, vertices.astype(np.int64), normals.reshape(-1, 3), stick.astype(bool),
                  force.astype(np.float64), pull.reshape(-1, 3))
    out.planes.offsets[:len(vertices)] = offsets
    return out


__all__ = ["MARGINAL_KINDS", "Margins", "adopt", "inferred", "position_rounding", "unsure"]
