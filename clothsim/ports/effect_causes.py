"""Causes in the scene's effects: a damping left out or of another coefficient, an obstacle
of another size. Each is tested by replaying clothsim's whole step (solve, position
corrections, velocity update) from the port's state with the effect changed.

- :func:`damping_cause`: the port's positions agree but its velocities do not ("velocities
  differ"). A velocity-changing damping ("velocity", "rigid") makes v_{k+1} linear in its
  coefficient c: two replays (c = 0 and the scene's c) fit the port's c, a third checks it.
- :func:`obstacle_cause`: in post-solve contact the port's projected vertices lie on its
  own obstacle: a sphere's radius (their common distance from the centre), a plane's
  offset (their common n · x) or a box's face (their common coordinate over the box's
  footprint), less the contact margin, is read off them, and the step replayed with it;
  else an obstacle's friction coefficient is fitted on replays (a secant from the scene's
  μ, 0 and 2 μ).
"""

from __future__ import annotations

import numpy as np

from ..simulation import State
from .held_readings import shared as _shared

__all__ = ["damping_cause", "obstacle_cause"]


def _replay_step(sim, state):
    """clothsim's whole step from ``state``: (x, v); the simulation's state is restored."""
    before = sim.state
    sim.state = State(state.positions.copy(), state.velocities.copy(), state.time, state.step)
    try:
        sim.step()
        return sim.state.positions, sim.state.velocities
    finally:
        sim.state = before


def damping_cause(sim, state, v_port, bound: float) -> str:
    """The damping coefficient under which clothsim's step gives the port's velocities.

    Parameters
    ----------
    sim : Simulation
    state : State
        The port's state x_k, v_k.
    v_port : ndarray, shape (n, 3)
        The port's v_{k+1} [m/s].
    bound : float
        Largest max |v − v_port| counted as the port's [m/s].

    Returns
    -------
    str
        The note ("damping (rigid) left out: ..."), or "" when no single damping
        coefficient explains the velocities.
    """
    for effect in [e for e in sim.effects if e.kind == "damping"]:
        if effect.damping_model not in ("velocity", "rigid"):
            continue          # 'inertial' moves y, hence the positions: not this verdict
        c0 = effect.coefficient
        try:
            effect.coefficient = 0.0
            _, v_free = _replay_step(sim, state)
            effect.coefficient = c0
            _, v_scene = _replay_step(sim, state)
            dv = v_scene - v_free
            if not np.any(dv):
                continue
            c = c0 * float(np.sum((v_port - v_free) * dv) / np.sum(dv * dv))
            c = min(max(c, 0.0), 0.999999 if effect.damping_model == "velocity" else 1.0)
            effect.coefficient = c
            _, v_fit = _replay_step(sim, state)
        finally:
            effect.coefficient = c0
        off = float(np.linalg.norm(v_fit - v_port, axis=1).max())
        scene = float(np.linalg.norm(v_scene - v_port, axis=1).max())
        if off > bound:
            continue
        what = ("left out (coefficient 0 instead of" if c < 0.005 * c0 else
                f"of another coefficient ({c:.3g} instead of")
        return (f"the port's velocities are clothsim's with the damping "
                f"(model \"{effect.damping_model}\") {what} {c0:g}): "
                f"{off:.1e} m/s off them, against {scene:.1e} m/s with the scene's damping")
    return ""


def _obstacles(sim):
    return [e for e in sim.effects if e.kind in ("sphere", "plane", "box")]


def obstacle_cause(sim, state, x_port, tol: float) -> str:
    """The obstacle size under which clothsim's post-solve step is the port's.

    Parameters
    ----------
    sim : Simulation
    state : State
        The port's state x_k, v_k.
    x_port : ndarray, shape (n, 3)
        The port's x_{k+1} [m].
    tol : float
        The step's tolerance [m].

    Returns
    -------
    str
        E.g. "a sphere of radius 0.25 m instead of 0.3 m (...)", or "" when none found.
    """
    x_scene, _ = _replay_step(sim, state)
    scene = float(np.linalg.norm(x_scene - x_port, axis=1).max())
    for effect in _obstacles(sim):
        for name, value, read in _readings(effect, x_port):
            if read is None or np.allclose(read, value, rtol=1e-9, atol=tol):
                continue
            try:
                _set(effect, name, read)
                x, _ = _replay_step(sim, state)
            except (ValueError, ArithmeticError, RuntimeError):
                x = None
            finally:
                _set(effect, name, value)
            if x is None:
                continue
            off = float(np.linalg.norm(x - x_port, axis=1).max())
            if off <= max(tol, 0.01 * scene):
                return (f"the port's steps are clothsim's with a {effect.kind} of {name} "
                        f"{_fmt(read)} instead of {_fmt(value)} (its vertices in contact "
                        f"lie there; replayed: {off:.1e} m off the port's answer, against "
                        f"{scene:.1e} m with the scene's {effect.kind})")
    for effect in (e for e in _obstacles(sim) if getattr(e, "friction", 0) > 0):
        found = _friction(sim, state, effect, x_scene, x_port)
        if found is not None and found[1] <= max(tol, 0.01 * scene):
            mu, off = found
            return (f"the port's steps are clothsim's with the {effect.kind}'s friction "
                    f"coefficient {mu:.3g} instead of {effect.friction:g} (replayed: "
                    f"{off:.1e} m off the port's answer, against {scene:.1e} m with the "
                    f"scene's)")
    return ""


def _friction(sim, state, effect, x_scene, x_port):
    """(μ, distance) of the friction coefficient fitted to the port's post-solve step: the
    step taken as linear in μ between the two replays nearest its answer (the scene's μ,
    0 and 2 μ), refined twice; None when a replay fails."""
    mu0 = effect.friction

    def at(mu):
        try:
            effect.friction = mu
            return _replay_step(sim, state)[0]
        except (ValueError, ArithmeticError, RuntimeError):
            return None
        finally:
            effect.friction = mu0

    def off(x):
        return float(np.linalg.norm(x - x_port, axis=1).max())

    points = [(mu0, x_scene)] + [(m, x) for m in (0.0, 2 * mu0) if (x := at(m)) is not None]
    for _ in range(3):
        points = sorted(points, key=lambda p: off(p[1]))[:2]
        if len(points) < 2:
            return None
        (a, xa), (b, xb) = points
        dx = xb - xa
        denom = float(np.sum(dx * dx))
        c = a + (b - a) * float(np.sum((x_port - xa) * dx)) / denom if denom else a
        if not 0 <= c <= 10 * mu0 or min(abs(c - a), abs(c - b)) <= 1e-6 * mu0:
            break
        x = at(c)
        if x is None:
            break
        points.append((c, x))
    mu, x = min(points, key=lambda p: off(p[1]))
    return (mu, off(x)) if mu != mu0 else None


def _set(effect, name, value):
    setattr(effect, name, np.array(value, dtype=np.float64) if np.ndim(value) else value)
    effect.set_margin(effect.margin)     # the contact surface follows the size


def _fmt(value) -> str:
    v = np.atleast_1d(value)
    return f"{float(v[0]):.6g} m" if v.size == 1 else "(" + ", ".join(f"{c:.6g}" for c in v) + ") m"


def _readings(effect, x):
    """(attribute, the scene's value, the value the port's vertices share)."""
    scale = max(float(np.abs(x).max()), 1.0)
    if effect.kind == "sphere":     # the contact surface is radius + margin
        shell = _shared(np.linalg.norm(x - effect.center, axis=1), scale)
        yield "radius", effect.radius, None if shell is None else shell - effect.margin
    elif effect.kind == "plane":    # n · x = n · point + margin
        level = _shared(x @ effect.normal, scale)
        shift = None if level is None else level - effect.margin - effect.point @ effect.normal
        yield "point", effect.point, None if shift is None else effect.point + shift * effect.normal
    elif effect.kind == "box":      # a face: its coordinate, over the box's footprint
        for name, side in (("min", -1), ("max", 1)):
            for axis in range(3):
                other = [a for a in range(3) if a != axis]
                over = np.all((x[:, other] >= effect.min[other]) &
                              (x[:, other] <= effect.max[other]), axis=1)
                face = _shared(x[over, axis], scale)
                if face is None:
                    continue
                read = getattr(effect, name).copy()
                read[axis] = face - side * effect.margin
                yield name, getattr(effect, name), read
