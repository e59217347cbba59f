"""What the camera of a picture sees: the view, which cloth triangles a solid hides, shading.

Pictures (:mod:`clothsim.plotting`) draw in 2-D with a depth sort (painter's algorithm), in
three layers: the cloth an obstacle hides, the obstacles' camera-facing faces, the rest of
the cloth. This module decides the layers and the brightness of every triangle; only numpy
is imported.

Which triangles a solid hides (:func:`hidden_triangles`)
    A triangle is hidden when the ray from its centroid toward the camera passes through a
    convex obstacle (sphere: exactly; box: the slabs of its faces). A triangle that *lies on*
    the obstacle (no vertex inside the solid by more than a tolerance) is tested against the
    solid shrunk by the depth of its centroid plus that tolerance: a flat triangle on a
    curved surface sags into it, and a triangle folded over a box's edge has its centroid
    inside, but such a triangle is hidden only when it lies on the far side of the solid
    (its centroid and its three corners).
    One vectorized test per obstacle, as many rows as triangles.

Shading (:func:`shade`)
    Two-sided Lambert with the light from the camera's side, from per-vertex normals (the
    area-weighted mean of the adjacent triangles' normals) averaged over each triangle, so
    folds and curvature show without edges; obstacles keep their flat faces. The cloth is
    also darkened with its distance from the camera (:func:`depth_cue`, up to 30 % at the
    far end of the picture), so that a flat sheet shows its tilt.
"""

from __future__ import annotations

import numpy as np


class View:
    """Orthographic camera, y up: azimuth about y and elevation above the xz plane [deg].

    Parameters
    ----------
    azimuth, elevation : float
        Camera direction [deg].

    Notes
    -----
    ``project(x)`` maps points (…, 3) to screen coordinates u (right), v (up) and a depth
    that grows toward the camera. Drawing in 2-D with a depth sort (painter's algorithm)
    is much faster than mplot3d and looks the same for a cloth. The light comes from the
    camera's side, a little above it.
    """

    def __init__(self, azimuth: float = 35.0, elevation: float = 25.0):
        a, e = np.radians(azimuth), np.radians(elevation)
        self.azimuth, self.elevation = float(azimuth), float(elevation)
        self.toward = np.array([np.cos(e) * np.sin(a), np.sin(e), np.cos(e) * np.cos(a)])
        self.right = np.array([np.cos(a), 0.0, -np.sin(a)])
        self.up = np.cross(self.toward, self.right)
        self.light = self.toward + 0.5 * self.up
        self.light /= np.linalg.norm(self.light)

    def project(self, x: np.ndarray) -> np.ndarray:
        """Project points.

        Parameters
        ----------
        x : ndarray, shape (..., 3)
            Points [m].

        Returns
        -------
        ndarray, shape (..., 3)
            Screen coordinates u, v [m] and depth [m] (larger is nearer the camera).
        """
        return x @ np.stack([self.right, self.up, self.toward], axis=1)


def _sphere(surface) -> tuple[np.ndarray, float]:
    center = surface.vertices.mean(axis=0)
    return center, float(np.linalg.norm(surface.vertices - center, axis=1).max())


def _face_planes(surface) -> tuple[np.ndarray, np.ndarray]:
    """Unit outward normals (F, 3) and offsets (F,) of a convex surface: inside is n·x < h."""
    tri = surface.vertices[surface.triangles]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    mid = tri.mean(axis=1)
    n *= np.sign(np.einsum("ij,ij->i", n, mid - surface.vertices.mean(axis=0)))[:, None]
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    return n, np.einsum("ij,ij->i", n, mid)


def solid_depth(surface, p: np.ndarray) -> np.ndarray:
    """How deep points lie inside a convex obstacle [m] (negative outside).

    Parameters
    ----------
    surface : clothsim.display.Surface
        A sphere or box (any closed convex surface).
    p : ndarray, shape (k, 3)
        Points [m].

    Returns
    -------
    ndarray, shape (k,)
        Distance to the surface inside the solid; outside, minus the distance to the
        sphere, or minus the largest distance to a face plane (a polytope's lower bound).
    """
    if surface.kind == "sphere":
        center, r = _sphere(surface)
        return r - np.linalg.norm(p - center, axis=1)
    n, h = _face_planes(surface)
    return np.min(h - p @ n.T, axis=1)


def _ray_meets(surface, c: np.ndarray, d: np.ndarray, shrink: np.ndarray,
               eps: float) -> np.ndarray:
    """Does the ray c + t d (t > 0) pass more than ``eps`` through the solid shrunk by
    ``shrink`` (k,) [m]? (sphere: exact; polytope: Cyrus–Beck clipping on its faces)"""
    if surface.kind == "sphere":
        center, r = _sphere(surface)
        radius = r - shrink
        w = c - center
        b = w @ d
        disc = b * b - (np.einsum("ij,ij->i", w, w) - radius * radius)
        return (radius > 0) & (disc > 0) & (-b + np.sqrt(np.maximum(disc, 0)) > eps)
    n, h = _face_planes(surface)
    num = (h[None, :] - shrink[:, None]) - c @ n.T  # (k, F): n·(c + t d) <= h - shrink
    den = n @ d
    with np.errstate(divide="ignore", invalid="ignore"):
        t = num / den
    exits, enters = den > 1e-12, den < -1e-12
    t_hi = np.min(np.where(exits, t, np.inf), axis=1)
    t_lo = np.max(np.where(enters, t, -np.inf), axis=1)
    parallel_out = np.any(~(exits | enters) & (num < 0), axis=1)
    return ~parallel_out & (t_hi > np.maximum(t_lo, 0.0)) & (t_hi > eps)


def hidden_triangles(surfaces, view: View, x: np.ndarray, triangles: np.ndarray,
                     eps: float) -> np.ndarray:
    """Mask of the cloth triangles a convex obstacle hides from the camera.

    Parameters
    ----------
    surfaces : sequence of clothsim.display.Surface
        The obstacles; planes are skipped (they are drawn behind everything).
    view : View
        The camera.
    x : ndarray, shape (n, 3)
        Cloth positions [m].
    triangles : ndarray, shape (m, 3), int
        Cloth triangles.
    eps : float
        Tolerance [m]: a vertex this close to the surface (or inside by less) lies on it,
        and a ray must pass more than this through the solid to hide a triangle.

    Returns
    -------
    ndarray, shape (m,), bool
        True for the triangles to draw under the obstacles' front faces.

    Notes
    -----
    A triangle whose vertices all lie on or outside the solid (inside by at most ``eps``)
    is tested against the solid shrunk by its centroid's depth plus ``eps``: its centroid
    then lies just outside, beside the part of the surface the triangle rests on, and the
    ray toward the camera meets the shrunk solid only when that part faces away from the
    camera; and it is hidden only when its three corners, tested the same way, are hidden
    too (a triangle folded over an edge of the silhouette is partly in view). Any other
    triangle is tested at its centroid against the solid itself.
    """
    triangles = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    hidden = np.zeros(len(triangles), bool)
    if not len(triangles):
        return hidden
    # only the vertices drawn (a decimated cloth uses few of them)
    used, local = np.unique(triangles, return_inverse=True)
    x, triangles = np.asarray(x)[used], local.reshape(-1, 3)
    c = x[triangles].mean(axis=1)
    for surf in surfaces:
        if surf.kind == "plane":
            continue
        depth = solid_depth(surf, x)
        resting = depth[triangles].max(axis=1) <= eps
        shrink = np.where(resting, np.maximum(solid_depth(surf, c), 0.0) + eps, 0.0)
        behind = _ray_meets(surf, c, view.toward, shrink, eps)
        # a resting triangle folded over an edge of the silhouette is partly in view: it
        # is hidden only when its corners are too
        corner = _ray_meets(surf, x, view.toward, np.maximum(depth, 0.0) + eps, eps)
        hidden |= behind & (~resting | corner[triangles].all(axis=1))
    return hidden


def vertex_normals(x: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Unit per-vertex normals: the area-weighted sum of the adjacent triangles' normals.

    Parameters
    ----------
    x : ndarray, shape (n, 3)
        Positions [m].
    triangles : ndarray, shape (m, 3), int
        Triangles (consistently oriented for a smooth result).

    Returns
    -------
    ndarray, shape (n, 3)
        Unit normals; zero for a vertex in no triangle.
    """
    t = x[triangles]
    fn = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])  # length = 2 × area
    idx = np.asarray(triangles).ravel()
    n = np.stack([np.bincount(idx, np.repeat(fn[:, k], 3), minlength=len(x))
                  for k in range(3)], axis=1)
    return n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)


def shade(view: View, x: np.ndarray, triangles: np.ndarray, *, smooth: bool = True
          ) -> np.ndarray:
    """Brightness of each triangle in [0.3, 1]: two-sided Lambert, light from the camera.

    Parameters
    ----------
    view : View
        Camera and light.
    x : ndarray, shape (n, 3)
        Positions [m].
    triangles : ndarray, shape (m, 3), int
        Triangles.
    smooth : bool
        Per-vertex normals averaged over each triangle (cloth); False: the triangle's own
        normal (flat faces, e.g. a box).

    Returns
    -------
    ndarray, shape (m,)
        0.3 + 0.7 |n·l| (vertex values averaged over the triangle when ``smooth``).
    """
    triangles = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    if smooth:
        lit = np.abs(vertex_normals(x, triangles) @ view.light)
        return 0.3 + 0.7 * lit[triangles].mean(axis=1)
    t = x[triangles]
    n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    return 0.3 + 0.7 * np.abs(n @ view.light)


def depth_cue(depth: np.ndarray, near: float, far: float, strength: float = 0.3
              ) -> np.ndarray:
    """Brightness factor that darkens what lies farther from the camera (aerial
    perspective), so even a flat sheet shows which way it is tilted.

    Parameters
    ----------
    depth : ndarray, shape (m,)
        Depths [m] (:meth:`View.project`'s third coordinate, larger is nearer).
    near, far : float
        Depths [m] of the nearest and farthest points of the picture.
    strength : float
        Darkening at ``far``, in [0, 1).

    Returns
    -------
    ndarray, shape (m,)
        1 at ``near`` down to ``1 - strength`` at ``far`` (clipped outside).
    """
    span = max(float(near - far), 1e-12)
    return 1.0 - strength * np.clip((near - np.asarray(depth)) / span, 0.0, 1.0)


__all__ = ["View", "hidden_triangles", "solid_depth", "vertex_normals", "shade", "depth_cue"]
