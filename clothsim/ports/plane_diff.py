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


def _port_face(obstacles, normal, x) -> str:
    """The face of an obstacle the port's plane lies on (its normal parallel there)."""
    best, where = np.inf, None
    for e in obstacles:
        _, n = e.closest(np.asarray(x, np.float64)[None])
        if abs(float(n[0] @ normal)) > 0.99:
            distance = float(np.linalg.norm(e.closest(x[None])[0][0] - x))
            if distance < best:
                best, where = distance, face_name(e, n[0])
    return where or "a plane"


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
    list of (int, str)
        (vertex, sentence), by vertex.
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
            out.append((v, f"vertex {v} held on {face_name(e, n)} by clothsim, free in the "
                           f"port"))
            continue
        if not mine:
            n, o = port[0]
            out.append((v, f"vertex {v} held on {_port_face(obstacles, n, x_port[v])} by the "
                           f"port (n = {_fmt(n)}, offset {o:.6g} m), free in clothsim"))
            continue
        text = _vertex_difference(v, mine, port, offset_tolerance, normal_tolerance)
        if text:
            out.append((v, text))
    return out


def _vertex_difference(v, mine, port, otol, ntol) -> str:
    """How one vertex's planes differ ("" when they are the same)."""
    e, n0 = mine[0][0], mine[0][1]
    face = face_name(e, n0)
    N_c = np.array([r[1] for r in mine])
    N_p = np.array([n for n, _ in port])
    sticks = any(r[3] for r in mine)
    rc, rp = _rank(N_c), _rank(N_p)
    if sticks and rp < 3 <= rc:
        return (f"vertex {v} sticks on {face} in clothsim (static friction: held in all three "
                f"directions), slides in the port (held on {rp} plane{'s' * (rp != 1)})")
    if rp == 3 and rc < 3:
        return (f"vertex {v} slides on {face} in clothsim, sticks in the port (held in all "
                f"three directions)")
    if rc == 3 and rp == 3:
        gap = float(np.linalg.norm(_point(N_c, np.array([r[2] for r in mine]))
                                   - _point(N_p, np.array([o for _, o in port]))))
        flip = _flipped(v, mine, port, face, ntol)
        if flip:
            return flip
        if gap > otol:
            return (f"vertex {v} sticks on {face} in both, the port {gap:.3e} m from where "
                    f"clothsim holds it")
        return ""
    for e_i, n, o, _, normal_row in mine:
        if not normal_row:
            continue
        dots = N_p @ n
        j = int(np.argmax(np.abs(dots)))
        f = face_name(e_i, n)
        if abs(dots[j]) < 1 - ntol:
            return (f"vertex {v} held on {f} (n = {_fmt(n)}) by clothsim, on another plane "
                    f"by the port (n = {_fmt(N_p[j])})")
        if dots[j] < 0:
            return (f"vertex {v}: the port's contact normal on {f} is {_fmt(N_p[j])}, "
                    f"clothsim's outward normal {_fmt(n)}: its sign is flipped")
        if abs(port[j][1] - o) > otol:
            return (f"vertex {v} held on {f} at n · x = {o:.9g} m by clothsim, "
                    f"{port[j][1]:.9g} m by the port ({abs(port[j][1] - o):.3e} m apart)")
    if rp != rc:
        return (f"vertex {v} held on {face} in {rc} direction{'s' * (rc != 1)} by clothsim, "
                f"{rp} by the port")
    return ""


def _flipped(v, mine, port, face, ntol) -> str:
    for _, n, _, _, normal_row in mine:
        if normal_row:
            for m, _ in port:
                if float(m @ n) < -(1 - ntol):
                    return (f"vertex {v}: the port's contact normal on {face} is {_fmt(m)}, "
                            f"clothsim's outward normal {_fmt(n)}: its sign is flipped")
    return ""


__all__ = ["clothsim_rows", "plane_differences"]
