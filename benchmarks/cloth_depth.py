"""How far an obstacle reaches through the cloth's triangles (contact tests only vertices).

Every vertex may be outside an obstacle while an edge of a box, or a sphere's cap, lies in
front of a triangle whose corners rest on the solid: over a box's top edge the triangle
between a vertex on the top face and one on the side face cuts the corner off, and the
box's edge shows through the cloth. :func:`depth_through_cloth` measures that, exactly,
for the three obstacle shapes, against the solid as declared (``min``/``max``, ``center``
and ``radius``, ``point``/``normal``), not the surface a contact ``thickness`` moves the
cloth to.

For a triangle T with unit normal n turned away from the solid's centre, its depth is the largest
n · (q − a) over the points q of the solid in the prism over T (q projects into T; a is a
corner of T): how far the solid stands in front of the cloth there.

- **box**: a linear function's maximum over the polytope box ∩ prism lies at one of its
  corners, which are box corners inside the prism, box edges crossing a side of the prism,
  or prism edges (the lines through T's corners along n) leaving the box; all three kinds
  are evaluated.
- **sphere**: R − dist(c, T), the distance from the centre to the nearest point of T
  (the two agree when c projects into T).
- **plane**: the deepest corner behind the plane (a triangle is a convex combination of
  its corners).
"""

from __future__ import annotations

import numpy as np


def _rowdot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.einsum("...k,...k->...", a, b)


def _inside_triangle(q, a, b, c):
    """Whether q (…, 3) projects into the triangles (a, b, c) (closed, either winding)."""
    w = np.cross(b - a, c - a)                       # the winding's normal
    inside = np.ones(np.broadcast_shapes(q.shape, w.shape)[:-1], bool)
    for p0, p1 in ((a, b), (b, c), (c, a)):
        inside &= _rowdot(np.cross(p1 - p0, q - p0), w) >= -1e-12 * _rowdot(w, w)
    return inside


def _near(x: np.ndarray, triangles: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Triangles whose bounding box, grown by their longest edge, meets [lo, hi]."""
    p = x[triangles]                                         # (T, 3, 3)
    size = np.linalg.norm(p - np.roll(p, 1, axis=1), axis=2).max(axis=1)[:, None]
    return triangles[np.all((p.min(axis=1) - size <= hi) & (p.max(axis=1) + size >= lo),
                            axis=1)]


def _frame(x, triangles, inner):
    """Corners a, b, c and unit normals turned away from the point ``inner`` (the solid's
    centre: for a triangle lying on a face, n is that face's outward normal)."""
    a, b, c = (x[triangles[:, k]] for k in range(3))
    n = np.cross(b - a, c - a)
    length = np.linalg.norm(n, axis=1)
    ok = length > 0
    a, b, c, n = a[ok], b[ok], c[ok], n[ok] / length[ok, None]
    n *= np.where(_rowdot(n, (a + b + c) / 3 - inner) < 0, -1.0, 1.0)[:, None]
    return a, b, c, n


def _meets_box(lo, hi, a, b, c) -> np.ndarray:
    """Whether each triangle (a, b, c) meets the closed box [lo, hi]: the separating axis
    test on the box's 3 face normals, the triangle's normal and the 9 edge × axis crosses."""
    centre, half = (lo + hi) / 2, (hi - lo) / 2
    p = np.stack([a, b, c], axis=1) - centre                   # (T, 3, 3)
    edges = [b - a, c - b, a - c]
    axes = [np.broadcast_to(np.eye(3)[k], a.shape) for k in range(3)]
    axes.append(np.cross(edges[0], edges[1]))
    axes += [np.cross(e, np.eye(3)[k]) for e in edges for k in range(3)]
    meets = np.ones(len(a), bool)
    for axis in axes:
        proj = np.einsum("tvk,tk->tv", p, axis)
        reach = np.abs(axis) @ half
        slack = 1e-12 * (np.abs(proj).max(axis=1) + reach)
        meets &= (proj.min(axis=1) <= reach + slack) & (proj.max(axis=1) >= -reach - slack)
    return meets


def box_depth(lo, hi, x: np.ndarray, triangles: np.ndarray) -> float:
    """The largest depth of the box [lo, hi] in front of a triangle [m] (0 when none is).

    Parameters
    ----------
    lo, hi : (3,) array_like
        Opposite corners of the box [m].
    x : ndarray, shape (n, 3)
        Cloth positions [m].
    triangles : ndarray, shape (T, 3), int

    Returns
    -------
    float
    """
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    tri = _near(x, np.asarray(triangles), lo, hi)
    if not len(tri):
        return 0.0
    a, b, c, n = _frame(x, tri, (lo + hi) / 2)
    meets = _meets_box(lo, hi, a, b, c)        # a triangle the box does not meet: depth 0
    a, b, c, n = a[meets], b[meets], c[meets], n[meets]
    if not len(a):
        return 0.0
    best = np.zeros(len(a))
    # box corners inside the prism
    corners = np.array([[(lo, hi)[i >> k & 1][k] for k in range(3)] for i in range(8)])
    q = np.broadcast_to(corners, (len(a), 8, 3))
    A, B, C, N = (v[:, None, :] for v in (a, b, c, n))
    d = np.where(_inside_triangle(q, A, B, C), _rowdot(q - A, N), 0.0)
    best = np.maximum(best, d.max(axis=1))
    # box edges crossing a side of the prism
    starts, dirs = [], []
    for k in range(3):
        e = np.zeros(3)
        e[k] = hi[k] - lo[k]
        for p in corners[corners[:, k] == lo[k]]:
            starts.append(p)
            dirs.append(e)
    P, E = np.array(starts)[None], np.array(dirs)[None]       # (1, 12, 3)
    for p0, p1 in ((a, b), (b, c), (c, a)):
        m = np.cross(n, p1 - p0)[:, None, :]
        P0, side = p0[:, None, :], (p1 - p0)[:, None, :]
        me = _rowdot(m, E)
        with np.errstate(divide="ignore", invalid="ignore"):
            s = _rowdot(m, P0 - P) / me
            q = P + s[..., None] * E
            t = _rowdot(q - P0, side) / _rowdot(side, side)
        hit = (me != 0) & (s >= 0) & (s <= 1) & (t >= 0) & (t <= 1)
        d = np.where(hit, _rowdot(q - P0, N), 0.0)
        best = np.maximum(best, d.max(axis=1))
    # the lines through the triangle's corners along n, where they leave the box
    for v in (a, b, c):
        with np.errstate(divide="ignore", invalid="ignore"):
            s0, s1 = (lo - v) / n, (hi - v) / n
        near, far = np.minimum(s0, s1), np.maximum(s0, s1)
        flat = n == 0
        inside_slab = (v >= lo) & (v <= hi)
        near = np.where(flat, np.where(inside_slab, -np.inf, np.inf), near)
        far = np.where(flat, np.where(inside_slab, np.inf, -np.inf), far)
        t_near, t_far = near.max(axis=1), far.min(axis=1)
        best = np.maximum(best, np.where(t_near <= t_far, t_far, 0.0))
    return float(best.max())


def sphere_depth(center, radius: float, x: np.ndarray, triangles: np.ndarray) -> float:
    """The largest R − dist(c, T) over the triangles [m] (0 when the sphere clears them all).

    Parameters
    ----------
    center : (3,) array_like
        Centre c [m].
    radius : float
        R [m].
    x : ndarray, shape (n, 3)
        Cloth positions [m].
    triangles : ndarray, shape (T, 3), int

    Returns
    -------
    float
    """
    center = np.asarray(center, float)
    tri = _near(x, np.asarray(triangles), center - radius, center + radius)
    if not len(tri):
        return 0.0
    a, b, c, n = _frame(x, tri, center)
    if not len(a):
        return 0.0
    plane = _rowdot(center - a, n)
    dist = np.where(_inside_triangle(center[None], a, b, c), np.abs(plane), np.inf)
    for p0, p1 in ((a, b), (b, c), (c, a)):
        e = p1 - p0
        t = np.clip(_rowdot(center - p0, e) / _rowdot(e, e), 0.0, 1.0)
        dist = np.minimum(dist, np.linalg.norm(p0 + t[:, None] * e - center, axis=1))
    return float(max(0.0, (radius - dist).max()))


def depth_through_cloth(obstacle, x: np.ndarray, triangles: np.ndarray) -> float:
    """How far ``obstacle`` (a Box, Sphere or Plane effect) lies in front of the cloth [m].

    Parameters
    ----------
    obstacle : Obstacle
        Measured as declared (its contact ``thickness`` is not part of the solid).
    x : ndarray, shape (n, 3)
        Cloth positions [m].
    triangles : ndarray, shape (T, 3), int

    Returns
    -------
    float
        The largest depth over the triangles (module docstring), 0 when none.
    """
    if obstacle.kind == "box":
        return box_depth(obstacle.min, obstacle.max, x, triangles)
    if obstacle.kind == "sphere":
        return sphere_depth(obstacle.center, obstacle.radius, x, triangles)
    if obstacle.kind == "plane":
        return float(max(0.0, -((x - obstacle.point) @ obstacle.normal).min()))
    raise ValueError(f"no depth for obstacle kind {obstacle.kind!r}")
