"""Contact thickness: how far the obstacles hold the cloth's vertices off their surface.

Contact is tested at vertices only. A triangle whose corners all rest on a solid can still
have the solid in front of it: over a box's edge the triangle between a vertex on the top
face and one on the side face cuts the edge off, and over a sphere a chord of length ℓ
passes ℓ²/(8R) inside it (the sagitta). An obstacle with a ``thickness`` δ > 0 holds the
vertices on the surface moved δ outwards (the box grown by δ on every side, the sphere's
radius R + δ, the plane moved by δ along its normal), so the cloth lies that far off the
declared solid and the edges between vertices clear it.

The ``"auto"`` thickness is the least margin that provably keeps every obstacle point out of
every triangle of the cloth at its rest shape scaled by :data:`STRETCH_ALLOWANCE`
(:func:`auto_thickness`). It rests on one number of the mesh, the covering radius r of its
triangles: every point of a triangle lies within r of one of its corners
(:func:`covering_radius`); a grid of spacing ℓ has r = ℓ/√2.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError, check_finite

#: The ``"auto"`` thickness covers triangles up to this scale of their rest shape: the
#: cloth in resting contact stretches a few per cent (docs/data/contact.md), and over a
#: sphere the bound is tight, so the rest shape alone leaves a sagitta of that order.
STRETCH_ALLOWANCE = 1.1


def check_thickness(name: str, value) -> float | str:
    """``value`` checked as a thickness: ``"auto"`` or one number >= 0 [m].

    Parameters
    ----------
    name : str
        The key, e.g. ``"box.thickness"``, for the error.
    value : object

    Returns
    -------
    float or "auto"
    """
    if isinstance(value, str):
        if value != "auto":
            raise InputError(f"{name}: must be a number >= 0 [m] or 'auto', got {value!r}")
        return value
    a = check_finite(name, value)
    if a.ndim != 0 or a < 0:
        raise InputError(f"{name}: must be one number >= 0 [m] or 'auto', got {value!r}")
    return float(a)


def covering_radius(points: np.ndarray, triangles: np.ndarray,
                    strands: np.ndarray | None = None) -> float:
    """The largest distance from a point of a cell to the cell's nearest corner [m].

    Parameters
    ----------
    points : ndarray, shape (n, 3)
        Vertex positions [m] (the rest shape).
    triangles : ndarray, shape (m, 3), int
    strands : ndarray, shape (s, 2), int, optional
        Line cells: half their length.

    Returns
    -------
    float
        r, the largest over the cells of: the farthest any point of the cell is from the
        cell's nearest corner, and half the cell's longest side (a point of a side is
        within that of one of the side's own ends). For a triangle without an obtuse
        angle, its circumradius abc / (4 A) (≥ a / 2); with an obtuse angle A opposite the
        longest side a, the largest of c / (2 cos B) and b / (2 cos C) (where the
        perpendicular bisectors of the shorter sides meet side a) and a / 2. At most
        a / √3 in every case; a triangle of zero area: a / 2.
    """
    r = 0.0
    if strands is not None and len(strands):
        r = 0.5 * float(np.linalg.norm(points[strands[:, 1]] - points[strands[:, 0]],
                                       axis=1).max())
    if not len(triangles):
        return r
    p = points[triangles]
    side = np.linalg.norm(np.roll(p, -1, axis=1) - np.roll(p, 1, axis=1), axis=2)  # opposite
    order = np.argsort(side, axis=1)
    a, b, c = (np.take_along_axis(side, order[:, [k]], axis=1)[:, 0] for k in (2, 1, 0))
    area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    flat = area <= 1e-12 * a * a
    with np.errstate(divide="ignore", invalid="ignore"):
        circum = a * b * c / (4 * area)
        cos_b = (a * a + c * c - b * b) / (2 * a * c)
        cos_c = (a * a + b * b - c * c) / (2 * a * b)
        obtuse = np.maximum(np.maximum(c / (2 * cos_b), b / (2 * cos_c)), a / 2)
    cover = np.where(flat, a / 2, np.where(a * a > b * b + c * c, obtuse, circum))
    return max(r, float(cover.max()))


def auto_thickness(kind: str, r: float, *, radius: float = 0.0) -> float:
    """The ``"auto"`` contact thickness of an obstacle for cells of covering radius ``r``.

    Parameters
    ----------
    kind : {"box", "sphere", "plane"}
    r : float
        The covering radius the thickness must cover [m]: the obstacles pass
        :data:`STRETCH_ALLOWANCE` × :func:`covering_radius` of the cloth at rest.
    radius : float
        The sphere's radius R [m].

    Returns
    -------
    float
        δ [m]:

        - ``"plane"``: 0. A triangle is a convex combination of its corners, so corners in
          front of a plane keep all of it in front.
        - ``"box"``: r. A vertex outside the grown box is at least δ from the box; a box
          point inside a triangle would be within r of one of its corners, so δ = r keeps
          every box point out of every triangle (the bound is reached where a box corner
          meets a triangle's circumcentre).
        - ``"sphere"``: √(R² + r²) − R ≈ r² / (2R). A triangle whose corners are at least
          R + δ from the centre c: if c projects into it at distance d, some corner is
          within r of the foot, so (R + δ)² ≤ d² + r², d ≥ R; when c projects outside the
          triangle, the same with the nearest point of a side and that side's ends.
    """
    if kind == "box":
        return float(r)
    if kind == "sphere":
        return float(np.hypot(radius, r) - radius)
    return 0.0


__all__ = ["STRETCH_ALLOWANCE", "auto_thickness", "check_thickness", "covering_radius"]
