"""Magnitudes that overflow float64 in a step, or vanish in its rounding: refused on build.

The solvers form squared norms of positions, spring vectors and gradients (the residual
and the energy): with coordinates or rest lengths near 1e200 (beyond the 1e100 m the scene
keys allow lengths), or stiffness times length² beyond 1e300, those overflow to inf, the
solver's convergence test misreads them, and the cloth never moves.
:func:`overflow_problem` finds such a model before the first step.
"""

from __future__ import annotations

import numpy as np

from ..springs import FAMILIES
from .checks import Invalid
from .effects import MAX_LENGTH  # [m]: the scene keys' limit on lengths, 1e100

#: Largest energy scale k (L + r)² · s [J] (and m |x|² / h²) the step may meet.
MAX_ENERGY = 1e300
#: Largest h² |f_i| √n [kg·m] of an external force: ∇g's squared norm stays below 1e300.
MAX_GRADIENT = 1e150
EPS = float(np.finfo(np.float64).eps)


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
    k = np.asarray(s.spring_stiffness, np.float64) + np.asarray(s.spring_damping) / h  # k + c/h
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




def _peak_forces(effect, n: int):
    """The largest force [N] per vertex ``effect`` applies at any time, (n, 3), or None."""
    if effect.kind == "impulse":
        f = np.zeros((n, 3))
        f[effect.vertices] = effect.vertex_force
        return f
    if effect.kind in ("gravity", "force"):
        return effect._force
    if effect.kind == "wind":  # on a cloth at rest facing it: ½ ρ C_d |v|² A n per triangle
        x, t = effect.model.mesh.vertices, effect._triangles
        twice_area = np.linalg.norm(np.cross(x[t[:, 1]] - x[t[:, 0]], x[t[:, 2]] - x[t[:, 0]]),
                                    axis=1)
        with np.errstate(over="ignore", invalid="ignore"):
            speed2 = np.abs(effect.velocity).max() ** 2 * 3.0  # float64: inf, not an error
            per = 0.25 * effect.density * effect.drag * speed2 * twice_area / 3.0
        return np.bincount(t.ravel(), np.repeat(per, 3), n)[:, None] * np.ones(3)
    return None


_FORCE_KEY = {"gravity": "acceleration", "impulse": "force", "pin": "velocity",
              "wind": "velocity"}


def force_problem(effects, model, h: float) -> tuple[str, str] | None:
    """The first bound effect whose force or motion overflows float64 in a step of ``h``.

    Gravity, force, impulse and wind (its drag on a cloth at rest facing it) count.

    A step's gradient ∇g = M (x − y) + h² (∇E(x) − f_ext) sums squares of h² f_i, and
    moves a vertex by h² f_i / m_i: with ``f`` the largest force an effect applies, either
    h² |f_i| √n > :data:`MAX_GRADIENT` (1e150 kg·m, so that ‖∇g‖² stays below 1e300) or
    h² |f_i| / m_i > :data:`~clothsim.scene.effects.MAX_LENGTH` (1e100 m, the limit of
    every length in a scene) is refused. A pin's ``velocity`` v moves its targets by h |v|
    per step, held to the same 1e100 m. Without this the step's residual overflowed, the
    solver did 0 iterations and the cloth never moved.

    Parameters
    ----------
    effects : list of (str, Effect)
        Each bound effect with its scene key (e.g. ``"effects[0]"``).
    model : Model
        Masses [kg] and the vertex count n.
    h : float
        Time step [s].

    Returns
    -------
    (str, str) or None
        ``(key, message)``, e.g. ``("effects[0].acceleration", "…")``; None when safe.
    """
    n, m = model.vertex_count, np.asarray(model.vertex_mass, np.float64)
    for path, e in effects:
        name = "file" if getattr(e, "file", None) else "per_vertex"
        key = f"{path}.{_FORCE_KEY.get(e.kind, name)}"
        velocity = getattr(e, "velocity", None) if e.kind == "pin" else None
        if velocity is not None and h * float(np.abs(velocity).max()) > MAX_LENGTH:
            return key, (f"{float(np.abs(velocity).max()):.3g} m/s moves the pins by "
                         f"{h * float(np.abs(velocity).max()):.3g} m in one step of h = "
                         f"{h:.3g} s, beyond the {MAX_LENGTH:.0e} m every length of a scene "
                         f"is limited to (the step's squares would overflow float64)")
        f = _peak_forces(e, n)
        if f is None or not len(f):
            continue
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            size = np.abs(f).max(axis=1)
            gradient = h * h * size * np.sqrt(n)
            move = np.where(m > 0, h * h * size / np.where(m > 0, m, 1.0), 0.0)
        for value, bound, says in (
                (gradient, MAX_GRADIENT, f"gives h²|f|·√n = {{v:.3g}} kg·m with h = {h:.3g} s, "
                                         f"n = {n}: beyond {MAX_GRADIENT:.0e}, the step's "
                                         f"gradient would overflow float64"),
                (move, MAX_LENGTH, f"moves it h²|f|/m = {{v:.3g}} m in one step of h = "
                                   f"{h:.3g} s, beyond the {MAX_LENGTH:.0e} m every length of "
                                   f"a scene is limited to (the step's squares would overflow "
                                   f"float64)")):
            i = int(np.argmax(value))
            if not value[i] <= bound:
                return key, (f"a force of {size[i]:.3g} N on vertex {i} (mass {m[i]:.3g} kg) "
                             + says.format(v=value[i]))
    return None


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


def lost_mass(model, h: float):
    """The vertex whose mass is lost to rounding in M + h²L, if any.

    When m_i ≤ ε h² L_ii, M is lost in M + h²L, which is then as singular as L (free
    translations): the factorization fails or its answer is noise.

    Parameters
    ----------
    model : Model
        Springs (stiffness [N/m], damping [N·s/m]: a damped spring's step has k + c/h) and
        masses [kg]; massless vertices are pinned and skipped.
    h : float
        Time step [s].

    Returns
    -------
    (int, int, float) or None
        The vertex, its stiffest spring and h² L_ii / m_i, when that ratio reaches 1/ε.
    """
    sv = model.springs.spring_vertices
    k = model.springs.spring_stiffness + model.springs.spring_damping / h  # damped: k + c/h
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


__all__ = ["overflow_problem", "scene_key", "force_problem", "check_extent", "lost_mass",
           "stiffness_problem",
           "MAX_ENERGY", "MAX_GRADIENT"]
