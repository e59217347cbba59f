"""Magnitudes that overflow float64 in a step, or vanish in its rounding, named by scene key.

The checks themselves live in :mod:`clothsim.magnitudes` (Simulation runs them too, for the
Python API); here they are given the scene's keys: :func:`scene_key` for
:func:`overflow_problem`, :func:`stiffness_problem` for :func:`lost_mass`, and
:func:`check_extent` for a cloth smaller than the rounding of its coordinates.
"""

from __future__ import annotations

import numpy as np

from ..magnitudes import (  # noqa: F401 (the scene's checks, shared with Simulation)
    EPS,
    MAX_ENERGY,
    MAX_GRADIENT,
    force_problem,
    lost_mass,
    overflow_problem,
)
from ..springs import FAMILIES
from .checks import Invalid


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


def check_extent(x: np.ndarray, shape: str) -> None:
    """Refuse a cloth whose size is below the rounding of its coordinates (meaningless).

    Parameters
    ----------
    x : ndarray, shape (n, 3)
        Vertex positions [m].
    shape : str
        ``cloth.shape``, which names the key to blame.

    Raises
    ------
    Invalid
        At ``cloth.center``, ``cloth.mesh`` or ``cloth.vertices``.
    """
    if len(x) < 2:
        return None
    scale = float(np.max(np.abs(x)))
    extent = float(np.max(np.ptp(x, axis=0)))
    if extent <= 1e3 * EPS * scale:
        key = {"grid": "cloth.center", "polygon": "cloth.center", "mesh": "cloth.mesh",
               "files": "cloth.vertices"}.get(shape, "cloth")
        raise Invalid(key, f"the cloth's extent {extent:.3g} m is below the rounding of its "
                           f"coordinates near {scale:.3g} m; move it nearer the origin")


def stiffness_problem(model, h: float, data: dict, table_springs: int):
    """Springs so stiff that M + h²L cannot be factored in float64: (key, message) or None.

    When a vertex's mass is at or below the rounding of h² L_ii (m_i ≤ ε h² L_ii), M is lost
    in M + h²L, which is then as singular as L (free translations): the factorization fails
    or its answer is noise. A damped spring counts with k + c/h (its step's stiffness). The
    key of the stiffest spring at the worst vertex is named.

    Parameters
    ----------
    model : Model
    h : float
        Time step [s].
    data : dict
        The resolved scene (its cloth shape names the key).
    table_springs : int
        How many of the model's springs (the last ones) come from ``springs.table``.

    Returns
    -------
    (str, str) or None
    """
    found = lost_mass(model, h)
    if found is None:
        return None

    v, i, ratio = found
    m, c = model.vertex_mass, model.springs.spring_damping
    k = model.springs.spring_stiffness + c / h
    key = ("cloth.file" if data["cloth"]["shape"] == "jacobson"
           else "springs.table" if i >= model.spring_count - table_springs
           else f"springs.{FAMILIES[model.springs.spring_family[i]]}")
    what = f"stiffness{' + damping/h' if c[i] else ''} {float(k[i]):.3g} N/m"
    return key, (f"{what} is too large for h = {h:.3g} s and vertex {v}'s mass "
                 f"{float(m[v]):.3g} kg: h²L_ii/m_i = {ratio:.3g} is beyond 1/ε = "
                 f"{1 / EPS:.3g}, so the mass is lost in M + h²L, which cannot be factored "
                 f"in float64")


__all__ = ["overflow_problem", "scene_key", "force_problem", "check_extent", "lost_mass",
           "stiffness_problem",
           "MAX_ENERGY", "MAX_GRADIENT"]
