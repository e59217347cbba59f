"""The size or place of a port's obstacle, read off the port's vertices in contact.

A hold-mode port's vertices in contact lie on its own obstacle's contact surface: the
value most of them share is read off them (a box face's coordinate over its footprint, a
sphere's distance from its centre, a plane's offset), and the sphere a patch of them lies
on is fitted (another centre). Each reading becomes a change of the scene's obstacle that
:mod:`clothsim.ports.held_causes` replays.
"""

from __future__ import annotations

import numpy as np

__all__ = ["NEAR", "SHARED", "geometry", "shared"]

#: Vertices that must share an obstacle surface for it to be read off them.
SHARED = 3
#: An obstacle is tried when the port's answer has a vertex within this share of the
#: cloth's size of its surface (and a face is read only as far from the scene's).
NEAR = 0.05


def _fmt(value) -> str:
    v = np.atleast_1d(np.asarray(value, np.float64))
    v = np.where(np.abs(v) < 1e-9 * max(float(np.abs(v).max()), 1.0), 0.0, v)   # no -2e-16
    return (f"{float(v[0]):.4g} m" if v.size == 1
            else "(" + ", ".join(f"{c + 0.0:.4g}" for c in v) + ") m")


def shared(values, scale):
    """The value at least :data:`SHARED` vertices share, the most shared.

    Parameters
    ----------
    values : array_like, shape (n,)
        A coordinate of each vertex (a distance, an offset) [m].
    scale : float
        Values within 1e-9 of it are the same [m].

    Returns
    -------
    float or None
        Their mean; None when fewer than :data:`SHARED` share one.
    """
    if not len(values):
        return None
    q = np.round(np.asarray(values) / (1e-9 * scale))
    uniq, counts = np.unique(q, return_counts=True)
    i = int(np.argmax(counts))
    return float(np.mean(np.asarray(values)[q == uniq[i]])) if counts[i] >= SHARED else None


def _fit4(p):
    """The sphere (centre, radius) through the points p (k >= 4), least squares."""
    A = np.column_stack([2 * p, np.ones(len(p))])
    sol = np.linalg.lstsq(A, np.einsum("ij,ij->i", p, p), rcond=None)[0]
    c = sol[:3]
    r2 = float(sol[3] + c @ c)
    return (c, float(np.sqrt(r2))) if r2 > 0 else None


def _sphere_fit(x, center, radius, near, tol):
    """The sphere (centre, radius) most of the points near the obstacle lie on exactly
    (within ``tol``): each near point and its 6 nearest near points fitted in turn (a
    patch of vertices in contact), the fit that holds most points kept and refitted on
    them. None when fewer than 4 + SHARED points lie on one sphere."""
    d = np.linalg.norm(x - center, axis=1)
    pts = x[np.abs(d - radius) <= near]
    if len(pts) < 4 + SHARED:
        return None
    best = None
    for p in pts[:400]:
        patch = pts[np.argsort(np.linalg.norm(pts - p, axis=1))[:7]]
        fit = _fit4(patch)
        if fit is None:
            continue
        count = int(np.sum(np.abs(np.linalg.norm(pts - fit[0], axis=1) - fit[1]) <= tol))
        if best is None or count > best[0]:
            best = (count, *fit)
    if best is None or best[0] < 4 + SHARED:
        return None
    on = np.abs(np.linalg.norm(pts - best[1], axis=1) - best[2]) <= tol
    return _fit4(pts[on])


def _sphere_change(e, key, center, shell, words):
    """The sphere whose contact surface has radius ``shell``: its radius and thickness
    (an ``"auto"`` thickness follows the radius: R + δ = √(R² + r²), r² read off the
    scene's sphere)."""
    if e.thickness == "auto":
        r2 = (e.radius + e.margin) ** 2 - e.radius ** 2
        radius = float(np.sqrt(max(shell ** 2 - r2, 0.0)))
    else:
        radius = shell - e.margin
    values = {"radius": radius, "margin": shell - radius}
    if np.linalg.norm(center - e.center) > 0:
        values["center"] = center
        what = (f"a sphere of centre {_fmt(center)} instead of {_fmt(e.center)} and radius "
                + (f"{_fmt(radius)}" if abs(radius - e.radius) <= 1e-4 * e.radius else
                   f"{_fmt(radius)} instead of {_fmt(e.radius)}"))
        setting = f"{key}.center and .radius (the sphere)"
    else:
        what = f"a sphere of radius {_fmt(radius)} instead of {_fmt(e.radius)}"
        setting = f"{key}.radius (the sphere)"
    return f"{what} ({words})", setting, values


def geometry(e, x, index: int, tol: float):
    """Changes of the obstacle's size or place read off the port's vertices.

    Parameters
    ----------
    e : Obstacle
    x : ndarray, shape (n, 3)
        The port's x_{k+1} [m].
    index : int
        The obstacle's place in the scene's effects (names its keys).
    tol : float
        The step's tolerance [m]: a value read within it of the scene's is no change.

    Yields
    ------
    (str, str, dict)
        The change in words, the scene keys to look at, and the obstacle's attributes
        with their changed values (:class:`clothsim.ports.held_causes.Change`).
    """
    scale = max(float(np.abs(x).max()), 1.0)
    key = f"effects[{index}]"
    if e.kind == "sphere":
        surface = e.radius + e.margin   # the nearest distances, near the surface: a
        d = np.linalg.norm(x - e.center, axis=1)   # flat cloth's symmetric rings share one
        nearest = d <= d.min() + max(tol, 1e-9 * scale)   # too, with vertices inside
        shell = shared(d[nearest & (np.abs(d - surface) <= NEAR * scale)], scale)
        if shell is not None and abs(shell - surface) > max(tol, 1e-9 * scale):
            yield _sphere_change(e, key, e.center, shell, f"its vertices in contact lie "
                                                          f"{_fmt(shell)} from its centre")
        fit = _sphere_fit(x, e.center, surface, NEAR * scale, max(tol, 1e-9 * scale))
        if fit is not None and np.linalg.norm(fit[0] - e.center) > max(tol, 1e-9 * scale):
            yield _sphere_change(e, key, fit[0], fit[1], f"its vertices in contact lie on "
                                                         f"a sphere of radius {_fmt(fit[1])}")
    elif e.kind == "plane":
        level = shared(x @ e.normal, scale)
        if level is not None:
            shift = level - e.margin - e.point @ e.normal
            if abs(shift) > max(tol, 1e-9 * scale):
                p = e.point + shift * e.normal
                yield (f"a plane through {_fmt(p)} instead of {_fmt(e.point)}",
                             f"{key}.point (the plane)", {"point": p})
    elif e.kind == "box":
        for name, side in (("min", -1), ("max", 1)):
            for axis in range(3):
                other = [a for a in range(3) if a != axis]
                over = np.all((x[:, other] >= e.min[other]) & (x[:, other] <= e.max[other]),
                              axis=1)
                face = shared(x[over, axis], scale)
                if face is None:
                    continue
                d = face - side * e.margin - getattr(e, name)[axis]
                if abs(d) <= max(tol, 1e-9 * scale) or abs(d) > NEAR * scale:
                    continue
                moved = getattr(e, name).copy()
                moved[axis] += d
                grown = side * d
                yield (f"a box of {name} {_fmt(moved)} instead of "
                                f"{_fmt(getattr(e, name))} (its vertices in contact lie there)",
                             f"{key}.{name} (the box)", {name: moved})
                size = "larger" if grown > 0 else "smaller"
                yield (f"a box {abs(grown) * 100:.3g} cm {size} on every side (min "
                                f"{_fmt(e.min - grown)}, max "
                                f"{_fmt(e.max + grown)} instead of {_fmt(e.min)}, "
                                f"{_fmt(e.max)})", f"{key}.min and .max (the box)",
                             {"min": e.min - grown, "max": e.max + grown})
                shift = np.zeros(3)
                shift[axis] = d
                yield _moved(e, key, shift, "")
        yield from _sideways(e, x, key, max(tol, 1e-9 * scale), NEAR * scale)


def _moved(e, key, shift, words):
    """A box moved by ``shift``, in words, its keys and its values."""
    return (f"a box moved by {_fmt(shift)} (min {_fmt(e.min + shift)}, max "
            f"{_fmt(e.max + shift)} instead of {_fmt(e.min)}, {_fmt(e.max)}){words}",
            f"{key}.min and .max (the box)", {"min": e.min + shift, "max": e.max + shift})


def _sideways(e, x, key, tol, near):
    """A box moved along a face it holds vertices on, read off the face's extent.

    The port's vertices on a face at the scene's level (≥ :data:`SHARED` of them) lie
    over its own footprint: along each axis of the face, those beyond the scene's
    footprint (the box grown by its thickness) say how far it moved at least, and the
    far side's gap how far at most (a grid's spacing: each step of the cloth caught over
    one footprint is caught over any in that range). The middle of the range is tried, in
    each axis with evidence, and in both together; a single axis's range goes with it
    (:attr:`~clothsim.ports.held_causes.Change.span`), for a later step that tells more
    to fit the shift in (:func:`shift_in_range`).
    """
    lo, hi = e.min - e.margin, e.max + e.margin
    bounds = {}
    for axis, level in [(a, v) for a in range(3) for v in (lo[a], hi[a])]:
        on = x[np.abs(x[:, axis] - level) <= tol]
        if len(on) < SHARED:
            continue
        for a in (b for b in range(3) if b != axis):
            least, most = float(on[:, a].max() - hi[a]), float(on[:, a].min() - lo[a])
            if least > most or (least <= tol and most >= -tol) or min(
                    abs(least), abs(most)) > near:
                continue          # over the scene's footprint, or wider than it
            bounds.setdefault(a, (least, most))
    shifts = []
    for a, (least, most) in sorted(bounds.items()):
        shift = np.zeros(3)
        shift[a] = 0.5 * (least + most)
        shifts.append((shift, f"{'xyz'[a]} by {_fmt(min(least, most, key=abs))} to "
                              f"{_fmt(max(least, most, key=abs))}", (a, least, most)))
    if len(shifts) > 1:
        shifts.insert(0, (sum(s for s, *_ in shifts), " and ".join(w for _, w, _ in shifts),
                          None))
    for shift, words, span in shifts:
        yield (*_moved(e, key, shift, f" (its vertices on a face lie beyond the scene's "
                                      f"footprint: moved along {words})"), "", None, span)


#: Secant steps of :func:`shift_in_range` (each one replay of the step's window).
REFINE = 8


def shift_in_range(change, x_port, test, tol: float) -> None:
    """The shift of a box moved sideways fitted in its range (:func:`_sideways`) on a step
    the range's middle does not reproduce: the step taken as linear in the shift between
    the two replays nearest the port's answer (a secant from the range's ends and middle),
    refined up to :data:`REFINE` times; each candidate goes through ``test`` (which keeps
    the nearest).

    A box moved 5 cm reads 0.009 to 0.074 m at its landing step, whose every shift in that
    range lands the same: its middle, 0.042 m, is named there and misses the steps after,
    where the cloth slides over the edge.

    Parameters
    ----------
    change : Change
        The middle's change, with its :attr:`~clothsim.ports.held_causes.Change.span`.
    x_port : ndarray, shape (n, 3)
        The port's x_{k+1} [m].
    test : callable
        ``test(Change) -> x`` (None when the replay fails): replays and records it.
    tol : float
        The step's tolerance [m].
    """
    axis, least, most = change.span
    e, key = change.obstacle, change.setting.split(".min")[0]

    def at(s):
        shift = np.zeros(3)
        shift[axis] = s
        words, setting, values = _moved(e, key, shift, f" (read off the step: the shift "
                                        f"along {'xyz'[axis]} in {_fmt(least)} to "
                                        f"{_fmt(most)} that reproduces it)")
        return test(type(change)(e, words, setting, values, span=change.span))

    def off(x):
        return float(np.linalg.norm(x - x_port, axis=1).max()) if x is not None else np.inf

    mid = 0.5 * (least + most)
    points = [(s, x) for s in (least, mid, most) if (x := at(s)) is not None]
    for _ in range(REFINE):
        points = sorted(points, key=lambda p: off(p[1]))[:2]
        if len(points) < 2 or off(points[0][1]) <= tol:
            return
        (a, xa), (b, xb) = points
        dx = xb - xa
        denom = float(np.sum(dx * dx))
        if denom == 0:
            return
        c = a + (b - a) * float(np.sum((x_port - xa) * dx)) / denom
        if not min(least, most) <= c <= max(least, most) or min(abs(c - a), abs(c - b)) \
                <= 1e-6 * abs(most - least):
            return
        x = at(c)
        if x is None:
            return
        points.append((c, x))
