"""Where a port's held contact planes differ from clothsim's, vertex by vertex, in words.

A hold-mode port that writes its planes (``contacts.txt``, the layout ``clothsim export``
writes) is checked on them before its positions: in each step, every vertex clothsim
holds must be held by the port on the same plane, with the same friction state, and no
other (:func:`plane_differences`). Each difference is one sentence naming the step's
vertex and the face, e.g. "vertex 48 held on the box's top by clothsim, free in the port".
"""

from __future__ import annotations

import numpy as np

from ..contacts import contact_basis
from .held_steps import face_name


def _fmt(n) -> str:
    return "(" + ", ".join(f"{float(c) + 0.0:.3g}" for c in n) + ")"   # no "-0"


def _rank(normals: np.ndarray) -> int:
    layers = contact_basis(np.zeros(len(normals), np.int64), normals)
    return sum(len(v) for v, _ in layers)


def _point(normals: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    return np.linalg.lstsq(normals, offsets, rcond=None)[0]


def port_face(obstacles, normal, x):
    """The obstacle a port's plane at ``x`` belongs to, and its outward normal there.

    Parameters
    ----------
    obstacles : list of Obstacle
        At least one.
    normal : ndarray, shape (3,)
        The port's normal (either sign).
    x : ndarray, shape (3,)
        The vertex's position [m].

    Returns
    -------
    (Obstacle, ndarray (3,))
        The nearest obstacle whose surface normal there is parallel to ``normal`` (the
        nearest one when none is).
    """
    x = np.asarray(x, np.float64)
    found = []
    for e in obstacles:
        q, n = e.closest(x[None])
        found.append((abs(float(n[0] @ normal)) <= 0.99, float(np.linalg.norm(q[0] - x)),
                      id(e), e, n[0]))
    found.sort(key=lambda f: f[:3])
    return found[0][3], found[0][4]


def clothsim_rows(planes) -> dict:
    """clothsim's held planes of a step per vertex: its obstacles' decision.

    Parameters
    ----------
    planes : list of (Obstacle, Holding)
        :meth:`clothsim.ports.held_steps.HeldSteps.planes`.

    Returns
    -------
    dict
        vertex -> list of (obstacle, normal (3,), offset, sticks), the contact planes first
        (one per obstacle face), then a sticking vertex's two tangent planes.
    """
    rows: dict = {}
    for e, h in planes:
        c, m = h.planes, len(h.vertices)
        for i in range(len(c)):
            v = int(c.vertices[i])
            stick = bool(h.stick[i]) if i < m else True
            rows.setdefault(v, []).append((e, c.normals[i], float(c.offsets[i]), stick, i < m))
    return rows


def plane_differences(ours: dict, vertices, normals, offsets, x_port, obstacles, *,
                      offset_tolerance: float, normal_tolerance: float,
                      skip=()) -> list[tuple[int, str]]:
    """The vertices whose held planes differ between clothsim and the port, in words.

    Parameters
    ----------
    ours : dict
        :func:`clothsim_rows` of the step.
    vertices, normals, offsets : ndarray, shapes (c,), (c, 3), (c,)
        The port's planes of the step: vertex v stays on n · x = offset [m].
    x_port : ndarray, shape (n, 3)
        The port's positions at the step's start [m] (to name the face of a plane
        clothsim does not hold).
    obstacles : list of Obstacle
        The holding obstacles.
    offset_tolerance : float
        Largest difference of two parallel planes' offsets counted as the same plane [m].
    normal_tolerance : float
        Largest |n_port − n_clothsim| counted as the same normal.
    skip : iterable of int
        Vertices pinned exactly (their planes are dropped, the pin holds).

    Returns
    -------
    list of (int, str, str)
        (vertex, kind, sentence), by vertex; kind is "clothsim" (held by clothsim only),
        "port" (held by the port only), "stick" (clothsim sticks, the port slides),
        "slide" (the other way), or "plane" (held on another plane, or its sign flipped).
    """
    theirs: dict = {}
    for v, n, o in zip(vertices, normals, offsets, strict=True):
        theirs.setdefault(int(v), []).append((np.asarray(n, np.float64), float(o)))
    skip = set(int(v) for v in skip)
    out = []
    for v in sorted((set(ours) | set(theirs)) - skip):
        mine, port = ours.get(v, []), theirs.get(v, [])
        if not port:
            e, n = mine[0][0], mine[0][1]
            out.append((v, "clothsim", f"vertex {v} held on {face_name(e, n)} by clothsim, "
                                       f"free in the port"))
            continue
        if not mine:
            n, o = port[0]
            face = face_name(*port_face(obstacles, n, x_port[v])) if obstacles else "a plane"
            out.append((v, "port", f"vertex {v} held on {face} by the port (n = {_fmt(n)}, "
                                   f"offset {o:.6g} m), free in clothsim"))
            continue
        kind, text = _vertex_difference(v, mine, port, offset_tolerance, normal_tolerance)
        if text:
            out.append((v, kind, text))
    return out


def _vertex_difference(v, mine, port, otol, ntol) -> tuple[str, str]:
    """How one vertex's planes differ: (kind, sentence), ("", "") when they are the same."""
    face = face_name(mine[0][0], mine[0][1])
    N_c = np.array([r[1] for r in mine])
    N_p = np.array([n for n, _ in port])
    rc, rp = _rank(N_c), _rank(N_p)
    if any(r[3] for r in mine) and rp < 3 <= rc:
        return "stick", (f"vertex {v} sticks on {face} in clothsim (static friction: held in "
                         f"all three directions), slides in the port (held on {rp} "
                         f"plane{'s' * (rp != 1)})")
    if rp == 3 and rc < 3:
        return "slide", (f"vertex {v} slides on {face} in clothsim, sticks in the port (held "
                         f"in all three directions)")
    for e_i, n, o, _, normal_row in mine:
        if not normal_row:
            continue
        dots = N_p @ n
        j = int(np.argmax(np.abs(dots)))
        f = face_name(e_i, n)
        if dots[j] < -(1 - ntol):
            return "plane", (f"vertex {v}: the port's contact normal on {f} is "
                             f"{_fmt(N_p[j])}, clothsim's outward normal {_fmt(n)}: its sign "
                             f"is flipped")
        if rc == 3 and rp == 3:
            continue               # sticking in both: compare the points below
        if abs(dots[j]) < 1 - ntol:
            return "plane", (f"vertex {v} held on {f} (n = {_fmt(n)}) by clothsim, on "
                             f"another plane by the port (n = {_fmt(N_p[j])})")
        if abs(port[j][1] - o) > otol:
            return "plane", (f"vertex {v} held on {f} at n · x = {o:.9g} m by clothsim, "
                             f"{port[j][1]:.9g} m by the port ({abs(port[j][1] - o):.3e} m "
                             f"apart)")
    if rc == 3 and rp == 3:
        gap = float(np.linalg.norm(_point(N_c, np.array([r[2] for r in mine]))
                                   - _point(N_p, np.array([o for _, o in port]))))
        if gap > otol:
            return "plane", (f"vertex {v} sticks on {face} in both, the port {gap:.3e} m from "
                             f"where clothsim holds it")
    elif rp != rc:
        return "plane", (f"vertex {v} held on {face} in {rc} direction{'s' * (rc != 1)} by "
                         f"clothsim, in {rp} by the port")
    return "", ""


__all__ = ["clothsim_rows", "plane_differences", "port_face"]
