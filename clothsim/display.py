"""Scene geometry for display: the surfaces of the obstacles and the pinned points.

The simulation never needs these (obstacles act through their ``correct_positions`` hook);
pictures and ParaView do. Everything is read from the effects' public attributes:

* :class:`~clothsim.effects.Plane` (``point``, ``normal``, ``thickness``): a finite square
  quad (two triangles) centred under the cloth, sized to frame it;
* :class:`~clothsim.effects.Sphere` (``center``, ``radius``): a triangulated UV sphere;
* :class:`~clothsim.effects.Box` (``min``, ``max``): 8 corners, 12 triangles;
* :class:`~clothsim.effects.Pin` (``vertices`` once bound, ``targets(t)``): points;
* a large cloth's preview: :func:`decimate` keeps at most a budget of triangles (every k-th
  row and column of a grid, a vertex subset of any other mesh); :func:`picture_mesh` puts
  them on the vertices they use, so that a picture touches only those.

Only numpy is imported here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .io.frames import OBSTACLES_NAME
from .io.meshes import write_mesh
from .mesh import Mesh

#: Colours (RGB in [0, 1]) of obstacle kinds in the pictures.
OBSTACLE_COLORS = {"plane": (0.80, 0.80, 0.78), "sphere": (0.85, 0.45, 0.25),
                   "box": (0.90, 0.60, 0.15)}
PIN_COLOR = (0.80, 0.10, 0.10)


@dataclass(frozen=True)
class Surface:
    """A triangulated obstacle surface.

    Attributes
    ----------
    kind : str
        ``"plane"``, ``"sphere"`` or ``"box"``.
    vertices : ndarray, shape (k, 3), float64
        Corner positions [m].
    triangles : ndarray, shape (t, 3), int64
        Vertex indices of each triangle (outward normals counter-clockwise).
    """

    kind: str
    vertices: np.ndarray
    triangles: np.ndarray


def _plane_surface(plane, extent: np.ndarray) -> Surface:
    n = np.asarray(plane.normal, dtype=np.float64)
    offset = float(np.asarray(plane.point) @ n) + float(getattr(plane, "thickness", 0.0))
    lo, hi = extent.min(axis=0), extent.max(axis=0)
    mid = (lo + hi) / 2
    half = max(0.75 * float(np.max(hi - lo)), 0.1)
    c = mid - (mid @ n - offset) * n  # the centre of the cloth projected onto the plane
    a = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(n, a)
    u /= np.linalg.norm(u)
    v = np.cross(n, u)
    corners = np.array([c + half * (su * u + sv * v)
                        for su, sv in ((-1, -1), (1, -1), (1, 1), (-1, 1))])
    return Surface("plane", corners, np.array([[0, 1, 2], [0, 2, 3]], np.int64))


def _sphere_surface(sphere, rings: int = 12, segments: int = 24) -> Surface:
    theta = np.linspace(0.0, np.pi, rings + 1)[1:-1]
    phi = np.linspace(0.0, 2 * np.pi, segments, endpoint=False)
    T, P = np.meshgrid(theta, phi, indexing="ij")
    ring = np.stack([np.sin(T) * np.cos(P), np.cos(T), np.sin(T) * np.sin(P)], axis=-1)
    unit = np.vstack([[0.0, 1.0, 0.0], ring.reshape(-1, 3), [0.0, -1.0, 0.0]])
    tris = []
    top, bottom = 0, len(unit) - 1

    def idx(i, j):
        return 1 + i * segments + j % segments

    for j in range(segments):
        tris.append([top, idx(0, j + 1), idx(0, j)])
        tris.append([bottom, idx(rings - 2, j), idx(rings - 2, j + 1)])
        for i in range(rings - 2):
            a, b, c, d = idx(i, j), idx(i, j + 1), idx(i + 1, j), idx(i + 1, j + 1)
            tris += [[a, b, d], [a, d, c]]
    x = np.asarray(sphere.center, float) + float(sphere.radius) * unit
    return Surface("sphere", x, np.asarray(tris, np.int64))


def _box_surface(box) -> Surface:
    lo, hi = np.asarray(box.min, float), np.asarray(box.max, float)
    corners = np.array([[(lo, hi)[(k >> a) & 1][a] for a in range(3)] for k in range(8)])
    # corner k has x from bit 0, y from bit 1, z from bit 2; two triangles per face
    quads = [(0, 2, 6, 4), (1, 5, 7, 3), (0, 4, 5, 1), (2, 3, 7, 6), (0, 1, 3, 2), (4, 6, 7, 5)]
    tris = [[q[0], q[1], q[2]] for q in quads] + [[q[0], q[2], q[3]] for q in quads]
    return Surface("box", corners, np.asarray(tris, np.int64)[:, ::-1].copy())


def obstacle_surfaces(effects, extent=None) -> list[Surface]:
    """Triangulated surfaces of the obstacles among ``effects``.

    Parameters
    ----------
    effects : iterable of Effect
        The effects of a simulation or scene; those that are not obstacles are skipped.
    extent : array_like, shape (..., 3), optional
        Points [m] the finite quad of a plane is framed on (the cloth's positions); default
        a 1 m square about the origin.

    Returns
    -------
    list of Surface
        In the order of ``effects``.

    Examples
    --------
    >>> import clothsim as cs
    >>> [s.triangles.shape for s in obstacle_surfaces([cs.Box([0, 0, 0], [1, 1, 1])])]
    [(12, 3)]
    """
    X = (np.array([[-0.5, 0.0, -0.5], [0.5, 0.0, 0.5]]) if extent is None
         else np.asarray(extent, dtype=np.float64).reshape(-1, 3))
    out = []
    for e in effects:
        kind = getattr(e, "kind", "")
        if kind == "plane":
            out.append(_plane_surface(e, X))
        elif kind == "sphere":
            out.append(_sphere_surface(e))
        elif kind == "box":
            out.append(_box_surface(e))
    return out


def pinned_points(effects, positions=None, t: float = 0.0) -> np.ndarray:
    """Positions of pinned vertices (the pins' targets at time ``t``).

    Parameters
    ----------
    effects : iterable of Effect
        Effects of a bound simulation (a pin knows its vertices once bound).
    positions : ndarray, shape (n, 3), optional
        When given, the pinned vertices are drawn at these positions [m] instead of at their
        targets.
    t : float
        Time [s] for the targets.

    Returns
    -------
    ndarray, shape (p, 3)
        Points [m]; empty when no pin is bound or active.
    """
    pts = [np.zeros((0, 3))]
    for e in effects:
        if getattr(e, "kind", "") != "pin" or getattr(e, "model", None) is None:
            continue
        if hasattr(e, "active") and not e.active(t):
            continue
        if positions is not None:
            pts.append(np.asarray(positions, float)[e.vertices])
        else:
            pts.append(np.asarray(e.targets(t), float).reshape(-1, 3))
    return np.vstack(pts)


def pinned_mask(effects, vertex_count: int, t: float = 0.0) -> np.ndarray:
    """Which vertices a bound, active pin holds at time ``t``.

    Parameters
    ----------
    effects : iterable of Effect
        Effects of a bound simulation (exact and penalty pins alike).
    vertex_count : int
        n, the cloth's vertices.
    t : float
        Time [s] (a pin with a ``release`` time holds nothing after it).

    Returns
    -------
    ndarray, shape (n,), bool
        True for the pinned vertices.
    """
    mask = np.zeros(int(vertex_count), bool)
    for e in effects:
        if getattr(e, "kind", "") != "pin" or getattr(e, "model", None) is None:
            continue
        if hasattr(e, "active") and not e.active(t):
            continue
        mask[np.asarray(e.vertices, dtype=np.int64)] = True
    return mask


def surfaces_mesh(surfaces):
    """Merge surfaces into one vertex array, triangle array and per-vertex obstacle index.

    Parameters
    ----------
    surfaces : sequence of Surface
        As :func:`obstacle_surfaces` returns them.

    Returns
    -------
    vertices : ndarray, shape (k, 3)
    triangles : ndarray, shape (t, 3), int64
    obstacle : ndarray, shape (k,), int64
        Index of the surface each vertex belongs to.
    """
    vs, ts, ids, base = [np.zeros((0, 3))], [np.zeros((0, 3), np.int64)], [], 0
    for i, s in enumerate(surfaces):
        vs.append(s.vertices)
        ts.append(s.triangles + base)
        ids.append(np.full(len(s.vertices), i, np.int64))
        base += len(s.vertices)
    obstacle = np.concatenate(ids) if ids else np.zeros(0, np.int64)
    return np.vstack(vs), np.vstack(ts), obstacle


def _grid_triangles(ny: int, nx: int, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """Triangles of the sub-grid on ``rows`` × ``cols`` of an ny × nx grid, with the grid's
    split and orientation (:func:`clothsim.mesh.grid`), indexing the full grid's vertices."""
    i, j = np.meshgrid(rows[:-1], cols[:-1], indexing="ij")
    i2, j2 = np.meshgrid(rows[1:], cols[1:], indexing="ij")
    a, b = (i * nx + j).ravel(), (i * nx + j2).ravel()
    c, d = (i2 * nx + j).ravel(), (i2 * nx + j2).ravel()
    return np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)])


def _cluster_triangles(mesh: Mesh, budget: int) -> np.ndarray:
    """Vertex clustering on the rest shape: cubes of side s, one vertex of each cube kept
    (a boundary vertex where there is one, so the outline stays), triangles whose three
    corners fall in three different cubes kept, mapped to the kept vertices."""
    v, t = mesh.vertices, mesh.triangles
    n = len(v)
    e = np.sort(np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]]), axis=1)
    key, count = np.unique(e[:, 0] * n + e[:, 1], return_counts=True)
    boundary = np.zeros(n, bool)
    boundary[key[count == 1] // n] = boundary[key[count == 1] % n] = True
    area = 0.5 * np.linalg.norm(np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]]),
                                axis=1).sum()
    s = np.sqrt(2.0 * area / budget)
    while True:
        cell = np.floor((v - v.min(axis=0)) / s).astype(np.int64)
        span = cell.max(axis=0) + 1
        _, cluster = np.unique((cell[:, 0] * span[1] + cell[:, 1]) * span[2] + cell[:, 2],
                               return_inverse=True)
        order = np.lexsort((~boundary, cluster))  # per cluster: boundary vertices first
        first = np.ones(n, bool)
        first[1:] = cluster[order][1:] != cluster[order][:-1]
        rep = np.empty(cluster.max() + 1, np.int64)
        rep[cluster[order][first]] = order[first]
        c = cluster[t]
        keep = (c[:, 0] != c[:, 1]) & (c[:, 1] != c[:, 2]) & (c[:, 0] != c[:, 2])
        c = c[keep]
        k = np.int64(len(rep))
        sc = np.sort(c, axis=1)
        _, first_of = np.unique((sc[:, 0] * k + sc[:, 1]) * k + sc[:, 2], return_index=True)
        if len(first_of) <= budget:
            return rep[c[np.sort(first_of)]]
        s *= 1.25


def decimate(mesh: Mesh, budget: int) -> tuple[Mesh, str]:
    """A mesh of at most ``budget`` triangles that keeps the cloth's shape, for pictures.

    Parameters
    ----------
    mesh : Mesh
        The cloth.
    budget : int
        Triangles allowed, >= 2.

    Returns
    -------
    mesh : Mesh
        ``mesh`` itself when it has at most ``budget`` triangles. Otherwise a mesh on the
        same vertex array (the positions of every frame index it unchanged) whose triangles
        use a vertex subset: for a :func:`clothsim.mesh.grid`, every k-th row and column
        (the last row and column always kept); for any other mesh, one vertex per cube of
        the rest shape (vertex clustering, boundary vertices preferred). Strands are kept.
    note : str
        ``""``, or what was drawn, e.g. ``"every 6th row and column drawn"`` (for a title).

    Examples
    --------
    >>> import clothsim as cs
    >>> small, note = decimate(cs.grid(101, 101), 5000)
    >>> small.triangle_count <= 5000, note
    (True, 'every 2nd row and column drawn')
    """
    m = mesh.triangle_count
    if m <= budget:
        return mesh, ""
    if mesh.grid_shape is not None:
        ny, nx = mesh.grid_shape
        k = 2
        while 2 * (-(-(ny - 1) // k)) * (-(-(nx - 1) // k)) > budget:
            k += 1
        rows = np.unique(np.append(np.arange(0, ny, k), ny - 1))
        cols = np.unique(np.append(np.arange(0, nx, k), nx - 1))
        tris = _grid_triangles(ny, nx, rows, cols)
        suffix = {1: "st", 2: "nd", 3: "rd"}.get(k % 10 if k % 100 not in (11, 12, 13) else 0,
                                               "th")
        note = f"every {k}{suffix} row and column drawn"
    else:
        tris = _cluster_triangles(mesh, budget)
        note = f"{len(tris):,} of {m:,} triangles drawn"
    return Mesh(mesh.vertices, tris, mesh.strands), note


def picture_mesh(mesh: Mesh, budget: int) -> tuple[Mesh, np.ndarray | None, str]:
    """The mesh a picture draws: :func:`decimate`'s, on the vertices it uses only.

    A picture of a decimated cloth then projects, shades and frames those vertices (a 513²
    grid drawn from 8,192 triangles uses 4,225 of its 263,169 vertices), not every vertex.

    Parameters
    ----------
    mesh, budget
        The cloth and the triangles allowed, as for :func:`decimate`.

    Returns
    -------
    mesh : Mesh
        ``mesh`` itself when it has at most ``budget`` triangles; otherwise the decimated
        mesh on its own vertex array: the vertices its triangles and strands use, in order.
    take : ndarray of int, or None
        Indices of that mesh's vertices among the cloth's (``positions[take]``), None for
        ``mesh`` itself.
    note : str
        :func:`decimate`'s note (``""`` when the whole cloth is drawn).

    Examples
    --------
    >>> import clothsim as cs
    >>> drawn, take, note = picture_mesh(cs.grid(101, 101), 5000)
    >>> drawn.triangle_count <= 5000, len(take), note
    (True, 2601, 'every 2nd row and column drawn')
    """
    drawn, note = decimate(mesh, budget)
    if drawn is mesh:
        return mesh, None, ""
    take = np.unique(np.concatenate([drawn.triangles.ravel(), drawn.strands.ravel()]))
    local = np.full(len(mesh.vertices), -1, np.int64)
    local[take] = np.arange(len(take))
    return Mesh(mesh.vertices[take], local[drawn.triangles], local[drawn.strands]), take, note


def write_obstacles(path, effects, positions) -> object | None:
    """Write the obstacles' surfaces as one triangle mesh (``obstacles.vtu`` for ParaView).

    Parameters
    ----------
    path : path-like
        Output file (any format :func:`clothsim.io.write_mesh` writes).
    effects : iterable of Effect
        The simulation's effects; planes (a square framed on ``positions``), spheres and
        boxes are written, the others skipped.
    positions : ndarray, shape (n, 3)
        Cloth positions [m] the plane's square is framed on.

    Returns
    -------
    path or None
        ``path``, or None (nothing written) when there is no obstacle. Point data
        ``obstacle`` holds the index of the surface each vertex belongs to.
    """
    surfaces = obstacle_surfaces(effects, positions)
    if not surfaces:
        return None
    x, tris, ids = surfaces_mesh(surfaces)
    write_mesh(path, Mesh(x, tris), point_data={"obstacle": ids})
    return path


__all__ = ["Surface", "obstacle_surfaces", "decimate", "picture_mesh", "pinned_points",
           "pinned_mask",
           "surfaces_mesh",
           "write_obstacles", "OBSTACLES_NAME",
           "OBSTACLE_COLORS", "PIN_COLOR"]
