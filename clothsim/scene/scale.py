"""Magnitudes that overflow float64 in a step: refused when the scene is built.

The solvers form squared norms of positions, spring vectors and gradients (the residual
and the energy): with coordinates or rest lengths near 1e200 (beyond the 1e100 m the scene
keys allow lengths), or stiffness times length² beyond 1e300, those overflow to inf, the
solver's convergence test misreads them, and the cloth never moves.
:func:`overflow_problem` finds such a model before the first step.
"""

from __future__ import annotations

import numpy as np

from .effects import MAX_LENGTH  # [m]: the scene keys' limit on lengths, 1e100

#: Largest energy scale k (L + r)² · s [J] (and m |x|² / h²) the step may meet.
MAX_ENERGY = 1e300


def overflow_problem(model, h: float) -> tuple[str, str] | None:
    """What in ``model`` overflows float64 in a step of length ``h``, if anything.

    Parameters
    ----------
    model : Model
        Vertices [m], springs (stiffness [N/m], rest lengths [m]), masses [kg].
    h : float
        Time step [s].

    Returns
    -------
    (str, str) or None
        ``(what, message)`` with ``what`` one of ``"vertices"``, ``"rest_length"``,
        ``"stiffness"``, ``"mass"``; None when every magnitude is safe.
    """
    x = np.asarray(model.mesh.vertices, np.float64)
    s = model.springs
    r = np.asarray(s.spring_rest_length, np.float64)
    k = np.asarray(s.spring_stiffness, np.float64)
    m = np.asarray(model.vertex_mass, np.float64)
    xmax = float(np.abs(x).max()) if x.size else 0.0
    if xmax > MAX_LENGTH:
        return "vertices", (f"coordinates up to {xmax:.3g} m are beyond the {MAX_LENGTH:.0e} m "
                            "every length of a scene is limited to (a step's squared norms "
                            "would overflow float64)")
    rmax = float(r.max()) if r.size else 0.0
    if rmax > MAX_LENGTH:
        i = int(np.argmax(r))
        return "rest_length", (f"spring {i}'s rest length {rmax:.3g} m is beyond the "
                               f"{MAX_LENGTH:.0e} m every length of a scene is limited to (a "
                               "step's residual would overflow float64)")
    extent = float(np.ptp(x, axis=0).max()) if len(x) else 0.0
    with np.errstate(over="ignore", invalid="ignore"):
        spring = k * (extent + r) ** 2 * max(len(k), 1)
        inertia = m * xmax ** 2 / (h * h) * max(len(m), 1)
    if k.size and not float(spring.max()) <= MAX_ENERGY:
        i = int(np.nanargmax(np.where(np.isfinite(spring), spring, np.inf)))
        return "stiffness", (f"spring {i}: stiffness {k[i]:.3g} N/m over lengths near "
                             f"{extent + r[i]:.3g} m makes the energy overflow float64 "
                             f"(beyond {MAX_ENERGY:.0e} J)")
    if m.size and not float(inertia.max()) <= MAX_ENERGY:
        i = int(np.argmax(np.where(np.isfinite(inertia), inertia, np.inf)))
        return "mass", (f"vertex {i}'s mass {m[i]:.3g} kg at {xmax:.3g} m with h = {h:.3g} s "
                        f"makes the energy overflow float64 (beyond {MAX_ENERGY:.0e} J)")
    return None


def scene_key(what: str, data: dict) -> str:
    """The scene key a problem of :func:`overflow_problem` comes from.

    Parameters
    ----------
    what : {"vertices", "rest_length", "stiffness", "mass"}
    data : dict
        The resolved scene (:meth:`clothsim.scene.Scene.to_dict`).

    Returns
    -------
    str
        E.g. ``"springs.table"``.
    """
    cloth, springs = data.get("cloth", {}), data.get("springs", {})
    shape = cloth.get("shape")
    if shape == "jacobson":
        return "cloth.file"
    if what == "vertices":
        return {"files": "cloth.vertices", "mesh": "cloth.mesh"}.get(shape, "cloth")
    if what == "mass":
        return "cloth.vertex_mass" if "vertex_mass" in cloth else "cloth.mass"
    return "springs.table" if "table" in springs else "springs"


__all__ = ["overflow_problem", "scene_key", "MAX_ENERGY"]


def lost_mass(model, h: float):
    """The vertex whose mass is lost to rounding in M + h²L, if any.

    When m_i ≤ ε h² L_ii, M is lost in M + h²L, which is then as singular as L (free
    translations): the factorization fails or its answer is noise.

    Parameters
    ----------
    model : Model
        Springs (stiffness [N/m]) and masses [kg]; massless vertices are pinned and skipped.
    h : float
        Time step [s].

    Returns
    -------
    (int, int, float) or None
        The vertex, its stiffest spring and h² L_ii / m_i, when that ratio reaches 1/ε.
    """
    sv, k = model.springs.spring_vertices, model.springs.spring_stiffness
    if not len(k):
        return None
    n, m = model.vertex_count, model.vertex_mass
    diag = np.bincount(sv[:, 0], k, n) + np.bincount(sv[:, 1], k, n)
    ratio = np.divide((h * h) * diag, m, out=np.zeros(n), where=m > 0)  # m = 0: pinned
    v = int(np.argmax(ratio))
    if ratio[v] * np.finfo(np.float64).eps < 1.0:
        return None
    at = np.flatnonzero((sv[:, 0] == v) | (sv[:, 1] == v))
    return v, int(at[np.argmax(k[at])]), float(ratio[v])
