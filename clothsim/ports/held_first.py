"""A vertex's first contact step: is its friction state too close to call from the port's state?

A held vertex's friction state is decided by the forces of the step before (the friction
cone; :class:`clothsim.ports.held_margins.Margins`). A new contact has no such force: the
step that caught it decided geometrically, by the seed's response in
:func:`clothsim.effects.holding.hold_step` (it sticks when friction stops its tangential
step, μ × depth against |Δ_t|). A port printed with 6 digits whose vertex lands within the
rounding of that edge may take the other decision; :func:`first_contact_flips` finds those
vertices by handing the obstacle's own ``correct_positions`` inputs moved by the rounding,
never by a copy of its rule.
"""

from __future__ import annotations

import numpy as np

from ..simulation import State
from .held_steps import _copy

__all__ = ["first_contact_flips"]


def _recorder(obstacle, out: dict):
    """The obstacle's correct_positions, recording what it is handed."""
    correct = type(obstacle).correct_positions

    def record(t, state, x):
        out[id(obstacle)] = (t, state, x.copy(), obstacle._holding)
        return correct(obstacle, t, state, x)

    return record


def first_contact_flips(held, rounding) -> set[int]:
    """The new contacts of the step whose friction state the rounding could flip.

    The step before is taken again from the port's state (x_{k−1}, v_{k−1}) on its
    planes; each holding obstacle's ``correct_positions`` (:mod:`clothsim.effects.holding`,
    the seed's response for vertices that reach it) is then handed that solve's answer
    and start moved by the rounding at each new contact: its answer along +(t̂ + n) and
    its start along −t̂ (a longer tangential step, a shallower entry: towards sliding),
    then the other way (towards sticking), t̂ the tangential direction of its step.

    Parameters
    ----------
    held : HeldSteps
        Anchored at the step k (its decision, the one of step k − 1).
    rounding : ndarray, shape (n,)
        How far each vertex of the port's state may be from what it computed [m].

    Returns
    -------
    set of int
        Vertices held in step k, not in step k − 1, that stick in one of the two and slide
        (or are not caught) in the other. Empty at the first step.
    """
    state, before = held.previous_state(), held.previous_decision()
    if state is None or before is None:
        return set()
    new = {}
    for (e, now), (h, _, _) in zip(held.planes(), before, strict=True):
        new[id(e)] = (np.setdiff1d(now.vertices, h.vertices), now)
    if not any(len(v) for v, _ in new.values()):
        return set()
    sim, saved, recorded, flips = held.sim, held.sim.state, {}, set()
    try:
        for e, (h, cv, cn) in zip(held.obstacles, before, strict=True):
            e._holding = _copy(h, state.positions)
            e.contact_vertices, e.contact_normals = cv, cn
            e.correct_positions = _recorder(e, recorded)
        sim.state = State(state.positions.copy(), state.velocities.copy(), state.time,
                          state.step)
        sim.step()
        for e in held.obstacles:
            v, now = new[id(e)]
            if not len(v) or id(e) not in recorded:
                continue
            t, start, x, h = recorded[id(e)]
            n = now.normals[[int(np.flatnonzero(now.vertices == u)[0]) for u in v]]
            d = x[v] - start.positions[v]
            dt = d - np.einsum("ij,ij->i", d, n)[:, None] * n
            length = np.linalg.norm(dt, axis=1)
            dt = np.divide(dt, length[:, None], out=np.zeros_like(dt),
                           where=length[:, None] > 0)
            r = rounding[v][:, None]
            decided = []
            for sign in (1.0, -1.0):      # towards sliding, towards sticking
                x0, xs = start.positions.copy(), x.copy()
                x0[v] -= sign * r * dt
                xs[v] += sign * r * (dt + n)
                e._holding = h
                type(e).correct_positions(e, t, State(x0, start.velocities, start.time,
                                                      start.step), xs)
                out = e._holding
                sticks = dict(zip(out.vertices.tolist(), out.stick.tolist(), strict=True))
                decided.append([sticks.get(int(u)) for u in v])
            flips |= {int(u) for u, a, b in zip(v, *decided, strict=True) if a != b}
    finally:
        held.restore()
        sim.state = saved
    return flips
