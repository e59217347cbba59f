"""Magnitudes a step of length h can hold in float64: what overflows, what rounds away.

A step squares positions, spring vectors and gradients (its residual and energy) and
factors M + h²L. Each function here finds, before the first step, a model, time step or
external force whose numbers would overflow float64 (the residual turns inf, the solver
does 0 iterations and the cloth never moves), make M + h²L singular in float64 (the
vertices' masses lost in its rounding: the factorization fails or answers noise), or move
the cloth by less than the rounding of its own coordinates (the motion is lost every step:
a frozen cloth). :func:`check_step` runs them all for
:class:`~clothsim.simulation.Simulation`; the scene loader runs the same ones first and
names its own keys (:mod:`clothsim.scene.scale`).
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from .errors import InputError
from .solvers.symplectic import StabilityWarning

#: [m]: the limit of every length of a scene (coordinates, radii): their squares stay finite.
MAX_LENGTH = 1e100
#: Largest energy scale k (L + r)² · s [J] (and m |x|² / h²) the step may meet.
MAX_ENERGY = 1e300
#: Largest h² |f_i| √n [kg·m] of an external force: ∇g's squared norm stays below 1e300.
MAX_GRADIENT = 1e150
EPS = float(np.finfo(np.float64).eps)
#: Smallest normal float64: h² below it is 0 or denormal (every h² term is lost).
TINY = float(np.finfo(np.float64).tiny)


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


def _force_key(path: str, effect) -> str:
    """The key of an effect's force or motion, e.g. ``effects[0].acceleration``."""
    name = "file" if getattr(effect, "file", None) else "per_vertex"
    return f"{path}.{_FORCE_KEY.get(effect.kind, name)}"


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
        key = _force_key(path, e)
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


def square_problem(h: float) -> str | None:
    """Why h² is no usable float64 number (overflow to inf, or below the normal range), if so.

    Parameters
    ----------
    h : float
        Time step [s], positive and finite.

    Returns
    -------
    str or None
    """
    lo, hi = math.sqrt(TINY), math.sqrt(np.finfo(np.float64).max)
    if lo <= h <= hi:
        return None
    return (f"h² = {h * h:.3g} s² {'overflows' if h > hi else 'underflows'} float64: a step "
            f"needs {lo:.3g} s ≤ h ≤ {hi:.3g} s, got {h:.3g} s")


def rounding_problem(effects, model, h: float) -> tuple[str, str] | None:
    """The first effect whose force cannot move the cloth in a step of ``h``: rounding eats it.

    A step moves vertex i by about h² |f_i| / m_i from rest (a moving pin by h |v|). When
    that is at or below ε max|x|, the rounding of the cloth's coordinates, x_n + h² f/m
    rounds back to x_n, the velocity (x_{n+1} − x_n) / h stays 0 and the cloth never starts
    to move, however many steps run (a frozen cloth, e.g. gravity with h = 1e-12 s).

    Parameters
    ----------
    effects : list of (str, Effect)
        Each bound effect with its key (e.g. ``"effects[0]"``).
    model : Model
    h : float
        Time step [s].

    Returns
    -------
    (str, str) or None
        ``(key, message)``; the message names the shortest step that resolves the motion.
    """
    x, m = np.asarray(model.mesh.vertices, np.float64), np.asarray(model.vertex_mass)
    resolution = EPS * (float(np.abs(x).max()) if x.size else 0.0)
    if resolution == 0.0:
        return None
    for path, e in effects:
        velocity = getattr(e, "velocity", None) if e.kind == "pin" else None
        if velocity is not None and np.any(velocity):
            speed = float(np.abs(velocity).max())
            key, move, shortest = f"{path}.velocity", h * speed, resolution / speed
            what = f"a pin velocity of {speed:.3g} m/s moves the pins h|v|"
        else:
            f = _peak_forces(e, len(m))
            if f is None or not np.any(f):
                continue
            with np.errstate(over="ignore", under="ignore", invalid="ignore"):
                accel = np.where(m > 0, np.abs(f).max(axis=1) / np.where(m > 0, m, 1.0), 0.0)
            i = int(np.argmax(accel))
            if accel[i] == 0.0:
                continue
            key = _force_key(path, e)
            move, shortest = h * h * float(accel[i]), math.sqrt(resolution / float(accel[i]))
            what = f"{e.kind}'s largest acceleration {accel[i]:.3g} m/s² moves vertex {i} h²|a|"
        if move <= resolution:
            return key, (f"{what} = {move:.3g} m in a step of h = {h:.3g} s, at or below the "
                         f"rounding of the cloth's coordinates (ε·max|x| = {resolution:.3g} m): "
                         f"the motion is lost every step and the cloth would never move; "
                         f"a step longer than {shortest:.2g} s resolves it")
    return None


def drag_problem(effects, model, h: float) -> tuple[str, str] | None:
    """The first wind whose drag, held over a step, may overshoot: h·ρ·C_d·|w|·A/M > 2.

    The wind's force is explicit: computed from v_n and held over the step. Linearized about
    a cloth of area A and mass M at rest facing the wind w, moving as one, its drag changes
    by ρ C_d |w| A per m/s of its velocity, a damping rate γ = ρ C_d |w| A / M; explicit
    Euler is stable for h γ ≤ 2 only. Beyond, each step's drag can reverse the
    relative velocity and enlarge it: the cloth is thrown faster than the wind, by a factor
    that grows every step (flag in a 1e12 m/s wind: 2e115 m after 3 frames; at 100 m/s,
    h γ = 12, it blows up in 2 s). A pinned cloth that turns edge-on to the wind escapes
    the bound (flag runs at h γ = 6, 50 m/s), so :func:`check_step` warns, not refuses.

    Parameters
    ----------
    effects : list of (str, Effect)
    model : Model
    h : float
        Time step [s].

    Returns
    -------
    (str, str) or None
        ``(key, message)`` naming the wind's ``velocity`` and the longest stable step.
    """
    m = np.asarray(model.vertex_mass, np.float64)
    mass = float(m.sum())
    for path, e in effects:
        if e.kind != "wind" or mass <= 0.0:
            continue
        x, t = np.asarray(model.mesh.vertices, np.float64), e._triangles
        with np.errstate(over="ignore", invalid="ignore"):
            area = 0.5 * float(np.linalg.norm(np.cross(x[t[:, 1]] - x[t[:, 0]],
                                                       x[t[:, 2]] - x[t[:, 0]]), axis=1).sum())
            speed = float(np.linalg.norm(e.velocity))
            rate = e.density * e.drag * speed * area / mass
        if h * rate > 2.0:
            return f"{path}.velocity", (
                f"the wind's drag is explicit (held over each step): h·ρ·C_d·|w|·A/M = "
                f"{h * rate:.3g} for the cloth (area {area:.3g} m², mass {mass:.3g} kg) with "
                f"|w| = {speed:.3g} m/s and h = {h:.3g} s is beyond 2, where a step's drag "
                f"can overshoot and throw the cloth faster than the wind (expect a blow-up "
                f"unless the cloth turns edge-on); a step shorter than {2.0 / rate:.2g} s, a "
                f"slower wind or a lower drag or density keeps it stable")
    return None


def check_step(model, h: float, effects) -> None:
    """Refuse a step whose numbers overflow float64 or round the motion away.

    Runs :func:`square_problem`, :func:`lost_mass`, :func:`overflow_problem`,
    :func:`force_problem` and :func:`rounding_problem`, in that order; then warns
    (:class:`~clothsim.solvers.symplectic.StabilityWarning`) when :func:`drag_problem`
    finds a wind whose explicit drag may overshoot.

    Parameters
    ----------
    model : Model
    h : float
        Time step [s].
    effects : list of (str, Effect)
        The bound effects with their keys.

    Raises
    ------
    InputError
        One line naming ``h``, ``model.*`` or the effect's key (e.g.
        ``effects[0].acceleration``) and the condition that fails.

    Warns
    -----
    StabilityWarning
        ``effects[i].velocity: the wind's drag is explicit …`` (:func:`drag_problem`).
    """
    if (problem := square_problem(h)) is not None:
        raise InputError(f"h: {problem}", field="h")
    if (found := lost_mass(model, h)) is not None:
        v, s, ratio = found
        sp = model.springs
        m, k = float(model.vertex_mass[v]), float(sp.spring_stiffness[s] + sp.spring_damping[s] / h)
        longest = h / math.sqrt(ratio * EPS)  # where h²L_ii/m_i reaches 1/ε
        raise InputError(f"h: h²L_ii/m_i = {ratio:.3g} at vertex {v} (mass {m:.3g} kg, its "
                         f"stiffest spring {s} of {k:.3g} N/m) is beyond 1/ε = {1 / EPS:.3g}: "
                         f"the mass is lost in M + h²L, which cannot be factored in float64; "
                         f"use h < {longest:.3g} s, softer springs or heavier vertices",
                         field="h")
    if (problem := overflow_problem(model, h)) is not None:
        field = {"vertices": "model.mesh.vertices", "mass": "model.vertex_mass"}.get(
            problem[0], "model.springs")
        raise InputError(f"{field}: {problem[1]}", field=field)
    for find in (force_problem, rounding_problem):
        if (problem := find(effects, model, h)) is not None:
            raise InputError(f"{problem[0]}: {problem[1]}", field=problem[0])
    if (problem := drag_problem(effects, model, h)) is not None:
        warnings.warn(f"{problem[0]}: {problem[1]}", StabilityWarning, stacklevel=3)


__all__ = ["overflow_problem", "force_problem", "lost_mass", "square_problem",
           "rounding_problem", "drag_problem", "check_step", "MAX_LENGTH", "MAX_ENERGY",
           "MAX_GRADIENT", "EPS"]
