"""A damping the scene has not, of another model, or left out: fitted on the port's velocities.

:func:`clothsim.ports.effect_causes.damping_cause` fits the coefficient of a damping the
scene declares, by replaying its step. A port that damps where the scene has no damping
(rigid 0.1 on an undamped scene), that damps by another model ("velocity" where the scene
says "rigid"), or a hold-mode port whose damping is left out, stayed "velocities differ"
with no cause. The models that change velocities after the step (clothsim.effects
damping kinds ``"velocity"``: v ← (1 − c) v, and ``"rigid"``: v ← v + c (v_rigid − v))
are linear in their coefficient, so no replay is needed: when the positions agree,
clothsim's v_{k+1} before its damping is its damped velocity with the scene's damping
undone (both are invertible for c < 1, and the rigid part is a projection:
R((1 − c) v + c R v) = R v), and each model's coefficient is the least-squares c of the
port's velocities about it. The one that reproduces them within the step's bound is
named, with what the scene has. An ``"inertial"`` damping moves the inertial target y,
hence the positions: not this verdict.
"""

from __future__ import annotations

import numpy as np

from ..effects.base import overrides
from ..effects.damping import rigid_velocity

__all__ = ["damping_model_cause"]

#: The velocity-changing damping models, in the order they are tried.
MODELS = ("rigid", "velocity")


def _undamped(sim, x, v):
    """clothsim's velocities before its damping (n, 3), or None when a damping cannot be
    undone (c = 1) or is not the last velocity correction."""
    hooks = [e for e in sim.effects if overrides(e, "correct_velocities")]
    damping = [e for e in hooks if e.kind == "damping"]
    if hooks[len(hooks) - len(damping):] != damping:
        return None     # another correction after a damping: not undone here
    for e in reversed(damping):
        c = e.coefficient
        if e.damping_model == "velocity":
            v = v / (1.0 - c)
        elif e.damping_model == "rigid":
            if c >= 1.0:
                return None
            v = (v - c * rigid_velocity(x, v, e.model.vertex_mass)) / (1.0 - c)
    return v


def _scene_words(sim) -> str:
    damping = [e for e in sim.effects if e.kind == "damping" and e.coefficient > 0]
    if not damping:
        return "the scene has no damping"
    return "the scene has " + " and ".join(
        f"\"{e.damping_model}\" {e.coefficient:g}" for e in damping)


def damping_model_cause(sim, x, v, v_port, bound: float) -> str:
    """The damping model and coefficient under which clothsim's velocities are the port's.

    Parameters
    ----------
    sim : Simulation
        The scene's simulation (its damping effects).
    x : ndarray, shape (n, 3)
        clothsim's x_{k+1} [m] (the positions agree with the port's).
    v : ndarray, shape (n, 3)
        clothsim's v_{k+1} [m/s], the scene's damping applied.
    v_port : ndarray, shape (n, 3)
        The port's v_{k+1} [m/s].
    bound : float
        Largest max |v − v_port| counted as the port's [m/s].

    Returns
    -------
    str
        The note ("the port's velocities are clothsim's with a damping the scene has not:
        model "rigid", coefficient 0.1 …"), or "" when no single model reproduces them.
    """
    raw = _undamped(sim, x, v)
    if raw is None:
        return ""
    mass = sim.model.vertex_mass
    scene = float(np.linalg.norm(v - v_port, axis=1).max())
    found = []
    for model in MODELS:
        direction = (rigid_velocity(x, raw, mass) - raw) if model == "rigid" else -raw
        dd = float(np.sum(direction * direction))
        if dd == 0:
            continue
        c = float(np.sum((v_port - raw) * direction)) / dd
        c = min(max(c, 0.0), 1.0 if model == "rigid" else 0.999999)
        off = float(np.linalg.norm(raw + c * direction - v_port, axis=1).max())
        found.append((off, model, c))
    none = float(np.linalg.norm(raw - v_port, axis=1).max())
    found.append((none, "none", 0.0))
    off, model, c = min(found)
    if off > bound:
        return ""
    declared = [e for e in sim.effects if e.kind == "damping" and e.damping_model in MODELS
                and e.coefficient > 0]
    if model == "none" or c < 1e-6:
        what = "the scene's damping left out"
    elif not declared:
        what = f"a damping the scene has not: model \"{model}\", coefficient {c:.3g}"
    elif all(e.damping_model == model for e in declared):
        what = f"the damping \"{model}\" of another coefficient: {c:.3g}"
    else:
        what = f"another damping model: \"{model}\" with coefficient {c:.3g}"
    return (f"the port's velocities are clothsim's with {what} ({_scene_words(sim)}): "
            f"{off:.1e} m/s off them, against {scene:.1e} m/s with the scene's damping")
