"""A hold-mode step's contact decisions too close to call, settled as the port took them.

Which vertices a step holds is decided by thresholds, and the port's state carries its
rounding (:mod:`clothsim.ports.held_margins`: which decisions are marginal, and how far
the rounding moves them). :func:`marginal_changes` finds the marginal decisions the port
took the other way, from its planes or from its answer; :func:`settle` adopts them and
solves the step again, and decides by solving the step both ways the marginal releases
the port's answer cannot show (:func:`~clothsim.ports.held_margins.unsure`).
:func:`marginal_entries` takes a contact entry within the step's tolerance as the port's
when only the velocities of the vertices it caught differ.
"""

from __future__ import annotations

import numpy as np

from .held_margins import MARGINAL_KINDS, Margins, _holding, adopt, inferred, unsure
from .plane_diff import clothsim_rows, plane_differences

__all__ = ["marginal_changes", "marginal_entries", "settle"]


def settle(k, held, model, problem, tol, port_planes, x_port, x_cs, rounding, solve):
    """Take the step's contact decisions too close to call as the port took them, and solve.

    The decisions the port's planes or its answer show it took otherwise
    (:func:`marginal_changes`) are adopted. Without planes, the marginal decisions its
    answer cannot show (:func:`~clothsim.ports.held_margins.unsure`: a vertex held by
    clothsim on a new contact within the rounding, on the surface in the port's answer
    either way) are decided by solving the step both ways: they are released when that
    brings clothsim's answer nearer the port's (drape-sphere with L-BFGS 10 printed with
    ``%g``, step 8 → 9: 8 vertices touching the sphere at depth 0 from the printed start
    and not from the port's; held, they turn L-BFGS's 10 iterations elsewhere, 1.2e-3 m
    at the free corner).

    Parameters
    ----------
    k, held, model, problem, tol, port_planes, x_port, x_cs, rounding
        As :func:`marginal_changes`.
    solve : callable
        () -> (problem, x, v, err, worst) of clothsim's step on the held decision.

    Returns
    -------
    (tuple or None, str)
        ``solve``'s result on the decision kept (None: clothsim's own, unchanged) and the
        note naming what was taken as the port's ("" when nothing).
    """
    margins = Margins(held, model, problem, rounding)
    changes, note = marginal_changes(k, held, model, problem, tol, port_planes, x_port,
                                     x_cs, rounding, margins=margins)
    others = [] if port_planes is not None else unsure(held, margins, x_port, changes)
    planes = None if port_planes is None else port_planes.step(k)
    decision, solved = held.decision(), None
    if changes:
        adopt(held, changes, planes)
        solved = solve()
    if not others:
        return solved, note
    before = float(np.linalg.norm(x_cs - x_port, axis=1).max() if solved is None
                   else solved[3].max())
    held.restart(decision)
    adopt(held, changes + others, planes)
    trial = solve()
    if trial[3].max() < before:
        v = others[0][0]
        new = margins.first_contact(v, "stick")
        where = (f"{'a new contact ' if new else ''}within "
                 f"{(margins.entry if new else margins.force)[v]:.2g} N of its threshold at "
                 f"vertex {v}")
        return trial, "; ".join(filter(None, (note, (
            f"{len(others)} contact decision{'s' * (len(others) != 1)} too close to call "
            f"from the port's state ({where}; on the obstacle's surface in the port's answer "
            f"held or not) taken as the port's: vertex {v} released (the step solved both "
            f"ways: {trial[3].max():.1e} m from the port's answer against {before:.1e} m)"))))
    held.restart(decision)   # clothsim's decision (with the changes) after all
    if changes:
        adopt(held, changes, planes)
    return solve(), note


def marginal_changes(k, held, model, problem, tol, port_planes, x_port, x_cs, rounding, *,
                     margins=None):
    """The contact decisions of step k too close to call that the port took otherwise.

    Parameters
    ----------
    k : int
    held : HeldSteps
        Anchored at the step, stepped.
    model : Model
    problem : StepProblem
    tol : float
        The step's tolerance [m].
    port_planes : PortPlanes or None
        The port's planes (the port's decisions); None: read off its answer.
    x_port, x_cs : ndarray, shape (n, 3)
        The port's and clothsim's x_{k+1} [m].
    rounding : ndarray, shape (n,)
        The rounding of the port's state per vertex [m]
        (:func:`~clothsim.ports.held_margins.position_rounding`).
    margins : Margins, optional
        The step's (built when not given).

    Returns
    -------
    (list of (int, str), str)
        The changes for :func:`clothsim.ports.held_margins.adopt` and a note naming them
        ("" when there are none).
    """
    margins = margins or Margins(held, model, problem, rounding)
    if port_planes is not None:
        v, n, o = port_planes.step(k)
        diffs = plane_differences(clothsim_rows(held.planes()), v, n, o, held.x(),
                                  held.obstacles,
                                  offset_tolerance=max(tol, port_planes.offset_rounding),
                                  normal_tolerance=port_planes.normal_tolerance,
                                  skip=problem.fixed_vertices)
        changes = [(u, kind) for u, kind, _ in diffs
                   if kind in MARGINAL_KINDS and margins.marginal(u, kind)]
    else:
        changes = inferred(held, margins, x_port, x_cs)
    if not changes:
        return [], ""
    v, kind = changes[0]
    words = {"clothsim": "released", "port": "held", "stick": "sliding",
             "slide": "sticking"}[kind]
    where = (f"vertex {v}'s first contact within the rounding of the friction cone's edge, "
             f"{margins.tol[v]:.1e} m" if margins.first_contact(v, kind) else
             f"within {margins.force[v]:.2g} N of its threshold at vertex {v}")
    return changes, (f"{len(changes)} contact decision{'s' * (len(changes) != 1)} too close "
                     f"to call from the port's state ({where}) taken as the port's: vertex "
                     f"{v} {words}")


def marginal_entries(held, x_port, rounding, tol, differ) -> str:
    """New contacts whose entry is too close to call, when only their velocities differ.

    clothsim's step catches a vertex that entered an obstacle (its inward normal velocity
    removed, held in the next step); from the port's state rounded, a vertex the port's
    step left a rounding outside the surface can enter. When the positions agree and the
    velocities differ only at such vertices (caught by clothsim's step, not held in it,
    at a depth within the step's tolerance, and the port's x_{k+1} within it of the
    obstacle's contact surface: the printed start moves clothsim's answer by that much),
    the entry is taken as the port's: not caught, and the next step's decision is left
    without them. A port that catches a vertex deeper and keeps its inward velocity still
    differs.

    Parameters
    ----------
    held : HeldSteps
        Anchored at the step, stepped (the obstacles hold the next step's decision).
    x_port : ndarray, shape (n, 3)
        The port's x_{k+1} [m].
    rounding : ndarray, shape (n,)
        The rounding of the port's positions per vertex [m].
    tol : float
        The step's tolerance [m].
    differ : ndarray of bool, shape (n,)
        The vertices whose velocities differ.

    Returns
    -------
    str
        The note (the decision changed), or "" (another difference: nothing changed).
    """
    vs = np.flatnonzero(differ)
    now = {int(u) for _, h in held.planes() for u in h.vertices}
    caught = {int(u): e for e in held.obstacles for u in e._holding.vertices}
    if not len(vs) or any(int(v) in now or int(v) not in caught for v in vs):
        return ""
    gaps = [float(np.linalg.norm(caught[int(v)].closest(x_port[v][None])[0][0] - x_port[v]))
            for v in vs]
    mass, h2 = held.sim.model.vertex_mass, held.sim.h ** 2
    depths = [float(caught[int(v)]._holding.normal_force[
        np.flatnonzero(caught[int(v)]._holding.vertices == v)[0]]) * h2 / mass[v] for v in vs]
    if any(max(g, d) > max(rounding[v], tol) for g, d, v in zip(gaps, depths, vs, strict=True)):
        return ""   # caught deeper than the rounding reaches (m depth / h², its force)
    for e in held.obstacles:
        h = e._holding
        keep = ~np.isin(h.vertices, vs)
        if keep.all():
            continue
        c = len(h.vertices)
        e._holding = _holding(x_port, h.vertices[keep], h.normals[keep], h.stick[keep],
                              h.normal_force[keep], h.pull[keep], h.planes.offsets[:c][keep])
        out = ~np.isin(e.contact_vertices, vs)
        e.contact_vertices, e.contact_normals = e.contact_vertices[out], e.contact_normals[out]
    held.stepped()
    v = int(vs[0])
    return (f"{len(vs)} contact entr{'y' if len(vs) == 1 else 'ies'} too close to call from "
            f"the port's state (vertex {v} ends {gaps[0]:.1e} m from the {caught[v].kind}'s "
            f"contact surface, caught by clothsim's step {depths[0]:.1e} m deep, both within "
            f"the step's tolerance {max(rounding[v], tol):.1e} m; its inward velocity "
            f"removed) taken as the port's: vertex {v} not caught")

